"""render: tree mesh -> silhouettes (mitsuba 3) -> the paper's edge chain -> sketch.

``from render import sketch, SketchRenderer, VIEWS, EdgeConfig``; mitsuba is imported only
when a renderer is built (see :mod:`render.backend`).  The dataset builder lives in
:mod:`render.dataset`.
"""

from .camera import VIEWS, Camera, Framing
from .edges import EdgeConfig
from .reader import SketchError, read_sketch
from .sketch import SketchRenderer, sketch

__all__ = [
    "VIEWS",
    "Camera",
    "EdgeConfig",
    "Framing",
    "SketchError",
    "SketchRenderer",
    "read_sketch",
    "sketch",
]
