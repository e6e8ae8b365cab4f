"""Sapling's shape-ratio functions and automatic taper (vectorised)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def shape_ratio(
    shape: int,
    ratio: np.ndarray | float,
    custom: Sequence[float] = (0.5, 1.0, 0.3, 0.5),
    peak: float = 0.0,
    power_high: float = 0.0,
    power_low: float = 0.0,
) -> np.ndarray:
    """Shape ratio ``shape`` at ``ratio`` (1 = base of the parent, 0 = its top)."""
    r = np.asarray(ratio, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if shape == 0:
            v = 0.05 + 0.95 * r
        elif shape == 1:
            v = 0.2 + 0.8 * np.sin(np.pi * r)
        elif shape == 2:
            v = 0.2 + 0.8 * np.sin(0.5 * np.pi * r)
        elif shape == 3:
            v = np.ones_like(r)
        elif shape == 4:
            v = 0.5 + 0.5 * r
        elif shape == 5:
            v = np.where(r <= 0.7, 0.05 + 0.95 * r / 0.7, 0.05 + 0.95 * (1.0 - r) / 0.3)
        elif shape == 6:
            v = 1.0 - 0.8 * r
        elif shape == 7:
            v = np.where(r <= 0.7, 0.5 + 0.5 * r / 0.7, 0.5 + 0.5 * (1.0 - r) / 0.3)
        elif shape == 8:
            c0, c1, c2, c3 = (float(c) for c in custom)
            x = 1.0 - r
            hi = (x - c2) / (1.0 - c2) if c2 != 1.0 else np.zeros_like(x)
            hi = hi * hi * (c3 - c1) + c1
            lo = x / c2
            lo = (1.0 - (1.0 - lo) * (1.0 - lo)) * (c1 - c0) + c0
            v = np.where(x == 1.0, c3, np.where(x >= c2, hi, lo))
        elif shape == 9:
            up = np.where(
                (r < 1.0 - peak) & (r > 0.0), np.abs(r / (1.0 - peak)) ** power_high, np.nan
            )
            low = np.where(
                (r >= 1.0 - peak) & (r < 1.0), np.abs((1.0 - r) / peak) ** power_low, np.nan
            )
            v = np.where(np.isnan(up), np.where(np.isnan(low), 0.0, low), up)
        elif shape == 10:
            v = 0.5 + 0.5 * (1.0 - r)
        else:
            raise ValueError(f"unknown shape ratio function {shape}")
    return np.nan_to_num(np.asarray(v, dtype=np.float64), nan=0.0, posinf=0.0, neginf=0.0)


def find_taper(
    length: Sequence[float],
    taper: Sequence[float],
    shape: int,
    shape_s: int,
    levels: int,
    custom: Sequence[float],
) -> list[float]:
    """Sapling's automatic taper: each level's share of the remaining length chain."""
    scaled = []
    for i, ln in enumerate(length):
        if i == 0:
            shp = 1.0
        elif i == 1:
            shp = float(shape_ratio(shape, 0.0, custom))
        else:
            shp = float(shape_ratio(shape_s, 0.0))
        scaled.append(float(ln) * shp)
    prods = [float(np.prod(scaled[: i + 1])) for i in range(len(scaled))]
    out = []
    for i in range(len(prods)):
        rest = sum(prods[i:levels])
        out.append(prods[i] / rest if rest != 0.0 else 1.0)
    return [t * float(tp) for t, tp in zip(out, taper, strict=True)]
