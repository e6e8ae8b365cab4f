"""The reference for ``bench_distance.py``: the shape distance as it was before issue 12's
recalibration (``refine/shape.py`` at d857490), kept so both are measured in one run.  Its
fill and pyramid are the current module's (``filled_shape``, ``ink_pyramid``: unchanged
since); what differs is here: a blurred fill compared by soft IoU and a plain chamfer.

A sketch distance that does not care about drawing style: compare the tree's *shape*.

People draw the same tree many ways (the paper's blobs, a clean pen outline, a cloud, a
scribble, light broken pencil, a few felt-tip strokes: ``render.styles``).  What they share
is the shape: the crown's outline and the trunk below it.  So each sketch is reduced to

- its **filled silhouette**: ink closed over small gaps (broken pencil lines, a trunk drawn
  as two lines), holes filled, then blurred (a soft mask, so the distance changes smoothly
  as the tree changes);
- its **outline**: the boundary of the filled silhouette, compared by a symmetric chamfer
  distance (mean distance from each outline pixel of one sketch to the other's outline,
  via Euclidean distance transforms, as a fraction of the side);

at each level of an image pyramid (2x2 "any ink" pooling, so coarse levels also close
larger gaps), and ``shape_distance = mean over levels of (1 - soft IoU) + OUTLINE_WEIGHT *
chamfer``.  What is inside the crown (blobs, scribbles, branch strokes) is left out on
purpose: it is where drawing styles differ most.

:class:`ShapeTarget` holds one sketch's features for repeated comparison (the refinement
prepares the input once and each candidate once).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from refine.prepare import prepare_sketch
from refine.shape import OUTLINE_WEIGHT, filled_shape, ink_pyramid, pyramid_distance

__all__ = ["OUTLINE_WEIGHT", "ShapeTarget", "shape_distance"]

_DARK = 0.5


@dataclass(frozen=True)
class _ShapeLevel:
    soft: np.ndarray  # float32 0..1, blurred filled silhouette
    outline: np.ndarray  # bool
    dist: np.ndarray  # float32, distance to the nearest outline pixel
    n: int  # outline pixels


def _level(ink: np.ndarray) -> _ShapeLevel:
    side = ink.shape[0]
    filled, outline = filled_shape(ink)
    soft = ndimage.gaussian_filter(filled.astype(np.float32), sigma=max(0.5, side / 96))
    n = int(outline.sum())
    dist = (
        ndimage.distance_transform_edt(~outline).astype(np.float32)
        if n
        else np.zeros(ink.shape, np.float32)
    )
    return _ShapeLevel(soft, outline, dist, n)


@dataclass(frozen=True)
class ShapeTarget:
    """A sketch's shape features at every pyramid level (see the module text)."""

    image: np.ndarray  # float32 0..1 (1 = white), the prepared sketch
    levels: tuple[_ShapeLevel, ...]

    @classmethod
    def from_image(cls, img: Any, size: int = 128, scales: int = 3) -> ShapeTarget:
        f = prepare_sketch(img, size)
        return cls(f, tuple(_level(x) for x in ink_pyramid(f < _DARK, scales)))

    @property
    def size(self) -> int:
        return int(self.image.shape[0])

    def distance(self, other: ShapeTarget) -> float:
        return target_shape_distance(self, other)


def _level_distance(a: _ShapeLevel, b: _ShapeLevel) -> float:
    side = a.soft.shape[0]
    inter = float(np.minimum(a.soft, b.soft).sum())
    union = float(np.maximum(a.soft, b.soft).sum())
    iou = inter / union if union > 0 else 1.0
    chamfer = 0.5 * (float(b.dist[a.outline].mean()) + float(a.dist[b.outline].mean())) / side
    return (1.0 - iou) + OUTLINE_WEIGHT * chamfer


def target_shape_distance(a: ShapeTarget, b: ShapeTarget) -> float:
    return pyramid_distance(a, b, _level_distance)


def shape_distance(a: Any, b: Any, size: int = 128, scales: int = 3) -> float:
    """Style-blind distance between two sketch images (any size; both resized to ``size``)."""
    return target_shape_distance(
        ShapeTarget.from_image(a, size, scales), ShapeTarget.from_image(b, size, scales)
    )
