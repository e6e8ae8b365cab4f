"""Child points and new stems for :mod:`weberpenn.grow`: where a grown level sprouts
(Sapling's t values, whorls, branch distribution, Bezier evaluation) and how the next
level's stems start (down angle, rotation, length, radius, level-1 'rotate' mode)."""

from __future__ import annotations

import math

import numpy as np

from ._grow_bezier import evaluate, handles
from ._grow_math import (
    TAU,
    apply,
    declination,
    euler_compat,
    mat_x,
    mat_z,
    run_rank,
    track_frames,
)
from ._grow_random import CHILD, TIP, WHORL, derive, uniform
from ._grow_shapes import shape_ratio
from ._grow_stems import Cfg, ChildPoints, Families, Splines


# --------------------------------------------------------------------------- child points
def _trunk_t(cfg: Cfg, children: float, base: float, key: np.ndarray) -> np.ndarray:
    """Sapling's list of child positions on the trunk (evenly spaced, whorls, distribution)."""
    c = int(children) if children > 0 else 0
    t = [(a + 1) / c for a in range(c)] if c > 0 else []
    t = t[int(base * (len(t) + 1)) :]
    if cfg.nrings > 0:
        ring = cfg.nrings
        jitter = 0.995 + 0.01 * uniform(key, WHORL, np.arange(max(len(t) - 1, 0)))
        t = [(math.floor(x * ring) / ring) * float(j) for x, j in zip(t[:-1], jitter, strict=True)]
        t.append(1.0)
        t = [x for x in t if x > base]
    tv = np.array(t, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        tv = (tv - base) / (1.0 - base)
        if cfg.branch_dist < 1.0:
            tv = np.abs(tv) ** (1.0 / cfg.branch_dist) * np.sign(tv)
        else:
            tv = 1.0 - np.abs(1.0 - tv) ** cfg.branch_dist * np.sign(1.0 - tv)
        tv = tv * (1.0 - base) + base
    return np.nan_to_num(tv, nan=1.0)


def _limit(cnt: np.ndarray, limit: int) -> np.ndarray:
    """Counts cut so that their running total stays within ``limit``."""
    before = np.cumsum(cnt) - cnt
    return np.clip(limit - before, 0, cnt)


def _pairs(
    cfg: Cfg,
    n: int,
    spl: Splines,
    s_ord: np.ndarray,
    cb: np.ndarray,
    ct: np.ndarray,
    children: np.ndarray,
    base: float,
    trunk_key: np.ndarray,
    limit: int,
) -> tuple[np.ndarray, np.ndarray]:
    """(spline, t) of every child position inside a spline's share of its family, in
    Sapling's order (splines in ``s_ord`` order, t in list order).  Only the t values near
    each spline's range are generated, at most about ``limit`` of them."""
    res = cfg.curve_res[min(n, 3)]
    cbo, cto = cb[s_ord], ct[s_ord]
    if n == 0:
        tv = _trunk_t(cfg, float(children[0]), base, trunk_key)
        srt = np.argsort(tv, kind="stable")
        ts = tv[srt]
        lo = np.searchsorted(ts, cbo, side="left")
        hi = np.searchsorted(ts, cto, side="right")
        cnt = _limit(np.maximum(hi - lo, 0), limit)
        rep = np.repeat(np.arange(len(s_ord)), cnt)
        local = np.arange(len(rep)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        orig = srt[lo[rep] + local]
        back = np.lexsort((orig, rep))  # Sapling walks the list in its own order
        ps, pt = s_ord[rep[back]], tv[orig[back]]
        return ps[pt < 1.0], pt[pt < 1.0]
    nfam = len(children)
    nseg = np.bincount(spl.fam, weights=(res - spl.start).astype(np.float64), minlength=nfam)
    num = np.where(children > 0, np.round(children / np.maximum(nseg, 1) * res), 0).astype(np.int64)
    trim = (base * (num + 1)).astype(np.int64)
    f = spl.fam[s_ord]
    numf = num[f].astype(np.float64)
    ok = np.isfinite(cbo) & np.isfinite(cto) & (numf > 0)
    with np.errstate(invalid="ignore"):
        a_lo = np.where(ok, np.floor(np.where(ok, cbo, 0.0) * numf) - 2, 0).astype(np.int64)
        a_hi = np.where(ok, np.ceil(np.where(ok, cto, 0.0) * numf) + 1, -1).astype(np.int64)
    a_lo = np.maximum(a_lo, trim[f])
    a_hi = np.minimum(a_hi, num[f] - 1)
    cnt = _limit(np.maximum(a_hi - a_lo + 1, 0), limit)
    rep = np.repeat(np.arange(len(s_ord)), cnt)
    local = np.arange(len(rep)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    a = a_lo[rep] + local
    pt = (a + 1) / numf[rep]
    keep = (pt >= cbo[rep]) & (pt <= cto[rep]) & (pt < 1.0)
    return s_ord[rep[keep]], pt[keep]


def child_points(
    cfg: Cfg,
    n: int,
    spl: Splines,
    order: np.ndarray,
    gid: np.ndarray,
    children: np.ndarray,
    base: float,
    fam_key: np.ndarray,
    cap: int,
) -> tuple[ChildPoints, bool]:
    """Where the grown level sprouts: Sapling's child points in Sapling's order, at most
    ``cap`` of them (the second value says whether the cap cut any)."""
    res = cfg.curve_res[min(n, 3)]
    nseg = res - spl.start
    seg_total = spl.seg_len * nseg
    max_off = np.zeros(len(children))
    np.maximum.at(max_off, spl.fam, spl.offset_len + seg_total)
    mo = max_off[spl.fam]
    with np.errstate(divide="ignore", invalid="ignore"):
        cb_s = spl.offset_len / mo
        ct_s = cb_s + seg_total / mo
    s_ord = order
    ps, pt = _pairs(
        cfg, n, spl, s_ord, cb_s, ct_s, children, base, fam_key[:1], cap + 5 * len(s_ord) + 1
    )

    # Sapling order: each spline's points, then its tip; cut at ``cap``
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    per_rank = np.bincount(rank[ps], minlength=len(order))
    tip_at = np.cumsum(per_rank) + np.arange(len(order))
    srt = np.empty(len(ps) + len(order), dtype=np.int64)
    is_tip = np.zeros(len(srt), dtype=bool)
    is_tip[tip_at] = True
    srt[~is_tip] = np.arange(len(ps))
    srt[tip_at] = len(ps) + np.arange(len(order))
    cut = len(srt) > cap
    srt = srt[:cap]
    is_pair = srt < len(ps)
    tip_sel = srt[~is_pair] - len(ps)
    ps, pt = ps[srt[is_pair]], pt[srt[is_pair]]

    cb, ct = cb_s[ps], ct_s[ps]
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = (pt - cb) / (ct - cb)
        ofst = ((pt - base) / (ct - base)) * (1.0 - base) + base
    scaled = np.nan_to_num(scaled, nan=0.0)
    ofst = np.nan_to_num(ofst, nan=1.0, posinf=1.0, neginf=0.0)
    length = nseg[ps] * scaled
    idx = np.floor(length).astype(np.int64)
    tt = length - idx
    over = idx >= nseg[ps]
    idx = np.where(over, nseg[ps] - 1, idx)
    tt = np.where(over, 1.0, tt)
    slot = spl.start[ps] + idx
    if len(ps):
        hl, hr = handles(spl.pts, spl.start)
        co, tan = evaluate(spl.pts, hl, hr, ps, slot, tt)
    else:
        co, tan = np.zeros((0, 3)), np.zeros((0, 3))
    radius = (1.0 - tt) * spl.rad[ps, slot] + tt * spl.rad[ps, slot + 1]

    # each child stem's key: its parent's, and its rank among the parent's child points
    rank = run_rank(ps)
    # tips: one per spline
    ts = s_ord[tip_sel]
    tip_co = spl.pts[ts, res]
    # the last point's AUTO handle mirrors the last segment: handle - point = 2/5.1228 * segment
    tip_tan = (tip_co - spl.pts[ts, res - 1]) * (2.0 / 5.1228)
    # both were selected in order: interleave them back
    m = len(srt)
    src = np.empty(m, dtype=np.int64)
    src[is_pair], src[~is_pair] = ps, ts

    def comb(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        out = np.empty((m,) + a.shape[1:], dtype=a.dtype)
        out[is_pair], out[~is_pair] = a, b
        return out

    cp = ChildPoints(
        co=comb(co, tip_co),
        frame=track_frames(comb(tan, tip_tan)),
        rad_par0=spl.rad_s[src],
        rad_par1=comb(radius, spl.rad[ts, res]),
        offset=comb(pt, np.ones(len(ts))),
        stem_offset=comb(ofst, np.ones(len(ts))),
        len_par=res * spl.seg_len[src],
        src=gid[src],
        key=comb(derive(spl.key[ps], CHILD, rank), derive(spl.key[ts], TIP)),
    )
    return cp, cut


# --------------------------------------------------------------------------- fabricate
def _running_rotate(rot: float, count: int | np.ndarray) -> np.ndarray:
    """Sapling's accumulated azimuth for the i-th child: (i+1)*rot, or alternating if
    rot < 0; ``count`` children numbered 0.., or each child's number ``i`` given."""
    i = np.asarray(np.arange(count) if np.ndim(count) == 0 else count, dtype=np.float64)
    if rot < 0.0:
        return abs(rot) * np.where(i % 2 == 0, -1.0, 1.0)
    return (i + 1.0) * rot


def _select_rotate(cfg: Cfg, cp: ChildPoints, base: float) -> tuple[np.ndarray, np.ndarray]:
    """Level-1 'rotate' mode: one child per height across trunk clones, aimed outwards."""
    tip = cp.offset == 1.0
    inner = np.nonzero(~tip)[0]
    if len(inner) == 0:
        tips = np.nonzero(tip)[0]
        return tips, np.zeros(len(tips))
    off = cp.offset[inner]
    srt = np.lexsort((inner, off))
    inner = inner[srt]
    off = off[srt]
    newg = np.concatenate([[True], off[1:] != off[:-1]])
    grp = np.cumsum(newg) - 1
    ng = int(grp[-1]) + 1
    brot = _running_rotate(cfg.rotate[1], ng) + cfg.rotate_v[1]
    a1 = np.mod(brot, TAU)[grp]
    co = cp.co[inner]
    a2 = np.arctan2(co[:, 0], -co[:, 1])
    d = np.minimum(np.mod(a1 - a2 + TAU, TAU), np.mod(a2 - a1 + TAU, TAU))
    pick_order = np.lexsort((np.arange(len(inner)), d, grp))
    firsts = pick_order[np.concatenate([[True], grp[pick_order][1:] != grp[pick_order][:-1]])]
    chosen = inner[firsts]
    b = cp.co[chosen]
    br = brot[grp[firsts]]
    bd = np.hypot(b[:, 0], b[:, 1])
    offc = cp.offset[chosen]
    bl = (
        cp.len_par[chosen]
        * cfg.length[1]
        * shape_ratio(cfg.shape, (1.0 - offc) / (1.0 - base), cfg.custom)
    )
    if cfg.down_angle_v[1] > 0:
        down_a = cfg.down_angle[1] + (-cfg.down_angle_v[1] * (1 - (1 - offc) / (1 - base)) ** 2)
    else:
        down_a = np.full(len(chosen), cfg.down_angle[1])
    bl = np.where(down_a < 0.5 * np.pi, bl * np.sin(down_a) ** 2, bl)
    bl = bl * 0.33
    vx = np.sin(br) * (bd + bl)
    vy = np.cos(br) * (bd + bl)
    rot_a = np.arctan2(vx - b[:, 0], vy + b[:, 1])
    tips = np.nonzero(tip)[0]
    return np.concatenate([chosen, tips]), np.concatenate([rot_a, np.zeros(len(tips))])


def fabricate(cfg: Cfg, n: int, cp: ChildPoints, base: float) -> Families:
    """Start the stems of level ``n`` at the child points of level ``n - 1``."""
    m = min(n, 3)
    base = min(0.999, base)
    rotate_mode = n == 1 and cfg.rmode_rotate
    if rotate_mode:
        sel, rot_a = _select_rotate(cfg, cp, base)
        cp = ChildPoints(*(getattr(cp, f)[sel] for f in ChildPoints.__dataclass_fields__))
    c = len(cp.offset)
    tip = cp.offset == 1.0
    dav = cfg.down_angle_v[m]
    rel = (1.0 - cp.offset) / (1.0 - base)
    if cfg.use_old_down:
        down_v = dav * (1.0 - 2.0 * (0.2 + 0.8 * rel)) if dav < 0.0 else np.full(c, dav)
    else:
        down_v = np.full(c, dav) if dav < 0.0 else -dav * (1.0 - rel) ** 2
    down = np.where(tip, 0.0, cfg.down_angle[m] + down_v)
    # the azimuth accumulates along each parent stem (Sapling: along the whole level, so
    # one extra child anywhere turned every later branch of the level)
    if not rotate_mode:
        b_rot = _running_rotate(cfg.rotate[m], run_rank(cp.src)) + cfg.rotate_v[m]
    else:
        b_rot = rot_a
    sd = np.sin(down)
    tp = np.stack([sd * np.sin(b_rot), -sd * np.cos(b_rot), np.cos(down)], axis=1)
    if rotate_mode:
        inner = ~tip
        out = apply(cp.frame, tp)
        if cfg.use_parent_angle:
            e2 = euler_compat(cp.frame, b_rot)[:, 2]
            dec = declination(cp.frame)
            rot = mat_z(e2) @ mat_x(dec) @ mat_z(-e2)
            tilted = apply(rot, tp)
        else:
            tilted = tp
        tp = np.where(inner[:, None], tilted, out)
    else:
        tp = apply(cp.frame, tp)

    max_bl = cfg.scale_val * float(np.prod(cfg.length[: m + 1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        srel = (1.0 - cp.stem_offset) / (1.0 - base)
    srel = np.nan_to_num(srel, nan=0.0)
    l_shape = shape_ratio(cfg.shape, srel, cfg.custom) if m == 1 else shape_ratio(cfg.shape_s, srel)
    branch_l = np.maximum(cp.len_par * cfg.length[m] * l_shape, 0.0)
    frac = branch_l / max_bl if max_bl > 0 else np.zeros(c)
    if n == cfg.levels - 1:
        if cfg.leaves < 0:
            children = np.zeros(c)
        else:
            children = cfg.leaves * (0.1 + 0.9 * frac) * shape_ratio(cfg.leaf_dist, 1.0 - cp.offset)
    else:
        children = cfg.branches[min(3, n + 1)] * (0.1 + 0.9 * frac)
    with np.errstate(divide="ignore", invalid="ignore"):
        lr = np.where(cp.len_par > 0, branch_l / cp.len_par, 0.0)
    start_rad = np.minimum(cp.rad_par0 * lr**cfg.ratio_power * cfg.radius_tweak[m], cp.rad_par1)
    start_rad = np.where(tip, cp.rad_par1, start_rad)
    end_rad = np.maximum(start_rad * (1.0 - cfg.taper[m]), 0.0) ** cfg.ratio_power
    start_rad = np.maximum(start_rad, cfg.min_radius)
    end_rad = np.minimum(np.maximum(end_rad, cfg.min_radius), start_rad)
    res = cfg.curve_res[m]
    return Families(
        pos=cp.co,
        dir=tp,
        curv=np.full(c, cfg.curve[m] / res),
        seg_len=branch_l / res,
        rad_s=start_rad,
        rad_e=end_rad,
        rad0=start_rad,
        children=children,
        parent=cp.src,
        key=cp.key,
    )


def trunk(cfg: Cfg, key: np.ndarray) -> Families:
    start_rad = cfg.scale_val * cfg.ratio * cfg.scale0 * cfg.scale_v0
    end_rad = max(start_rad * (1.0 - cfg.taper[0]), 0.0) ** cfg.ratio_power
    start_rad = max(start_rad, cfg.min_radius)
    end_rad = min(max(end_rad, cfg.min_radius), start_rad)
    children = cfg.leaves if cfg.levels == 1 else cfg.branches[1]
    res = cfg.curve_res[0]
    return Families(
        pos=np.zeros((1, 3)),
        dir=np.array([[0.0, 0.0, 1.0]]),
        curv=np.array([cfg.curve[0] / res]),
        seg_len=np.array([cfg.scale_val * cfg.length[0] / res]),
        rad_s=np.array([start_rad]),
        rad_e=np.array([end_rad]),
        rad0=np.array([start_rad * cfg.root_flare]),
        children=np.array([float(max(children, 0))]),
        parent=np.array([-1], dtype=np.int64),
        key=np.asarray(key, dtype=np.uint64).reshape(1),
    )
