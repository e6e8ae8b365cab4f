"""A sketch at the size a comparison works at (both distances start here)."""

from __future__ import annotations

from typing import Any

import numpy as np

from render.reader import SketchError, read_sketch

__all__ = ["prepare_sketch"]


def prepare_sketch(img: Any, size: int) -> np.ndarray:
    """A sketch as a (size, size) float32 image in 0..1 (1 = white); area-resized.

    A 2-D array (uint8 0..255 or float 0..1) is used as it is; anything else (colour,
    alpha, a path, bytes) goes through the one sketch reader, ``render.reader``.
    """
    a = np.asarray(img) if isinstance(img, np.ndarray) else None
    if a is None or a.ndim != 2 or a.dtype.kind not in "uif":
        a = read_sketch(img)
    if min(a.shape) < 8:
        raise SketchError(f"a sketch must be at least 8x8 pixels, got {a.shape}")
    scale = 255.0 if a.dtype == np.uint8 else 1.0
    f = np.asarray(a, dtype=np.float32) / scale
    if not np.all(np.isfinite(f)):
        raise SketchError("the sketch holds non-finite values")
    f = np.clip(f, 0.0, 1.0)
    if f.shape != (size, size):
        from PIL import Image

        im = Image.fromarray(np.ascontiguousarray(f), mode="F")
        f = np.asarray(im.resize((size, size), Image.Resampling.BOX), dtype=np.float32)
    return f
