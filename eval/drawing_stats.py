"""What a drawing of a tree looks like, in numbers: for comparing people's drawings with the
doodles made by code (:mod:`eval.doodles`).

Two kinds of measure:

- :func:`stroke_stats`, from the strokes (a list of ``(n, 2)`` point arrays in page pixels,
  y down): how many strokes, how many of them closed, how shaky the points are;
- :func:`image_stats`, from a drawing's image (uint8, 255 paper): how much ink, where the
  drawing sits and how big it is on the page, and its crown and trunk read from the ink's
  row-width profile (the crown is the wide top part, the trunk the narrow bottom part), with
  a ground line under it or not.

People's strokes (``shared/people_doodles/strokes``, a canvas of :data:`PEOPLE_CANVAS` px)
are read with :func:`read_strokes` and drawn on a :data:`eval.doodles.SIZE` page with
:func:`rasterise`, placed where the person put them.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

__all__ = [
    "PEOPLE_CANVAS",
    "image_stats",
    "rasterise",
    "read_strokes",
    "stroke_stats",
    "summarise",
]

#: The side of the canvas people drew the ``strokes/`` drawings on (the web page's square
#: sketch pad; a few points stray past it and are clipped when drawn).
PEOPLE_CANVAS = 400

#: Going down from its widest row, the crown ends where a row spans less than this
#: fraction of the widest (the trunk below it may flare out again at its base).
_CROWN_ROW = 0.5


def read_strokes(path: str | Path) -> list[dict]:
    """The drawings of one ``strokes/*.ndjson`` file: ``author``, ``session`` and
    ``strokes`` (a list of ``(n, 2)`` float arrays; strokes of no point are dropped)."""
    out = []
    with open(path, encoding="utf-8") as f:
        for raw in f:
            if not raw.strip():
                continue
            row = json.loads(raw)
            strokes = [np.asarray(s, dtype=float).reshape(-1, 2) for s in row["strokes"]]
            row["strokes"] = [s for s in strokes if len(s)]
            out.append(row)
    return out


def rasterise(
    strokes: Sequence[np.ndarray], canvas: float = PEOPLE_CANVAS, size: int = 256, width: int = 3
) -> np.ndarray:
    """The strokes drawn black on a white ``size`` page, the ``canvas`` scaled onto it (so
    the drawing keeps its place and size on the page): uint8, 255 paper."""
    im = Image.new("L", (size, size), 255)
    d = ImageDraw.Draw(im)
    scale = size / canvas
    for st in strokes:
        pts = np.clip(np.asarray(st, dtype=float) * scale, 0, size - 1)
        xy = [tuple(p) for p in pts]
        if len(xy) == 1:  # a dot
            x, y = xy[0]
            d.ellipse((x - width / 2, y - width / 2, x + width / 2, y + width / 2), fill=0)
        else:
            d.line(xy, fill=0, width=width, joint="curve")
    return np.asarray(im, dtype=np.uint8)


def _length(st: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(st, axis=0), axis=1).sum()) if len(st) > 1 else 0.0


def _resample(st: np.ndarray, step: float) -> np.ndarray:
    seg = np.linalg.norm(np.diff(st, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    t = np.linspace(0.0, s[-1], max(2, int(s[-1] / step) + 1))
    return np.stack([np.interp(t, s, st[:, 0]), np.interp(t, s, st[:, 1])], axis=1)


def _is_closed(st: np.ndarray) -> bool:
    """A stroke that comes back to where it began: its ends closer than a tenth of its
    length (and it goes somewhere: a dot or a tick is neither open nor closed)."""
    length = _length(st)
    return length > 20 and float(np.linalg.norm(st[0] - st[-1])) < 0.1 * length


def _jitter(st: np.ndarray, step: float) -> float:
    """How far the points stray from the stroke smoothed over five ``step``-spaced points:
    the hand's shake, in pixels."""
    pts = _resample(st, step)
    if len(pts) < 7:
        return float("nan")
    k = np.ones(5) / 5
    smooth = np.stack([np.convolve(pts[:, i], k, mode="valid") for i in range(2)], axis=1)
    return float(np.linalg.norm(pts[2:-2] - smooth, axis=1).mean())


def stroke_stats(strokes: Sequence[np.ndarray]) -> dict[str, float]:
    """Measures of a drawing's strokes: ``strokes`` (how many), ``closed`` (the fraction of
    strokes longer than 20 px that come back to their start), ``jitter`` (the points' mean
    stray from the smoothed stroke, per 100 px of the drawing's longest side) and
    ``points_per_100px`` (how densely the hand sampled its path)."""
    strokes = [np.asarray(s, dtype=float) for s in strokes if len(s)]
    pts = np.concatenate(strokes)
    side = max(float(np.ptp(pts, axis=0).max()), 1.0)
    long = [s for s in strokes if _length(s) > 20]
    step = side / 50  # the same step relative to the drawing, whatever the canvas
    jit = [_jitter(s, step) for s in long]
    jit = [j for j in jit if np.isfinite(j)]
    total = sum(_length(s) for s in strokes)
    return {
        "strokes": float(len(strokes)),
        "closed": float(np.mean([_is_closed(s) for s in long])) if long else 0.0,
        "jitter": float(np.mean(jit)) / side * 100 if jit else 0.0,
        "points_per_100px": len(pts) / max(total, 1.0) * 100,
    }


def _ground(widths: np.ndarray, crown_w: float, side: int) -> int:
    """How many rows at the bottom of the ink box are a ground line: a thin band (at most
    6% of the box's height) that spans at least half the crown's width and twice the row
    just above it (spreading roots widen gradually, a ground line at once)."""
    band = max(3, int(0.06 * side))
    if len(widths) <= band + 1:
        return 0
    span = widths[-band:].max()
    above = widths[-band - 1]
    return band if span >= 0.5 * crown_w and span >= 2 * above else 0


def _row_widths(box: np.ndarray) -> np.ndarray:
    """The span of ink in each row of the box, first inked column to last (0 for none)."""
    first = np.argmax(box, axis=1)
    last = box.shape[1] - 1 - np.argmax(box[:, ::-1], axis=1)
    return np.where(box.any(axis=1), last - first + 1, 0).astype(float)


def image_stats(img: np.ndarray) -> dict[str, float]:
    """Measures of a drawing's image (uint8, 255 paper; ink is below 128): ``ink`` (its
    fraction of the page), ``size`` (the ink box's longest side over the page's), ``cx``,
    ``cy`` (the box's centre, 0-1 of the page), ``aspect`` (the box's height over width),
    ``ground`` (1 where a ground line runs under the tree), and from the row-width profile
    above any ground: ``crown_aspect`` (crown height over width), ``trunk_height`` (the
    trunk's share of the tree's height), ``trunk_width`` (the trunk's median width over the
    crown's width).  The crown runs from the top down past its widest row to where a row is
    less than half as wide; the trunk is everything below."""
    ink = np.asarray(img) < 128
    h, w = ink.shape
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if not rows.size:
        raise ValueError("the image has no ink")
    box = ink[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
    bh, bw = box.shape
    widths = _row_widths(box)
    # the crown's width first from the top half (a ground line may be the widest row)
    crown_w = float(widths[: max(1, bh // 2)].max())
    ground = _ground(widths, crown_w, bh)
    tree = widths[: bh - ground]
    widest = int(np.argmax(tree))
    crown_w = float(tree[widest])
    below = np.flatnonzero(tree[widest:] < _CROWN_ROW * crown_w)
    crown_end = widest + int(below[0]) if below.size else len(tree)
    top = int(np.flatnonzero(tree > 0)[0])
    trunk = tree[crown_end:]
    trunk = trunk[trunk > 0]
    return {
        "ink": float(ink.mean()),
        "size": max(bh, bw) / max(h, w),
        "cx": (cols[0] + cols[-1]) / 2 / w,
        "cy": (rows[0] + rows[-1]) / 2 / h,
        "aspect": bh / bw,
        "ground": float(ground > 0),
        "crown_aspect": (crown_end - top) / crown_w,
        "trunk_height": len(trunk) / max(len(tree), 1),
        "trunk_width": float(np.median(trunk)) / crown_w if trunk.size else 0.0,
    }


def summarise(rows: Iterable[dict[str, float]]) -> dict[str, tuple[float, float, float]]:
    """Per measure, its 25th, 50th and 75th percentile over the drawings."""
    rows = list(rows)
    return {
        k: tuple(float(v) for v in np.nanpercentile([r[k] for r in rows], [25, 50, 75]))
        for k in rows[0]
    }
