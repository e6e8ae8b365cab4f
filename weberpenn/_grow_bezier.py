"""Blender Bezier handles and evaluation for :mod:`weberpenn.grow` (batched over splines).

Splines of one level live in a padded ``(N, R + 1, 3)`` array: spline ``i`` owns slots
``start[i] .. R``.  Handles follow Blender's rule for AUTO handles (mirrored neighbour at
the ends, tangent = sum of unit neighbour directions, legs of length |leg| / (2.5614 |t|),
each leg first clamped to 5x the other); the first point of every spline is VECTOR.
"""

from __future__ import annotations

import numpy as np


def handles(pts: np.ndarray, start: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Left and right handles, same shape as ``pts`` (slots before ``start`` are junk)."""
    n, s1, _ = pts.shape
    r = s1 - 1
    j = np.arange(s1)[None, :]
    first = j == start[:, None]
    last = j == r
    prev = np.empty_like(pts)
    nxt = np.empty_like(pts)
    prev[:, 1:] = pts[:, :-1]
    prev[:, 0] = pts[:, 0]
    nxt[:, :-1] = pts[:, 1:]
    nxt[:, -1] = pts[:, -1]
    mir_prev = 2.0 * pts - nxt
    mir_next = 2.0 * pts - prev
    prev = np.where(first[..., None], mir_prev, prev)
    nxt = np.where(last[..., None], mir_next, nxt)
    # a spline of a single segment mirrors both ways at its ends; handled above because
    # 'first' uses the real next point and 'last' the real previous one.
    da = pts - prev
    db = nxt - pts
    la = np.sqrt(np.einsum("nsk,nsk->ns", da, da))
    lb = np.sqrt(np.einsum("nsk,nsk->ns", db, db))
    la = np.where(la == 0.0, 1.0, la)
    lb = np.where(lb == 0.0, 1.0, lb)
    t = db / lb[..., None] + da / la[..., None]
    lt = np.sqrt(np.einsum("nsk,nsk->ns", t, t)) * 2.5614
    la = np.minimum(la, 5.0 * lb)
    lb = np.minimum(lb, 5.0 * la)
    ok = lt != 0.0
    lts = np.where(ok, lt, 1.0)
    hl = np.where(ok[..., None], pts - t * (la / lts)[..., None], pts)
    hr = np.where(ok[..., None], pts + t * (lb / lts)[..., None], pts)
    # VECTOR handles on the first point: one third towards the neighbours
    vl = pts - da / 3.0
    vr = pts + db / 3.0
    hl = np.where(first[..., None], vl, hl)
    hr = np.where(first[..., None], vr, hr)
    return hl, hr


def evaluate(
    pts: np.ndarray,
    hl: np.ndarray,
    hr: np.ndarray,
    spline: np.ndarray,
    slot: np.ndarray,
    t: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Position and (unnormalised) tangent on segment ``slot -> slot+1`` at parameter ``t``."""
    s1 = pts.shape[1]
    flat = spline * s1 + slot
    p1 = np.take(pts.reshape(-1, 3), flat, axis=0)
    h1 = np.take(hr.reshape(-1, 3), flat, axis=0)
    h2 = np.take(hl.reshape(-1, 3), flat + 1, axis=0)
    p2 = np.take(pts.reshape(-1, 3), flat + 1, axis=0)
    u = 1.0 - t
    b0, b1, b2, b3 = u * u * u, 3.0 * t * u * u, 3.0 * t * t * u, t * t * t
    pos = b0[:, None] * p1 + b1[:, None] * h1 + b2[:, None] * h2 + b3[:, None] * p2
    d0 = -3.0 * u * u
    d1 = -6.0 * t * u + 3.0 * u * u
    d2 = -3.0 * t * t + 6.0 * t * u
    d3 = 3.0 * t * t
    tan = d0[:, None] * p1 + d1[:, None] * h1 + d2[:, None] * h2 + d3[:, None] * p2
    return pos, tan
