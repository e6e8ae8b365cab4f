"""Strokes as a person draws them: polylines in page pixels and the shapes they are made of.

The hand drawings of ``examples/hand`` (``scripts/make_hand_png.py``) and the code-made
doodles of :mod:`eval.doodles` are written with these, never with :mod:`render.styles`
(those derive from our renderer's trees; these are test inputs made outside it).  A stroke
is an ``(n, 2)`` float array, x right, y down.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["Stroke", "arc", "branches", "bumpy", "curve", "jag", "line", "wobble"]

Stroke = np.ndarray  # (n, 2) page pixels, x right, y down


def _resample(pts: Stroke, step: float) -> Stroke:
    """The stroke's points every ``step`` px along it (at least its two ends)."""
    pts = np.asarray(pts, dtype=float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.linspace(0.0, s[-1], max(2, int(s[-1] / step) + 1))
    return np.stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])], axis=1)


def wobble(pts: Stroke, rng: np.random.Generator, amp: float = 2.0, step: float = 6.0) -> Stroke:
    """The stroke resampled every ``step`` px with a smooth sideways wobble of ``amp`` px."""
    out = _resample(pts, step)
    n = len(out)
    k = np.ones(5) / 5
    noise = np.stack(
        [np.convolve(rng.normal(0, amp, n + 4), k, mode="valid") for _ in range(2)], axis=1
    )
    return out + noise[:n] * 1.5


def arc(cx: float, cy: float, rx: float, ry: float, a0: float, a1: float, n: int = 60) -> Stroke:
    """Ellipse arc from ``a0`` to ``a1`` degrees (0 = right, 90 = down)."""
    a = np.radians(np.linspace(a0, a1, n))
    return np.stack([cx + rx * np.cos(a), cy + ry * np.sin(a)], axis=1)


def bumpy(
    cx: float,
    cy: float,
    rx: float,
    ry: float,
    bumps: int,
    depth: float,
    a0: float = 0.0,
    a1: float = 360.0,
) -> Stroke:
    """A cloud outline: an ellipse with ``bumps`` scallops of relative ``depth``."""
    a = np.radians(np.linspace(a0, a1, bumps * 16))
    r = 1.0 + depth * np.abs(np.sin(a * bumps / 2))
    return np.stack([cx + rx * r * np.cos(a), cy + ry * r * np.sin(a)], axis=1)


def jag(pts: Stroke, rng: np.random.Generator, amp: float = 2.0, step: float = 8.0) -> Stroke:
    """The stroke resampled every ``step`` px with independent ``amp`` px jumps at each
    point: the jaggy, shaky line of a mouse (no smoothing, unlike :func:`wobble`)."""
    out = _resample(pts, step)
    return out + rng.normal(0.0, amp, out.shape)


def curve(
    p0: tuple[float, float], p1: tuple[float, float], p2: tuple[float, float], n: int = 30
) -> Stroke:
    """A quadratic Bezier from ``p0`` to ``p2`` pulled towards ``p1``: one swept stroke."""
    t = np.linspace(0.0, 1.0, n)[:, None]
    a, b, c = (np.asarray(p, dtype=float) for p in (p0, p1, p2))
    return (1 - t) ** 2 * a + 2 * (1 - t) * t * b + t**2 * c


def line(*pts: tuple[float, float]) -> Stroke:
    """A polyline through the given points."""
    return np.array(pts, dtype=float)


def branches(
    x: float, y: float, angle: float, length: float, depth: int, rng: np.random.Generator
) -> list[Stroke]:
    """A recursive branching (angle in degrees, 90 = up), one stroke per limb."""
    a = math.radians(angle)
    x2, y2 = x + length * math.cos(a), y - length * math.sin(a)
    out = [line((x, y), (x2, y2))]
    if depth > 0:
        for turn in (-1, 1):
            spread = turn * rng.uniform(20, 40)
            out += branches(x2, y2, angle + spread, length * rng.uniform(0.6, 0.8), depth - 1, rng)
    return out
