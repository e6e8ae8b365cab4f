"""Silhouette coverage without a ray-tracing scene: a numpy scanline rasteriser.

Orthographic ``ray_test`` rays that all travel along one direction hit a mesh exactly
where their start point, projected on the image plane, lies inside the projection of
some triangle.  :func:`hit_mask` answers that question for the same regular sample grid
as :meth:`render.camera.Camera.rays` (sample centres, top row first), triangle by
triangle and row by row: for every sample row a triangle spans, the row's entry and exit
points on the triangle's edges give a run of covered samples, and all runs are summed
into one difference image.  Its cost follows the number of sample rows the triangles
span, not the triangle count, and nothing (no acceleration structure) is built first,
so a tree that is drawn once costs a few milliseconds instead of mitsuba's BVH build.

Samples that lie exactly on a triangle edge count as covered; mitsuba (Embree,
float32) decides such ties its own way, so the two masks may differ in a handful of
samples of a whole image (measured in ``benchmarks/RESULTS.md``, "Faster evaluations").
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .camera import Camera, Framing, check_size
from .silhouette import Coverage, downsample, mesh_arrays

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
    few samples are lost.
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
    xs = [px[f[:, i]] for i in range(3)]
    ys = [py[f[:, i]] for i in range(3)]
    # only triangles whose box holds a sample centre can cover one
    x_min = np.minimum(np.minimum(xs[0], xs[1]), xs[2])
    x_max = np.maximum(np.maximum(xs[0], xs[1]), xs[2])
    y_min = np.minimum(np.minimum(ys[0], ys[1]), ys[2])
    y_max = np.maximum(np.maximum(ys[0], ys[1]), ys[2])
    first_row = np.maximum(np.ceil(y_min), 0)
    rows = np.minimum(np.floor(y_max), n - 1) - first_row + 1
    live = (rows > 0) & (np.maximum(np.ceil(x_min), 0) <= np.minimum(np.floor(x_max), n - 1))
    if front_only:  # rows grow downwards: facing the camera = negative signed area
        area = (xs[1] - xs[0]) * (ys[2] - ys[0]) - (ys[1] - ys[0]) * (xs[2] - xs[0])
        live &= area < 0
    if not live.any():
        return out
    h = rows[live].astype(np.int64)
    y0 = first_row[live].astype(np.int64)
    xs = [x[live] for x in xs]
    ys = [y[live] for y in ys]
    # corners from top to bottom (a: the smallest row value, then b, c): three swaps
    for p, q in ((0, 1), (1, 2), (0, 1)):
        swap = ys[q] < ys[p]
        xs[p], xs[q] = np.where(swap, xs[q], xs[p]), np.where(swap, xs[p], xs[q])
        ys[p], ys[q] = np.where(swap, ys[q], ys[p]), np.where(swap, ys[p], ys[q])

    def line(i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """Edge i-j as x = c + k * row; a flat edge (k = 0) is met only at its ends,
        which the other two edges share."""
        dy = ys[j] - ys[i]
        flat = dy == 0
        k = np.where(flat, 0.0, (xs[j] - xs[i]) / np.where(flat, 1.0, dy))
        return xs[i] - ys[i] * k, k

    (c_ac, k_ac), (c_ab, k_ab), (c_bc, k_bc) = line(0, 2), line(0, 1), line(1, 2)
    # row j of every triangle spanning more than j rows at once: with the triangles in
    # order of falling row count those are a prefix, so each pass works on slices
    order = np.argsort((n - h).astype(np.uint16), kind="stable")  # a radix sort
    h, y0, yb = h[order], y0[order], ys[1][order]
    c_ac, k_ac, c_ab, k_ab, c_bc, k_bc = (a[order] for a in (c_ac, k_ac, c_ab, k_ab, c_bc, k_bc))
    counts = np.searchsorted(-h, -np.arange(1, int(h[0]) + 1), side="right")
    rows, lo, hi = [], [], []
    for j, c in enumerate(counts):
        r = y0[:c] + j
        ry = r.astype(np.float64)
        x_long = c_ac[:c] + ry * k_ac[:c]  # edge a-c spans every row of the triangle
        upper = ry < yb[:c]  # rows above b meet edge a-b, the others edge b-c
        x_short = np.where(upper, c_ab[:c] + ry * k_ab[:c], c_bc[:c] + ry * k_bc[:c])
        rows.append(r)
        lo.append(np.minimum(x_long, x_short))
        hi.append(np.maximum(x_long, x_short))
    row = np.concatenate(rows)
    c0 = np.maximum(np.ceil(np.concatenate(lo)), 0)
    c1 = np.minimum(np.floor(np.concatenate(hi)), n - 1)
    keep = c1 >= c0
    row, c0i, c1i = row[keep], c0[keep].astype(np.int64), c1[keep].astype(np.int64)
    m = n + 1  # one spare column for the run ends
    runs = np.bincount(row * m + c0i, minlength=n * m)
    runs -= np.bincount(row * m + c1i + 1, minlength=n * m)
    return np.cumsum(runs.reshape(n, m), axis=1)[:, :n] > 0


class RasterScene:
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
        self.framing = framing or Framing.from_vertices(
            np.vstack(verts) if verts else np.zeros((0, 3))
        )

    @property
    def is_empty(self) -> bool:
        return all(p is None for p in self._parts)

    def coverage(
        self,
        yaw: float = 0.0,
        size: int = 256,
        supersample: int = 2,
        pitch: float = 0.0,
        keep_hr: bool = False,
        leaf_supersample: int | None = None,
    ) -> Coverage:
        """As :meth:`render.silhouette.TreeScene.coverage`, from :func:`hit_mask`."""
        cam = Camera(self.framing, float(yaw), float(pitch))
        size = check_size(size)
        ss = int(supersample)
        ss_leaf = ss if leaf_supersample is None else int(leaf_supersample)
        if ss < 1 or ss_leaf < 1:
            raise ValueError(f"supersample must be >= 1, got {supersample!r}, {leaf_supersample!r}")
        hits = []
        for part, k in zip(self._parts, (ss, ss_leaf), strict=True):
            n = size * k
            if part is None:
                hits.append(np.zeros((n, n), bool))
            else:  # tubes: their front half covers them; leaves are seen from both sides
                hits.append(hit_mask(*part, cam, n, front_only=len(hits) == 0))
        cov_b = downsample(hits[0].astype(np.float32), ss)
        cov_l = downsample(hits[1].astype(np.float32), ss_leaf)
        return Coverage(cov_b, cov_l, hits[0] if keep_hr else None)
