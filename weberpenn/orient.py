"""Where a tree faces and which way is up when it leaves the generator.

The generator's world is Z-up (trunk base at the origin, metres).  glTF is Y-up and
Blender's default OBJ import expects the same (up +Y, forward -Z), so exports map
``(x, y, z) -> (x, z, -y)``: Blender maps it back and shows the tree standing on +Z.

A camera at yaw ``a`` (``render.camera``: yaw 0 looks along +Y with +X to the right, the
view Blender calls Front) sees the tree turned by ``-a`` about Z exactly as a yaw-0
camera sees it; :func:`face_view_matrix` gives that turn so the exported tree faces the
front view the way it was drawn.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Y_UP", "face_view_matrix", "to_export_frame"]

#: Z-up world -> Y-up (glTF / Blender's default OBJ axes): (x, y, z) -> (x, z, -y).
Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def face_view_matrix(yaw: float) -> np.ndarray:
    """3x3 turn about Z by ``-yaw`` degrees: the view seen at camera yaw ``yaw`` becomes
    the front view (camera yaw 0)."""
    yaw = float(yaw)
    if not np.isfinite(yaw):
        raise ValueError(f"yaw must be a finite number of degrees, got {yaw!r}")
    a = np.radians(-yaw)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def to_export_frame(vertices: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    """Z-up generator vertices (n, 3) -> Y-up export vertices, turned to face the view
    drawn at ``yaw`` degrees."""
    m = Y_UP @ face_view_matrix(yaw)
    v = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    # column by column rather than ``v @ m.T``: that product goes through BLAS, whose
    # threads spin on a busy machine (0.1-0.2 s for 150k vertices against 2 ms)
    out = np.empty_like(v)
    for i in range(3):
        out[:, i] = v[:, 0] * m[i, 0] + v[:, 1] * m[i, 1] + v[:, 2] * m[i, 2]
    return out
