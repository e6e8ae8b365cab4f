"""A stand-in ``build_mesh`` for when ``weberpenn.build_mesh`` is not available yet.

It follows the geometry that :class:`weberpenn.skeleton.Skeleton` documents: every stem
is a cubic Bezier through its control points with Blender's AUTO handles (VECTOR on the
first point), sampled ``res_u`` times per segment, swept with a round cross-section of
``4 + 2 * bevel_res`` sides and linearly interpolated radii; every leaf is the unit
template (``hex`` or ``rect``, one unit tall along +Y, centred on X, base at the origin)
transformed by ``leaf_matrices[j]`` and moved to ``leaf_positions[j]``.  Silhouettes at
sketch resolution match the real mesher's closely; the dataset builder records which
mesher it used.  Only :mod:`render.dataset` uses this, and only as a fallback.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import trimesh

HEX = np.array(
    [[0.0, 0.0], [0.5, 0.3], [0.5, 0.7], [0.0, 1.0], [-0.5, 0.7], [-0.5, 0.3]], dtype=np.float64
)
HEX_FACES = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
RECT = np.array([[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]], dtype=np.float64)
RECT_FACES = np.array([[0, 1, 2], [0, 2, 3]])


def _empty() -> trimesh.Trimesh:
    return trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64))


def _sample_group(pts: np.ndarray, rad: np.ndarray, res_u: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample ``g`` stems of ``n`` control points each: (g, m, 3) positions, (g, m) radii."""
    from weberpenn._grow_bezier import evaluate, handles

    g, n, _ = pts.shape
    hl, hr = handles(pts, np.zeros(g, dtype=np.int64))
    seg = np.append(np.repeat(np.arange(n - 1), res_u), n - 2)
    t = np.append(np.tile(np.arange(res_u) / res_u, n - 1), 1.0)
    m = len(seg)
    spline = np.repeat(np.arange(g), m)
    pos, _ = evaluate(pts, hl, hr, spline, np.tile(seg, g), np.tile(t, g))
    r = rad[:, seg] * (1 - t) + rad[:, seg + 1] * t
    return pos.reshape(g, m, 3), r


def _frames(path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (u, w) perpendicular to the tangents of paths (g, m, 3)."""
    tan = np.gradient(path, axis=1)
    tan /= np.maximum(np.linalg.norm(tan, axis=-1, keepdims=True), 1e-12)
    ref = np.where(np.abs(tan[..., 2:3]) < 0.9, [0.0, 0.0, 1.0], [1.0, 0.0, 0.0])
    u = np.cross(tan, ref)
    u /= np.maximum(np.linalg.norm(u, axis=-1, keepdims=True), 1e-12)
    return u, np.cross(tan, u)


def branches_mesh(sk: Any) -> trimesh.Trimesh:
    sides = 4 + 2 * int(sk.bevel_res)
    res_u = max(int(sk.res_u), 1)
    ang = np.linspace(0.0, 2.0 * np.pi, sides, endpoint=False)
    k = np.arange(sides)
    kn = (k + 1) % sides
    counts = np.diff(np.asarray(sk.offsets))
    verts, faces = [], []
    offset = 0
    for n in np.unique(counts):
        if n < 2:
            continue
        idx = np.flatnonzero(counts == n)
        sel = np.asarray(sk.offsets)[idx][:, None] + np.arange(n)[None, :]
        path, r = _sample_group(
            np.asarray(sk.points, float)[sel], np.asarray(sk.radii, float)[sel], res_u
        )
        u, w = _frames(path)
        ring = np.cos(ang)[:, None] * u[:, :, None, :] + np.sin(ang)[:, None] * w[:, :, None, :]
        v = path[:, :, None, :] + r[:, :, None, None] * ring  # (g, m, sides, 3)
        g, m = path.shape[:2]
        base = (np.arange(m - 1) * sides)[:, None]
        quad_a = np.stack([base + k, base + kn, base + kn + sides], axis=-1)
        quad_b = np.stack([base + k, base + kn + sides, base + k + sides], axis=-1)
        f = np.concatenate([quad_a, quad_b], axis=1).reshape(-1, 3)
        f = f[None] + (np.arange(g) * m * sides)[:, None, None] + offset
        verts.append(v.reshape(-1, 3))
        faces.append(f.reshape(-1, 3))
        offset += g * m * sides
    if not verts:
        return _empty()
    return trimesh.Trimesh(np.vstack(verts), np.vstack(faces), process=False)


def leaves_mesh(sk: Any) -> trimesh.Trimesh:
    if sk.n_leaves == 0:
        return _empty()
    tmpl, tf = (RECT, RECT_FACES) if str(sk.leaf_shape) == "rect" else (HEX, HEX_FACES)
    t3 = np.column_stack([tmpl, np.zeros(len(tmpl))])
    v = np.einsum("lij,kj->lki", sk.leaf_matrices, t3) + sk.leaf_positions[:, None, :]
    f = (tf[None] + len(tmpl) * np.arange(sk.n_leaves)[:, None, None]).reshape(-1, 3)
    return trimesh.Trimesh(v.reshape(-1, 3), f, process=False)


def build_mesh(sk: Any) -> Any:
    from weberpenn.treemesh import TreeMesh

    return TreeMesh(branches_mesh(sk), leaves_mesh(sk), meta={"mesher": "render._fallback_mesh"})
