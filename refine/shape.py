"""A sketch distance that does not care about drawing style: compare the tree's *shape*.

People draw the same tree many ways (the paper's blobs, a clean pen outline, a cloud, a
scribble, light broken pencil, a few felt-tip strokes: ``render.styles``).  What they share
is the shape: the crown's outline and the trunk below it.  So each sketch is reduced to

- its **ink**, seen at twice the work size and pooled ("any ink"), so a thin light line
  survives the downscale; dust (pieces of ink, joined over small gaps, smaller than
  ``SPECK_AREA`` of the frame) is dropped, and the rest is **framed by its height** (trunk
  base on the bottom margin, as ``render.reader`` frames a tree, but without its side
  margins, so the width decides only for a tree too wide for the frame: a cloud outline
  drawn wider than the leaves must not shrink the whole tree);
- its **filled silhouette**: ink closed over small gaps (broken pencil lines, a trunk drawn
  as two lines), holes filled, kept as a signed distance field (outside positive);
- its **outline**, the silhouette's boundary.

Two silhouettes are compared at each level of an image pyramid ("any ink" pooling, so coarse
levels also close larger gaps) *modulo a uniform offset*: the signed distances of each
outline from the other silhouette give the offset ``c`` (their median, at most
``OFFSET_LIMIT`` of the side: an outline drawn around the leaves rather than through them),
and the level's distance is ``(1 - soft IoU of the silhouettes moved c/2 towards each
other) + OUTLINE_WEIGHT * mean |signed outline distance - c| + OFFSET_WEIGHT * |c|`` (lengths
as fractions of the side); ``shape_distance`` is the mean over levels.  What is inside the
crown (blobs, scribbles, branch strokes) is left out on purpose: it is where drawing styles
differ most.

:func:`line_distance` asks the other question, "is this drawing a tree at all?": the
drawing's ink the tree's silhouette does not explain (farther outside it than the offset
allowance: text, a grid, noise around the shape), the tree's trunk where the drawing has
nothing (outside its filled shape), and a drawing that does not stand on a stem (a face, a circle or a spiral is widest
near its base; a tree, however drawn, has a trunk under its crown: at least ``MIN_STEM`` of
its height narrower than ``TRUNK_WIDTH`` of its widest row).  Extra outline line that the
filled shape explains costs nothing, so a plain outline drawing is not punished for being
one.

The silhouette alone cannot always tell two trees of one species apart once a style has
smoothed or scalloped the crown; a learned embedding of the same two masks
(``refine.embed``, trained so its Euclidean distance is the style-free shape distance of
the two trees) adds ``EMBED_WEIGHT`` times that distance when both sketches carry one
(``ShapeTarget.from_image(..., embedder=...)``; the refinement uses the shipped one).

:class:`ShapeTarget` holds one sketch's features for repeated comparison (the refinement
prepares the input once and each candidate once).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Protocol

import numpy as np
from scipy import ndimage

from render.distance import distance_to_background
from render.reader import crown_axis, stroke_width

from .envelope import CLOSE_FRACTION, envelope_of_ink, mask_iou
from .prepare import prepare_sketch

__all__ = [
    "EMBED_WEIGHT",
    "Embedder",
    "OFFSET_LIMIT",
    "OUTLINE_WEIGHT",
    "ShapeTarget",
    "embedding_distance",
    "filled_shape",
    "ink_pyramid",
    "line_distance",
    "outline_gap",
    "prepared_envelope",
    "pyramid_distance",
    "shape_distance",
]

OUTLINE_WEIGHT = 4.0  # one side-fraction of mean outline offset weighs as 4 IoU units
OFFSET_WEIGHT = 2.0  # the forgiven uniform offset still costs a little
OFFSET_LIMIT = 0.06  # of the side: how far around the leaves an outline may be drawn
CLOSE_RADIUS = 1 / 14  # of the side: gaps up to twice this close before the fill
SPECK_AREA = 1e-3  # of the frame: smaller pieces of ink are dust, not drawing
TRUNK_WIDTH = 0.2  # of the widest row: narrower rows at the bottom are the trunk
# of the side: the widest line ``ShapeTarget.inside_ink`` counts as drawn (4.5 px at 128:
# people's web-page strokes are 2 px wide there, the renderer's styles and the paper's
# drawings up to 4.5 px; a 28 px Quick, Draw! doodle scaled up draws every line 8-10 px
# wide, and its outline's own ink filled half its crown's inside, as a scribble does;
# the band left out along the outline grows by a wider line's excess, which its ink
# reaches into the crown: Quick, Draw!'s doodles with a few lines inside read as
# outlines, 52 of 389, their median overlap 0.717 -> 0.779; no drawing of the other sets
# moves: RESULTS.md, "The tree follows the drawing")
INSIDE_STROKE = 4.5 / 128
MIN_STEM = 0.02  # of the height: a drawing with less trunk than this does not stand on one
STEM_WEIGHT = 5.0  # line distance added per unit of missing stem (0.1 with no stem at all)
# the frame of render.reader (trunk base row, top margin), as fractions of the side
FRAME_BOTTOM = 0.969
FRAME_EDGE = 0.043
_DARK = 0.5
# one unit of the learned embedding's distance (``refine.embed``) weighs as this much
# hand-made shape distance: chosen on the benchmark's development pairs and the style
# drawings' refinement (RESULTS.md)
EMBED_WEIGHT = 4.0


class Embedder(Protocol):
    """What :meth:`ShapeTarget.from_image` needs of ``refine.embed.ShapeEmbedder``."""

    size: int  # the work size its network reads

    def embed(self, target: ShapeTarget) -> np.ndarray: ...


@dataclass(frozen=True)
class _ShapeLevel:
    sdf: np.ndarray  # float32 signed distance to the outline (outside > 0, inside < 0), px
    outline: np.ndarray  # bool, boundary pixels of the filled silhouette
    n: int  # outline pixels


def _drop_dust(ink: np.ndarray) -> np.ndarray:
    """``ink`` without pieces (joined over gaps of ``side / 64``) of less than
    ``SPECK_AREA`` of the frame; unchanged if that would leave nothing."""
    side = ink.shape[0]
    joined = ndimage.binary_dilation(ink, iterations=max(1, side // 64))
    lab, k = ndimage.label(joined, structure=np.ones((3, 3)))
    if k <= 1:
        return ink
    sizes = ndimage.sum_labels(ink, lab, index=np.arange(1, k + 1))
    keep = sizes >= SPECK_AREA * ink.size
    if not keep.any():
        return ink
    return ink & np.concatenate([[False], keep])[lab]


def _frame_by_height(ink: np.ndarray) -> np.ndarray:
    """``ink`` moved and scaled so its base is on the bottom margin, its axis on the
    centre line and its height fills the frame (its width only when it would not fit)."""
    side = ink.shape[0]
    ys = np.flatnonzero(ink.any(axis=1))
    xs = np.flatnonzero(ink.any(axis=0))
    top, bottom, left, right = ys[0], ys[-1], xs[0], xs[-1]
    axis = crown_axis(ink)  # as refine.objective.framed frames it
    half = max(axis - left, right + 1 - axis, 0.5)
    scale = min((FRAME_BOTTOM - FRAME_EDGE) * side / (bottom - top + 1), 0.5 * side / half)
    rows = (np.arange(side) + 0.5 - FRAME_BOTTOM * side) / scale + bottom + 0.5
    cols = (np.arange(side) + 0.5 - side / 2) / scale + axis - 0.5
    if scale >= 1.0:  # enlarging: nearest pixel keeps lines binary and as thin as drawn
        ri, ci = np.round(rows).astype(int), np.round(cols).astype(int)
        okr, okc = (ri >= 0) & (ri < side), (ci >= 0) & (ci < side)
        out = np.zeros_like(ink)
        out[np.ix_(okr, okc)] = ink[np.ix_(ri[okr], ci[okc])]
        return out
    grid = np.meshgrid(rows, cols, indexing="ij")
    return ndimage.map_coordinates(ink.astype(np.float32), grid, order=1, cval=0.0) > 0.25


def filled_shape(ink: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``ink`` (bool) closed over gaps up to ``2 * CLOSE_RADIUS`` of the side and its
    holes filled: (the filled silhouette, its outline pixels)."""
    side = ink.shape[0]
    r = max(1, int(round(side * CLOSE_RADIUS)))
    pad = r + 1  # near the border the fat brush must not touch the edge
    # closing with a disk of radius r, by distance transforms (linear time at any r)
    fat = distance_to_background(~np.pad(ink, pad)) <= r
    filled = distance_to_background(ndimage.binary_fill_holes(fat)) > r
    filled = filled[pad:-pad, pad:-pad] | ink
    return filled, filled & ~ndimage.binary_erosion(filled, border_value=0)


def ink_pyramid(ink: np.ndarray, scales: int) -> list[np.ndarray]:
    """``ink`` and up to ``scales - 1`` halvings of it by 2x2 "any ink" pooling (coarser
    levels close larger gaps), stopping before a level under 16 pixels."""
    levels = []
    for _ in range(scales):
        levels.append(ink)
        s = ink.shape[0] // 2
        if s < 16:
            break
        ink = ink[: 2 * s, : 2 * s].reshape(s, 2, s, 2).any(axis=(1, 3))
    return levels


def _level(ink: np.ndarray) -> _ShapeLevel:
    filled, outline = filled_shape(ink)
    n = int(outline.sum())
    if n == 0:
        return _ShapeLevel(np.zeros(ink.shape, np.float32), outline, 0)
    # zero on the outline pixels (the silhouette's own boundary), negative inside
    inside = np.maximum(distance_to_background(filled) - 1.0, 0.0)
    sdf = distance_to_background(~filled) - inside
    return _ShapeLevel(sdf.astype(np.float32), outline, n)


@dataclass(frozen=True)
class ShapeTarget:
    """A sketch's shape features at every pyramid level (see the module text)."""

    image: np.ndarray  # float32 0..1 (1 = white), the prepared sketch
    ink: np.ndarray  # bool, the cleaned, height-framed ink at full size
    levels: tuple[_ShapeLevel, ...]
    embedding: np.ndarray | None = None  # from a learned embedder (refine.embed), if one is used

    @classmethod
    def from_image(
        cls, img: Any, size: int = 128, scales: int = 3, embedder: Embedder | None = None
    ) -> ShapeTarget:
        """``img``'s shape features; with ``embedder`` (``refine.embed.ShapeEmbedder``) its
        learned embedding too, which :meth:`distance` then adds in."""
        f = prepare_sketch(img, size)
        fine = prepare_sketch(img, 2 * size) < _DARK
        ink = fine.reshape(size, 2, size, 2).any(axis=(1, 3))
        if ink.any():
            ink = _frame_by_height(_drop_dust(ink))
        out = cls(f, ink, tuple(_level(x) for x in ink_pyramid(ink, scales)))
        if embedder is not None:  # the network reads its own work size, whatever ours is
            seen = out if size == embedder.size else cls.from_image(img, embedder.size, scales)
            out = dataclasses.replace(out, embedding=np.asarray(embedder.embed(seen), np.float32))
        return out

    @property
    def size(self) -> int:
        return int(self.image.shape[0])

    @cached_property
    def trunk(self) -> np.ndarray:
        """(k, 2) row, column of the trunk's centre line: the rows at the bottom of the
        filled silhouette narrower than ``TRUNK_WIDTH`` of its widest row."""
        filled = self.levels[0].sdf <= 0 if self.levels[0].n else self.ink
        width = filled.sum(axis=1)
        rows = np.flatnonzero(width)
        if rows.size == 0:
            return np.zeros((0, 2))
        narrow = width[rows] < TRUNK_WIDTH * width.max()
        k = int(np.argmin(narrow[::-1])) if not narrow.all() else rows.size
        trunk_rows = rows[rows.size - k :]
        cols = np.arange(filled.shape[1])
        centre = (filled[trunk_rows] * cols).sum(axis=1) / width[trunk_rows]
        return np.stack([trunk_rows, centre], axis=1)

    @cached_property
    def envelope(self) -> np.ndarray:
        """The sketch's envelope as framed (``refine.envelope``; not height-framed: where
        the tree stands in the frame counts)."""
        return prepared_envelope(self.image)

    @cached_property
    def inside_ink(self) -> float:
        """The share of the envelope's inside (less a band of the closing radius along
        its outline) that is ink: near 0 for a drawing of outlines only, more where
        branches, leaves or shading are drawn within the crown.  Lines wider than
        ``INSIDE_STROKE`` count as if drawn that wide: what is drawn inside is told by
        its lines' length, not by the pen; and the band is as much wider as such a line
        is, since the outline's own ink reaches that far in."""
        ink = self.image < _DARK
        width, widest = stroke_width(ink), INSIDE_STROKE * self.size
        depth = max(1, round(CLOSE_FRACTION * self.size)) + max(0, math.ceil(width - widest))
        inner = ndimage.binary_erosion(self.envelope, iterations=depth)
        n = int(np.count_nonzero(inner))
        if n == 0:
            return 0.0
        share = int(np.count_nonzero(inner & ink)) / n
        return share * min(1.0, widest / width)

    @property
    def stem(self) -> float:
        """The trunk's height as a fraction of the drawing's height (0 when blank)."""
        rows = np.flatnonzero(self.ink.any(axis=1))
        if rows.size == 0:
            return 0.0
        return len(self.trunk) / (rows[-1] - rows[0] + 1)

    def distance(self, other: ShapeTarget) -> float:
        return target_shape_distance(self, other)


def pyramid_distance(a: Any, b: Any, level_distance: Callable[[Any, Any], float]) -> float:
    """The mean over two prepared sketches' pyramid levels (``a.levels``, items with ``n``
    outline pixels) of ``level_distance``, which sees levels that both have an outline: a
    level blank in both scores 0, one blank in one only ``1 + OUTLINE_WEIGHT``."""
    if a.image.shape != b.image.shape:
        raise ValueError(f"sketch sizes differ: {a.image.shape} vs {b.image.shape}")
    terms = [
        level_distance(x, y) if x.n and y.n else (0.0 if x.n == y.n else 1.0 + OUTLINE_WEIGHT)
        for x, y in zip(a.levels, b.levels, strict=False)
    ]
    return float(np.mean(terms))


def _level_distance(a: _ShapeLevel, b: _ShapeLevel) -> float:
    side = a.sdf.shape[0]
    # a's outline seen from b (outside b > 0) and b's from a, with a's sign: an outline
    # drawn t pixels around the other gives t everywhere
    v = np.concatenate([b.sdf[a.outline], -a.sdf[b.outline]])
    c = float(np.clip(np.median(v), -OFFSET_LIMIT * side, OFFSET_LIMIT * side))
    chamfer = float(np.abs(v - c).mean()) / side
    ramp = max(2.0, side / 48)  # soft edge: the distance moves smoothly with the outline
    sa = np.clip(0.5 - (a.sdf + 0.5 * c) / ramp, 0.0, 1.0)
    sb = np.clip(0.5 - (b.sdf - 0.5 * c) / ramp, 0.0, 1.0)
    union = float(np.maximum(sa, sb).sum())
    iou = float(np.minimum(sa, sb).sum()) / union if union > 0 else 1.0
    return (1.0 - iou) + OUTLINE_WEIGHT * chamfer + OFFSET_WEIGHT * abs(c) / side


def target_shape_distance(a: ShapeTarget, b: ShapeTarget) -> float:
    if (a.embedding is None) != (b.embedding is None):
        raise ValueError("one sketch has a learned embedding and the other has none")
    d = pyramid_distance(a, b, _level_distance)
    if a.embedding is not None and b.embedding is not None:
        d += EMBED_WEIGHT * embedding_distance(a.embedding, b.embedding)
    return d


def prepared_envelope(image: np.ndarray) -> np.ndarray:
    """The envelope (``refine.envelope``) of a prepared sketch (float 0..1, paper white,
    as ``refine.prepare.prepare_sketch`` gives it): ``ShapeTarget.envelope`` without the
    shape features built first."""
    return envelope_of_ink(image < _DARK)


def outline_gap(a: ShapeTarget, b: ShapeTarget) -> float:
    """One minus the overlap of two framed sketches' envelopes (``refine.envelope``): how
    far one's outline row by row, and where it stands in the frame, is from the other's.
    The search adds it to the shape distance (``refine.objective.search_distance``); the
    shape distance itself stays blind to it, since an envelope moves with line width and
    drawing style where the shape distance must not."""
    if a.image.shape != b.image.shape:
        raise ValueError(f"sketch sizes differ: {a.image.shape} vs {b.image.shape}")
    return 1.0 - mask_iou(a.envelope, b.envelope)


def embedding_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Euclidean distance of two embeddings (``refine.embed``: in shape-distance units)."""
    return float(np.linalg.norm(np.asarray(a, np.float64) - np.asarray(b, np.float64)))


def shape_distance(
    a: Any, b: Any, size: int = 128, scales: int = 3, embedder: Embedder | None = None
) -> float:
    """Style-blind distance between two sketch images (any size; both resized to ``size``),
    with the learned embedding's term when ``embedder`` is given."""
    return target_shape_distance(
        ShapeTarget.from_image(a, size, scales, embedder),
        ShapeTarget.from_image(b, size, scales, embedder),
    )


def line_distance(drawing: ShapeTarget, tree: ShapeTarget) -> float:
    """How far ``drawing`` is from being a drawing of ``tree`` (both prepared at one size):
    the mean distance of the drawing's ink outside the tree's silhouette beyond the
    ``OFFSET_LIMIT`` allowance, plus the mean distance of the tree's trunk centre line
    outside the drawing's filled shape, both as fractions of the side, plus ``STEM_WEIGHT``
    times the drawing's missing stem, ``max(0, MIN_STEM - drawing.stem)`` (see the module
    text)."""
    if drawing.image.shape != tree.image.shape:
        raise ValueError(f"sketch sizes differ: {drawing.image.shape} vs {tree.image.shape}")
    side = drawing.size
    if not drawing.ink.any() or tree.levels[0].n == 0:
        return 1.0
    outside = tree.levels[0].sdf[drawing.ink] - OFFSET_LIMIT * side
    stray = float(np.maximum(outside, 0.0).mean()) / side
    stemless = STEM_WEIGHT * max(0.0, MIN_STEM - drawing.stem)
    pts = tree.trunk
    if len(pts) == 0:
        return stray + stemless
    r = pts[:, 0].astype(int)
    c = np.clip(np.round(pts[:, 1]).astype(int), 0, side - 1)
    # from the drawing's filled shape, not its lines: a trunk drawn as two lines has
    # its centre line between them
    missing = float(np.maximum(drawing.levels[0].sdf[r, c], 0.0).mean()) / side
    return stray + missing + stemless
