"""Grow a Weber-Penn tree skeleton the way Blender's Sapling Tree Gen does.

``grow(params, seed)`` follows Sapling 0.3.x's algorithm (see
``reference/weber_penn_notes.md``) with TreeSketchNet's realised keys in place of
Sapling's random draws: ``curveV1/2`` are the per-segment curve draws, ``splitAngleV1/2``
the split-angle draws, ``choiceNegPos1/2`` the split signs, ``rLastAng`` the initial split
roll, ``scaleV``/``scaleV0``/``leafScaleV`` realised offsets and multipliers, and
``rotateV``/``downAngleV``/``leafRotateV``/``leafDownAngleV`` realised offsets.

What stays random in Sapling and has no realised key (whether a segment splits,
``lengthV`` and the whorl jitter of ``nrings``) comes from a numpy ``Generator`` seeded by
``seed`` and ``params['seed']``; each split draw is shifted by ``rSplits2`` (modulo 1), so
it stays uniform (Sapling's statistics) while ``rSplits2`` still changes the tree.  So
``grow`` is a pure function: the same input gives byte-identical arrays.

Deliberate differences from Sapling: a stem's end radius is capped at its start radius
(Sapling's ``(startRad * (1 - taper)) ** ratioPower`` exceeds the start radius when the
start radius is above 1, so radii would grow towards the tip); operator options that the
TreeSketchNet dictionary does not store take Sapling's defaults (rMode 'rotate',
autoTaper on, closeTip off, splitByLen off).  The trunk-split rule is checked draw for
draw against Sapling's own statistics by ``benchmarks/compare_sapling.py``.

The implementation is vectorised: all stems of a level grow together, one Bezier
segment at a time, with local frames as rotation matrices (Sapling's quaternions from
``to_track_quat('Z', 'Y')``, replicated in :mod:`weberpenn._grow_math`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._grow_bezier import evaluate, handles
from ._grow_leaves import leaf_transforms
from ._grow_math import (
    TAU,
    anglemean,
    apply,
    declination,
    euler_compat,
    euler_frames_no_roll,
    euler_to_mat,
    mat_x,
    mat_z,
    normalize,
    rot_axis,
    rot_y,
    rot_z,
    track_frames,
)
from ._grow_shapes import find_taper, shape_ratio
from .params import TreeParams, validate
from .skeleton import Skeleton

__all__ = ["Skeleton", "grow"]


@dataclass
class _Families:
    """Stems of one level before they grow (one 'family' each: the stem and its clones)."""

    pos: np.ndarray  # (F, 3) first point
    dir: np.ndarray  # (F, 3) initial growth direction
    curv: np.ndarray  # (F,) curvature per segment, radians
    seg_len: np.ndarray  # (F,)
    rad_s: np.ndarray  # (F,)
    rad_e: np.ndarray  # (F,)
    rad0: np.ndarray  # (F,) radius of the first point
    children: np.ndarray  # (F,) children (or leaves) per stem; 0 = only the tip sprouts
    parent: np.ndarray  # (F,) global id of the parent stem (-1 for the trunk)


@dataclass
class _Splines:
    """Grown splines of one level in padded arrays (slots ``start .. R``)."""

    pts: np.ndarray  # (N, R+1, 3)
    rad: np.ndarray  # (N, R+1)
    start: np.ndarray  # (N,)
    fam: np.ndarray  # (N,)
    seg_len: np.ndarray  # (N,)
    rad_s: np.ndarray  # (N,)
    offset_len: np.ndarray  # (N,)
    parent: np.ndarray  # (N,) local index of the spline a clone split from, -1 = root


@dataclass
class _ChildPoints:
    co: np.ndarray  # (C, 3)
    frame: np.ndarray  # (C, 3, 3)
    rad_par0: np.ndarray  # (C,) parent spline start radius
    rad_par1: np.ndarray  # (C,) parent radius here
    offset: np.ndarray  # (C,) t along the parent family (1 = tip)
    stem_offset: np.ndarray  # (C,)
    len_par: np.ndarray  # (C,) parent nominal length
    src: np.ndarray  # (C,) global id of the parent spline


class _Cfg:
    """Parameters in the units the algorithm uses (radians, floats, ints)."""

    def __init__(self, p: Mapping[str, Any]):
        r = math.radians
        self.levels = int(p["levels"])
        self.length = [float(x) for x in p["length"]]
        self.length_v = [float(x) for x in p["lengthV"]]
        self.taper_crown = float(p["taperCrown"])
        self.branches = [int(x) for x in p["branches"]]
        self.curve_res = [max(1, int(x)) for x in p["curveRes"]]
        self.curve = [r(x) for x in p["curve"]]
        self.curve_v1 = [r(x) for x in p["curveV1"]]
        self.curve_v2 = [r(x) for x in p["curveV2"]]
        self.curve_back = [r(x) for x in p["curveBack"]]
        self.base_splits = int(p["baseSplits"])
        self.seg_splits = [float(x) for x in p["segSplits"]]
        self.split_angle = [r(x) for x in p["splitAngle"]]
        self.split_angle_v1 = [r(x) for x in p["splitAngleV1"]]
        self.split_angle_v2 = [r(x) for x in p["splitAngleV2"]]
        self.cnp1 = float(p["choiceNegPos1"])
        self.cnp2 = float(p["choiceNegPos2"])
        self.r_last = [r(x) for x in p["rLastAng"]]
        self.r_splits2 = float(p["rSplits2"])
        self.scale_val = float(p["scale"]) + float(p["scaleV"])
        self.scale_val += math.copysign(1e-6, self.scale_val)
        self.attract_up = [float(x) for x in p["attractUp"]]
        self.attract_out = [float(x) for x in p["attractOut"]]
        self.shape = int(p["shape"])
        self.shape_s = int(p["shapeS"])
        self.custom = [float(x) for x in p["customShape"]]
        self.branch_dist = float(p["branchDist"])
        self.nrings = int(p["nrings"])
        self.base_size = float(p["baseSize"])
        self.base_size_s = float(p["baseSize_s"])
        self.split_height = float(p["splitHeight"])
        self.split_bias = float(p["splitBias"])
        self.ratio = float(p["ratio"])
        self.min_radius = float(p["minRadius"])
        self.root_flare = float(p["rootFlare"])
        self.ratio_power = float(p["ratioPower"])
        self.radius_tweak = [float(x) for x in p["radiusTweak"]]
        self.down_angle = [r(x) for x in p["downAngle"]]
        self.down_angle_v = [r(x) for x in p["downAngleV"]]
        self.rotate = [r(x) for x in p["rotate"]]
        self.rotate_v = [r(x) for x in p["rotateV"]]
        self.scale0 = float(p["scale0"])
        self.scale_v0 = float(p["scaleV0"])
        self.use_old_down = bool(p["useOldDownAngle"])
        self.use_parent_angle = bool(p["useParentAngle"])
        self.prune = bool(p["prune"])
        self.prune_width = float(p["pruneWidth"])
        self.prune_base = min(float(p["pruneBase"]), self.base_size)
        self.prune_peak = float(p["pruneWidthPeak"])
        self.prune_high = float(p["prunePowerHigh"])
        self.prune_low = float(p["prunePowerLow"])
        self.prune_ratio = float(p["pruneRatio"])
        self.leaves = int(p["leaves"])
        self.leaf_dist = int(p["leafDist"])
        # Sapling defaults for operator options TreeSketchNet does not store
        self.close_tip = False
        self.rmode_rotate = True
        self.taper = find_taper(
            self.length,
            [float(x) for x in p["taper"]],
            self.shape,
            self.shape_s,
            self.levels,
            self.custom,
        )


def _rng_for(seed: int, params_seed: int, level: int, stream: int) -> np.random.Generator:
    words = [int(seed) & 0xFFFFFFFF, (int(seed) >> 32) & 0xFFFFFFFF]
    words += [int(params_seed) & 0xFFFFFFFF, (int(params_seed) >> 32) & 0xFFFFFFFF]
    return np.random.default_rng(np.random.SeedSequence(words + [level, stream]))


# --------------------------------------------------------------------------- growth
def _attract_up(v: np.ndarray, att: float, res: int) -> np.ndarray:
    if att == 0.0 or len(v) == 0:
        return v
    t = track_frames(v)
    dec = np.arccos(np.clip(normalize(v)[:, 2], -1.0, 1.0))
    yz = t[:, 2, 1]
    a = att * dec * np.abs(yz) / res
    a = np.where(-dec + a < -np.pi, -np.pi + dec, a)
    a = np.where(dec - a < 0.0, dec, a)
    return rot_axis(v, t[:, :, 0], -a)


def _grow_level(
    cfg: _Cfg, n: int, fam: _Families, scale: np.ndarray, rng: np.random.Generator
) -> _Splines:
    """Grow every family of level ``n`` (param index ``m = min(n, 3)``) segment by segment."""
    m = min(n, 3)
    res = cfg.curve_res[m]
    trunk = n == 0
    f = len(fam.pos)
    stem_seg = fam.seg_len * scale  # Sapling's stemsegL (per family)
    lv = cfg.length_v[m]
    seg_len = stem_seg * (rng.uniform(1.0 - lv, 1.0 + lv, f) if lv > 0.0 else 1.0)

    pts = np.zeros((f, res + 1, 3))
    pts[:, 0] = fam.pos
    rad = np.zeros((f, res + 1))
    rad[:, 0] = fam.rad0
    start = np.zeros(f, dtype=np.int64)
    famid = np.arange(f, dtype=np.int64)
    rad_s = fam.rad_s.copy()
    rad_e = fam.rad_e.copy()
    curv = fam.curv.copy()
    sign = np.ones(f)
    split_last = np.zeros(f, dtype=bool)
    r_last = np.full(f, np.nan)
    dirv = fam.dir.copy()
    offset_len = np.zeros(f)
    parent = np.full(f, -1, dtype=np.int64)

    seg_splits = cfg.seg_splits[m]
    cv1, cv2 = cfg.curve_v1[m], cfg.curve_v2[m]
    att_up = cfg.attract_up[m]
    att_out = cfg.attract_out[m]
    split_ang = cfg.split_angle[m]
    angle0 = cfg.cnp1 * (split_ang + cfg.split_angle_v1[m])
    spread = cfg.cnp2 * (split_ang + cfg.split_angle_v2[m])
    branch_step = cfg.rotate[0] + cfg.rotate_v[0]
    h_forced = int((res - 1) * cfg.split_height) + 1
    k_back = int(res / 2 + 0.5)

    for k in range(res):
        nsp = len(famid)
        kp = k / (res - 1) if res > 1 else 1.0
        # ---- how many clones each spline makes at this segment
        sv = seg_splits
        if trunk:
            sv = max(((2.0 * cfg.split_bias) * (kp - 0.5) + 1.0) * sv, 0.0)
        sval = np.where(split_last, sv * sv, sv * 1.33)
        u = np.mod(rng.random(nsp) + cfg.r_splits2, 1.0)
        if k == 0 or trunk and k < (res - 1) * cfg.split_height and k != 1:
            nsplit = np.zeros(nsp, dtype=np.int64)
        elif trunk and k == 1:
            nsplit = np.full(nsp, cfg.base_splits, dtype=np.int64)
        elif trunk and k == h_forced:
            nsplit = (sval > 0.0).astype(np.int64)
        else:
            nsplit = (u < sval).astype(np.int64)
        if k == k_back and cfg.curve_back[m] != 0.0:
            curv = curv + 2.0 * cfg.curve_back[m] / res

        # ---- growSpline for all splines at once
        scurv = np.zeros(nsp) if (trunk and kp <= cfg.split_height) else curv
        cang = scurv + cv1 * kp * sign
        cvar = cv2 * kp * sign
        sign = -sign
        if trunk:
            frame = euler_frames_no_roll(dirv)
            dec = declination(frame) / np.pi
            tf = np.maximum(0.1, 1.0 - dec * dec * cfg.taper_crown * 30.0)
        else:
            frame = track_frames(dirv)
            tf = np.ones(nsp)
        tip = pts[np.arange(nsp), k]
        if n > 0 and kp > 0.0 and att_out > 0.0:
            d = np.arctan2(tip[:, 0], -tip[:, 1]) + TAU
            e = euler_compat(frame, d)
            e[:, 2] = anglemean(e[:, 2], d, kp * att_out)
            frame = euler_to_mat(e)

        sp = nsplit > 0
        angle = np.full(nsp, angle0)
        branch_rot = np.zeros(nsp)
        new = None
        if sp.any():
            if n > 0:
                angle = angle * (
                    np.maximum(1.0 - np.degrees(declination(frame)) / 90.0, 0.0) * 0.67 + 0.33
                )
            rl = np.where(np.isnan(r_last), cfg.r_last[m], r_last)
            branch_rot = rl + branch_step
            r_last = np.where(sp, branch_rot, r_last)
            par = np.repeat(np.nonzero(sp)[0], nsplit[sp])
            first = np.concatenate([[0], np.cumsum(nsplit[sp])[:-1]])
            idx = np.arange(len(par)) - np.repeat(first, nsplit[sp])
            ncl = len(par)
            lv_c = rng.uniform(1.0 - lv, 1.0 + lv, ncl) if lv > 0.0 else np.ones(ncl)
            bscale = np.minimum(lv_c * tf[par], 1.0)
            a = angle[par] + cang[par]
            v = np.stack([np.zeros(ncl), -np.sin(a), np.cos(a)], axis=1)
            v = rot_y(v, cvar[par])
            if trunk:
                v = rot_z(v, branch_rot[par])
                v = rot_z(v, np.pi - (TAU / (nsplit[par] + 1)) * (idx + 1))
            else:
                v = rot_y(v, spread)
            v = apply(frame[par], v)
            v = _attract_up(v, att_up, res)
            stem_l = stem_seg[famid[par]] * lv_c
            v = normalize(v) * (stem_l * tf[par])[:, None]
            c_pts = np.zeros((ncl, res + 1, 3))
            c_pts[:, k] = tip[par]
            c_pts[:, k + 1] = tip[par] + v
            c_rad = np.zeros((ncl, res + 1))
            c_rad[:, k] = (rad_s[par] * (1 - k / res) + rad_e[par] * (k / res)) * bscale
            c_rad[:, k + 1] = (
                rad_s[par] * (1 - (k + 1) / res) + rad_e[par] * ((k + 1) / res)
            ) * bscale
            if cfg.close_tip and k == res - 1 and n == cfg.levels - 1:
                c_rad[:, k + 1] = 0.0
            new = dict(
                pts=c_pts,
                rad=c_rad,
                start=np.full(ncl, k, dtype=np.int64),
                famid=famid[par],
                rad_s=rad_s[par] * bscale,
                rad_e=rad_e[par] * bscale,
                curv=curv[par],
                sign=np.ones(ncl),  # a new stem: its first bend (at k + 1) is positive
                split_last=np.ones(ncl, dtype=bool),
                r_last=branch_rot[par] + np.pi,
                dirv=v,
                offset_len=offset_len[par] + seg_len[par] * (k - start[par]),
                parent=par,
                seg_len=stem_l,
            )

        a = np.where(sp, -angle + cang, cang)
        v = np.stack([np.zeros(nsp), -np.sin(a), np.cos(a)], axis=1)
        v = rot_y(v, cvar)
        if sp.any():
            if trunk:
                v = np.where(sp[:, None], rot_z(v, branch_rot), v)
            else:
                v = np.where(sp[:, None], rot_y(v, -spread), v)
        v = apply(frame, v)
        split_last = sp
        v = _attract_up(v, att_up, res)
        v = normalize(v) * (seg_len * tf)[:, None]
        pts[:, k + 1] = tip + v
        rad[:, k + 1] = rad_s * (1 - (k + 1) / res) + rad_e * ((k + 1) / res)
        if cfg.close_tip and k == res - 1 and n == cfg.levels - 1:
            rad[:, k + 1] = 0.0
        dirv = v

        if new is not None:
            pts = np.concatenate([pts, new["pts"]])
            rad = np.concatenate([rad, new["rad"]])
            start = np.concatenate([start, new["start"]])
            famid = np.concatenate([famid, new["famid"]])
            rad_s = np.concatenate([rad_s, new["rad_s"]])
            rad_e = np.concatenate([rad_e, new["rad_e"]])
            curv = np.concatenate([curv, new["curv"]])
            sign = np.concatenate([sign, new["sign"]])
            split_last = np.concatenate([split_last, new["split_last"]])
            r_last = np.concatenate([r_last, new["r_last"]])
            dirv = np.concatenate([dirv, new["dirv"]])
            offset_len = np.concatenate([offset_len, new["offset_len"]])
            parent = np.concatenate([parent, new["parent"]])
            seg_len = np.concatenate([seg_len, new["seg_len"]])

    return _Splines(pts, rad, start, famid, seg_len, rad_s, offset_len, parent)


# --------------------------------------------------------------------------- ordering
def _order(spl: _Splines) -> np.ndarray:
    """Sapling's spline order: by family, then creation (clones after their stem)."""
    return np.lexsort((np.arange(len(spl.fam)), spl.fam))


# --------------------------------------------------------------------------- child points
def _t_values(
    cfg: _Cfg, n: int, spl: _Splines, children: np.ndarray, base: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """(family, t) of every candidate child position, families ascending, t ascending."""
    res = cfg.curve_res[min(n, 3)]
    nfam = len(children)
    if n == 0:
        c = int(children[0]) if children[0] > 0 else 0
        t = [(a + 1) / c for a in range(c)] if c > 0 else []
        t = t[int(base * (len(t) + 1)) :]
        if cfg.nrings > 0:
            ring = cfg.nrings
            t = [(math.floor(x * ring) / ring) * float(rng.uniform(0.995, 1.005)) for x in t[:-1]]
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
        tv = np.nan_to_num(tv, nan=1.0)
        return np.zeros(len(tv), dtype=np.int64), tv
    nseg = np.bincount(spl.fam, weights=(res - spl.start).astype(np.float64), minlength=nfam)
    num = np.where(children > 0, np.round(children / np.maximum(nseg, 1) * res), 0).astype(np.int64)
    trim = (base * (num + 1)).astype(np.int64)
    cnt = np.maximum(num - trim, 0)
    fam_t = np.repeat(np.arange(nfam), cnt)
    first = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    a = np.arange(len(fam_t)) - np.repeat(first, cnt) + np.repeat(trim, cnt)
    t = (a + 1) / np.repeat(num, cnt).astype(np.float64)
    return fam_t, t


def _child_points(
    cfg: _Cfg,
    n: int,
    spl: _Splines,
    order: np.ndarray,
    gid: np.ndarray,
    children: np.ndarray,
    base: float,
    rng: np.random.Generator,
) -> _ChildPoints:
    res = cfg.curve_res[min(n, 3)]
    nseg = res - spl.start
    seg_total = spl.seg_len * nseg
    max_off = np.zeros(len(children))
    np.maximum.at(max_off, spl.fam, spl.offset_len + seg_total)
    fam_t, tv = _t_values(cfg, n, spl, children, base, rng)

    # pair every spline (in Sapling order) with its family's t values
    tcount = np.bincount(fam_t, minlength=len(children))
    tfirst = np.concatenate([[0], np.cumsum(tcount)[:-1]])
    s_ord = order
    per = tcount[spl.fam[s_ord]]
    ps = np.repeat(s_ord, per)
    base_idx = np.repeat(tfirst[spl.fam[s_ord]], per)
    local = np.arange(len(ps)) - np.repeat(np.concatenate([[0], np.cumsum(per)[:-1]]), per)
    pt = tv[base_idx + local]
    mo = max_off[spl.fam[ps]]
    with np.errstate(divide="ignore", invalid="ignore"):
        cb = spl.offset_len[ps] / mo
        ct = cb + seg_total[ps] / mo
        keep = (pt >= cb) & (pt <= ct) & (pt < 1.0)
        ps, pt, cb, ct = ps[keep], pt[keep], cb[keep], ct[keep]
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

    # tips: one per spline
    tip_co = spl.pts[s_ord, res]
    # the last point's AUTO handle mirrors the last segment: handle - point = 2/5.1228 * segment
    tip_tan = (tip_co - spl.pts[s_ord, res - 1]) * (2.0 / 5.1228)
    # pairs are already in Sapling order (spline rank, then t): put each tip after its
    # spline's points
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    per_rank = np.bincount(rank[ps], minlength=len(order))
    tip_at = np.cumsum(per_rank) + np.arange(len(order))
    srt = np.empty(len(ps) + len(order), dtype=np.int64)
    is_tip = np.zeros(len(srt), dtype=bool)
    is_tip[tip_at] = True
    srt[~is_tip] = np.arange(len(ps))
    srt[tip_at] = len(ps) + np.arange(len(order))
    src = np.concatenate([ps, s_ord])[srt]
    cp = _ChildPoints(
        co=np.concatenate([co, tip_co])[srt],
        frame=track_frames(np.concatenate([tan, tip_tan])[srt]),
        rad_par0=spl.rad_s[src],
        rad_par1=np.concatenate([radius, spl.rad[s_ord, res]])[srt],
        offset=np.concatenate([pt, np.ones(len(s_ord))])[srt],
        stem_offset=np.concatenate([ofst, np.ones(len(s_ord))])[srt],
        len_par=res * spl.seg_len[src],
        src=gid[src],
    )
    return cp


# --------------------------------------------------------------------------- fabricate
def _running_rotate(rot: float, count: int) -> np.ndarray:
    """Sapling's accumulated azimuth for the i-th child: i*rot, or alternating if rot < 0."""
    i = np.arange(count, dtype=np.float64)
    if rot < 0.0:
        return abs(rot) * np.where(i % 2 == 0, -1.0, 1.0)
    return (i + 1.0) * rot


def _select_rotate(cfg: _Cfg, cp: _ChildPoints, base: float) -> tuple[np.ndarray, np.ndarray]:
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


def _fabricate(cfg: _Cfg, n: int, cp: _ChildPoints, base: float) -> _Families:
    """Start the stems of level ``n`` at the child points of level ``n - 1``."""
    m = min(n, 3)
    base = min(0.999, base)
    rotate_mode = n == 1 and cfg.rmode_rotate
    if rotate_mode:
        sel, rot_a = _select_rotate(cfg, cp, base)
        cp = _ChildPoints(*(getattr(cp, f)[sel] for f in _ChildPoints.__dataclass_fields__))
    c = len(cp.offset)
    tip = cp.offset == 1.0
    dav = cfg.down_angle_v[m]
    rel = (1.0 - cp.offset) / (1.0 - base)
    if cfg.use_old_down:
        down_v = dav * (1.0 - 2.0 * (0.2 + 0.8 * rel)) if dav < 0.0 else np.full(c, dav)
    else:
        down_v = np.full(c, dav) if dav < 0.0 else -dav * (1.0 - rel) ** 2
    down = np.where(tip, 0.0, cfg.down_angle[m] + down_v)
    b_rot = rot_a if rotate_mode else _running_rotate(cfg.rotate[m], c) + cfg.rotate_v[m]
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
    return _Families(
        pos=cp.co,
        dir=tp,
        curv=np.full(c, cfg.curve[m] / res),
        seg_len=branch_l / res,
        rad_s=start_rad,
        rad_e=end_rad,
        rad0=start_rad,
        children=children,
        parent=cp.src,
    )


def _trunk(cfg: _Cfg) -> _Families:
    start_rad = cfg.scale_val * cfg.ratio * cfg.scale0 * cfg.scale_v0
    end_rad = max(start_rad * (1.0 - cfg.taper[0]), 0.0) ** cfg.ratio_power
    start_rad = max(start_rad, cfg.min_radius)
    end_rad = min(max(end_rad, cfg.min_radius), start_rad)
    children = cfg.leaves if cfg.levels == 1 else cfg.branches[1]
    res = cfg.curve_res[0]
    return _Families(
        pos=np.zeros((1, 3)),
        dir=np.array([[0.0, 0.0, 1.0]]),
        curv=np.array([cfg.curve[0] / res]),
        seg_len=np.array([cfg.scale_val * cfg.length[0] / res]),
        rad_s=np.array([start_rad]),
        rad_e=np.array([end_rad]),
        rad0=np.array([start_rad * cfg.root_flare]),
        children=np.array([float(max(children, 0))]),
        parent=np.array([-1], dtype=np.int64),
    )


# --------------------------------------------------------------------------- pruning
def _prune_scales(cfg: _Cfg, n: int, fam: _Families, seed: int, pseed: int) -> np.ndarray:
    """Sapling's pruning: bisect each family's length scale until its spline ends fit
    inside the envelope (regrowing with the same draws), then blend by ``pruneRatio``."""
    f = len(fam.pos)
    res = cfg.curve_res[min(n, 3)]
    cmax, cmin, cs, old = np.ones(f), np.zeros(f), np.ones(f), np.ones(f)
    used = np.ones(f)
    active = np.ones(f, dtype=bool)
    sv = cfg.scale_val
    for _ in range(64):
        if not active.any():
            break
        near = active & ((cmax - cmin) < 0.01)
        cs = np.where(near, (cs - 1.0) * cfg.prune_ratio + 1.0, cs)
        used = np.where(active, cs, used)
        spl = _grow_level(cfg, n, fam, used, _rng_for(seed, pseed, n, 0))
        end = spl.pts[:, res]
        ratio = (sv - end[:, 2]) / (sv * max(1.0 - cfg.prune_base, 1e-6))
        env = cfg.prune_width * shape_ratio(
            9, ratio, peak=cfg.prune_peak, power_high=cfg.prune_high, power_low=cfg.prune_low
        )
        inside = np.hypot(end[:, 0], end[:, 1]) / sv < env
        if n == 0:
            inside |= end[:, 2] < cfg.prune_base * sv
        fam_in = np.bincount(spl.fam, weights=(~inside).astype(np.float64), minlength=f) == 0
        out = active & ~fam_in
        old = np.where(out, cmax, old)
        cmax = np.where(out, cs, cmax)
        cs = np.where(out, 0.5 * (cmax + cmin), cs)
        inn = active & fam_in & (cs != 1.0)
        cmin = np.where(inn, cs, cmin)
        cmax = np.where(inn, old, cmax)
        cs = np.where(inn, 0.5 * (cmax + cmin), cs)
        cmin = np.where(active & fam_in & ((cmax - cmin) == 1.0), 1.0, cmin)
        active = active & ~near & ((cmax - cmin) > 0.005)
    return used


# --------------------------------------------------------------------------- public API
def grow(params: TreeParams | Mapping[str, Any], seed: int = 0) -> Skeleton:
    """Grow the skeleton of the tree described by ``params`` (pure and deterministic).

    ``seed`` and ``params['seed']`` together seed the draws Sapling makes that have no
    realised TreeSketchNet key (which segments split, ``lengthV``, whorl jitter).
    """
    p = validate(params)
    cfg = _Cfg(p)
    pseed = int(p["seed"])
    all_pts: list[np.ndarray] = []
    all_rad: list[np.ndarray] = []
    counts: list[np.ndarray] = []
    levels_out: list[np.ndarray] = []
    parents_out: list[np.ndarray] = []
    next_gid = 0
    base = cfg.base_size
    fam = _trunk(cfg)
    cp: _ChildPoints | None = None
    for n in range(cfg.levels):
        m = min(n, 3)
        if n > 0:
            assert cp is not None
            fam = _fabricate(cfg, n, cp, base)
        if m > 0:
            base *= cfg.base_size_s
        if n == cfg.levels - 1:
            base = 0.0
        scale = _prune_scales(cfg, n, fam, seed, pseed) if cfg.prune else np.ones(len(fam.pos))
        spl = _grow_level(cfg, n, fam, scale, _rng_for(seed, pseed, n, 0))
        order = _order(spl)
        gid = np.empty(len(order), dtype=np.int64)
        gid[order] = next_gid + np.arange(len(order))
        # output: stems of this level in Sapling order
        res = cfg.curve_res[m]
        slots = np.arange(res + 1)
        mask = slots[None, :] >= spl.start[order][:, None]
        all_pts.append(spl.pts[order][mask])
        all_rad.append(spl.rad[order][mask])
        counts.append(mask.sum(axis=1))
        levels_out.append(np.full(len(order), n, dtype=np.int64))
        par = np.where(
            spl.parent[order] >= 0,
            gid[np.maximum(spl.parent[order], 0)],
            fam.parent[spl.fam[order]],
        )
        parents_out.append(par)
        cp = _child_points(cfg, n, spl, order, gid, fam.children, base, _rng_for(seed, pseed, n, 1))
        next_gid += len(order)

    assert cp is not None
    leaf_pos, leaf_mat = leaf_transforms(p, cp)
    points = np.concatenate(all_pts).astype(np.float64)
    radii = np.concatenate(all_rad).astype(np.float64)
    cnt = np.concatenate(counts)
    offsets = np.concatenate([[0], np.cumsum(cnt)]).astype(np.int64)
    return Skeleton(
        points=np.ascontiguousarray(points),
        radii=np.ascontiguousarray(radii),
        offsets=offsets,
        levels=np.concatenate(levels_out),
        parents=np.concatenate(parents_out).astype(np.int64),
        leaf_positions=np.ascontiguousarray(leaf_pos),
        leaf_matrices=np.ascontiguousarray(leaf_mat),
        leaf_shape=str(p["leafShape"]),
        res_u=int(p["resU"]),
        bevel_res=int(p["bevelRes"]),
    )
