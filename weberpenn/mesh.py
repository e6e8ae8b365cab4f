"""Skeleton -> TreeMesh: Bezier tubes for the stems and quads/hexes for the leaves.

The geometry is what Blender makes of Sapling's curve object (see the Skeleton docstring):
every stem is a cubic Bezier through its control points with Blender's AUTO handles
(VECTOR handles on the first point of every spline), sampled ``res_u`` times per segment
plus the end point, radius interpolated linearly per segment, swept with a round
cross-section of ``4 + 2*bevel_res`` sides along minimum-twist (parallel transport)
frames, ends left open.  Leaves are the unit template (hex: 6 vertices / 2 quads,
rect: 4 vertices / 1 quad, quads split into triangles) transformed by ``leaf_matrices``
and moved to ``leaf_positions``, with UVs.

Everything is vectorised across stems: stems are grouped by control-point count and each
group is evaluated as one ``(G, n, 3)`` array; only the parallel-transport sweep loops,
over ring index, for all stems of a group at once.
"""

from __future__ import annotations

import numba
import numpy as np
import trimesh
from trimesh.visual import TextureVisuals

from .limits import check_mesh, mesh_size
from .skeleton import Skeleton
from .treemesh import TreeMesh

__all__ = ["HEX", "HEX_FACES", "RECT", "RECT_FACES", "TreeMesh", "build_mesh", "tube_counts"]

# Leaf templates in the Skeleton contract's frame: XY plane, one unit tall along +Y.
HEX = np.array(
    [[0.0, 0.0], [0.5, 1 / 3], [0.5, 2 / 3], [0.0, 1.0], [-0.5, 2 / 3], [-0.5, 1 / 3]],
    dtype=np.float64,
)
HEX_FACES = np.array([[0, 1, 4], [0, 4, 5], [1, 2, 3], [1, 3, 4]], dtype=np.int64)  # 2 quads
RECT = np.array([[0.5, 0.0], [0.5, 1.0], [-0.5, 1.0], [-0.5, 0.0]], dtype=np.float64)
RECT_FACES = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)  # 1 quad

_AUTO = 2.5614  # Blender's auto-handle length divisor
_EPS = 1e-12


def _empty_mesh() -> trimesh.Trimesh:
    m = trimesh.Trimesh(
        vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), dtype=np.int64), process=False
    )
    m.visual = TextureVisuals(uv=np.zeros((0, 2)))
    return m


def tube_counts(n_points: int, res_u: int, bevel_res: int) -> tuple[int, int]:
    """(vertices, triangles) of one stem's tube with ``n_points`` control points."""
    sides = 4 + 2 * bevel_res
    rings = (n_points - 1) * res_u + 1
    return sides * rings, 2 * sides * (rings - 1)


def _norm(v: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(v, axis=-1)`` for float arrays (same arithmetic, less call overhead)."""
    return np.sqrt(np.add.reduce(v * v, axis=-1))


def _cross_into(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``out[...] = np.cross(a, b)`` by components (numpy's own arithmetic, fewer calls)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])


def _unit(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = _norm(v)
    return v / np.maximum(n, _EPS)[..., None], n


def _handles(p: np.ndarray, first: np.ndarray, last: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left and right Bezier handles of the control points ``p`` (N, 3) of all stems at
    once, Blender's AUTO rule; stem ``i`` owns rows ``first[i] .. last[i]`` (2 or more)."""
    prev = np.empty_like(p)
    nxt = np.empty_like(p)
    prev[1:] = p[:-1]
    prev[0] = p[0]
    nxt[:-1] = p[1:]
    nxt[-1] = p[-1]
    prev[first] = 2.0 * p[first] - p[first + 1]  # end points mirror their neighbour
    nxt[last] = 2.0 * p[last] - p[last - 1]
    da = p - prev
    db = nxt - p
    la = _norm(da)
    lb = _norm(db)
    la = np.where(la == 0.0, 1.0, la)
    lb = np.where(lb == 0.0, 1.0, lb)
    t = da / la[..., None] + db / lb[..., None]
    tl = _norm(t) * _AUTO
    ok = tl > _EPS
    tl = np.where(ok, tl, 1.0)
    la = np.minimum(la, 5.0 * lb)  # each leg at most five times the other
    lb = np.minimum(lb, 5.0 * la)
    left = np.where(ok[..., None], p - t * (la / tl)[..., None], p)
    right = np.where(ok[..., None], p + t * (lb / tl)[..., None], p)
    # Sapling sets the first point of every spline to VECTOR handles
    right[first] = p[first] + (p[first + 1] - p[first]) / 3.0
    left[first] = p[first] - (p[first + 1] - p[first]) / 3.0
    return left, right


def _sample(
    p: np.ndarray, left: np.ndarray, right: np.ndarray, r: np.ndarray, res_u: int
) -> tuple[np.ndarray, np.ndarray]:
    """Evaluate the Bezier splines of a group (points and handles (G, n, 3), radii (G, n)):
    (G, R, 3) positions and (G, R) radii."""
    g, n, _ = p.shape
    t = np.arange(res_u, dtype=np.float64) / res_u
    b0 = (1 - t) ** 3
    b1 = 3 * (1 - t) ** 2 * t
    b2 = 3 * (1 - t) * t**2
    b3 = t**3
    p0, p1, p2, p3 = p[:, :-1], right[:, :-1], left[:, 1:], p[:, 1:]  # (G, n-1, 3)
    x = (
        p0[:, :, None] * b0[:, None]
        + p1[:, :, None] * b1[:, None]
        + p2[:, :, None] * b2[:, None]
        + p3[:, :, None] * b3[:, None]
    )  # (G, n-1, res_u, 3)
    rad = r[:, :-1, None] * (1 - t) + r[:, 1:, None] * t  # (G, n-1, res_u)
    x = np.concatenate([x.reshape(g, (n - 1) * res_u, 3), p[:, -1:]], axis=1)
    rad = np.concatenate([rad.reshape(g, (n - 1) * res_u), r[:, -1:]], axis=1)
    return x, rad


def _tangents(x: np.ndarray) -> np.ndarray:
    """Unit tangents of sampled paths (G, R, 3); degenerate spots inherit a neighbour's."""
    d = np.empty_like(x)
    d[:, 1:-1] = x[:, 2:] - x[:, :-2]
    d[:, 0] = x[:, 1] - x[:, 0]
    d[:, -1] = x[:, -1] - x[:, -2]
    t, n = _unit(d)
    bad = n <= _EPS
    if bad.any():
        for j in range(1, t.shape[1]):  # forward fill, then backward, then +Z
            m = bad[:, j] & ~bad[:, j - 1]
            t[m, j] = t[m, j - 1]
            bad[m, j] = False
        for j in range(t.shape[1] - 2, -1, -1):
            m = bad[:, j] & ~bad[:, j + 1]
            t[m, j] = t[m, j + 1]
            bad[m, j] = False
        t[bad] = (0.0, 0.0, 1.0)
    return t


def _frames(t: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Minimum-twist normals along unit tangents ``t`` (S, Rmax, 3).

    Row ``i`` holds ``lengths[i]`` valid rings; rows are sorted by length, longest first,
    so each parallel-transport step works on a prefix of the rows (all stems at once).
    """
    s, rmax, _ = t.shape
    t0 = t[:, 0]
    axis = np.zeros((s, 3))
    axis[np.arange(s), np.argmin(np.abs(t0), axis=1)] = 1.0
    n0, _ = _unit(np.cross(t0, axis))
    normals = np.empty_like(t)
    normals[:, 0] = n0
    active = np.searchsorted(-lengths, -np.arange(rmax), side="left")  # rows with len > j
    for j in range(1, rmax):  # parallel transport: project, renormalise
        a = int(active[j])
        nj = normals[:a, j - 1]
        tj = t[:a, j]
        v = nj - np.einsum("gi,gi->g", nj, tj)[:, None] * tj
        v, ln = _unit(v)
        bad = ln < 1e-6  # the tangent turned onto the normal: take any perpendicular
        if bad.any():
            alt = np.cross(tj[bad], np.array([0.0, 0.0, 1.0]))
            alt = np.where(_norm(alt)[:, None] > 1e-6, alt, (1.0, 0.0, 0.0))
            v[bad] = _unit(alt)[0]
        normals[:a, j] = v
    return normals


def _ring_faces(rings: int, sides: int) -> np.ndarray:
    """Triangles of one tube, vertex index = ring * sides + side (outward winding)."""
    j = np.arange(rings - 1, dtype=np.int64)[:, None]
    k = np.arange(sides, dtype=np.int64)[None, :]
    a = j * sides + k
    b = j * sides + (k + 1) % sides
    tri = np.empty((rings - 1, sides, 2, 3), dtype=np.int64)
    tri[:, :, 0, 0] = a
    tri[:, :, 0, 1] = b
    tri[:, :, 0, 2] = b + sides
    tri[:, :, 1, 0] = a
    tri[:, :, 1, 1] = b + sides
    tri[:, :, 1, 2] = a + sides
    return tri.reshape(-1, 3)


def _tube_uv(x: np.ndarray, rr: np.ndarray, u_ring: np.ndarray, out: np.ndarray) -> None:
    """Bark UVs of a group of tubes into ``out`` (G, R, sides, 2).

    u runs once around the stem (0 .. (sides-1)/sides; the exporter closes the seam at
    u = 1), v along it by arc length in units of the stem's mean circumference, so a
    square tiling bark texture keeps its aspect and flows on unbroken from ring to ring.
    """
    seg = _norm(np.diff(x, axis=1))  # (G, R-1)
    arc = np.zeros(x.shape[:2])
    np.cumsum(seg, axis=1, out=arc[:, 1:])
    circ = 2.0 * np.pi * np.maximum(rr.mean(axis=1), 1e-4)  # (G,)
    out[..., 0] = u_ring
    out[..., 1] = (arc / circ[:, None])[:, :, None]


def _branches(sk: Skeleton) -> tuple[trimesh.Trimesh, dict]:
    s = sk.n_stems
    if s == 0:
        return _empty_mesh(), {"stems": 0}
    sides = 4 + 2 * int(sk.bevel_res)
    res_u = max(int(sk.res_u), 1)
    offsets = np.asarray(sk.offsets, dtype=np.int64)
    counts = np.diff(offsets)
    pts = np.asarray(sk.points, dtype=np.float64)
    rad = np.asarray(sk.radii, dtype=np.float64)
    ang = 2.0 * np.pi * np.arange(sides) / sides
    circle = np.stack([np.cos(ang), np.sin(ang)], axis=1)  # (sides, 2)
    groups = [int(n) for n in np.unique(counts) if n >= 2]
    if not groups:
        return _empty_mesh(), {"stems": s}
    rings_of = {n: (n - 1) * res_u + 1 for n in groups}
    members = {n: np.nonzero(counts == n)[0] for n in groups}
    nv_total = sum(len(members[n]) * rings_of[n] * sides for n in groups)
    nf_total = sum(len(members[n]) * 2 * sides * (rings_of[n] - 1) for n in groups)
    verts = np.empty((nv_total, 3), dtype=np.float64)
    faces = np.empty((nf_total, 3), dtype=np.int64)
    uv = np.empty((nv_total, 2), dtype=np.float64)
    u_ring = np.arange(sides, dtype=np.float64) / sides
    v0 = f0 = 0
    # stems grouped by control-point count, stem order kept inside a group
    sampled = {}
    tubes = counts >= 2
    left, right = _handles(pts, offsets[:-1][tubes], offsets[1:][tubes] - 1)
    for n in groups:
        sel = offsets[members[n]][:, None] + np.arange(n)[None, :]
        x, rr = _sample(pts[sel], left[sel], right[sel], rad[sel], res_u)  # (G, R, 3), (G, R)
        sampled[n] = (x, rr, _tangents(x))
    # one parallel-transport sweep over all stems, longest first (prefix slices)
    desc = groups[::-1]
    rmax = rings_of[desc[0]]
    tan = np.empty((sum(len(members[n]) for n in groups), rmax, 3))
    lengths = np.concatenate([np.full(len(members[n]), rings_of[n]) for n in desc])
    row = {}
    r0 = 0
    for n in desc:
        g = len(members[n])
        tan[r0 : r0 + g, : rings_of[n]] = sampled[n][2]
        row[n] = r0
        r0 += g
    nor_all = _frames(tan, lengths)
    v0 = f0 = 0
    for n in groups:
        x, rr, tg = sampled[n]
        g, rings = len(members[n]), rings_of[n]
        r0 = row[n]
        nor = nor_all[r0 : r0 + g, :rings]
        frame = np.empty((g, rings, 2, 3))  # (G, R, 2, 3): normal, tangent x normal
        frame[:, :, 0] = nor
        _cross_into(tg, nor, frame[:, :, 1])
        frame *= rr[:, :, None, None]
        nv, nf = rings * sides, 2 * sides * (rings - 1)
        out = verts[v0 : v0 + g * nv].reshape(g, rings, sides, 3)
        np.matmul(circle, frame, out=out)
        out += x[:, :, None]
        _tube_uv(x, rr, u_ring, uv[v0 : v0 + g * nv].reshape(g, rings, sides, 2))
        tmpl = _ring_faces(rings, sides)
        fout = faces[f0 : f0 + g * nf].reshape(g, nf, 3)
        np.add(tmpl[None], (v0 + nv * np.arange(g, dtype=np.int64))[:, None, None], out=fout)
        v0 += g * nv
        f0 += g * nf
    mesh = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
    mesh.visual = TextureVisuals(uv=uv)
    return mesh, {"stems": s, "sides": sides, "res_u": res_u}


@numba.njit(cache=True)
def _leaf_corners(tmpl2: np.ndarray, mats: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(L, T, 3): each template corner (x, y, 0) placed by each leaf's matrix and
    position, ``x * col0 + y * col1 + pos`` (the template lies in z = 0, so only the
    matrix's first two columns matter), added in that order as numpy adds the
    broadcast arrays, in one pass over the leaves (compiled: a tree has 10^4 leaves, and
    numpy's broadcasts over the matrices' strided columns took 3x as long)."""
    out = np.empty((mats.shape[0], tmpl2.shape[0], 3))
    for i in range(mats.shape[0]):
        for j in range(tmpl2.shape[0]):
            for k in range(3):
                a = tmpl2[j, 0] * mats[i, k, 0]
                b = tmpl2[j, 1] * mats[i, k, 1]
                out[i, j, k] = (a + b) + pos[i, k]
    return out


def _leaves(sk: Skeleton) -> trimesh.Trimesh:
    nl = sk.n_leaves
    rect = str(sk.leaf_shape) == "rect"
    tmpl2, tf = (RECT, RECT_FACES) if rect else (HEX, HEX_FACES)
    if nl == 0:
        return _empty_mesh()
    mats = np.ascontiguousarray(sk.leaf_matrices, dtype=np.float64)
    pos = np.ascontiguousarray(sk.leaf_positions, dtype=np.float64)
    v = _leaf_corners(np.ascontiguousarray(tmpl2), mats, pos)
    nt = len(tmpl2)
    faces = (np.arange(nl)[:, None, None] * nt + tf[None]).reshape(-1, 3)
    uv = np.tile(tmpl2 + np.array([0.5, 0.0]), (nl, 1))
    mesh = trimesh.Trimesh(vertices=v.reshape(-1, 3), faces=faces, process=False)
    mesh.visual = TextureVisuals(uv=uv)
    return mesh


def build_mesh(skeleton: Skeleton, species: str | None = None) -> TreeMesh:
    """Mesh a grown skeleton: tubes for the stems, leaf quads/hexes, both with UVs.

    ``species`` is recorded on the TreeMesh (it picks export/render colours).  An empty
    skeleton gives two empty meshes; one whose mesh would exceed :mod:`weberpenn.limits`
    raises :class:`~weberpenn.params.ParamError` before anything is allocated.
    """
    if not isinstance(skeleton, Skeleton):
        raise TypeError(f"build_mesh expects a weberpenn Skeleton, got {type(skeleton).__name__}")
    sk = skeleton
    size = mesh_size(np.diff(sk.offsets), sk.res_u, sk.bevel_res, sk.n_leaves, sk.leaf_shape)
    check_mesh(*size, {"resU": int(sk.res_u), "bevelRes": int(sk.bevel_res)})
    branches, meta = _branches(skeleton)
    leaves = _leaves(skeleton)
    meta = {**meta, "leaves": skeleton.n_leaves, "leaf_shape": str(skeleton.leaf_shape)}
    return TreeMesh(branches=branches, leaves=leaves, species=species, meta=meta, skeleton=skeleton)
