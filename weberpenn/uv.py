"""UV helpers for export: closing the wrap-around seam of the bark coordinates.

Branch tubes share one ring of vertices all round, with u = k / sides; the faces
between the last side and the first would interpolate u from ~1 back to 0 and smear
the whole texture across one face.  :func:`close_seams` gives the first-side corners of
those faces their own vertex copies at u + 1, so a tiling texture runs on unbroken.
"""

from __future__ import annotations

import numpy as np

__all__ = ["close_seams"]


def close_seams(faces: np.ndarray, uv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(faces, source vertex index per output vertex, uv) with wrapped faces mended.

    A face whose corners' u spans more than half the period wraps around; its corners
    with u < 0.5 are pointed at duplicates of their vertex with u + 1.  Vertices are
    only ever appended: output vertex ``i`` is input vertex ``source[i]``.
    """
    faces = np.asarray(faces, dtype=np.int64)
    uv = np.asarray(uv, dtype=np.float64)
    n = len(uv)
    source = np.arange(n, dtype=np.int64)
    if len(faces) == 0:
        return faces.copy(), source, uv.copy()
    fu = uv[faces, 0]  # (F, 3)
    wraps = (fu.max(axis=1) - fu.min(axis=1)) > 0.5
    low = wraps[:, None] & (fu < 0.5)
    if not low.any():
        return faces.copy(), source, uv.copy()
    dup = np.unique(faces[low])
    out = faces.copy()
    out[low] = n + np.searchsorted(dup, faces[low])
    new_uv = uv[dup].copy()
    new_uv[:, 0] += 1.0
    return out, np.concatenate([source, dup]), np.vstack([uv, new_uv])
