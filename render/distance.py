"""The Euclidean distance transform, compiled: each pixel's distance to the nearest
background pixel, exactly as ``scipy.ndimage.distance_transform_edt`` gives it.

scipy computes the whole feature transform (the nearest background pixel's indices) and
the distances from it; the refinement only needs the distances, of masks a few hundred
pixels wide, about a thousand times per drawing (the candidate's framing, its shape and
its envelope).  Felzenszwalb and Huttenlocher's two passes (a 1-D distance down each
column, then the lower envelope of parabolas along each row) give the same squared
distances, whole numbers held exactly in float64, and their square roots are the same
floats: the values are identical, at about a third of the time (RESULTS.md, "The same
searches, faster").
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["distance_to_background"]

_FAR = 1e300  # no background in this column (yet): farther than any real distance


def distance_to_background(mask: np.ndarray) -> np.ndarray:
    """float64, ``mask``'s shape: each nonzero pixel's Euclidean distance (in pixels) to
    the nearest zero pixel, 0 on the zeros; ``scipy.ndimage.distance_transform_edt(mask)``
    to the last bit.  A mask with no zero pixel (no distance is defined) gets scipy's own
    answer."""
    m = np.asarray(mask).astype(bool, copy=False)
    if m.ndim != 2 or m.all():
        from scipy import ndimage

        return ndimage.distance_transform_edt(m)
    return np.sqrt(_squared(np.ascontiguousarray(m)))


@numba.njit(cache=True)
def _squared(mask: np.ndarray) -> np.ndarray:
    """Squared distances of ``mask`` (2-D bool with a False pixel somewhere)."""
    h, w = mask.shape
    down = np.empty((h, w))
    for c in range(w):
        run = _FAR
        for r in range(h):
            run = 0.0 if not mask[r, c] else (run + 1.0 if run < _FAR else _FAR)
            down[r, c] = run
        run = _FAR
        for r in range(h - 1, -1, -1):
            run = 0.0 if not mask[r, c] else (run + 1.0 if run < _FAR else _FAR)
            down[r, c] = min(down[r, c], run)
    out = np.empty((h, w))
    f, v, z = np.empty(w), np.empty(w, np.int64), np.empty(w + 1)
    for r in range(h):
        for c in range(w):
            f[c] = down[r, c] * down[r, c] if down[r, c] < _FAR else _FAR
        _row(f, w, out[r], v, z)
    return out


@numba.njit(cache=True)
def _row(f: np.ndarray, n: int, d: np.ndarray, v: np.ndarray, z: np.ndarray) -> None:
    """``d[q] = min_p (q - p)^2 + f[p]``: the lower envelope of the parabolas rooted at
    the finite ``f[p]`` (``v`` their positions, ``z`` where each takes over)."""
    k = -1
    for q in range(n):
        if f[q] >= _FAR:
            continue
        s = -_FAR
        while k >= 0:
            p = v[k]
            s = ((f[q] + q * q) - (f[p] + p * p)) / (2.0 * q - 2.0 * p)
            if s > z[k]:
                break
            k -= 1
        k += 1
        v[k] = q
        z[k] = s if k > 0 else -_FAR
        z[k + 1] = _FAR
    if k < 0:  # a row no column reaches background from: cannot happen with a zero pixel
        d[:n] = _FAR
        return
    k = 0
    for q in range(n):
        while z[k + 1] < q:
            k += 1
        p = v[k]
        d[q] = (q - p) * (q - p) + f[p]
