"""Stem growth for :mod:`weberpenn.grow`: the parameters in working units, the stems of a
level grown together one Bezier segment at a time (splits included), and pruning."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
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


@dataclass
class _LevelRules:
    """The parameters of one level in the form the segment loop reads them, worked out
    once per level (``grow_level`` runs up to 64 times per level while pruning)."""

    n: int
    m: int  # parameter index, min(n, 3)
    res: int  # segments per stem
    trunk: bool
    lv: float  # lengthV
    seg_splits: float
    curve_back: float
    cv1: float  # curveV1
    cv2: float  # curveV2
    att_up: float
    att_out: float
    angle0: float  # split angle before it is scaled by declination
    spread: float  # the clones' turn away from their parent
    branch_step: float  # roll added at each split
    h_forced: int  # the trunk segment that splits whenever it may
    k_back: int  # the segment where curveBack starts
    close_tip: bool  # the last level's stems end in a point

    @classmethod
    def of(cls, cfg: Cfg, n: int) -> _LevelRules:
        """The rules of level ``n`` (levels past the fourth reuse the fourth's values)."""
        m = min(n, 3)
        res = cfg.curve_res[m]
        split_ang = cfg.split_angle[m]
        return cls(
            n=n,
            m=m,
            res=res,
            trunk=n == 0,
            lv=cfg.length_v[m],
            seg_splits=cfg.seg_splits[m],
            curve_back=cfg.curve_back[m],
            cv1=cfg.curve_v1[m],
            cv2=cfg.curve_v2[m],
            att_up=cfg.attract_up[m],
            att_out=cfg.attract_out[m],
            angle0=cfg.cnp1 * (split_ang + cfg.split_angle_v1[m]),
            spread=cfg.cnp2 * (split_ang + cfg.split_angle_v2[m]),
            branch_step=cfg.rotate[0] + cfg.rotate_v[0],
            h_forced=int((res - 1) * cfg.split_height) + 1,
            k_back=int(res / 2 + 0.5),
            close_tip=cfg.close_tip and n == cfg.levels - 1,
        )

    def length_factor(self, key: np.ndarray) -> np.ndarray | float:
        """A stem's (or clone's) lengthV multiplier, drawn from its own key."""
        return (1.0 - self.lv) + 2.0 * self.lv * uniform(key, LENGTH) if self.lv > 0.0 else 1.0


@dataclass
class _Growing:
    """The splines of a level while they grow: one row per spline (clones appended)."""

    pts: np.ndarray  # (N, R+1, 3), filled up to the current segment
    rad: np.ndarray  # (N, R+1)
    start: np.ndarray  # (N,) first slot
    famid: np.ndarray  # (N,) family
    rad_s: np.ndarray  # (N,)
    rad_e: np.ndarray  # (N,)
    curv: np.ndarray  # (N,) curvature per segment
    sign: np.ndarray  # (N,) sign of the next curveV1/2 bend (alternates)
    split_last: np.ndarray  # (N,) split at the previous segment
    r_last: np.ndarray  # (N,) roll of the last split, NaN = none yet
    dirv: np.ndarray  # (N, 3) last segment's vector
    offset_len: np.ndarray  # (N,) length along the family before the spline starts
    parent: np.ndarray  # (N,) local index of the spline a clone split from, -1 = root
    seg_len: np.ndarray  # (N,)
    key: np.ndarray  # (N,) uint64 random-stream key

    @classmethod
    def start_of(cls, fam: Families, rules: _LevelRules, seg_len: np.ndarray) -> _Growing:
        """Every family's stem, at its first point."""
        f, res = len(fam.pos), rules.res
        pts = np.zeros((f, res + 1, 3))
        pts[:, 0] = fam.pos
        rad = np.zeros((f, res + 1))
        rad[:, 0] = fam.rad0
        return cls(
            pts=pts,
            rad=rad,
            start=np.zeros(f, dtype=np.int64),
            famid=np.arange(f, dtype=np.int64),
            rad_s=fam.rad_s.copy(),
            rad_e=fam.rad_e.copy(),
            curv=fam.curv.copy(),
            sign=np.ones(f),
            split_last=np.zeros(f, dtype=bool),
            r_last=np.full(f, np.nan),
            dirv=fam.dir.copy(),
            offset_len=np.zeros(f),
            parent=np.full(f, -1, dtype=np.int64),
            seg_len=seg_len,
            key=fam.key.copy(),
        )

    def extend(self, more: _Growing) -> None:
        """Append ``more`` (new clones) after the existing splines."""
        for f in fields(self):
            setattr(self, f.name, np.concatenate([getattr(self, f.name), getattr(more, f.name)]))


@dataclass
class _Segment:
    """What one segment step shares between the splines and the clones they make."""

    k: int
    nsplit: np.ndarray  # (N,) clones each spline makes here
    frame: np.ndarray  # (N, 3, 3) local frames
    tf: np.ndarray  # (N,) trunk-crown taper factor (1 off the trunk)
    cang: np.ndarray  # (N,) bend of this segment
    cvar: np.ndarray  # (N,) curveV2 bend
    angle: np.ndarray  # (N,) split angle
    branch_rot: np.ndarray  # (N,) roll of a split made here

    @property
    def splits(self) -> np.ndarray:
        """Which splines split here."""
        return self.nsplit > 0


def _split_counts(cfg: Cfg, r: _LevelRules, g: _Growing, k: int, kp: float) -> np.ndarray:
    """How many clones each spline makes at segment ``k`` (Sapling's split rule: none
    below splitHeight on the trunk, baseSplits at its second segment, a forced split at
    the first segment above splitHeight, otherwise a draw against segSplits)."""
    sv = r.seg_splits
    if r.trunk:
        sv = max(((2.0 * cfg.split_bias) * (kp - 0.5) + 1.0) * sv, 0.0)
    sval = np.where(g.split_last, sv * sv, sv * 1.33)
    u = np.mod(uniform(g.key, SPLIT, k) + cfg.r_splits2, 1.0)
    nsp = len(g.famid)
    if k == 0 or r.trunk and k < (r.res - 1) * cfg.split_height and k != 1:
        return np.zeros(nsp, dtype=np.int64)
    if r.trunk and k == 1:
        return np.full(nsp, cfg.base_splits, dtype=np.int64)
    if r.trunk and k == r.h_forced:
        return (sval > 0.0).astype(np.int64)
    return (u < sval).astype(np.int64)


def _frames(
    cfg: Cfg, r: _LevelRules, g: _Growing, k: int, kp: float
) -> tuple[np.ndarray, np.ndarray]:
    """Each spline's local frame at segment ``k`` (attractOut turns it towards the
    outside) and the trunk's crown taper, which shortens steep trunk segments."""
    if r.trunk:
        frame = euler_frames_no_roll(g.dirv)
        dec = declination(frame) / np.pi
        tf = np.maximum(0.1, 1.0 - dec * dec * cfg.taper_crown * 30.0)
    else:
        frame = track_frames(g.dirv)
        tf = np.ones(len(g.famid))
    if r.n > 0 and kp > 0.0 and r.att_out > 0.0:
        tip = g.pts[:, k]
        d = np.arctan2(tip[:, 0], -tip[:, 1]) + TAU
        e = euler_compat(frame, d)
        e[:, 2] = anglemean(e[:, 2], d, kp * r.att_out)
        frame = euler_to_mat(e)
    return frame, tf


def _split_roll(
    cfg: Cfg, r: _LevelRules, g: _Growing, frame: np.ndarray, sp: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The split angle (off the trunk, smaller the more a stem leans) and the roll of the
    splits ``sp`` made here; records the roll, from which a spline's next split turns."""
    angle = np.full(len(g.famid), r.angle0)
    if not sp.any():
        return angle, np.zeros(len(g.famid))
    if r.n > 0:
        angle = angle * (np.maximum(1.0 - np.degrees(declination(frame)) / 90.0, 0.0) * 0.67 + 0.33)
    rl = np.where(np.isnan(g.r_last), cfg.r_last[r.m], g.r_last)
    branch_rot = rl + r.branch_step
    g.r_last = np.where(sp, branch_rot, g.r_last)
    return angle, branch_rot


def _segment(
    cfg: Cfg, r: _LevelRules, g: _Growing, k: int, kp: float, nsplit: np.ndarray
) -> _Segment:
    """Work out segment ``k`` for every spline: its frame, bend and split roll.  Applies
    curveBack from its segment on and advances the splines' alternating bend sign."""
    if k == r.k_back and r.curve_back != 0.0:
        g.curv = g.curv + 2.0 * r.curve_back / r.res
    scurv = np.zeros(len(g.famid)) if (r.trunk and kp <= cfg.split_height) else g.curv
    cang = scurv + r.cv1 * kp * g.sign
    cvar = r.cv2 * kp * g.sign
    g.sign = -g.sign
    frame, tf = _frames(cfg, r, g, k, kp)
    angle, branch_rot = _split_roll(cfg, r, g, frame, nsplit > 0)
    return _Segment(k, nsplit, frame, tf, cang, cvar, angle, branch_rot)


def _bent(a: np.ndarray, cvar: np.ndarray) -> np.ndarray:
    """+Z turned by ``a`` about X and ``cvar`` about Y: a segment's direction in its frame."""
    v = np.empty((len(a), 3))
    v[:, 0] = 0.0
    v[:, 1] = -np.sin(a)
    v[:, 2] = np.cos(a)
    return rot_y(v, cvar)


def _clones(
    r: _LevelRules, g: _Growing, s: _Segment, stem_seg: np.ndarray
) -> tuple[_Growing, np.ndarray, np.ndarray]:
    """The clones split off at segment ``s.k``, their first point and radii set; with
    their segment vectors in world space (not yet attracted or scaled) and lengths.

    A clone's key, and so its lengthV draw, comes from its parent's key, the segment and
    its number among the parent's clones.
    """
    k, res, sp, nsplit = s.k, r.res, s.splits, s.nsplit
    par = np.repeat(np.nonzero(sp)[0], nsplit[sp])
    first = np.concatenate([[0], np.cumsum(nsplit[sp])[:-1]])
    idx = np.arange(len(par)) - np.repeat(first, nsplit[sp])
    ncl = len(par)
    ckey = derive(g.key[par], CLONE, k * 1024 + idx)
    lv_c = r.length_factor(ckey) if r.lv > 0.0 else np.ones(ncl)
    bscale = np.minimum(lv_c * s.tf[par], 1.0)
    v = _bent(s.angle[par] + s.cang[par], s.cvar[par])
    if r.trunk:
        v = rot_z(v, s.branch_rot[par])
        v = rot_z(v, np.pi - (TAU / (nsplit[par] + 1)) * (idx + 1))
    else:
        v = rot_y(v, r.spread)
    v_cl = apply(s.frame[par], v)
    stem_l = stem_seg[g.famid[par]] * lv_c
    c_pts = np.zeros((ncl, res + 1, 3))
    c_pts[:, k] = g.pts[par, k]
    c_rad = np.zeros((ncl, res + 1))
    c_rad[:, k] = (g.rad_s[par] * (1 - k / res) + g.rad_e[par] * (k / res)) * bscale
    c_rad[:, k + 1] = (g.rad_s[par] * (1 - (k + 1) / res) + g.rad_e[par] * ((k + 1) / res)) * bscale
    if r.close_tip and k == res - 1:
        c_rad[:, k + 1] = 0.0
    clones = _Growing(
        pts=c_pts,
        rad=c_rad,
        start=np.full(ncl, k, dtype=np.int64),
        famid=g.famid[par],
        rad_s=g.rad_s[par] * bscale,
        rad_e=g.rad_e[par] * bscale,
        curv=g.curv[par],
        sign=np.ones(ncl),  # a new stem: its first bend (at k + 1) is positive
        split_last=np.ones(ncl, dtype=bool),
        r_last=s.branch_rot[par] + np.pi,
        offset_len=g.offset_len[par] + g.seg_len[par] * (k - g.start[par]),
        parent=par,
        seg_len=stem_l,
        key=ckey,
        dirv=v_cl,  # replaced by the finished vectors in _grow_segment
    )
    return clones, v_cl, stem_l * s.tf[par]


def _parent_vectors(r: _LevelRules, s: _Segment) -> np.ndarray:
    """The splines' own segment vectors in world space (a split turns the parent away
    from its clones), not yet attracted or scaled."""
    sp = s.splits
    v = _bent(np.where(sp, -s.angle + s.cang, s.cang), s.cvar)
    if sp.any():
        if r.trunk:
            v = np.where(sp[:, None], rot_z(v, s.branch_rot), v)
        else:
            v = np.where(sp[:, None], rot_y(v, -r.spread), v)
    return apply(s.frame, v)


def _grow_segment(
    cfg: Cfg, r: _LevelRules, g: _Growing, k: int, stem_seg: np.ndarray, stems_before: int
) -> None:
    """Grow every spline by segment ``k``, appending the clones that split off there."""
    nsp = len(g.famid)
    kp = k / (r.res - 1) if r.res > 1 else 1.0
    nsplit = _split_counts(cfg, r, g, k, kp)
    if nsplit.any():
        grown = nsp + int(nsplit.sum())
        check_grow(cfg.params, r.n, stems_before + grown, grown * (r.res + 1))
    s = _segment(cfg, r, g, k, kp, nsplit)
    clones = None
    if s.splits.any():
        clones, v_cl, len_cl = _clones(r, g, s, stem_seg)
    v = _parent_vectors(r, s)
    g.split_last = s.splits
    tip = g.pts[:, k]  # a view: only column k + 1 of ``pts`` is written below
    if clones is None:
        v = _attract_up(v, r.att_up, r.res)
        v = normalize(v) * (g.seg_len * s.tf)[:, None]
    else:
        # the parents' and clones' vectors finish in one batch (row-wise arithmetic: the
        # same numbers as two separate batches, fewer numpy calls)
        both = _attract_up(np.concatenate([v, v_cl]), r.att_up, r.res)
        both = normalize(both) * np.concatenate([g.seg_len * s.tf, len_cl])[:, None]
        v, v_cl = both[:nsp], both[nsp:]
        clones.pts[:, k + 1] = clones.pts[:, k] + v_cl
        clones.dirv = v_cl
    g.pts[:, k + 1] = tip + v
    g.rad[:, k + 1] = g.rad_s * (1 - (k + 1) / r.res) + g.rad_e * ((k + 1) / r.res)
    if r.close_tip and k == r.res - 1:
        g.rad[:, k + 1] = 0.0
    g.dirv = v
    if clones is not None:
        g.extend(clones)


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
    rules = _LevelRules.of(cfg, n)
    stem_seg = fam.seg_len * scale  # Sapling's stemsegL (per family)
    seg_len = stem_seg * rules.length_factor(fam.key)
    g = _Growing.start_of(fam, rules, seg_len)
    f = len(fam.pos)
    check_grow(cfg.params, n, stems_before + f, f * (rules.res + 1))
    for k in range(rules.res):
        _grow_segment(cfg, rules, g, k, stem_seg, stems_before)
    return Splines(
        g.pts, g.rad, g.start, g.famid, g.seg_len, g.rad_s, g.offset_len, g.parent, g.key
    )


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
