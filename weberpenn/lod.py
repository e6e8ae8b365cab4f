"""Level of detail: a lighter TreeMesh under a triangle budget.

:func:`lod` keeps the tree's shape and gives up detail in this order, stopping as soon
as the tree fits ``max_faces`` triangles (branches + leaves):

1. coarser tubes: the stems are re-meshed from the skeleton with fewer sides around
   (``bevel_res``) and fewer samples along each segment (``res_u``), taking the finest
   pair that fits (the curves themselves are unchanged);
2. lighter leaves: hexagonal leaves become rectangles (2 triangles instead of 4; with
   the alpha-masked leaf texture they look alike), then every k-th leaf is kept and
   scaled up by k ** 0.25 (some of the lost foliage area back without pushing leaves
   out past the crown); leaves get at most half the budget when the tubes do not fit
   at their coarsest;
3. fewer twigs: when even the coarsest tubes exceed what is left, the thinnest stems
   are left out (a tree of thousands of twigs cannot keep them all at a few triangles
   each; quadric decimation there collapses whole twigs into far-off slivers);
4. decimation: only when the kept stems still do not fit (budgets below the trunk's own
   coarsest tube), pymeshlab's quadric edge collapse brings the branch mesh down; its
   UVs are taken from the nearest vertex of the undecimated mesh.

A TreeMesh without its skeleton (e.g. turned by ``eval``) skips step 1 and the
rectangle switch.  :func:`lod_chain` makes a series of LODs (lod0 = the full tree).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
import trimesh
from trimesh.visual import TextureVisuals

from .limits import MAX_MESH_FACES
from .mesh import build_mesh
from .skeleton import Skeleton
from .treemesh import TreeMesh

__all__ = ["MIN_FACES", "branch_faces", "drop_thin_stems", "lod", "lod_chain"]

#: The smallest budget accepted: below it no tree stays recognisable.
MIN_FACES = 100


def branch_faces(skeleton: Skeleton, res_u: int, bevel_res: int) -> int:
    """Triangles of the branch mesh ``build_mesh`` would make at this resolution."""
    counts = np.diff(np.asarray(skeleton.offsets, dtype=np.int64))
    counts = counts[counts >= 2]
    sides = 4 + 2 * int(bevel_res)
    return int(2 * sides * int(res_u) * (counts - 1).sum())


def _leaf_faces(n_leaves: int, shape: str) -> int:
    return n_leaves * (2 if shape == "rect" else 4)


def check_budget(max_faces: int) -> int:
    """``max_faces`` as an int in ``MIN_FACES..MAX_MESH_FACES`` (no tree has more: a
    larger budget is a mistake); ValueError otherwise."""
    if isinstance(max_faces, bool) or not isinstance(max_faces, int | np.integer):
        raise ValueError(f"max_faces must be an integer, got {max_faces!r}")
    if not MIN_FACES <= max_faces <= MAX_MESH_FACES:
        # str() of an int of 5000 digits fails, and one of 400 says nothing more
        digits = int(int(max_faces).bit_length() * 0.30103) + 1
        shown = str(max_faces) if digits < 30 else f"a number of about {digits} digits"
        raise ValueError(
            f"max_faces={shown} is out of range: from {MIN_FACES} to {MAX_MESH_FACES:,} triangles"
        )
    return int(max_faces)


def _resolutions(sk: Skeleton) -> list[tuple[int, int, int]]:
    """(branch faces, res_u, bevel_res) for every resolution up to the skeleton's own,
    finest first."""
    out = [
        (branch_faces(sk, r, b), r, b)
        for r in range(1, max(int(sk.res_u), 1) + 1)
        for b in range(0, max(int(sk.bevel_res), 0) + 1)
    ]
    return sorted(out, reverse=True)


def _thickest_stems(sk: Skeleton, budget: int, sides: int) -> Skeleton:
    """The skeleton's thickest stems whose coarsest tubes (``sides`` around, one ring per
    control point) fit ``budget`` triangles; at least the first (the trunk)."""
    offsets = np.asarray(sk.offsets, dtype=np.int64)
    counts = np.diff(offsets)
    cost = np.where(counts >= 2, 2 * sides * (counts - 1), 0)
    radius = np.maximum.reduceat(np.asarray(sk.radii), offsets[:-1]) if len(counts) else counts
    order = np.argsort(-radius, kind="stable")
    fits = np.cumsum(cost[order]) <= budget
    fits[0] = True
    return _keep_stems(sk, np.sort(order[fits]))


def _keep_stems(sk: Skeleton, keep: np.ndarray) -> Skeleton:
    """The skeleton with only the stems numbered ``keep`` (ascending); a kept stem whose
    parent is dropped gets none.  Leaves are untouched."""
    offsets = np.asarray(sk.offsets, dtype=np.int64)
    counts = np.diff(offsets)
    starts = offsets[:-1][keep]
    lens = counts[keep]
    idx = np.repeat(starts - (np.cumsum(lens) - lens), lens) + np.arange(int(lens.sum()))
    new_index = np.full(len(counts), -1, dtype=np.int64)
    new_index[keep] = np.arange(len(keep))
    parents = np.asarray(sk.parents, dtype=np.int64)[keep]
    return dataclasses.replace(
        sk,
        points=sk.points[idx],
        radii=sk.radii[idx],
        offsets=np.concatenate([[0], np.cumsum(counts[keep])]).astype(np.int64),
        levels=np.asarray(sk.levels)[keep],
        parents=np.where(parents >= 0, new_index[np.maximum(parents, 0)], -1),
    )


def drop_thin_stems(skeleton: Skeleton, min_radius: float) -> Skeleton:
    """The skeleton without the stems whose thickest point is thinner than
    ``min_radius`` (the trunk, stem 0, always stays); leaves are kept.

    For drawings where such stems cannot show: a silhouette sampled on a grid whose
    thinning needs a 2 x 2 block of covered samples (``render.sketch.sample_width``)
    never keeps a stem narrower than one sample spacing, i.e. ``min_radius`` = half of
    it.  The mesh of the result has the same tubes for every kept stem, so what is
    drawn of it is the full tree's drawing up to where a dropped twig touched another
    branch.  ``min_radius <= 0`` returns the skeleton itself.
    """
    r = float(min_radius)
    if not np.isfinite(r):
        raise ValueError(f"min_radius must be a finite number, got {min_radius!r}")
    offsets = np.asarray(skeleton.offsets, dtype=np.int64)
    counts = np.diff(offsets)
    if r <= 0 or len(counts) == 0:
        return skeleton
    radii = np.asarray(skeleton.radii, dtype=np.float64)
    thickest = np.full(len(counts), -np.inf)
    has = counts > 0
    if has.any():
        thickest[has] = np.maximum.reduceat(radii, offsets[:-1][has])
    keep = thickest >= r
    keep[0] = True
    if keep.all():
        return skeleton
    return _keep_stems(skeleton, np.flatnonzero(keep))


def _leaf_growth(n: int, keep: int) -> float:
    """Scale of the kept leaves when ``keep`` of ``n`` remain: (n / keep) ** 0.25 gives
    back half the lost foliage area (in log terms); the full sqrt would keep the area
    but push big leaves out past the crown (measured: benchmarks/bench_lod.py)."""
    return float((n / keep) ** 0.25)


def _thin_leaves(sk: Skeleton, keep: int) -> Skeleton:
    """Every k-th leaf, enlarged by :func:`_leaf_growth`."""
    n = sk.n_leaves
    if keep >= n:
        return sk
    idx = (np.arange(keep) * n) // keep
    grow = _leaf_growth(n, keep)
    return dataclasses.replace(
        sk,
        leaf_positions=sk.leaf_positions[idx],
        leaf_matrices=sk.leaf_matrices[idx] * grow,
    )


def _thin_leaf_mesh(leaves: trimesh.Trimesh, per_leaf: int, keep: int) -> trimesh.Trimesh:
    """Leaf mesh without a skeleton: keep whole leaves (blocks of ``per_leaf`` vertices),
    each scaled about its centroid by :func:`_leaf_growth`."""
    nv = len(leaves.vertices)
    n = nv // per_leaf
    if keep >= n or n * per_leaf != nv:
        return leaves
    idx = (np.arange(keep) * n) // keep
    v = np.asarray(leaves.vertices).reshape(n, per_leaf, 3)[idx]
    c = v.mean(axis=1, keepdims=True)
    v = c + (v - c) * _leaf_growth(n, keep)
    nf = len(leaves.faces) // n
    f = np.asarray(leaves.faces).reshape(n, nf, 3)[:1]  # leaf 0's faces: every leaf's template
    faces = (f + (np.arange(keep) * per_leaf)[:, None, None]).reshape(-1, 3)
    out = trimesh.Trimesh(vertices=v.reshape(-1, 3), faces=faces, process=False)
    uv = getattr(leaves.visual, "uv", None)
    if uv is not None and len(uv) == nv:
        out.visual = TextureVisuals(uv=np.asarray(uv).reshape(n, per_leaf, 2)[idx].reshape(-1, 2))
    return out


def _decimate(mesh: trimesh.Trimesh, target: int) -> trimesh.Trimesh:
    """Quadric edge collapse to about ``target`` triangles, UVs from the nearest vertex."""
    import pymeshlab
    from scipy.spatial import cKDTree

    ms = pymeshlab.MeshSet()
    ms.add_mesh(
        pymeshlab.Mesh(
            vertex_matrix=np.asarray(mesh.vertices, dtype=np.float64),
            face_matrix=np.asarray(mesh.faces, dtype=np.int32),
        )
    )
    ms.meshing_decimation_quadric_edge_collapse(
        targetfacenum=max(int(target), 4), preservetopology=False, planarquadric=True
    )
    cur = ms.current_mesh()
    v, f = cur.vertex_matrix(), cur.face_matrix().astype(np.int64)
    out = trimesh.Trimesh(vertices=v, faces=f, process=False)
    uv = getattr(mesh.visual, "uv", None)
    if uv is not None and len(uv) == len(mesh.vertices) and len(v):
        _, near = cKDTree(np.asarray(mesh.vertices)).query(v)
        out.visual = TextureVisuals(uv=np.asarray(uv)[near])
    return out


def lod(tree_mesh: TreeMesh, max_faces: int) -> TreeMesh:
    """A TreeMesh with at most ``max_faces`` triangles (the same object when it fits).

    ``meta["lod"]`` records what was given up: ``res_u``, ``bevel_res``, ``leaf_shape``,
    ``leaves`` kept, and ``decimated`` (True when step 3 ran).
    """
    budget = check_budget(max_faces)
    if tree_mesh.n_faces <= budget:
        return tree_mesh
    sk = tree_mesh.skeleton
    info: dict = {"max_faces": budget, "decimated": False}
    if sk is not None:
        res = _resolutions(sk)
        shape = str(sk.leaf_shape)
        full_leaves = _leaf_faces(sk.n_leaves, shape)
        fit = [r for r in res if r[0] + full_leaves <= budget]
        if fit:
            _, res_u, bevel = fit[0]
        else:
            coarse = res[-1][0]
            leaf_budget = max(budget - coarse, budget // 2)
            if full_leaves > leaf_budget and shape == "hex":
                sk = dataclasses.replace(sk, leaf_shape="rect")
                shape = "rect"
            per = _leaf_faces(1, shape)
            if sk.n_leaves * per > leaf_budget:
                sk = _thin_leaves(sk, max(leaf_budget // per, 1))
            left = budget - _leaf_faces(sk.n_leaves, shape)
            fit = [r for r in res if r[0] <= left]
            if fit:
                _, res_u, bevel = fit[0]
            else:
                _, res_u, bevel = res[-1]
                n_stems = sk.n_stems
                sk = _thickest_stems(sk, left, 4 + 2 * bevel)
                info["stems_dropped"] = n_stems - sk.n_stems
        built = build_mesh(
            dataclasses.replace(sk, res_u=res_u, bevel_res=bevel), species=tree_mesh.species
        )
        branches, leaves = built.branches, built.leaves
        info.update(res_u=res_u, bevel_res=bevel, leaf_shape=shape, leaves=sk.n_leaves)
    else:
        branches, leaves = tree_mesh.branches, tree_mesh.leaves
        shape = str(tree_mesh.meta.get("leaf_shape", "hex"))
        per_v, per_f = (4, 2) if shape == "rect" else (6, 4)
        n_leaves = len(leaves.faces) // per_f
        leaf_budget = max(budget - len(branches.faces), budget // 2)
        if len(leaves.faces) > leaf_budget:
            leaves = _thin_leaf_mesh(leaves, per_v, max(leaf_budget // per_f, 1))
        info.update(leaf_shape=shape, leaves=len(leaves.faces) // per_f if n_leaves else 0)
    left = budget - len(leaves.faces)
    if len(branches.faces) > left:
        branches = _decimate(branches, left)
        # quadric collapse lands near, not exactly on, its target
        while len(branches.faces) > left:
            branches = _decimate(branches, int(left * 0.9))
        info["decimated"] = True
    meta = {**tree_mesh.meta, "lod": info}
    return TreeMesh(
        branches=branches,
        leaves=leaves,
        species=tree_mesh.species,
        meta=meta,
        skeleton=tree_mesh.skeleton,
    )


def lod_chain(tree_mesh: TreeMesh, budgets: Sequence[int | None]) -> list[TreeMesh]:
    """One LOD per budget (None = the full tree), e.g. ``(None, 50_000, 10_000)`` for
    lod0/lod1/lod2."""
    return [tree_mesh if b is None else lod(tree_mesh, b) for b in budgets]
