"""Silhouette coverage without a ray-tracing scene: a numpy scanline rasteriser.

Orthographic ``ray_test`` rays that all travel along one direction hit a mesh exactly
where their start point, projected on the image plane, lies inside the projection of
some triangle.  :func:`hit_mask` answers that question for the same regular sample grid
as :meth:`render.camera.Camera.rays` (sample centres, top row first), polygon by polygon
and row by row: for every sample row a convex polygon (a triangle, or two triangles that
make a convex quad on screen) spans, its edges bound a run of covered samples, and all
runs are summed into one difference image.  Its cost follows the number of sample rows
the polygons span, not the triangle count, and nothing (no acceleration structure) is
built first, so a tree drawn once or twice costs milliseconds instead of mitsuba's BVH
build.  :class:`RasterScene` draws branch tubes by their camera-facing half only.

Samples that lie exactly on an edge count as covered; mitsuba (Embree, float32) decides
such ties its own way, so the two masks may differ in a handful of samples of a whole
image (measured in ``benchmarks/RESULTS.md``, "Faster evaluations").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .camera import Camera, Framing
from .silhouette import CoverageScene, mesh_arrays

__all__ = ["RasterScene", "hit_mask"]


def hit_mask(
    vertices: np.ndarray,
    faces: np.ndarray,
    camera: Camera,
    n: int,
    front_only: bool = False,
) -> np.ndarray:
    """(n, n) bool: which samples of the ``n`` x ``n`` grid of ``camera`` a triangle covers.

    The grid is :meth:`Camera.rays` with ``size * supersample == n``.  ``front_only``
    draws only the triangles that face the camera (counter-clockwise seen from it, i.e.
    an outward normal towards it): the front half of a closed surface covers all of its
    silhouette, so a tube mesh costs half; where a surface is open (a tube's ends) a
    few samples are lost.  Two consecutive triangles (a, b, c), (a, c, d) whose union is
    a convex quad seen from the camera (a leaf, a tube's side) are drawn as that quad,
    which spans the rows once instead of twice.
    """
    out = np.zeros((n, n), dtype=bool)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(f) == 0:
        return out
    right, up, _ = camera.basis()
    s = camera.framing.span
    d = np.asarray(vertices, dtype=np.float64).reshape(-1, 3) - camera.framing.centre
    # sample k sits at ((k + 0.5) / n - 0.5) * s: column k <-> x, row k <-> -y
    # (not ``d @ right``: a BLAS call per 3-vector is slower than three products)
    px = (d[:, 0] * right[0] + d[:, 1] * right[1] + d[:, 2] * right[2]) * (n / s) + (0.5 * n - 0.5)
    py = (0.5 * n - 0.5) - (d[:, 0] * up[0] + d[:, 1] * up[1] + d[:, 2] * up[2]) * (n / s)
    quads, tris = _pair_quads(f, px, py, front_only)
    runs = [_convex_runs([px[q] for q in quads.T], [py[q] for q in quads.T], n)]
    if len(tris):
        xs, ys = [px[t] for t in tris.T], [py[t] for t in tris.T]
        if front_only:  # rows grow downwards: facing the camera = negative signed area
            facing = _cross(xs, ys, 0) < 0
            xs, ys = [x[facing] for x in xs], [y[facing] for y in ys]
        runs.append(_convex_runs(xs, ys, n))
    row = np.concatenate([r[0] for r in runs])
    c0 = np.concatenate([r[1] for r in runs])
    c1 = np.concatenate([r[2] for r in runs])
    m = n + 1  # one spare column for the run ends
    cover = np.bincount(row * m + c0, minlength=n * m)
    cover -= np.bincount(row * m + c1 + 1, minlength=n * m)
    return np.cumsum(cover.reshape(n, m), axis=1)[:, :n] > 0


def _cross(xs: list[np.ndarray], ys: list[np.ndarray], i: int) -> np.ndarray:
    """Signed turn at corner ``i + 1`` of polygons given corner by corner."""
    k = len(xs)
    a, b, c = i % k, (i + 1) % k, (i + 2) % k
    return (xs[b] - xs[a]) * (ys[c] - ys[b]) - (ys[b] - ys[a]) * (xs[c] - xs[b])


def _pair_quads(
    f: np.ndarray, px: np.ndarray, py: np.ndarray, front_only: bool
) -> tuple[np.ndarray, np.ndarray]:
    """(Q, 4) quads made of consecutive triangle pairs (a, b, c), (a, c, d) that are
    strictly convex on screen (and facing the camera when ``front_only``), and the
    (T, 3) triangles left over."""
    even = len(f) - len(f) % 2
    t0, t1 = f[0:even:2], f[1:even:2]
    pair = (t0[:, 0] == t1[:, 0]) & (t0[:, 2] == t1[:, 1])
    quad = np.column_stack([t0[:, 0], t0[:, 1], t0[:, 2], t1[:, 2]])
    xs, ys = [px[q] for q in quad.T], [py[q] for q in quad.T]
    turns = [_cross(xs, ys, i) for i in range(4)]
    neg = (turns[0] < 0) & (turns[1] < 0) & (turns[2] < 0) & (turns[3] < 0)
    convex = (
        neg
        if front_only
        else neg | ((turns[0] > 0) & (turns[1] > 0) & (turns[2] > 0) & (turns[3] > 0))
    )
    # a pair facing away (front_only) is dropped whole, like its two triangles would be
    away = front_only & pair & (turns[0] > 0) & (turns[1] > 0) & (turns[2] > 0) & (turns[3] > 0)
    take = pair & convex
    rest = ~(take | away)
    tris = np.concatenate([t0[rest], t1[rest], f[even:]])
    return quad[take], tris


def _convex_runs(
    xs: list[np.ndarray], ys: list[np.ndarray], n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row, first column, last column) of the samples inside each convex polygon
    (corners ``xs[i], ys[i]`` in order, either winding; triangles included).

    A convex polygon is where every edge's inner half-plane meets: on a row, the
    run starts at the rightmost left-hand edge and ends at the leftmost right-hand one.
    """
    empty = np.zeros(0, dtype=np.int64)
    if len(xs[0]) == 0:
        return empty, empty, empty
    k = len(xs)
    x_min, x_max, y_min, y_max = xs[0], xs[0], ys[0], ys[0]
    for x, y in zip(xs[1:], ys[1:], strict=True):
        x_min, x_max = np.minimum(x_min, x), np.maximum(x_max, x)
        y_min, y_max = np.minimum(y_min, y), np.maximum(y_max, y)
    first_row = np.maximum(np.ceil(y_min), 0)
    rows = np.minimum(np.floor(y_max), n - 1) - first_row + 1
    # only polygons whose box holds a sample centre can cover one; one seen edge-on
    # (no area) covers none, as no ray along its plane hits it
    turn = _cross(xs, ys, 0)  # the winding: > 0 when the corners go clockwise on screen
    live = (rows > 0) & (np.maximum(np.ceil(x_min), 0) <= np.minimum(np.floor(x_max), n - 1))
    live &= turn != 0
    if not live.any():
        return empty, empty, empty
    h = rows[live].astype(np.int64)
    y0 = first_row[live].astype(np.int64)
    xs, ys, turn = [x[live] for x in xs], [y[live] for y in ys], turn[live]
    # each edge as x = c + slope * row, bounding the run from the left (x >= line) or
    # the right, by its direction and the winding (a sliver whose winding rounding got
    # wrong gets its bounds swapped: an empty run); a flat edge bounds only the rows,
    # which first_row..y_max already do
    left, right = [], []
    for i in range(k):
        j = (i + 1) % k
        dy = ys[j] - ys[i]
        flat = dy == 0
        slope = np.where(flat, 0.0, (xs[j] - xs[i]) / np.where(flat, 1.0, dy))
        c = xs[i] - ys[i] * slope
        is_left = dy * turn < 0
        left.append((np.where(flat | ~is_left, -np.inf, c), np.where(is_left, slope, 0.0)))
        right.append((np.where(flat | is_left, np.inf, c), np.where(is_left, 0.0, slope)))
    # row j of every polygon spanning more than j rows at once: with the polygons in
    # order of falling row count those are a prefix, so each pass works on slices
    order = np.argsort((n - h).astype(np.uint16), kind="stable")  # a radix sort
    h, y0 = h[order], y0[order]
    left = [(c[order], sl[order]) for c, sl in left]
    right = [(c[order], sl[order]) for c, sl in right]
    counts = np.searchsorted(-h, -np.arange(1, int(h[0]) + 1), side="right")
    out_rows, out_lo, out_hi = [], [], []
    for j, m in enumerate(counts):
        r = y0[:m] + j
        ry = r.astype(np.float64)
        lo = left[0][0][:m] + ry * left[0][1][:m]
        hi = right[0][0][:m] + ry * right[0][1][:m]
        for c, sl in left[1:]:
            lo = np.maximum(lo, c[:m] + ry * sl[:m])
        for c, sl in right[1:]:
            hi = np.minimum(hi, c[:m] + ry * sl[:m])
        out_rows.append(r)
        out_lo.append(lo)
        out_hi.append(hi)
    row = np.concatenate(out_rows)
    c0 = np.maximum(np.ceil(np.concatenate(out_lo)), 0)
    c1 = np.minimum(np.floor(np.concatenate(out_hi)), n - 1)
    keep = c1 >= c0
    return row[keep], c0[keep].astype(np.int64), c1[keep].astype(np.int64)


class RasterScene(CoverageScene):
    """A tree's branch and leaf triangles, drawn by :func:`hit_mask` (no mitsuba); the
    branch tubes by their triangles facing the camera.

    Offers the silhouette part of :class:`render.silhouette.TreeScene`'s interface
    (``framing``, ``is_empty``, :meth:`coverage`); colour pictures need mitsuba.
    """

    def __init__(self, tree_mesh: Any, framing: Framing | None = None) -> None:
        parts = [mesh_arrays(getattr(tree_mesh, name)) for name in ("branches", "leaves")]
        self._parts = [
            None if a is None else (a[0].reshape(-1, 3), a[1].reshape(-1, 3)) for a in parts
        ]
        verts = [p[0] for p in self._parts if p is not None]
        self.framing = framing or Framing.from_parts(verts)

    @property
    def is_empty(self) -> bool:
        return all(p is None for p in self._parts)

    def _hit(self, part: int, cam: Camera, size: int, k: int) -> np.ndarray:
        n = size * k
        arrays = self._parts[part]
        if arrays is None:
            return np.zeros((n, n), bool)
        # tubes: their front half covers them; leaves are seen from both sides
        return hit_mask(*arrays, cam, n, front_only=part == 0)
