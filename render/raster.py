"""Silhouette coverage without a ray-tracing scene: a compiled scanline rasteriser.

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

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numba
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
    f = np.asarray(faces).reshape(-1, 3)
    if len(f) == 0:
        return np.zeros((n, n), dtype=bool)
    v = np.asarray(vertices).reshape(-1, 3)
    if f.dtype.kind not in "iu" or int(f.min()) < 0 or int(f.max()) >= len(v):
        raise IndexError(f"faces must index the {len(v)} vertices")
    right, up, _ = camera.basis()
    s = camera.framing.span
    # sample k sits at ((k + 0.5) / n - 0.5) * s: column k <-> x, row k <-> -y
    centre = np.asarray(camera.framing.centre, dtype=np.float64)
    px, py = _project(
        v, centre, np.asarray(right, np.float64), np.asarray(up, np.float64), n / s, 0.5 * n - 0.5
    )
    f = np.ascontiguousarray(f)
    front_only, n = bool(front_only), int(n)
    if len(f) < SPLIT_FACES or _cores() < 2:
        return _mask_of(_cover(px, py, f, front_only, n))
    # two halves on two threads (the compiled loops let go of the GIL); the cut falls
    # between two pairs, so every quad is drawn as before, and a sum of run starts and
    # ends is the same in any order: the same mask
    cut = len(f) // 4 * 2
    with ThreadPoolExecutor(1) as pool:
        other = pool.submit(_cover, px, py, f[cut:], front_only, n)
        cover = _cover(px, py, f[:cut], front_only, n)
        cover += other.result()
    return _mask_of(cover)


# a mesh with fewer faces than this is drawn on one thread (a thread costs ~0.1 ms; a
# tree's branch tubes, the bulk of a refinement's drawing, have 10^5 and more)
SPLIT_FACES = 20_000


def _cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


# The scanline loops run compiled (numba): a tree's mesh has tens of thousands of small
# polygons a few rows tall, where numpy's per-row passes over all of them cost 2-3 times
# as much (RESULTS.md, "The rasteriser compiled").  ``cache``: compiled once per machine.


@numba.njit(cache=True)
def _project(
    v: np.ndarray, centre: np.ndarray, right: np.ndarray, up: np.ndarray, k: float, o: float
) -> tuple[np.ndarray, np.ndarray]:
    """Each vertex's column and row on the sample grid (``k`` samples per unit, ``o`` the
    grid's centre sample)."""
    px, py = np.empty(len(v)), np.empty(len(v))
    for i in range(len(v)):
        d0 = np.float64(v[i, 0]) - centre[0]
        d1 = np.float64(v[i, 1]) - centre[1]
        d2 = np.float64(v[i, 2]) - centre[2]
        px[i] = (d0 * right[0] + d1 * right[1] + d2 * right[2]) * k + o
        py[i] = o - (d0 * up[0] + d1 * up[1] + d2 * up[2]) * k
    return px, py


@numba.njit(cache=True)
def _cross(x0: float, y0: float, x1: float, y1: float, x2: float, y2: float) -> float:
    """Signed turn at corner 1 of the corners 0, 1, 2 (> 0: clockwise on screen)."""
    return (x1 - x0) * (y2 - y1) - (y1 - y0) * (x2 - x1)


@numba.njit(cache=True)
def _fill_convex(
    xs: np.ndarray, ys: np.ndarray, k: int, n: int, cover: np.ndarray, edges: np.ndarray
) -> None:
    """Add the samples inside the convex polygon ``xs[:k], ys[:k]`` (corners in order,
    either winding) to ``cover``, a (n, n + 1) difference image: +1 where a row's run
    starts, -1 after it ends.  ``edges``: (4, 4) scratch space.

    A convex polygon is where every edge's inner half-plane meets: on a row, the run
    starts at the rightmost left-hand edge and ends at the leftmost right-hand one.
    Only a polygon whose box holds a sample centre can cover one; one seen edge-on (no
    area) covers none, as no ray along its plane hits it.
    """
    x_min, x_max, y_min, y_max = xs[0], xs[0], ys[0], ys[0]
    for i in range(1, k):
        x_min, x_max = min(x_min, xs[i]), max(x_max, xs[i])
        y_min, y_max = min(y_min, ys[i]), max(y_max, ys[i])
    first_row = max(np.ceil(y_min), 0.0)
    rows = min(np.floor(y_max), n - 1.0) - first_row + 1.0
    if not rows > 0 or not max(np.ceil(x_min), 0.0) <= min(np.floor(x_max), n - 1.0):
        return
    turn = _cross(xs[0], ys[0], xs[1], ys[1], xs[2], ys[2])
    if turn == 0:
        return
    # each edge as x = c + slope * row, bounding the run from the left (x >= line) or
    # the right, by its direction and the winding (a sliver whose winding rounding got
    # wrong gets its bounds swapped: an empty run); a flat edge bounds only the rows,
    # which first_row..y_max already do
    lc, ls, rc, rs = edges[0], edges[1], edges[2], edges[3]
    for i in range(k):
        j = (i + 1) % k
        dy = ys[j] - ys[i]
        flat = dy == 0
        slope = 0.0 if flat else (xs[j] - xs[i]) / dy
        c = xs[i] - ys[i] * slope
        is_left = dy * turn < 0
        lc[i] = -np.inf if (flat or not is_left) else c
        ls[i] = slope if is_left else 0.0
        rc[i] = np.inf if (flat or is_left) else c
        rs[i] = 0.0 if is_left else slope
    y0 = np.int64(first_row)
    for r in range(y0, y0 + np.int64(rows)):
        ry = np.float64(r)
        lo = lc[0] + ry * ls[0]
        hi = rc[0] + ry * rs[0]
        for e in range(1, k):
            lo = max(lo, lc[e] + ry * ls[e])
            hi = min(hi, rc[e] + ry * rs[e])
        c0 = max(np.ceil(lo), 0.0)
        c1 = min(np.floor(hi), n - 1.0)
        if c1 >= c0:
            cover[r, np.int64(c0)] += 1
            cover[r, np.int64(c1) + 1] -= 1


@numba.njit(cache=True)
def _fill_triangle(
    px: np.ndarray,
    py: np.ndarray,
    face: np.ndarray,
    front_only: bool,
    n: int,
    xs: np.ndarray,
    ys: np.ndarray,
    cover: np.ndarray,
    edges: np.ndarray,
) -> None:
    """Add one triangle to ``cover``; with ``front_only`` only when it faces the camera
    (rows grow downwards: facing = a negative signed area)."""
    for i in range(3):
        xs[i], ys[i] = px[face[i]], py[face[i]]
    if front_only and not _cross(xs[0], ys[0], xs[1], ys[1], xs[2], ys[2]) < 0:
        return
    _fill_convex(xs, ys, 3, n, cover, edges)


@numba.njit(cache=True, nogil=True)
def _cover(px: np.ndarray, py: np.ndarray, f: np.ndarray, front_only: bool, n: int) -> np.ndarray:
    """The faces ``f`` over the projected corners ``px, py`` as a (n, n + 1) difference
    image of row runs: consecutive triangles (a, b, c), (a, c, d) strictly convex on
    screen (and facing the camera when ``front_only``) drawn as one quad, a pair facing
    away dropped whole, the rest as triangles."""
    cover = np.zeros((n, n + 1), np.int32)
    xs, ys, edges = np.empty(4), np.empty(4), np.empty((4, 4))
    even = len(f) - len(f) % 2
    for p in range(0, even, 2):
        a, b = f[p], f[p + 1]
        take = away = False
        if a[0] == b[0] and a[2] == b[1]:
            quad = (a[0], a[1], a[2], b[2])
            for i in range(4):
                xs[i], ys[i] = px[quad[i]], py[quad[i]]
            neg = pos = True
            for i in range(4):
                j, m = (i + 1) % 4, (i + 2) % 4
                t = _cross(xs[i], ys[i], xs[j], ys[j], xs[m], ys[m])
                neg, pos = neg and t < 0, pos and t > 0
            take = neg or (pos and not front_only)
            away = front_only and pos
        if take:
            _fill_convex(xs, ys, 4, n, cover, edges)
        elif not away:
            _fill_triangle(px, py, a, front_only, n, xs, ys, cover, edges)
            _fill_triangle(px, py, b, front_only, n, xs, ys, cover, edges)
    for g in range(even, len(f)):
        _fill_triangle(px, py, f[g], front_only, n, xs, ys, cover, edges)
    return cover


@numba.njit(cache=True)
def _mask_of(cover: np.ndarray) -> np.ndarray:
    """The (n, n) hit mask of a difference image of row runs."""
    n = cover.shape[0]
    out = np.empty((n, n), np.bool_)
    for r in range(n):
        run = 0
        for c in range(n):
            run += cover[r, c]
            out[r, c] = run > 0
    return out


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
