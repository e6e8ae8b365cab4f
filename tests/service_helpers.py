"""Helpers for the service tests: a cheap estimator that spawned workers can import."""

from __future__ import annotations

import io
from typing import Any

import numpy as np

from weberpenn import TreeParams, species


def palm_estimator(img: Any) -> tuple[TreeParams, str]:
    """A fixed palm: the first estimate without a network (fast to grow and render)."""
    return species.sample("palm", 8), "palm"


def png(img: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG")
    return buf.getvalue()


def palm_sketch_png(seed: int = 3) -> bytes:
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow

    m = build_mesh(grow(species.sample("palm", seed)), species="palm")
    return png(SketchRenderer(m).sketch(0, 256))
