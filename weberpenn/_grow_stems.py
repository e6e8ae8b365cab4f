"""Stem growth for :mod:`weberpenn.grow`: the parameters in working units, the stems of a
level grown together one Bezier segment at a time (splits included), and pruning."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._grow_math import (
    TAU,
    anglemean,
    apply,
    declination,
    euler_compat,
    euler_frames_no_roll,
    euler_to_mat,
    normalize,
    rot_axis,
    rot_y,
    rot_z,
    track_frames,
    track_x_and_yz,
)
from ._grow_random import CLONE, LENGTH, SPLIT, derive, uniform
from ._grow_shapes import find_taper, shape_ratio
from .limits import check_grow


@dataclass
class Families:
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
    key: np.ndarray  # (F,) uint64 random-stream key (see _grow_random)


@dataclass
class Splines:
    """Grown splines of one level in padded arrays (slots ``start .. R``)."""

    pts: np.ndarray  # (N, R+1, 3)
    rad: np.ndarray  # (N, R+1)
    start: np.ndarray  # (N,)
    fam: np.ndarray  # (N,)
    seg_len: np.ndarray  # (N,)
    rad_s: np.ndarray  # (N,)
    offset_len: np.ndarray  # (N,)
    parent: np.ndarray  # (N,) local index of the spline a clone split from, -1 = root
    key: np.ndarray  # (N,) uint64 random-stream key


@dataclass
class ChildPoints:
    co: np.ndarray  # (C, 3)
    frame: np.ndarray  # (C, 3, 3)
    rad_par0: np.ndarray  # (C,) parent spline start radius
    rad_par1: np.ndarray  # (C,) parent radius here
    offset: np.ndarray  # (C,) t along the parent family (1 = tip)
    stem_offset: np.ndarray  # (C,)
    len_par: np.ndarray  # (C,) parent nominal length
    src: np.ndarray  # (C,) global id of the parent spline
    key: np.ndarray  # (C,) uint64 random-stream key of the stem that starts here


class Cfg:
    """Parameters in the units the algorithm uses (radians, floats, ints)."""

    def __init__(self, p: Mapping[str, Any]):
        r = math.radians
        self.params = p  # for errors that name the keys responsible
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


# --------------------------------------------------------------------------- growth
def _attract_up(v: np.ndarray, att: float, res: int) -> np.ndarray:
    if att == 0.0 or len(v) == 0:
        return v
    axis_x, yz = track_x_and_yz(v)
    n = np.sqrt(np.einsum("ij,ij->i", v, v))  # normalize(v)[:, 2], Z only
    dec = np.arccos(np.clip(v[:, 2] / np.where(n > 0.0, n, 1.0), -1.0, 1.0))
    a = att * dec * np.abs(yz) / res
    a = np.where(-dec + a < -np.pi, -np.pi + dec, a)
    a = np.where(dec - a < 0.0, dec, a)
    return rot_axis(v, axis_x, -a)


def grow_level(
    cfg: Cfg,
    n: int,
    fam: Families,
    scale: np.ndarray,
    stems_before: int,
) -> Splines:
    """Grow every family of level ``n`` (param index ``m = min(n, 3)``) segment by segment.

    ``stems_before`` stems exist in the tree already; a split that takes the tree past
    :data:`weberpenn.limits.MAX_STEMS` raises :class:`ParamError` before it is made.
    """
    m = min(n, 3)
    res = cfg.curve_res[m]
    trunk = n == 0
    f = len(fam.pos)
    stem_seg = fam.seg_len * scale  # Sapling's stemsegL (per family)
    lv = cfg.length_v[m]
    key = fam.key.copy()
    seg_len = stem_seg * ((1.0 - lv) + 2.0 * lv * uniform(key, LENGTH) if lv > 0.0 else 1.0)

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
    check_grow(cfg.params, n, stems_before + f, f * (res + 1))
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
        u = np.mod(uniform(key, SPLIT, k) + cfg.r_splits2, 1.0)
        if k == 0 or trunk and k < (res - 1) * cfg.split_height and k != 1:
            nsplit = np.zeros(nsp, dtype=np.int64)
        elif trunk and k == 1:
            nsplit = np.full(nsp, cfg.base_splits, dtype=np.int64)
        elif trunk and k == h_forced:
            nsplit = (sval > 0.0).astype(np.int64)
        else:
            nsplit = (u < sval).astype(np.int64)
        if nsplit.any():
            grown = nsp + int(nsplit.sum())
            check_grow(cfg.params, n, stems_before + grown, grown * (res + 1))
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
        tip = pts[:, k]  # a view: only column k + 1 of ``pts`` is written below
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
            ckey = derive(key[par], CLONE, k * 1024 + idx)
            lv_c = (1.0 - lv) + 2.0 * lv * uniform(ckey, LENGTH) if lv > 0.0 else np.ones(ncl)
            bscale = np.minimum(lv_c * tf[par], 1.0)
            a = angle[par] + cang[par]
            v = np.empty((ncl, 3))
            v[:, 0] = 0.0
            v[:, 1] = -np.sin(a)
            v[:, 2] = np.cos(a)
            v = rot_y(v, cvar[par])
            if trunk:
                v = rot_z(v, branch_rot[par])
                v = rot_z(v, np.pi - (TAU / (nsplit[par] + 1)) * (idx + 1))
            else:
                v = rot_y(v, spread)
            # the clones' directions finish below, in one batch with the parents' (row-wise
            # arithmetic: the same numbers as two separate batches, fewer numpy calls)
            v_cl = apply(frame[par], v)
            stem_l = stem_seg[famid[par]] * lv_c
            len_cl = stem_l * tf[par]
            c_pts = np.zeros((ncl, res + 1, 3))
            c_pts[:, k] = tip[par]
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
                offset_len=offset_len[par] + seg_len[par] * (k - start[par]),
                parent=par,
                seg_len=stem_l,
                key=ckey,
            )

        a = np.where(sp, -angle + cang, cang)
        v = np.empty((nsp, 3))
        v[:, 0] = 0.0
        v[:, 1] = -np.sin(a)
        v[:, 2] = np.cos(a)
        v = rot_y(v, cvar)
        if sp.any():
            if trunk:
                v = np.where(sp[:, None], rot_z(v, branch_rot), v)
            else:
                v = np.where(sp[:, None], rot_y(v, -spread), v)
        v = apply(frame, v)
        split_last = sp
        if new is None:
            v = _attract_up(v, att_up, res)
            v = normalize(v) * (seg_len * tf)[:, None]
        else:
            both = _attract_up(np.concatenate([v, v_cl]), att_up, res)
            both = normalize(both) * np.concatenate([seg_len * tf, len_cl])[:, None]
            v, v_cl = both[:nsp], both[nsp:]
            new["pts"][:, k + 1] = tip[par] + v_cl
            new["dirv"] = v_cl
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
            key = np.concatenate([key, new["key"]])

    return Splines(pts, rad, start, famid, seg_len, rad_s, offset_len, parent, key)


# --------------------------------------------------------------------------- ordering
def spline_order(spl: Splines) -> np.ndarray:
    """Sapling's spline order: by family, then creation (clones after their stem)."""
    return np.lexsort((np.arange(len(spl.fam)), spl.fam))


# --------------------------------------------------------------------------- pruning
def prune_scales(cfg: Cfg, n: int, fam: Families, stems_before: int) -> np.ndarray:
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
        spl = grow_level(cfg, n, fam, used, stems_before)
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
