"""Drawing styles: the same tree view drawn the way people draw, so labels stay exact.

Every style is a pure function ``style(sil, rng, size) -> (size, size) uint8`` (255 = white
paper) of one view's two silhouettes (:class:`Silhouettes`, the branch and leaf pictures
the renderer makes for the paper's chain), a seeded ``numpy.random.Generator`` (which
draws the style's free choices: wave, stroke width, gaps, ...) and the output size:

- ``sg``: the paper's chain (:mod:`render.edges`), the same pixels as
  ``SketchRenderer.sketch``; it ignores ``rng``.
- ``pen``: a clean pen outline: a closed wavy crown contour, trunk and main branches as
  single strokes of varying width (sometimes the trunk as two lines), no leaf blobs.
- ``cloud``: an architect's tree: a scalloped cloud outline around the crown, the trunk as
  two lines, a few main branches inside.
- ``scribble``: the crown filled with a looping scribble, a filled trunk and branches.
- ``pencil``: thin, light, broken and doubled lines on off-white or grey textured paper.
- ``felt``: a felt tip: few thick strokes, a smooth crown outline, the trunk as one stroke.
- ``bare``: a winter tree: no foliage, the trunk and branches down to the twigs as pen
  strokes (the thick parts often as two lines).
- ``doodle``: a quick finger or mouse doodle: the crown as a polyline of 5 to 20 jittered
  segments (sometimes left open), a fitted "lollipop" ellipse, a zigzag (pointed crowns:
  a Christmas tree) or loops; thin foliage (palm fronds, hanging twigs) as single strokes;
  the trunk as two lines or one; a few branches as single strokes; one even line width
  of a phone or a mouse.

Each function takes its constants as keyword arguments (pixel sizes are for a 256-pixel
drawing and scale with the work size); ``STYLES`` maps a name to its function and
:func:`draw` is the one entry point.  Drawing happens at ``max(size, 256)`` pixels and is
area-averaged down, as for the SG chain; everything is whole-image numpy/scipy work
(distance transforms, Gaussian noise fields, one skeletonisation), a few milliseconds
per style at 256 pixels.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.special import ndtri

from .distance import distance_to_background
from .edges import EdgeConfig, branch_sketch, combine, foliage_sketch

__all__ = [
    "STYLES",
    "Silhouettes",
    "StyleFn",
    "bare",
    "check_styles",
    "cloud",
    "doodle",
    "draw",
    "felt",
    "pen",
    "pencil",
    "scribble",
    "sg",
]

REFERENCE = 256  # pixel constants are given for this drawing size


@dataclass(frozen=True)
class Silhouettes:
    """One view's silhouettes, black on white floats (1 = background), square, same size."""

    branches: np.ndarray
    leaves: np.ndarray
    # the foliage is drawn as single strokes (palm fronds, hanging willow twigs): a fact
    # of the species (``weberpenn.species.doodle_foliage``), not of the pixels
    foliage_strokes: bool = False

    def __post_init__(self) -> None:
        b = np.asarray(self.branches)
        f = np.asarray(self.leaves)
        if b.ndim != 2 or b.shape[0] != b.shape[1] or b.shape != f.shape:
            raise ValueError(
                f"silhouettes must be two square images of one size, got {b.shape} and {f.shape}"
            )

    @classmethod
    def from_parts(cls, parts: Any, foliage_strokes: bool = False) -> Silhouettes:
        """From a :class:`render.sketch.SketchParts` (its silhouettes are at work size)."""
        return cls(parts.branch_silhouette, parts.leaf_silhouette, foliage_strokes)

    @property
    def n(self) -> int:
        return int(np.asarray(self.branches).shape[0])


StyleFn = Callable[..., np.ndarray]


# --------------------------------------------------------------------------- primitives
def _noise(rng: np.random.Generator, n: int, sigma: float) -> np.ndarray:
    """A smooth random field of unit standard deviation (features about ``sigma`` px)."""
    if sigma <= 3.0:
        f = ndimage.gaussian_filter(rng.standard_normal((n, n)).astype(np.float32), sigma)
    else:  # a coarse field, smoothed and interpolated up: the same look, much cheaper
        step = sigma / 2.0
        m = int(np.ceil(n / step)) + 4
        coarse = ndimage.gaussian_filter(rng.standard_normal((m, m)).astype(np.float32), 2.0)
        at = (np.arange(n, dtype=np.float32) + 0.5) / step + 1.5
        i0 = np.floor(at).astype(int)
        w = (at - i0)[:, None]
        rows = coarse[i0] * (1 - w) + coarse[i0 + 1] * w  # linear, one axis at a time
        f = rows[:, i0] * (1 - w.T) + rows[:, i0 + 1] * w.T
    sd = float(f.std())
    return f / sd if sd > 0 else f


def _sdf(mask: np.ndarray) -> np.ndarray:
    """Signed distance to a mask's edge in pixels (positive inside)."""
    if not mask.any():
        return np.full(mask.shape, -1e6, np.float32)
    if mask.all():
        return np.full(mask.shape, 1e6, np.float32)
    inside = distance_to_background(mask)
    outside = distance_to_background(~mask)
    # pixel centres sit half a pixel from the edge between a mask pixel and its neighbour
    return np.where(mask, inside - 0.5, 0.5 - outside).astype(np.float32)


def _stroke(dist: np.ndarray, width: np.ndarray | float) -> np.ndarray:
    """Anti-aliased ink (0..1) of a line at distance ``|dist|`` with ``width`` px."""
    return np.clip(np.asarray(width) / 2.0 + 0.5 - np.abs(dist), 0.0, 1.0).astype(np.float32)


def _dist_to(mask: np.ndarray) -> np.ndarray:
    if not mask.any():
        return np.full(mask.shape, 1e6, np.float32)
    return distance_to_background(~mask).astype(np.float32)


def _along_lines(lines: np.ndarray, width: np.ndarray | float) -> np.ndarray:
    """Ink of strokes ``width`` px wide along the pixels of ``lines`` (a one-pixel mask)."""
    return _stroke(_dist_to(lines), width)


def _components(mask: np.ndarray, eight: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Labels of a mask's connected parts (``eight``: diagonal neighbours connect) and
    each part's size in pixels (part ``i`` is label ``i + 1``)."""
    lab, k = ndimage.label(mask, structure=np.ones((3, 3)) if eight else None)
    return lab, ndimage.sum_labels(mask, lab, index=np.arange(1, k + 1))


def _keep(lab: np.ndarray, sel: np.ndarray) -> np.ndarray:
    """The pixels of the parts ``sel`` picks (a boolean per part of :func:`_components`)."""
    return np.isin(lab, np.flatnonzero(sel) + 1)


def _opening(mask: np.ndarray, radius: float) -> np.ndarray:
    """The parts of ``mask`` at least ``2 * radius`` px wide (opening by a disc)."""
    if radius <= 0 or not mask.any():
        return mask
    core = distance_to_background(mask) >= radius
    return (_dist_to(core) <= radius) & mask


def _warp(ink: np.ndarray, rng: np.random.Generator, amp: float, sigma: float) -> np.ndarray:
    """Displace the drawing by a smooth random field: a hand's wobble."""
    n = ink.shape[0]
    if amp <= 0:
        return ink
    dy = _noise(rng, n, sigma) * amp
    dx = _noise(rng, n, sigma) * amp
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float32)
    return ndimage.map_coordinates(ink, [yy + dy, xx + dx], order=1, mode="constant", cval=0.0)


def _area_resize(img: np.ndarray, size: int) -> np.ndarray:
    n = img.shape[0]
    if n == size:
        return img
    if n % size == 0:
        k = n // size
        return img.reshape(size, k, size, k).mean(axis=(1, 3), dtype=np.float32)
    from PIL import Image

    im = Image.fromarray(np.ascontiguousarray(img, dtype=np.float32), mode="F")
    return np.asarray(im.resize((size, size), Image.Resampling.BOX), dtype=np.float32)


def _finish(ink: np.ndarray, size: int, paper: np.ndarray | float = 1.0) -> np.ndarray:
    """Ink (0..1, 1 = black) over paper (0..1 brightness) -> uint8 at ``size``."""
    img = np.asarray(paper, dtype=np.float32) * (1.0 - np.clip(ink, 0.0, 1.0))
    return np.round(np.clip(_area_resize(img, size), 0.0, 1.0) * 255.0).astype(np.uint8)


def _contours(mask: np.ndarray) -> list[np.ndarray]:
    """A mask's closed outlines, each ``(k, 2)`` row/column points (padded so that parts
    touching the border close too)."""
    from skimage import measure

    return [c - 1.0 for c in measure.find_contours(np.pad(mask, 1).astype(np.float32), 0.5)]


def _arc_length(c: np.ndarray) -> np.ndarray:
    """The length along a contour at each of its points (0 at the first)."""
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(c, axis=0).T))])


def _along(c: np.ndarray, arc: np.ndarray, at: np.ndarray) -> np.ndarray:
    """The points of contour ``c`` at lengths ``at`` along it (``arc``: its arc length)."""
    return np.stack([np.interp(at, arc, c[:, 0]), np.interp(at, arc, c[:, 1])], axis=1)


def _pixels(pts: np.ndarray, n: int) -> np.ndarray:
    """Row/column points as whole pixel indices on an ``n``-pixel page."""
    return np.clip(np.round(pts).astype(int), 0, n - 1)


@dataclass(frozen=True)
class _Geometry:
    """What the styles draw from: masks and distance fields at work size."""

    n: int
    s: float  # work size / 256
    branches: np.ndarray  # bool: branch silhouette
    branch_sdf: np.ndarray
    leaves: np.ndarray  # bool: leaf silhouette
    skeleton: np.ndarray  # bool: one-pixel centre lines of the branches
    radius: np.ndarray  # half width of the branch at each pixel (edt inside)

    def crown(self, sigma_px: float, level: float = 0.12) -> np.ndarray:
        """A closed, hole-free foliage region around the leaves (what people outline)."""
        if not self.leaves.any():
            return self.leaves
        blur = ndimage.gaussian_filter(self.leaves.astype(np.float32), sigma_px * self.s)
        m = blur >= level
        m = ndimage.binary_fill_holes(m)
        lab, areas = _components(m)
        if len(areas) > 1:  # specks far from the crown are not drawn
            m = _keep(lab, areas >= 0.02 * areas.max())
        return m

    def main_branches(self, min_width_px: float) -> np.ndarray:
        """Skeleton pixels of branches at least ``min_width_px`` wide (twigs dropped),
        kept only when connected to the trunk through such branches."""
        wide = self.skeleton & (self.radius * 2.0 >= min_width_px * self.s)
        if not wide.any():
            return wide
        lab, sizes = _components(wide, eight=True)
        if len(sizes) > 1:
            wide = _keep(lab, sizes >= max(4.0 * self.s, 0.05 * sizes.max()))
        return wide


def _geometry(sil: Silhouettes) -> _Geometry:
    from skimage.morphology import skeletonize

    b = np.asarray(sil.branches, dtype=np.float32) <= 0.5
    f = np.asarray(sil.leaves, dtype=np.float32) < 0.9
    n = sil.n
    radius = distance_to_background(b).astype(np.float32) if b.any() else np.zeros((n, n))
    skel = skeletonize(b) if b.any() else b
    return _Geometry(n, n / REFERENCE, b, _sdf(b), f, skel, radius)


def _skeleton_strokes(
    g: _Geometry, skel: np.ndarray, widths: tuple[float, ...], scale: float, min_w: float
) -> np.ndarray:
    """Strokes along ``skel`` whose width follows the branch width (``scale`` x the
    silhouette's width, at least ``min_w`` px), in a few width classes."""
    ink = np.zeros((g.n, g.n), np.float32)
    if not skel.any():
        return ink
    w = np.maximum(2.0 * g.radius * scale, min_w * g.s)
    edges = [*widths, np.inf]
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = skel & (w >= lo * g.s) & (w < hi * g.s)
        if sel.any():
            width = float(np.median(w[sel]))
            ink = np.maximum(ink, _along_lines(sel, width))
    return ink


@dataclass
class _Drawing:
    """One drawing in progress: what it is drawn from, the hand's line width (drawn
    first from ``rng``, so every style's later choices keep their place in the stream)
    and the ink so far."""

    g: _Geometry
    rng: np.random.Generator
    lw: float
    ink: np.ndarray

    @classmethod
    def start(
        cls, sil: Silhouettes, rng: np.random.Generator, line_px: tuple[float, float]
    ) -> _Drawing:
        g = _geometry(sil)
        return cls(g, rng, rng.uniform(*line_px) * g.s, np.zeros((g.n, g.n), np.float32))

    def crown(self, sigma_px: tuple[float, float], level: float = 0.12) -> np.ndarray:
        """The foliage region, blurred by a width drawn from ``sigma_px``."""
        return self.g.crown(self.rng.uniform(*sigma_px), level)

    def add(self, layer: np.ndarray | float) -> None:
        self.ink = np.maximum(self.ink, layer)

    def done(self, size: int, wobble_px: tuple[float, float], sigma_px: float) -> np.ndarray:
        """The hand's wobble (a drawn amount, features of ``sigma_px``), then the paper."""
        s = self.g.s
        return _finish(
            _warp(self.ink, self.rng, self.rng.uniform(*wobble_px) * s, sigma_px * s), size
        )


def _wave(
    rng: np.random.Generator, n: int, sigma: float, amp_px: tuple[float, float], s: float
) -> np.ndarray:
    """A smooth offset field (features of ``sigma`` px, size drawn from ``amp_px``): added
    to a distance field, it makes a drawn outline wavy."""
    return _noise(rng, n, sigma) * rng.uniform(*amp_px) * s


def _thick_lines(mask: np.ndarray, radius: float, lw: float) -> tuple[np.ndarray, np.ndarray]:
    """The parts of ``mask`` at least ``2 * radius`` wide drawn as two lines (their edges),
    and the pixels next to them, where single strokes of the thinner parts stop."""
    thick = _opening(mask, radius)
    if not thick.any():
        return np.zeros(mask.shape, np.float32), np.zeros(mask.shape, bool)
    return _stroke(_sdf(thick), lw), ndimage.binary_dilation(thick, iterations=2)


# --------------------------------------------------------------------------- the styles
def sg(sil: Silhouettes, rng: np.random.Generator | None = None, size: int = 256) -> np.ndarray:
    """The paper's SG chain (the same pixels as ``SketchRenderer.sketch``)."""
    cfg = EdgeConfig()
    out = branch_sketch(np.asarray(sil.branches, np.float32), cfg) * foliage_sketch(
        np.asarray(sil.leaves, np.float32), cfg
    )
    return combine(_area_resize(out, int(size)), np.float32(1.0))


def pen(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    crown_sigma_px: tuple[float, float] = (3.0, 6.0),
    wave_px: tuple[float, float] = (1.0, 3.0),
    wave_sigma_px: tuple[float, float] = (5.0, 10.0),
    line_px: tuple[float, float] = (1.4, 2.6),
    twig_px: float = 1.2,
    two_line_trunk: float = 0.5,
    wobble_px: tuple[float, float] = (0.5, 1.5),
) -> np.ndarray:
    """Clean pen: wavy closed crown contour, trunk and main branches as strokes."""
    d = _Drawing.start(sil, rng, line_px)
    n, s = d.g.n, d.g.s
    crown = d.crown(crown_sigma_px)
    if crown.any():
        wave = _wave(rng, n, rng.uniform(*wave_sigma_px) * s, wave_px, s)
        width = d.lw * (1.0 + 0.25 * _noise(rng, n, 12 * s))
        d.add(_stroke(_sdf(crown) + wave, width))
    d.add(_branch_lines(d.g, rng, d.lw, twig_px, two_line_trunk))
    return d.done(size, wobble_px, 14)


def _branch_lines(
    g: _Geometry, rng: np.random.Generator, lw: float, twig_px: float, two_line_trunk: float
) -> np.ndarray:
    """Trunk and branches down to ``twig_px`` wide as pen strokes of varying width; with
    probability ``two_line_trunk`` the thick parts are drawn as two lines instead."""
    s = g.s
    main = g.main_branches(twig_px)
    if rng.random() < two_line_trunk:  # thick parts as two lines, thin ones as strokes
        ink, near = _thick_lines(g.branches, 2.5 * s, lw)
        return np.maximum(ink, _skeleton_strokes(g, main & ~near, (0.0, 2.0, 3.5), 1.0, lw / s))
    return _skeleton_strokes(g, main, (0.0, 2.0, 3.5, 6.0, 10.0), 1.0, lw / s)


def bare(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    line_px: tuple[float, float] = (1.2, 2.4),
    twig_px: tuple[float, float] = (0.5, 1.2),
    two_line_trunk: float = 0.6,
    wobble_px: tuple[float, float] = (0.5, 1.5),
) -> np.ndarray:
    """A bare (winter) tree: no foliage at all, the trunk and the branches down to the
    twigs as pen strokes (the thick parts often as two lines), as people draw a tree's
    branching when they leave out its leaves."""
    d = _Drawing.start(sil, rng, line_px)
    d.add(_branch_lines(d.g, rng, d.lw, rng.uniform(*twig_px), two_line_trunk))
    return d.done(size, wobble_px, 14)


def cloud(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    crown_sigma_px: tuple[float, float] = (3.5, 6.0),
    scallop_px: tuple[float, float] = (8.0, 14.0),
    line_px: tuple[float, float] = (1.6, 2.6),
    inner_branches: float = 0.6,
    wobble_px: tuple[float, float] = (0.5, 1.2),
) -> np.ndarray:
    """Architect's cloud: scalloped crown outline, trunk as two lines."""
    d = _Drawing.start(sil, rng, line_px)
    g, s, lw = d.g, d.g.s, d.lw
    crown = d.crown(crown_sigma_px)
    cloud_mask = crown
    if crown.any():
        r0 = rng.uniform(*scallop_px) * s
        radii = (0.75 * r0, r0, 1.3 * r0)
        centres = [np.zeros((g.n, g.n), bool) for _ in radii]
        for c in _contours(crown):
            arc = _arc_length(c)
            if arc[-1] < 2 * r0:
                continue
            step = r0 * rng.uniform(1.5, 1.8)
            pts = _pixels(_along(c, arc, np.arange(rng.uniform(0, step), arc[-1], step)), g.n)
            which = rng.integers(0, len(radii), len(pts))
            for k in range(len(radii)):
                sel = pts[which == k]
                centres[k][sel[:, 0], sel[:, 1]] = True
        for k, r in enumerate(radii):  # discs on the outline: the union bulges in arcs
            cloud_mask = cloud_mask | (_dist_to(centres[k]) <= r)
        d.add(_stroke(_sdf(cloud_mask), lw))
    trunk = _opening(g.branches, 1.5 * s) & ~cloud_mask  # below the cloud: two lines
    if trunk.any():
        trunk_sdf = _sdf(trunk | (g.branches & ndimage.binary_dilation(cloud_mask, iterations=3)))
        d.add(_stroke(trunk_sdf, lw) * ~ndimage.binary_erosion(cloud_mask))
    if rng.random() < inner_branches:
        main = g.main_branches(2.0) & cloud_mask
        d.add(_skeleton_strokes(g, main, (0.0, 3.0), 0.6, lw / s))
    return d.done(size, wobble_px, 16)


def scribble(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    crown_sigma_px: tuple[float, float] = (3.0, 5.0),
    loop_sigma_px: tuple[float, float] = (2.5, 4.5),
    spacing: tuple[float, float] = (0.6, 1.0),
    line_px: tuple[float, float] = (1.2, 2.0),
    coverage: tuple[float, float] = (0.75, 1.0),
    outline: float = 0.5,
    wobble_px: tuple[float, float] = (0.5, 1.5),
) -> np.ndarray:
    """Scribbled foliage: looping lines fill the crown; trunk and branches filled."""
    d = _Drawing.start(sil, rng, line_px)
    g, s, lw = d.g, d.g.s, d.lw
    crown = d.crown(crown_sigma_px)
    if crown.any():
        edge = _sdf(crown) + _noise(rng, g.n, 6 * s) * 2.0 * s
        # level lines of a smooth random field look like a hand's loops
        field = _noise(rng, g.n, rng.uniform(*loop_sigma_px) * s) / rng.uniform(*spacing)
        gy, gx = np.gradient(field)
        dist = np.abs(field - np.round(field)) / np.maximum(np.hypot(gy, gx), 1e-3)
        holes = _noise(rng, g.n, 10 * s) < -(2.0 * rng.uniform(*coverage) - 1.0) * 1.5
        d.add(_stroke(dist, lw) * np.clip(edge, 0.0, 1.0) * ~holes)
        if rng.random() < outline:
            d.add(_stroke(edge, lw))
    trunk = g.branches & (~crown | (g.radius * 2.0 >= 3.0 * s))
    d.add(np.clip(g.branch_sdf + 0.5, 0.0, 1.0) * trunk)
    d.add(_skeleton_strokes(g, g.main_branches(1.0) & ~crown, (0.0,), 1.0, lw / s))
    return d.done(size, wobble_px, 14)


def pencil(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    paper: tuple[float, float] = (0.70, 0.96),
    grain: tuple[float, float] = (0.01, 0.035),
    shading: tuple[float, float] = (0.0, 0.08),
    darkness: tuple[float, float] = (0.4, 0.75),
    line_px: tuple[float, float] = (1.1, 1.7),
    gaps: tuple[float, float] = (0.1, 0.3),
    double: float = 0.6,
    wave_px: tuple[float, float] = (1.0, 2.5),
) -> np.ndarray:
    """Light pencil: thin, broken, sometimes doubled lines on grey or off-white paper."""
    d = _Drawing.start(sil, rng, line_px)
    g, s, n, lw = d.g, d.g.s, d.g.n, d.lw
    crown = d.crown((3.0, 6.0))
    crown_sdf = _sdf(crown) if crown.any() else None
    thick, near = _thick_lines(g.branches, 2.0 * s, lw)
    limbs = _skeleton_strokes(g, g.main_branches(1.2) & ~near, (0.0, 2.5), 0.6, lw / s)
    tree = np.maximum(thick, limbs)  # the same in every pass: only the hand moves
    passes = 2 if rng.random() < double else 1
    for _ in range(passes):  # a second pass a little off the first: a sketchy line
        layer = tree
        if crown_sdf is not None:
            layer = np.maximum(layer, _stroke(crown_sdf + _wave(rng, n, 8 * s, wave_px, s), lw))
        layer = _warp(layer, rng, rng.uniform(0.6, 1.5) * s, 12 * s)
        broken = _noise(rng, n, 3 * s) > ndtri(rng.uniform(*gaps))  # that fraction lifts
        d.add(layer * broken * rng.uniform(0.7, 1.0))
    pressure = np.clip(1.0 + 0.25 * _noise(rng, n, 20 * s), 0.5, 1.5)
    ink = d.ink * pressure * rng.uniform(*darkness)
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float32) / n
    light = rng.uniform(*paper) + rng.uniform(*shading) * (
        rng.uniform(-1, 1) * (yy - 0.5) + rng.uniform(-1, 1) * (xx - 0.5)
    )
    tooth = ndimage.gaussian_filter(rng.standard_normal((n, n)).astype(np.float32), 0.7 * s)
    sheet = np.clip(light + tooth / max(float(tooth.std()), 1e-6) * rng.uniform(*grain), 0, 1)
    return _finish(ink, size, sheet)


def felt(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    crown_sigma_px: tuple[float, float] = (6.0, 10.0),
    line_px: tuple[float, float] = (3.5, 6.0),
    branch_px: float = 2.5,
    wobble_px: tuple[float, float] = (0.8, 2.0),
) -> np.ndarray:
    """Felt tip: a thick smooth crown outline, the trunk and a few limbs as thick strokes."""
    d = _Drawing.start(sil, rng, line_px)
    g, s, lw = d.g, d.g.s, d.lw
    crown = d.crown(crown_sigma_px, level=0.2)
    if crown.any():
        d.add(_stroke(_sdf(crown) + _wave(rng, g.n, 14 * s, (0.5, 2.0), s), lw))
    d.add(_skeleton_strokes(g, g.main_branches(branch_px), (0.0, 8.0), 1.0, 0.8 * lw / s))
    return d.done(size, wobble_px, 18)


def _polylines(n: int, lines: list[np.ndarray]) -> np.ndarray:
    """One-pixel mask of polylines (each ``(k, 2)`` row/column points, clipped to the page)."""
    from skimage.draw import line

    mask = np.zeros((n, n), bool)
    for pts in lines:
        p = _pixels(pts, n)
        for (r0, c0), (r1, c1) in zip(p[:-1], p[1:], strict=True):
            rr, cc = line(r0, c0, r1, c1)
            mask[rr, cc] = True
    return mask


def _outline(mask: np.ndarray) -> np.ndarray:
    """The longest closed contour of a mask, ``(k, 2)``, as arc-length samples."""
    return max(_contours(mask), key=len)


def _resample(c: np.ndarray, k: int, start: float) -> np.ndarray:
    """``k`` points spaced evenly along a closed contour, from ``start`` (0..1) of its length."""
    arc = _arc_length(c)
    return _along(c, arc, (start + np.arange(k) / k) % 1.0 * arc[-1])


def _crown_lines(
    crown: np.ndarray, rng: np.random.Generator, s: float, mode: str, open_p: float
) -> list[np.ndarray]:
    """The crown as a doodle: polyline, ellipse, zigzag or loops (row/column points)."""
    c = _outline(crown)
    centre = c.mean(axis=0)
    if mode == "ellipse":  # the lollipop: the crown's second moments as an ellipse
        rr, cc = np.nonzero(crown)
        cov = np.cov(np.stack([rr, cc]).astype(np.float64))
        w, v = np.linalg.eigh(cov)
        t = np.linspace(0, 2 * np.pi, int(rng.integers(10, 21)) + 1) + rng.uniform(0, 2 * np.pi)
        unit = np.stack([np.cos(t), np.sin(t)], axis=1) * (2.0 * np.sqrt(np.maximum(w, 1.0)))
        pts = unit @ v.T + np.array([rr.mean(), cc.mean()])
        return [pts + rng.normal(0, 1.5 * s, pts.shape)]
    if mode == "zigzag":  # a Christmas tree: tiers whose tips follow the crown's width
        rows = np.nonzero(crown.any(axis=1))[0]
        top, bottom = float(rows[0]), float(rows[-1])
        cols = np.nonzero(crown.any(axis=0))[0]
        mid = (cols[0] + cols[-1]) / 2.0
        tiers = int(rng.integers(3, 7))
        ys = top + (bottom - top) * (np.arange(1, tiers + 1) / tiers) ** rng.uniform(0.8, 1.1)
        half = np.array([crown[int(min(y, bottom))].sum() / 2.0 for y in ys])
        inner = rng.uniform(0.4, 0.7)
        left = [(top, mid)]
        for i, (y, w) in enumerate(zip(ys, half, strict=True)):
            left.append((y, mid - w))
            if i < tiers - 1:
                left.append((y, mid - inner * w))
        right = [(y, 2 * mid - x) for y, x in reversed(left[1:])]
        pts = np.array(left + right + [(top, mid)], dtype=np.float64)
        return [pts + rng.normal(0, 1.0 * s, pts.shape)]
    elif mode == "loops":  # a chain of small loops around the crown
        k = int(rng.integers(8, 15))
        at = _resample(c, 12 * k, rng.uniform())
        r = rng.uniform(5.0, 10.0) * s
        t = np.linspace(0.0, 2 * np.pi * k, len(at))
        normal = at - centre
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-6)
        pts = at + normal * (r * (0.5 + 0.5 * np.cos(t)))[:, None]
    else:  # a polyline of 5 to 20 segments
        pts = _resample(c, int(rng.integers(5, 21)), rng.uniform())
    pts = pts + rng.normal(0, 1.5 * s, pts.shape)
    pts = np.concatenate([pts, pts[:1]])
    if rng.random() < open_p:  # the stroke stops short of where it began
        pts = pts[: max(3, int(len(pts) * rng.uniform(0.8, 0.95)))]
    return [pts]


def doodle(
    sil: Silhouettes,
    rng: np.random.Generator,
    size: int = 256,
    *,
    line_px: tuple[float, float] = (1.5, 5.0),
    open_crown: float = 0.3,
    inner_branches: float = 0.4,
    two_line_trunk: float = 0.5,
    bare_line_px: tuple[float, float] = (1.2, 2.5),
    wobble_px: tuple[float, float] = (0.5, 2.0),
) -> np.ndarray:
    """A quick doodle: polyline, lollipop, zigzag or looped crown, or thin foliage as
    single strokes; the trunk as two lines or one; one even line width."""
    d = _Drawing.start(sil, rng, line_px)
    g, s, n, lw = d.g, d.g.s, d.g.n, d.lw
    crown = d.crown((3.0, 6.0))
    leaf_px = float(g.leaves.sum())
    thin = sil.foliage_strokes
    if crown.any() and leaf_px > 0:
        rows = np.nonzero(crown.any(axis=1))[0]
        top, bottom = rows[0], rows[-1]
        width = crown.sum(axis=1)
        upper = width[top : top + max(1, (bottom - top) // 3)].mean()
        lower = width[bottom - max(1, (bottom - top) // 3) : bottom + 1].mean()
        pointed = upper < 0.5 * lower
        modes = ("polyline", "ellipse", "zigzag", "loops", "strokes")
        weights = np.array(
            [0.35, 0.2, 0.8 if pointed else 0.02, 0.15, 1.2 if thin else 0.05], np.float64
        )
        mode = str(rng.choice(modes, p=weights / weights.sum()))
        if mode == "strokes":
            from skimage.morphology import skeletonize

            strokes = skeletonize(g.leaves) & ~ndimage.binary_dilation(g.branches, iterations=1)
            lab, sizes = _components(strokes, eight=True)
            strokes = _keep(lab, sizes >= 6 * s)  # specks of a stroke are not drawn
            d.add(_along_lines(strokes, lw))
        else:
            d.add(_along_lines(_polylines(n, _crown_lines(crown, rng, s, mode, open_crown)), lw))
    else:
        crown = np.zeros((n, n), bool)
    below = g.branches & ~crown
    if rng.random() < two_line_trunk:
        # the trunk as two lines (a bare tree: its thickest limbs only)
        thick, near = _thick_lines(below, (1.5 if leaf_px else 3.0) * s, lw)
        d.add(thick)
        below = below & ~near
    if leaf_px == 0:  # a bare tree: thinner lines, the main limbs only
        lw = min(lw, rng.uniform(*bare_line_px) * s)
    main = g.main_branches(2.5 if leaf_px == 0 else 2.0)
    keep = main & ~crown if leaf_px and rng.random() >= inner_branches else main
    keep = keep & (below | crown | (leaf_px == 0))
    d.add(_along_lines(keep, lw))
    return d.done(size, wobble_px, 16)


STYLES: dict[str, StyleFn] = {
    "sg": sg,
    "pen": pen,
    "cloud": cloud,
    "scribble": scribble,
    "pencil": pencil,
    "felt": felt,
    "bare": bare,
    "doodle": doodle,
}


def check_styles(names: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """Validate a list of style names (known, not repeated, at least one)."""
    names = tuple(names)
    if not names:
        raise ValueError("no drawing style given")
    for name in names:
        if name not in STYLES:
            raise ValueError(f"unknown drawing style {name!r}: choose from {', '.join(STYLES)}")
    if len(set(names)) != len(names):
        raise ValueError(f"drawing style listed twice: {', '.join(names)}")
    return names


def draw(
    style: str, sil: Silhouettes, rng: np.random.Generator | int | None = 0, size: int = 256
) -> np.ndarray:
    """One view drawn in ``style``: (size, size) uint8, 255 = white paper."""
    check_styles((style,))
    size = int(size)
    if not 8 <= size <= sil.n:
        raise ValueError(f"size must be in 8..{sil.n} (the silhouettes' size), got {size}")
    if not isinstance(rng, np.random.Generator):
        rng = np.random.default_rng(rng)
    return STYLES[style](sil, rng, size)
