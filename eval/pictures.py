"""Simple pictures that are not trees, made by code: noise, circles, ellipses, squares, a
house, a face, text, random strokes, a spiral, a grid, a star, a car-like outline, a
zigzag, rings.

:func:`non_trees` gives the 50 pictures the benchmarks score (``benchmarks/bench_drawings``,
``bench_species detector``), the same for the same seed; :func:`picture` one of a kind
(:data:`PICTURE_KINDS`) from its own seed, for fitting (``scripts/fit_tree_detector.py``
draws from seeds the benchmarks do not use).  Each is a ``(SIZE, SIZE)`` uint8 image, 255
paper, dark ink.  The doodles a person would make (``eval.doodles``) are the richer set;
these are the shapes a tree detector must not take for a crown.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = ["PICTURE_KINDS", "SIZE", "non_trees", "picture"]

SIZE = 256


def _canvas() -> tuple[Image.Image, ImageDraw.ImageDraw]:
    im = Image.new("L", (SIZE, SIZE), 255)
    return im, ImageDraw.Draw(im)


def _box(rng: np.random.Generator, lo: float = 0.3, hi: float = 0.8) -> tuple[float, ...]:
    w, h = rng.uniform(lo, hi, 2) * SIZE
    x0, y0 = rng.uniform(0, SIZE - w), rng.uniform(0, SIZE - h)
    return (x0, y0, x0 + w, y0 + h)


def noise(rng: np.random.Generator, density: float) -> np.ndarray:
    return np.where(rng.random((SIZE, SIZE)) < density, 0, 255).astype(np.uint8)


def circle(rng: np.random.Generator, filled: bool) -> np.ndarray:
    im, d = _canvas()
    r = rng.uniform(0.2, 0.45) * SIZE
    cx, cy = rng.uniform(r, SIZE - r, 2)
    d.ellipse((cx - r, cy - r, cx + r, cy + r), fill=0 if filled else None, outline=0, width=3)
    return np.asarray(im)


def ellipse(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    d.ellipse(_box(rng, 0.2, 0.9), outline=0, width=int(rng.integers(2, 6)))
    return np.asarray(im)


def square(rng: np.random.Generator, filled: bool) -> np.ndarray:
    im, d = _canvas()
    s = rng.uniform(0.3, 0.7) * SIZE
    x, y = rng.uniform(0, SIZE - s, 2)
    d.rectangle((x, y, x + s, y + s), fill=0 if filled else None, outline=0, width=3)
    return np.asarray(im)


def house(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    x0, x1 = rng.uniform(30, 70), rng.uniform(180, 226)
    y0, y1 = rng.uniform(100, 130), rng.uniform(210, 240)
    d.rectangle((x0, y0, x1, y1), outline=0, width=3)
    d.line([(x0 - 10, y0), ((x0 + x1) / 2, rng.uniform(20, 60)), (x1 + 10, y0)], fill=0, width=3)
    dx = (x1 - x0) / 5
    d.rectangle((x0 + 2 * dx, y1 - 60, x0 + 3 * dx, y1), outline=0, width=3)
    d.rectangle((x0 + 0.5 * dx, y0 + 15, x0 + 1.5 * dx, y0 + 45), outline=0, width=2)
    return np.asarray(im)


def face(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    c, r = SIZE / 2 + rng.uniform(-20, 20), rng.uniform(80, 115)
    d.ellipse((c - r, c - r, c + r, c + r), outline=0, width=3)
    for sx in (-1, 1):
        ex = c + sx * r * 0.4
        d.ellipse((ex - 10, c - r * 0.35 - 10, ex + 10, c - r * 0.35 + 10), fill=0)
    d.arc((c - r * 0.5, c - r * 0.2, c + r * 0.5, c + r * 0.6), 20, 160, fill=0, width=3)
    d.line([(c, c - 0.1 * r), (c - 8, c + 0.2 * r), (c, c + 0.2 * r)], fill=0, width=2)
    return np.asarray(im)


def text(rng: np.random.Generator) -> np.ndarray:
    small = Image.new("L", (128, 128), 255)
    d = ImageDraw.Draw(small)
    words = ["tree", "hello world", "TreeSketch", "lorem ipsum", "sketch me", "12345"]
    font = ImageFont.load_default()
    for k in range(int(rng.integers(2, 6))):
        d.text((rng.uniform(2, 40), 8 + 22 * k), str(rng.choice(words)), fill=0, font=font)
    return np.asarray(small.resize((SIZE, SIZE), Image.NEAREST))


def strokes(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    for _ in range(int(rng.integers(5, 25))):
        pts = np.cumsum(rng.normal(0, 20, (int(rng.integers(2, 8)), 2)), axis=0)
        pts += rng.uniform(40, SIZE - 40, 2)
        d.line([tuple(p) for p in pts], fill=0, width=int(rng.integers(1, 5)))
    return np.asarray(im)


def spiral(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    t = np.linspace(0, rng.uniform(4, 8) * math.pi, 400)
    r = t / t[-1] * rng.uniform(80, 120)
    c = SIZE / 2 + rng.uniform(-10, 10, 2)
    d.line(list(zip(c[0] + r * np.cos(t), c[1] + r * np.sin(t), strict=True)), fill=0, width=3)
    return np.asarray(im)


def grid(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    step = int(rng.integers(16, 48))
    for v in range(step // 2, SIZE, step):
        d.line([(v, 0), (v, SIZE)], fill=0, width=2)
        d.line([(0, v), (SIZE, v)], fill=0, width=2)
    return np.asarray(im)


def star(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    n, r0 = int(rng.integers(5, 9)), rng.uniform(80, 120)
    a = np.arange(2 * n) * math.pi / n + rng.uniform(0, math.pi)
    r = np.where(np.arange(2 * n) % 2 == 0, r0, r0 * 0.4)
    pts = list(zip(128 + r * np.cos(a), 128 + r * np.sin(a), strict=True))
    d.polygon(pts, outline=0, width=3)
    return np.asarray(im)


def car(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    y = rng.uniform(140, 180)
    body = [(20, y), (20, y - 40), (70, y - 45), (100, y - 85), (170, y - 85), (200, y - 45)]
    body += [(236, y - 35), (236, y), (20, y)]
    d.line(body, fill=0, width=3)
    for wx in (65, 190):
        d.ellipse((wx - 22, y - 22, wx + 22, y + 22), outline=0, width=4)
    return np.asarray(im)


def zigzag(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    n = int(rng.integers(4, 12))
    xs = np.linspace(20, SIZE - 20, n)
    ys = np.where(np.arange(n) % 2 == 0, 60.0, 200.0) + rng.normal(0, 10, n)
    d.line(list(zip(xs, ys, strict=True)), fill=0, width=3)
    return np.asarray(im)


def rings(rng: np.random.Generator) -> np.ndarray:
    im, d = _canvas()
    for r in range(20, int(rng.uniform(90, 125)), int(rng.integers(10, 25))):
        d.ellipse((128 - r, 128 - r, 128 + r, 128 + r), outline=0, width=2)
    return np.asarray(im)


def non_trees(seed: int = 0) -> list[tuple[str, np.ndarray]]:
    """The 50 non-tree pictures (name, (SIZE, SIZE) uint8), the same for the same seed."""
    rng = np.random.default_rng(seed)
    makers: list[tuple[str, Callable[[np.random.Generator], np.ndarray]]] = [
        *[(f"noise{d:g}", lambda g, d=d: noise(g, d)) for d in (0.01, 0.03, 0.1, 0.3, 0.5)],
        *[(f"circle{k}", lambda g, k=k: circle(g, k % 2 == 1)) for k in range(5)],
        *[(f"ellipse{k}", ellipse) for k in range(4)],
        *[(f"square{k}", lambda g, k=k: square(g, k % 2 == 1)) for k in range(4)],
        *[(f"house{k}", house) for k in range(3)],
        *[(f"face{k}", face) for k in range(3)],
        *[(f"text{k}", text) for k in range(4)],
        *[(f"strokes{k}", strokes) for k in range(5)],
        *[(f"spiral{k}", spiral) for k in range(3)],
        *[(f"grid{k}", grid) for k in range(3)],
        *[(f"star{k}", star) for k in range(3)],
        *[(f"car{k}", car) for k in range(3)],
        *[(f"zigzag{k}", zigzag) for k in range(3)],
        *[(f"rings{k}", rings) for k in range(2)],
    ]
    assert len(makers) == 50
    return [(name, make(rng)) for name, make in makers]


_KINDS: dict[str, Callable[[np.random.Generator], np.ndarray]] = {
    "noise": lambda g: noise(g, float(g.choice([0.03, 0.1, 0.3, 0.5]))),
    "circle": lambda g: circle(g, bool(g.integers(2))),
    "ellipse": ellipse,
    "square": lambda g: square(g, bool(g.integers(2))),
    "house": house,
    "face": face,
    "text": text,
    "strokes": strokes,
    "spiral": spiral,
    "grid": grid,
    "star": star,
    "car": car,
    "zigzag": zigzag,
    "rings": rings,
}
#: The kinds :func:`picture` draws.
PICTURE_KINDS = tuple(_KINDS)


def picture(kind: str, seed: int) -> np.ndarray:
    """One picture of ``kind`` (:data:`PICTURE_KINDS`) from its own seed."""
    if kind not in _KINDS:
        raise ValueError(f"unknown picture kind {kind!r}; one of {', '.join(PICTURE_KINDS)}")
    return _KINDS[kind](np.random.default_rng([seed, PICTURE_KINDS.index(kind)]))
