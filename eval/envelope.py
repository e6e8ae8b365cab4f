"""Does the tree follow the drawing's outline?  The envelope overlap (issue 48).

A picture's **envelope** is its ink (darker than half white) seen at :data:`SIDE` pixels,
closed with a disk of radius :data:`CLOSE_RADIUS` pixels (``refine.envelope.CLOSE_FRACTION``
of the side) (a trunk drawn as two lines, a
broken crown outline become one shape), then every row filled between its leftmost and
rightmost ink (``refine.envelope``).  The **overlap** of two pictures is the intersection
over the union of their envelopes: 1 when the tree has the drawn outline (its crown's
width profile, its crown base, its trunk's width and height, where it stands), 0 when
they share nothing.

Both pictures are compared as they are framed: ``Result.input_sketch`` is the drawing
framed on its tree (``render.reader.normalise_drawing``) and ``Result.sketch_after`` the
tree's sketch framed by the same rule (``treesketch.steps.as_drawn``), the frame the
refinement compares them in; a tree whose proportions differ from the drawn ones (a tall
crown for a flat one, a long trunk for a short one) overlaps little.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from PIL import Image

from refine.envelope import CLOSE_FRACTION, envelope_of_ink, mask_iou

__all__ = ["CLOSE_RADIUS", "SIDE", "envelope", "envelope_overlap"]

SIDE = 256  # pixels: the side the envelope is measured at
CLOSE_RADIUS = CLOSE_FRACTION * SIDE  # pixels at SIDE (6): the disk the ink is closed with
_DARK = 128  # of 255: a darker pixel is ink


def _ink_at_side(img: Any) -> np.ndarray:
    """``img`` (2-D, uint8 0..255 or float 0..1, paper light) as a (SIDE, SIDE) ink mask."""
    a = np.asarray(img)
    if a.ndim != 2:
        raise ValueError(f"a picture must be 2-D (grey), got shape {a.shape}")
    grey = a.astype(np.float32) * (255.0 if a.dtype.kind == "f" else 1.0)
    if grey.shape != (SIDE, SIDE):
        im = Image.fromarray(np.ascontiguousarray(grey), mode="F")
        grey = np.asarray(im.resize((SIDE, SIDE), Image.Resampling.BOX), dtype=np.float32)
    return grey < _DARK


def envelope(img: Any) -> np.ndarray:
    """The picture's envelope: a (SIDE, SIDE) bool mask (see the module text)."""
    return envelope_of_ink(_ink_at_side(img), CLOSE_RADIUS)


def envelope_overlap(a: Any, b: Any) -> float:
    """The envelope overlap of two pictures (see the module text), in 0..1."""
    return mask_iou(envelope(a), envelope(b))
