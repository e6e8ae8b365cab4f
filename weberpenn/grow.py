"""Grow a Weber-Penn tree skeleton the way Blender's Sapling Tree Gen does.

``grow(params, seed)`` follows Sapling 0.3.x's algorithm (see
``reference/weber_penn_notes.md``) with TreeSketchNet's realised keys in place of
Sapling's random draws: ``curveV1/2`` are the per-segment curve draws, ``splitAngleV1/2``
the split-angle draws, ``choiceNegPos1/2`` the split signs, ``rLastAng`` the initial split
roll, ``scaleV``/``scaleV0``/``leafScaleV`` realised offsets and multipliers, and
``rotateV``/``downAngleV``/``leafRotateV``/``leafDownAngleV`` realised offsets.

What stays random in Sapling and has no realised key (whether a segment splits,
``lengthV`` and the whorl jitter of ``nrings``) comes from random streams that follow the
tree's structure (:mod:`weberpenn._grow_random`): the trunk's key comes from ``seed`` and
``params['seed']``, every other stem's from its parent's and its place on the parent,
so a small change of one value changes the stems it touches, not every later draw of
the level (``benchmarks/probes/step_curve.py`` measures it).  Each split draw is shifted by
``rSplits2`` (modulo 1), so it stays uniform (Sapling's statistics) while ``rSplits2`` still changes the tree.  (The
third-party Render Tree code compares *every* split draw with ``rSplits2``, so a level
splits at every segment or never; that loses Sapling's stem counts, which the project
compares against.)  So ``grow`` is a pure function: the same input gives byte-identical
arrays.

Deliberate differences from Sapling: the azimuth of successive children
(``rotate``) and leaves (``leafRotate + leafRotateV``) accumulates along each parent stem,
not along the whole level or tree (Sapling's running total turned the n-th leaf by n
times any change of ``leafRotateV``, and one extra child turned every later branch); a
stem's end radius is capped at its start radius
(Sapling's ``(startRad * (1 - taper)) ** ratioPower`` exceeds the start radius when the
start radius is above 1, so radii would grow towards the tip); operator options that the
TreeSketchNet dictionary does not store take Sapling's defaults (rMode 'rotate',
autoTaper on, closeTip off, splitByLen off).  A dictionary whose tree would exceed
:mod:`weberpenn.limits` (stems, control points, leaves, or the vertices and triangles of
its mesh) is refused with a :class:`~weberpenn.params.ParamError` naming the keys
responsible, as soon as growing reaches the limit.  The trunk-split rule is checked draw for
draw against Sapling's own statistics by ``benchmarks/compare_sapling.py``.

The implementation is vectorised: all stems of a level grow together, one Bezier
segment at a time, with local frames as rotation matrices (Sapling's quaternions from
``to_track_quat('Z', 'Y')``, replicated in :mod:`weberpenn._grow_math`).
"""

from __future__ import annotations

from collections.abc import Generator, Mapping
from typing import Any

import numpy as np

from ._grow_children import child_points, fabricate, trunk
from ._grow_leaves import leaf_transforms
from ._grow_random import root_key
from ._grow_stems import Cfg, ChildPoints, grow_level, prune_scales, spline_order
from .limits import MAX_LEAVES, MAX_STEMS, check_grow, check_leaves, check_mesh, mesh_size
from .params import TreeParams, validate
from .skeleton import Skeleton

__all__ = ["Skeleton", "grow", "grow_levels", "growing"]


def _no_child_points() -> ChildPoints:
    z = np.zeros(0)
    i = z.astype(np.int64)
    return ChildPoints(np.zeros((0, 3)), np.zeros((0, 3, 3)), z, z, z, z, z, i, z.astype(np.uint64))


# --------------------------------------------------------------------------- public API
def grow(params: TreeParams | Mapping[str, Any], seed: int = 0) -> Skeleton:
    """Grow the skeleton of the tree described by ``params`` (pure and deterministic).

    ``seed`` and ``params['seed']`` together seed the draws Sapling makes that have no
    realised TreeSketchNet key (which segments split, ``lengthV``, whorl jitter).
    """
    return grow_levels(params, seed)[1]


def grow_levels(
    params: TreeParams | Mapping[str, Any], seed: int = 0
) -> tuple[list[tuple[np.ndarray, np.ndarray]], Skeleton]:
    """:func:`growing` run to its end: each level's stem points and radii, and the
    skeleton."""
    levels = growing(params, seed)
    out: list[tuple[np.ndarray, np.ndarray]] = []
    while True:
        try:
            out.append(next(levels))
        except StopIteration as done:
            return out, done.value


def growing(
    params: TreeParams | Mapping[str, Any], seed: int = 0
) -> Generator[tuple[np.ndarray, np.ndarray], None, Skeleton]:
    """:func:`grow`, a level at a time: yields each level's stem points and radii (its
    stems in Sapling order, as the skeleton will hold them) as soon as the level is
    grown, and returns the skeleton.  A caller asking only whether two trees differ
    stops at the first level that does, before the costlier levels and the leaves
    (``refine.objective.SearchSpace.live``)."""
    p = validate(params)
    cfg = Cfg(p)
    pseed = int(p["seed"])
    all_pts: list[np.ndarray] = []
    all_rad: list[np.ndarray] = []
    counts: list[np.ndarray] = []
    levels_out: list[np.ndarray] = []
    parents_out: list[np.ndarray] = []
    next_gid = 0
    base = cfg.base_size
    fam = trunk(cfg, root_key(seed, pseed))
    cp = _no_child_points()
    res_u, bevel_res, leaf_shape = int(p["resU"]), int(p["bevelRes"]), str(p["leafShape"])
    for n in range(cfg.levels):
        m = min(n, 3)
        if n > 0:
            fam = fabricate(cfg, n, cp, base)
            if len(fam.pos) == 0:
                break
        if m > 0:
            base *= cfg.base_size_s
        if n == cfg.levels - 1:
            base = 0.0
        scale = prune_scales(cfg, n, fam, next_gid) if cfg.prune else np.ones(len(fam.pos))
        spl = grow_level(cfg, n, fam, scale, next_gid)
        order = spline_order(spl)
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
        next_gid += len(order)
        # the branch mesh so far, exactly: refuse before growing (or meshing) any more
        check_mesh(*mesh_size(np.concatenate(counts), res_u, bevel_res, 0, leaf_shape), p)
        yield all_pts[-1], all_rad[-1]
        last = n == cfg.levels - 1
        if last and cfg.leaves == 0:
            cp = _no_child_points()
            break
        per_point = max(1, -cfg.leaves)
        cap = MAX_LEAVES // per_point if last else MAX_STEMS - next_gid
        cp, cut = child_points(cfg, n, spl, order, gid, fam.children, base, fam.key, cap)
        if cut and last:
            check_leaves(p, (cap + 1) * per_point)
        elif cut:
            check_grow(p, n + 1, next_gid + cap + 1, 0)

    leaf_pos, leaf_mat = leaf_transforms(p, cp)
    check_mesh(*mesh_size(np.concatenate(counts), res_u, bevel_res, len(leaf_pos), leaf_shape), p)
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
