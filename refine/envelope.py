"""A picture's envelope: its outline as a person sees it, whatever is drawn inside.

The ink is closed with a disk (a trunk drawn as two lines, a broken crown outline become
one shape), then every row is filled between its leftmost and rightmost ink.  What is
left is the tree's outline up its height: the crown's width row by row, the crown base,
the trunk's width and height, where the tree stands.  ``eval.envelope`` measures the
overlap of two envelopes at 256 px (issue 48); the refinement's distance adds the same
overlap at its work size (``refine.shape``) and the start reads the drawing's width
profile from it (``refine.start``).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from render.distance import distance_to_background

__all__ = [
    "CLOSE_FRACTION",
    "close_disk",
    "envelope_of_ink",
    "mask_iou",
    "outlines_rgb",
    "row_fill",
]

CLOSE_FRACTION = 6 / 256  # of the picture's side: the disk the ink is closed with


def close_disk(ink: np.ndarray, radius: float) -> np.ndarray:
    """``ink`` (bool) closed with a disk of ``radius`` pixels (by distance transforms:
    linear time at any radius; padded so the page's edge does not cut the closing)."""
    if radius <= 0 or not ink.any():
        return ink.copy()
    pad = int(np.ceil(radius)) + 1
    fat = distance_to_background(~np.pad(ink, pad)) <= radius
    closed = distance_to_background(fat) > radius
    return closed[pad:-pad, pad:-pad] | ink


def row_fill(mask: np.ndarray) -> np.ndarray:
    """``mask`` with every row filled between its leftmost and rightmost set pixel."""
    cols = np.arange(mask.shape[1])
    has = mask.any(axis=1)
    left = np.where(has, np.argmax(mask, axis=1), mask.shape[1])
    right = np.where(has, mask.shape[1] - 1 - np.argmax(mask[:, ::-1], axis=1), -1)
    return (cols[None, :] >= left[:, None]) & (cols[None, :] <= right[:, None])


def envelope_of_ink(ink: np.ndarray, radius: float | None = None) -> np.ndarray:
    """The envelope of an ink mask: closed with a disk of ``radius`` px (default
    ``CLOSE_FRACTION`` of its height), rows filled."""
    r = CLOSE_FRACTION * ink.shape[0] if radius is None else radius
    return row_fill(close_disk(ink, r))


def mask_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two bool masks (1 when both are empty)."""
    union = int(np.count_nonzero(a | b))
    return 1.0 if union == 0 else int(np.count_nonzero(a & b)) / union


DRAWING_RED = (220, 30, 30)
TREE_BLUE = (30, 60, 220)


def outlines_rgb(drawing: np.ndarray, tree: np.ndarray, radius: float | None = None) -> np.ndarray:
    """The tree's sketch faded, with the drawing's envelope outline in red and the tree's
    in blue (RGB uint8): what a person checks the tree against.  Both sketches uint8 of
    one size, paper light; ``radius`` of the closing (default ``CLOSE_FRACTION``)."""
    a, b = np.asarray(drawing), np.asarray(tree)
    if a.shape != b.shape:
        raise ValueError(f"sketch sizes differ: {a.shape} vs {b.shape}")
    faded = 255 - (255 - b.astype(np.float32)) * 0.35
    rgb = np.repeat(faded[..., None], 3, axis=2).astype(np.uint8)
    width = max(1, round(a.shape[0] / 128))
    for ink, colour in ((a < 128, DRAWING_RED), (b < 128, TREE_BLUE)):
        env = envelope_of_ink(ink, radius)
        rgb[env & ~ndimage.binary_erosion(env, iterations=width, border_value=0)] = colour
    return rgb
