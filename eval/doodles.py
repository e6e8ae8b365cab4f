"""Doodles made by code, the way people draw on a phone, with a mouse or a pen: test inputs
made outside the training styles.

- :func:`nontree_doodle` (``kind`` of :data:`NONTREE_KINDS`: houses, cars, faces, animals,
  cups, words, a sun, a flower, a bicycle, a chair...) for the "is this a tree?" calibration;
- :func:`tree_doodle` (``species`` of :data:`TREE_SPECIES`, the project's eleven) for held-out
  tree doodles with the species a person would name (:func:`tree_doodle_strokes`: the same
  drawing's strokes in page pixels);
- :func:`palm_doodle` (``form`` of :data:`PALM_FORMS`) for palms as people draw them: a
  curved or straight trunk, often ringed, and 3-8 fronds, each a closed pointed leaf, a
  drooping arc, a jagged leaf or a spike of a star burst.  There are no palms among
  people's drawings (``shared/people_doodles``), so these forms are all there is.

``tree_doodle`` mixes in varieties besides each species' own drawer, chosen per seed on a
stream of their own (a seed that keeps the species' own drawer keeps its bytes): half the
palms are drawn in the forms of ``palm_doodle``; about 40% of oaks, maples and cherries as
people draw "a tree" (measured on their drawings with :mod:`eval.drawing_stats`: a crown of
big loops often left open where a thick, short, flaring trunk comes in, sometimes roots, a
ground line, a hill, grass, a sun or a cloud beside it, few and shaky strokes, near the
middle of the page or now and then small in a corner).

Seeds: the benchmarks score seeds below 1000; the fitting scripts draw from 1000 up.

Each returns a ``(256, 256)`` uint8 image, 255 paper, dark ink.  Each drawing is written as
strokes (:mod:`eval.strokes`), never from :mod:`render.styles` (``render.styles.doodle``
derives from our renderer's trees; these do not, so a network trained on that style is
tested on drawings it never saw the like of).  Every drawing varies with its seed: its
proportions and optional parts, then the hand (pen, marker, phone finger or mouse: line width
2 to 6 px, 6 to 9 px for a finger, wobble or mouse jags, antialiased or not, ink from
black to pencil grey), its size, position and a small tilt.  Same ``(kind, seed)``, same
bytes.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw

from .strokes import Stroke, arc, bumpy, curve, jag, line, wobble

__all__ = [
    "NONTREE_KINDS",
    "PALM_FORMS",
    "SIZE",
    "TREE_SPECIES",
    "nontree_doodle",
    "palm_doodle",
    "tree_doodle",
    "tree_doodle_strokes",
]

#: The side of every doodle, in pixels.
SIZE = 256

Strokes = list[Stroke]
Drawer = Callable[[np.random.Generator], Strokes]  # one kind of doodle, seeded


# --------------------------------------------------------------------- shape helpers


def _circle(cx: float, cy: float, r: float, n: int = 40) -> Stroke:
    return arc(cx, cy, r, r, 0, 360, n)


def _closed(*pts: tuple[float, float]) -> Stroke:
    return line(*pts, pts[0])


def _few_segments(pts: Stroke, k: int) -> Stroke:
    """The stroke redrawn as ``k`` straight segments (a quick polyline doodle)."""
    idx = np.linspace(0, len(pts) - 1, k + 1).round().astype(int)
    return pts[idx]


def _u(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(rng.uniform(lo, hi))


def _chance(rng: np.random.Generator, p: float) -> bool:
    return bool(rng.random() < p)


# --------------------------------------------------------------------- things, not trees
# each: rng -> strokes in any units, x right, y down (the drawing is fitted to the page)


def _house(rng: np.random.Generator) -> Strokes:
    w, h = _u(rng, 80, 130), _u(rng, 60, 95)
    roof = _u(rng, 35, 70)
    s = [_closed((0, 0), (w, 0), (w, h), (0, h))]
    over = _u(rng, 0, 12)
    if _chance(rng, 0.7):
        s.append(line((-over, 0), (w / 2, -roof), (w + over, 0)))
    else:  # a flat-topped roof
        s.append(line((-over, 0), (w * 0.2, -roof), (w * 0.8, -roof), (w + over, 0)))
    dw, dh = w * _u(rng, 0.16, 0.24), h * _u(rng, 0.4, 0.6)
    dx = _u(rng, 0.15, 0.85 - dw / w) * w
    s.append(line((dx, h), (dx, h - dh), (dx + dw, h - dh), (dx + dw, h)))
    for _ in range(int(rng.integers(1, 3))):
        wx, wy, ws = _u(rng, 0.08, 0.7) * w, _u(rng, 0.12, 0.35) * h, w * _u(rng, 0.14, 0.2)
        s.append(_closed((wx, wy), (wx + ws, wy), (wx + ws, wy + ws), (wx, wy + ws)))
        if _chance(rng, 0.6):
            s += [line((wx + ws / 2, wy), (wx + ws / 2, wy + ws))]
            s += [line((wx, wy + ws / 2), (wx + ws, wy + ws / 2))]
    if _chance(rng, 0.5):
        cx = w * _u(rng, 0.65, 0.8)
        s.append(line((cx, -roof * 0.45), (cx, -roof * 0.85), (cx + 12, -roof * 0.85),
                      (cx + 12, -roof * 0.3)))  # fmt: skip
    return s


def _car(rng: np.random.Generator) -> Strokes:
    w, h = _u(rng, 150, 200), _u(rng, 28, 40)
    cab_h, r = _u(rng, 25, 40), _u(rng, 13, 19)
    c0, c1 = w * _u(rng, 0.15, 0.3), w * _u(rng, 0.65, 0.8)
    body = line((0, 0), (0, -h), (c0, -h), (c0 + 15, -h - cab_h), (c1 - 10, -h - cab_h),
                (c1 + 10, -h), (w, -h + 5), (w, 0))  # fmt: skip
    wheels = [_circle(w * 0.22, 0, r), _circle(w * 0.78, 0, r)]
    s = [body, line((0, 0), (w * 0.22 - r, 0)), line((w * 0.22 + r, 0), (w * 0.78 - r, 0))]
    s += [line((w * 0.78 + r, 0), (w, 0)), *wheels]
    if _chance(rng, 0.6):  # the windows
        s.append(line(((c0 + c1) / 2, -h), ((c0 + c1) / 2, -h - cab_h)))
    if _chance(rng, 0.4):
        s += [_circle(w * 0.22, 0, r * 0.35, 14), _circle(w * 0.78, 0, r * 0.35, 14)]
    return s


def _face(rng: np.random.Generator) -> Strokes:
    rx, ry = _u(rng, 55, 70), _u(rng, 60, 80)
    s = [arc(0, 0, rx, ry, 0, 360, 50)]
    ey, ex, er = -ry * 0.25, rx * _u(rng, 0.3, 0.45), _u(rng, 4, 9)
    s += [_circle(-ex, ey, er, 12), _circle(ex, ey, er, 12)]
    smile = _u(rng, -0.2, 1.0)
    s.append(curve((-rx * 0.4, ry * 0.35), (0, ry * (0.35 + 0.4 * smile)), (rx * 0.4, ry * 0.35)))
    if _chance(rng, 0.5):
        s.append(line((0, -ry * 0.1), (-6, ry * 0.12), (3, ry * 0.14)))
    if _chance(rng, 0.5):  # hair
        for k in range(int(rng.integers(3, 9))):
            a = math.radians(-140 + k * 100 / 8 + _u(rng, -5, 5))
            x, y = rx * math.cos(a), ry * math.sin(a)
            s.append(line((x, y), (x * 1.25, y * 1.25 + _u(rng, -8, 0))))
    if _chance(rng, 0.4):  # ears
        s += [arc(-rx, 0, 10, 16, 90, 270, 14), arc(rx, 0, 10, 16, -90, 90, 14)]
    return s


def _cat(rng: np.random.Generator) -> Strokes:
    r = _u(rng, 40, 50)
    ear = _u(rng, 22, 35)
    s = [arc(0, 0, r * 1.1, r, 0, 360, 44)]
    s += [line((-r * 0.9, -r * 0.45), (-r * 0.75, -r - ear), (-r * 0.2, -r * 0.95))]
    s += [line((r * 0.9, -r * 0.45), (r * 0.75, -r - ear), (r * 0.2, -r * 0.95))]
    s += [_circle(-r * 0.38, -r * 0.15, 5, 10), _circle(r * 0.38, -r * 0.15, 5, 10)]
    s += [line((-5, r * 0.15), (5, r * 0.15), (0, r * 0.25), (-5, r * 0.15))]
    for side in (-1, 1):
        for dy in (-6, 4):
            s.append(line((side * r * 0.3, r * 0.25), (side * r * 1.4, r * 0.25 + dy * 1.5)))
    if _chance(rng, 0.5):  # sitting, with a body and a tail
        bw, bh = r * _u(rng, 1.1, 1.4), r * _u(rng, 1.2, 1.6)
        s.append(arc(0, r + bh * 0.9, bw, bh, -60, 240, 40))
        s.append(curve((bw, r + bh * 1.6), (bw * 2.2, r + bh), (bw * 1.6, r)))
    return s


def _fish(rng: np.random.Generator) -> Strokes:
    L, H = _u(rng, 90, 140), _u(rng, 35, 60)
    s = [arc(0, 0, L / 2, H / 2, 0, 360, 44)]
    t = _u(rng, 25, 45)
    s.append(_closed((-L / 2 + 4, 0), (-L / 2 - t, -t * 0.8), (-L / 2 - t, t * 0.8)))
    s.append(_circle(L * 0.28, -H * 0.1, _u(rng, 3, 6), 10))
    if _chance(rng, 0.5):
        s.append(curve((L * 0.15, -H / 2 + 3), (L * 0.02, H * 0.02), (L * 0.17, H / 2 - 3)))
    if _chance(rng, 0.5):  # bubbles
        for k in range(int(rng.integers(1, 4))):
            s.append(_circle(L * 0.6 + k * 8, -H * 0.5 - 14 * (k + 1), 4 + 2 * k, 12))
    return s


def _bird(rng: np.random.Generator) -> Strokes:
    if _chance(rng, 0.35):  # a few flying "m"s
        s = []
        for _ in range(int(rng.integers(2, 5))):
            x, y, w = _u(rng, 0, 150), _u(rng, 0, 90), _u(rng, 25, 45)
            s += [curve((x - w, y), (x - w / 2, y - w * 0.5), (x, y))]
            s += [curve((x, y), (x + w / 2, y - w * 0.5), (x + w, y))]
        return s
    r = _u(rng, 35, 50)
    s = [arc(0, 0, r * 1.3, r, 0, 360, 40), _circle(r * 1.2, -r * 0.9, r * 0.5, 24)]
    bx = r * 1.65
    s.append(line((bx, -r * 1.0), (bx + 20, -r * 0.85), (bx - 1, -r * 0.7)))
    s.append(_circle(r * 1.3, -r * 1.0, 3, 8))
    s.append(curve((-r * 0.6, -r * 0.1), (0, r * 0.5), (r * 0.6, -r * 0.05)))
    s.append(line((-r * 1.25, -r * 0.2), (-r * 2.0, -r * 0.6), (-r * 1.9, r * 0.1), (-r * 1.25, 0)))
    for x in (-8, 8):
        s.append(line((x, r), (x, r + 22), (x + 8, r + 26)))
    return s


def _cup(rng: np.random.Generator) -> Strokes:
    w, h = _u(rng, 60, 90), _u(rng, 70, 100)
    taper = _u(rng, 0, 10)
    s = [line((0, 0), (taper, h), (w - taper, h), (w, 0))]
    s.append(arc(w / 2, 0, w / 2, _u(rng, 4, 10), 0, 360, 30))
    s.append(arc(w - 2, h * 0.45, _u(rng, 18, 26), h * 0.22, -90, 90, 20))
    if _chance(rng, 0.5):  # steam
        for k in range(int(rng.integers(1, 4))):
            x = w * (0.3 + 0.2 * k)
            ys = np.linspace(-10, -45, 10)
            s.append(np.stack([x + 5 * np.sin(ys / 6), ys], 1))
    if _chance(rng, 0.4):  # a saucer
        s.append(arc(w / 2, h + 3, w * 0.85, 9, 0, 180, 24))
    return s


# a single-stroke alphabet (unit cell 1 wide, 1.4 tall, y down): enough for a few words
_LETTERS: dict[str, list[list[tuple[float, float]]]] = {
    "A": [[(0, 1.4), (0.5, 0), (1, 1.4)], [(0.22, 0.8), (0.78, 0.8)]],
    "C": [],
    "E": [[(1, 0), (0, 0), (0, 1.4), (1, 1.4)], [(0, 0.7), (0.8, 0.7)]],
    "H": [[(0, 0), (0, 1.4)], [(1, 0), (1, 1.4)], [(0, 0.7), (1, 0.7)]],
    "I": [[(0.5, 0), (0.5, 1.4)]],
    "K": [[(0, 0), (0, 1.4)], [(1, 0), (0, 0.8)], [(0.3, 0.55), (1, 1.4)]],
    "L": [[(0, 0), (0, 1.4), (0.9, 1.4)]],
    "M": [[(0, 1.4), (0, 0), (0.5, 0.8), (1, 0), (1, 1.4)]],
    "N": [[(0, 1.4), (0, 0), (1, 1.4), (1, 0)]],
    "O": [],
    "S": [],
    "T": [[(0, 0), (1, 0)], [(0.5, 0), (0.5, 1.4)]],
    "V": [[(0, 0), (0.5, 1.4), (1, 0)]],
    "W": [[(0, 0), (0.25, 1.4), (0.5, 0.5), (0.75, 1.4), (1, 0)]],
    "X": [[(0, 0), (1, 1.4)], [(1, 0), (0, 1.4)]],
    "Y": [[(0, 0), (0.5, 0.7), (1, 0)], [(0.5, 0.7), (0.5, 1.4)]],
    "Z": [[(0, 0), (1, 0), (0, 1.4), (1, 1.4)]],
}
_WORDS = ("HELLO", "HI", "LOVE", "MAX", "WOW", "OK", "SALE", "ZOE", "TOM", "YES", "NO",
          "MILK", "COOL", "SAM", "LILA", "TAXI", "HOME", "ANNA")  # fmt: skip


def _letter(ch: str) -> Strokes:
    if ch == "O":
        return [arc(0.5, 0.7, 0.5, 0.7, 0, 360, 30)]
    if ch == "C":
        return [arc(0.55, 0.7, 0.5, 0.7, -50, -310, 24)]
    if ch == "S":
        top = arc(0.5, 0.36, 0.45, 0.36, -20, -270, 16)
        bottom = arc(0.5, 1.04, 0.45, 0.36, -90, 160, 16)
        return [np.concatenate([top, bottom])]
    return [line(*p) for p in _LETTERS[ch]]


def _word(rng: np.random.Generator) -> Strokes:
    word = _WORDS[int(rng.integers(len(_WORDS)))]
    size, gap, slant = _u(rng, 30, 45), _u(rng, 0.25, 0.5), _u(rng, -0.25, 0.1)
    s = []
    for i, ch in enumerate(word):
        for st in _letter(ch):
            pts = st * size
            pts[:, 0] += i * size * (1 + gap) + slant * (pts[:, 1] - 1.4 * size)
            pts[:, 1] += _u(rng, -3, 3)
            s.append(pts)
    if _chance(rng, 0.3):
        s.append(line((-5, 1.4 * size + 10), (len(word) * size * (1 + gap), 1.4 * size + 12)))
    return s


def _sun(rng: np.random.Generator) -> Strokes:
    r = _u(rng, 35, 50)
    s = [_circle(0, 0, r, 40)]
    n = int(rng.integers(7, 15))
    long = _u(rng, 18, 35)
    for k in range(n):
        a = 2 * math.pi * k / n
        s.append(line(((r + 7) * math.cos(a), (r + 7) * math.sin(a)),
                      ((r + 7 + long) * math.cos(a), (r + 7 + long) * math.sin(a))))  # fmt: skip
    if _chance(rng, 0.4):
        s += [_circle(-r * 0.35, -r * 0.2, 4, 8), _circle(r * 0.35, -r * 0.2, 4, 8)]
        s.append(arc(0, r * 0.1, r * 0.45, r * 0.35, 20, 160, 16))
    return s


def _flower(rng: np.random.Generator) -> Strokes:
    stem = _u(rng, 90, 150)
    r, n = _u(rng, 12, 18), int(rng.integers(5, 9))
    s = [_circle(0, 0, r, 20), curve((0, r), (_u(rng, -20, 20), stem / 2), (0, stem))]
    petal = _u(rng, 18, 28)
    for k in range(n):
        a = 2 * math.pi * k / n
        cx, cy = (r + petal * 0.8) * math.cos(a), (r + petal * 0.8) * math.sin(a)
        pts = arc(0, 0, petal, petal * 0.55, 0, 360, 20)
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        s.append(pts @ rot.T + (cx, cy))
    for side in (-1, 1)[: int(rng.integers(1, 3))]:
        y = stem * _u(rng, 0.5, 0.75)
        s.append(curve((0, y), (side * 30, y - 30), (side * 45, y - 15)))
        s.append(curve((0, y), (side * 30, y + 5), (side * 45, y - 15)))
    return s


def _bicycle(rng: np.random.Generator) -> Strokes:
    r = _u(rng, 30, 40)
    d = _u(rng, 2.4, 3.0) * r
    s = [_circle(0, 0, r), _circle(d, 0, r)]
    crank, seat, head = (d * 0.45, 0), (d * 0.3, -r * 1.2), (d * 0.85, -r * 1.2)
    s.append(line((0, 0), crank, seat, (0, 0)))
    s.append(line(crank, head, (d, 0)))
    s.append(line(seat, head))
    s.append(line((seat[0] - 12, seat[1] - 8), (seat[0] + 10, seat[1] - 8)))
    s.append(line(head, (head[0] - 4, head[1] - 18), (head[0] + 14, head[1] - 22)))
    return s


def _chair(rng: np.random.Generator) -> Strokes:
    w, seat, back = _u(rng, 55, 80), _u(rng, 45, 65), _u(rng, 50, 80)
    if _chance(rng, 0.5):  # from the side
        s = [line((0, -seat - back), (0, 0)), line((0, -seat), (w, -seat), (w, 0))]
        if _chance(rng, 0.5):
            s.append(line((0, -seat - back * 0.5), (w * 0.3, -seat - back * 0.5)))
        return s
    d = _u(rng, 10, 18)  # from the front, a little from above
    s = [_closed((0, -seat), (w, -seat), (w + d, -seat - d), (d, -seat - d))]
    s += [
        line((d, -seat - d), (d, -seat - d - back)),
        line((w + d, -seat - d), (w + d, -seat - d - back)),
    ]
    s += [line((d, -seat - d - back), (w + d, -seat - d - back))]
    s += [line((0, -seat), (0, 0)), line((w, -seat), (w, 0)), line((w + d, -seat - d), (w + d, -d))]
    return s


def _star(rng: np.random.Generator) -> Strokes:
    r, inner = _u(rng, 50, 70), _u(rng, 0.35, 0.5)
    rot = _u(rng, -0.2, 0.2)
    if _chance(rng, 0.5):  # one stroke, the way it is learnt at school
        a = [rot - math.pi / 2 + k * 4 * math.pi / 5 for k in range(6)]
        return [np.array([(r * math.cos(t), r * math.sin(t)) for t in a])]
    pts = []
    for k in range(11):
        t = rot - math.pi / 2 + k * math.pi / 5
        rr = r if k % 2 == 0 else r * inner
        pts.append((rr * math.cos(t), rr * math.sin(t)))
    return [np.array(pts)]


def _heart(rng: np.random.Generator) -> Strokes:
    w, h = _u(rng, 3.5, 4.5), _u(rng, 3.5, 4.5)
    t = np.linspace(0, 2 * math.pi, 60) + _u(rng, -0.3, 0.3)
    x = 16 * np.sin(t) ** 3
    y = -(13 * np.cos(t) - 5 * np.cos(2 * t) - 2 * np.cos(3 * t) - np.cos(4 * t))
    return [np.stack([w * x, h * y], 1)]


def _boat(rng: np.random.Generator) -> Strokes:
    w, d = _u(rng, 120, 170), _u(rng, 25, 35)
    mast = _u(rng, 70, 110)
    s = [_closed((0, 0), (w, 0), (w * 0.85, d), (w * 0.15, d))]
    mx = w * _u(rng, 0.4, 0.55)
    s.append(line((mx, 0), (mx, -mast)))
    s.append(_closed((mx + 4, -mast), (mx + 4, -8), (mx + w * 0.4, -8)))
    if _chance(rng, 0.5):
        s.append(_closed((mx - 4, -mast * 0.85), (mx - 4, -8), (mx - w * 0.3, -8)))
    if _chance(rng, 0.6):  # waves
        xs = np.linspace(-20, w + 20, 40)
        s.append(np.stack([xs, d + 8 + 5 * np.sin(xs / 9)], 1))
    return s


def _person(rng: np.random.Generator) -> Strokes:
    head, body, leg = _u(rng, 14, 20), _u(rng, 50, 70), _u(rng, 45, 60)
    s = [_circle(0, -body - leg - head, head, 24), line((0, -body - leg), (0, -leg))]
    spread = _u(rng, 15, 30)
    s += [line((-spread, 0), (0, -leg), (spread, 0))]
    ay, up = -leg - body * 0.7, _u(rng, -30, 25)
    s += [line((-40, ay + up), (0, ay), (40, ay + up * _u(rng, -1, 1)))]
    if _chance(rng, 0.4):
        s.append(arc(0, -body - leg - head, head * 0.5, head * 0.4, 20, 160, 10))
    return s


def _umbrella(rng: np.random.Generator) -> Strokes:
    r = _u(rng, 60, 80)
    top = arc(0, 0, r, r * _u(rng, 0.6, 0.8), 180, 360, 40)
    n = int(rng.integers(3, 6))
    hem = np.concatenate([arc(-r + (2 * k + 1) * r / n, 0, r / n, r / n * 0.5, 0, -180, 10)[::-1]
                          for k in range(n)])  # fmt: skip
    s = [np.concatenate([top, hem[::-1]])]
    handle = _u(rng, 70, 100)
    s.append(np.concatenate([line((0, 0), (0, handle)), arc(-10, handle, 10, 10, 0, 180, 10)]))
    return s


def _envelope(rng: np.random.Generator) -> Strokes:
    w, h = _u(rng, 110, 160), _u(rng, 65, 95)
    s = [
        _closed((0, 0), (w, 0), (w, h), (0, h)),
        line((0, 0), (w / 2, h * _u(rng, 0.45, 0.6)), (w, 0)),
    ]
    if _chance(rng, 0.4):
        s.append(_closed((w * 0.75, h * 0.65), (w * 0.9, h * 0.65), (w * 0.9, h * 0.88),
                         (w * 0.75, h * 0.88)))  # fmt: skip
    return s


def _by_name(*drawers: Drawer) -> dict[str, Drawer]:
    """Drawers by what they draw: their name without the leading underscore."""
    return {f.__name__.removeprefix("_"): f for f in drawers}


_NONTREES = _by_name(
    _house,
    _car,
    _face,
    _cat,
    _fish,
    _bird,
    _cup,
    _word,
    _sun,
    _flower,
    _bicycle,
    _chair,
    _star,
    _heart,
    _boat,
    _person,
    _umbrella,
    _envelope,
)

#: What :func:`nontree_doodle` draws.  ``flower`` and ``umbrella`` (a stem under a head) are
#: the hardest to tell from a tree.
NONTREE_KINDS: tuple[str, ...] = tuple(_NONTREES)


# --------------------------------------------------------------------- trees
# each: rng -> strokes, the trunk's base near (0, 0), up is -y


def _trunk(rng: np.random.Generator, height: float, half: float, lean: float = 0.0) -> Strokes:
    """Two lines (most people) or one (a quick doodle) from the ground up to ``-height``."""
    top = (lean, -height)
    if _chance(rng, 0.3):
        return [line((0, 0), top)]
    taper = _u(rng, 0.6, 1.0)
    return [
        line((-half, 0), (lean - half * taper, -height)),
        line((half, 0), (lean + half * taper, -height)),
    ]


def _outline(rng: np.random.Generator, pts: Stroke, open_gap: float = 0.3) -> Stroke:
    """A crown outline the way it is doodled: sometimes a few straight segments, sometimes
    not quite closed."""
    if _chance(rng, 0.35):
        pts = _few_segments(pts, int(rng.integers(7, 20)))
    if _chance(rng, open_gap):
        cut = int(len(pts) * _u(rng, 0.03, 0.1))
        pts = pts[cut:]
    return pts


def _crown_loop(
    rng: np.random.Generator, cx: float, cy: float, rx: float, ry: float, bumps: int
) -> Stroke:
    """A closed crown outline starting at the bottom: round (``bumps`` 0) or a cloud."""
    start = 90 + _u(rng, -20, 20)
    if bumps:
        return bumpy(cx, cy, rx, ry, bumps, _u(rng, 0.1, 0.3), start, start + 360)
    return arc(cx, cy, rx, ry, start, start + 360 + _u(rng, 0, 25), 60)


def _inner_branches(
    rng: np.random.Generator, top: float, reach_x: float, reach_y: float
) -> Strokes:
    """A Y or a few limbs from the trunk's top into the crown."""
    s = []
    for side in (-1, 1):
        if _chance(rng, 0.8):
            s.append(
                line(
                    (0, top),
                    (side * reach_x * _u(rng, 0.4, 0.8), top - reach_y * _u(rng, 0.4, 0.8)),
                )
            )
    if _chance(rng, 0.5):
        s.append(line((0, top), (_u(rng, -5, 5), top - reach_y * _u(rng, 0.5, 0.9))))
    return s


def _crown_inside(
    rng: np.random.Generator, branches: float, h: float, cy: float, rx: float, ry: float
) -> Strokes:
    """What is drawn inside a round crown (centre ``cy``, radii ``rx``, ``ry``) over a
    trunk ``h`` tall: branches with probability ``branches``, then the extras."""
    s = _inner_branches(rng, -h, rx, ry) if _chance(rng, branches) else []
    return s + _crown_extras(rng, cy, rx, ry)


def _crown_extras(rng: np.random.Generator, cy: float, rx: float, ry: float) -> Strokes:
    """What people add inside a round crown: a scribbled fill, or a few apples."""
    if _chance(rng, 0.2):  # scribbled in, back and forth
        t = np.linspace(0, 1, 160)
        ys = cy + ry * 0.85 * (2 * t - 1)
        reach = rx * 0.85 * np.sqrt(np.clip(1 - ((ys - cy) / (ry * 0.85)) ** 2, 0, 1))
        zig = np.sin(t * 2 * np.pi * int(rng.integers(6, 12)))
        return [np.stack([reach * zig, ys], 1)]
    if _chance(rng, 0.15):
        n = int(rng.integers(3, 8))
        return [
            _circle(rx * 0.6 * _u(rng, -1, 1), cy + ry * 0.6 * _u(rng, -1, 1), _u(rng, 4, 7), 12)
            for _ in range(n)
        ]
    return []


def _maple(rng: np.random.Generator) -> Strokes:
    rx, ry = _u(rng, 45, 60), _u(rng, 55, 75)
    h = ry * _u(rng, 0.6, 0.9)
    cy = -h - ry * 0.85
    s = _trunk(rng, h, _u(rng, 5, 9))
    bumps = int(rng.choice([0, 0, 8, 10, 12]))
    s.append(_outline(rng, _crown_loop(rng, 0, cy, rx, ry, bumps)))
    return s + _crown_inside(rng, 0.5, h, cy, rx, ry)


def _generic(rng: np.random.Generator) -> Strokes:
    """A tree, as most people draw one: a lollipop or a cloud on a stick (a round crown,
    about as tall as wide, on a thin trunk), which means a round-crowned broadleaf."""
    r = _u(rng, 45, 75)
    rx, ry = r * _u(rng, 0.9, 1.2), r
    # the stick: from a stub to longer than the crown is wide (a lollipop on a tall stick)
    h = r * _u(rng, 0.6, 2.2)
    s = _trunk(rng, h, _u(rng, 2.5, 7))
    cy = -h - ry * _u(rng, 0.8, 0.95)
    bumps = int(rng.choice([0, 0, 6, 8, 10]))
    s.append(_outline(rng, _crown_loop(rng, 0, cy, rx, ry, bumps)))
    return s + _crown_inside(rng, 0.35, h, cy, rx, ry)


def _oak(rng: np.random.Generator) -> Strokes:
    if _chance(rng, 0.35):
        return _generic(rng)
    rx, ry = _u(rng, 75, 100), _u(rng, 42, 58)
    h = ry * _u(rng, 0.55, 0.85)
    half = _u(rng, 9, 15)
    s = _trunk(rng, h, half)
    if _chance(rng, 0.4):  # flared roots
        s += [line((-half, 0), (-half - 12, 3)), line((half, 0), (half + 12, 3))]
    cy = -h - ry * 0.8
    if _chance(rng, 0.35):  # a stout trunk that forks into two or three limbs under the crown
        s += _limbs(rng, half, h, rx, ry)
    if _chance(rng, 0.25):  # the crown drawn as a chain of loops around its edge
        loops, r = int(rng.integers(9, 15)), _u(rng, 0.16, 0.24) * ry
        t = np.linspace(0, 2 * math.pi, loops * 24) + math.pi / 2
        xs = (rx - r) * np.cos(t) + r * np.cos(t * loops)
        ys = cy + (ry - r) * np.sin(t) + r * np.sin(t * loops)
        s.append(np.stack([xs, ys], 1))
    else:
        s.append(_outline(rng, _crown_loop(rng, 0, cy, rx, ry, int(rng.integers(6, 11)))))
    return s + _crown_inside(rng, 0.6, h, cy, rx, ry)


def _limbs(rng: np.random.Generator, half: float, h: float, rx: float, ry: float) -> Strokes:
    """Limbs from a trunk's top (half-width ``half``, ``h`` tall) up into a crown of radii
    ``rx``, ``ry``: two spreading, sometimes a third straight up."""
    s = [
        line((side * half, -h), (side * rx * _u(rng, 0.3, 0.6), -h - ry * _u(rng, 0.3, 0.7)))
        for side in (-1, 1)
    ]
    if _chance(rng, 0.6):
        s.append(line((0, -h), (_u(rng, -8, 8), -h - ry * _u(rng, 0.4, 0.8))))
    return s


def _cherry(rng: np.random.Generator) -> Strokes:
    rx, ry = _u(rng, 85, 105), _u(rng, 40, 55)
    h = ry * _u(rng, 0.9, 1.3)
    fork = h * _u(rng, 0.45, 0.65)
    half = _u(rng, 6, 10)
    s = [line((-half, 0), (-half, -fork)), line((half, 0), (half, -fork))]
    for side in (-1, 1):  # the trunk forks into limbs that spread under the crown
        s.append(line((side * half, -fork), (side * rx * _u(rng, 0.35, 0.6), -h - ry * 0.3)))
    if _chance(rng, 0.5):
        s.append(line((0, -fork), (_u(rng, -8, 8), -h - ry * 0.5)))
    cy = -h - ry * 0.6
    s.append(_outline(rng, _crown_loop(rng, 0, cy, rx, ry, int(rng.integers(8, 14))), 0.5))
    if _chance(rng, 0.6):  # blossoms
        for _ in range(int(rng.integers(4, 12))):
            a, rr = _u(rng, 0, 2 * math.pi), math.sqrt(_u(rng, 0, 0.7))
            s.append(_circle(rx * rr * math.cos(a), cy + ry * rr * math.sin(a), _u(rng, 3, 5), 8))
    return s


def _pine(rng: np.random.Generator) -> Strokes:
    h = _u(rng, 200, 260)
    s = _trunk(rng, h, _u(rng, 4, 7))
    w0, low = _u(rng, 60, 85), _u(rng, 0.3, 0.45)
    if _chance(rng, 0.6):  # flat layers of foliage along a straight trunk, smaller upwards
        tiers = int(rng.integers(3, 6))
        for k in range(tiers):
            f = k / max(1, tiers - 1)
            y = -h * (low + (0.95 - low) * f)
            w, th = w0 * (1 - 0.6 * f), _u(rng, 14, 24) * (1 - 0.3 * f)
            tier = bumpy(0, y, w, th, int(rng.integers(5, 9)), 0.2, 180, 540)
            s.append(_outline(rng, tier, 0.2))
    else:  # drooping limbs with tufts of needles, shorter upwards
        limbs = int(rng.integers(3, 6))
        for k in range(limbs):
            f = k / (limbs - 1)
            y, w = -h * (low + (0.95 - low) * f), w0 * (1 - 0.5 * f)
            for side in (-1, 1):
                s.append(curve((0, y), (side * w * 0.5, y - 6), (side * w, y + 6), 10))
                for x in (w * 0.45, w * 0.85):
                    s.append(line((side * x, y - 1), (side * (x + 3), y - 10)))
    return s


def _fir(rng: np.random.Generator) -> Strokes:
    h, w = _u(rng, 190, 250), _u(rng, 60, 85)
    stub = _u(rng, 15, 30)
    if _chance(rng, 0.6):  # a box of a trunk, or two lines
        s = [line((-8, 0), (-8, -stub), (8, -stub), (8, 0))]
    else:
        s = [line((-6, 0), (-6, -stub)), line((6, 0), (6, -stub))]
    mode = int(rng.integers(3))
    top = -stub - h
    if mode == 0:  # a zigzag outline: out to a tip, back in, down each side
        zigs = int(rng.integers(3, 6))
        left = [(0.0, top)]
        for k in range(1, zigs + 1):
            y = top + h * k / zigs
            left.append((-w * k / zigs, y))
            if k < zigs:
                left.append((-w * k / zigs * _u(rng, 0.45, 0.65), y - _u(rng, 4, 10)))
        right = [(-x, y) for x, y in reversed(left)]
        s.append(line(*left, *right))
    elif mode == 1:  # stacked triangles, each overlapping the one above
        n = int(rng.integers(2, 5))
        for k in range(n):
            t0, t1 = top + h * k / (n + 1), top + h * (k + 2) / (n + 1)
            half = w * (k + 2) / (n + 1)
            s.append(_closed((-half, t1), (0, t0), (half, t1)))
    else:  # one triangle with its limbs drawn in, a trunk line up the middle
        s.append(_closed((-w, -stub), (0, top), (w, -stub)))
        s.append(line((0, -stub), (0, top + 10)))
        for y in np.linspace(top + h * 0.2, -stub - 10, int(rng.integers(4, 8))):
            span = w * (y - top) / h * 0.8
            s += [line((0, y - 10), (-span, y)), line((0, y - 10), (span, y))]
    if _chance(rng, 0.25):  # baubles
        for _ in range(int(rng.integers(3, 9))):
            y = top + h * _u(rng, 0.3, 0.9)
            x = w * (y - top) / h * _u(rng, -0.6, 0.6)
            s.append(_circle(x, y, _u(rng, 3, 6), 10))
    if _chance(rng, 0.15):  # a star on top
        r = _u(rng, 8, 12)
        a = [-math.pi / 2 + k * 4 * math.pi / 5 for k in range(6)]
        s.append(np.array([(r * math.cos(t), top - r * 0.8 + r * math.sin(t)) for t in a]))
    return s


def _willow(rng: np.random.Generator) -> Strokes:
    h = _u(rng, 70, 110)
    rx, ry = _u(rng, 80, 105), _u(rng, 50, 70)
    cy = -h - ry * 0.3
    dome = _chance(rng, 0.5)
    # under a dome the trunk stops at the crown; a fountain of limbs fans out from its top
    s = _trunk(rng, h if dome else h + ry * 0.9, _u(rng, 6, 10))
    if dome:
        s.append(arc(0, cy, rx, ry, 180 + _u(rng, -10, 0), 360 + _u(rng, 0, 10), 40))
        roots = [(float(x), float(cy - ry * math.sqrt(max(0.0, 1 - (x / rx) ** 2))))
                 for x in np.linspace(-rx * 0.95, rx * 0.95, int(rng.integers(9, 16)))]  # fmt: skip
    else:  # limbs arching over like a fountain
        roots, top = [], -h - ry * 0.9
        for side in (-1, 1):
            for k in range(int(rng.integers(2, 4))):
                a = curve((0, top), (side * rx * (0.35 + 0.2 * k), top - ry * (0.45 - 0.15 * k)),
                          (side * rx * (0.85 + 0.1 * k), cy + ry * 0.2))  # fmt: skip
                s.append(a)
                roots += [tuple(a[i]) for i in (12, 20, 29)]
    for x, y in roots:  # strands hanging nearly to the ground
        drop = np.linspace(0, 1, 10)
        length = (0 - y) * _u(rng, 0.55, 0.95)
        sway = _u(rng, -6, 6)
        s.append(np.stack([x + sway * np.sin(drop * 4), y + length * drop], 1))
    return s


def _birch(rng: np.random.Generator) -> Strokes:
    h = _u(rng, 200, 260)
    half = _u(rng, 4, 7)
    bend = _u(rng, -15, 15)
    t = np.linspace(0, 1, 12)
    xs = bend * np.sin(t * 2.5)
    s = [np.stack([xs - half, -h * t], 1), np.stack([xs + half, -h * t], 1)]
    for y in np.linspace(-h * 0.1, -h * 0.8, int(rng.integers(4, 9))):
        x = float(np.interp(-y, h * t, xs))
        s.append(line((x - half, y), (x + _u(rng, -2, half * 0.6), y - _u(rng, 1, 4))))
    w = _u(rng, 45, 75)
    limbs = []
    for side in (-1, 1):  # thin limbs up and out from the upper trunk
        for _ in range(int(rng.integers(1, 3))):
            y = -h * _u(rng, 0.45, 0.8)
            end = (side * w * _u(rng, 0.5, 0.95), y - _u(rng, 25, 60))
            x0 = float(np.interp(-y, h * t, xs))
            limbs.append(end)
            s.append(line((x0, y), end))
    if _chance(rng, 0.5):  # light, broken clumps of leaves at the limbs' ends and the top
        for cx, cy in [*limbs, (xs[-1], -h)]:
            a0, rx = _u(rng, 0, 90), _u(rng, 18, 30)
            arc_deg = _u(rng, 200, 330)
            s.append(bumpy(cx, cy - 8, rx, rx * _u(rng, 0.6, 0.85), 5, 0.3, a0, a0 + arc_deg))
    else:  # a loose, lumpy, open outline around the upper half
        cy, ry = -h * 0.78, h * _u(rng, 0.2, 0.27)
        a0 = 90 + _u(rng, 25, 50)
        a1 = 90 + 360 - _u(rng, 25, 50)
        crown = bumpy(xs[-1] * 0.5, cy, w, ry, int(rng.integers(7, 12)), 0.15, a0, a1)
        s.append(_few_segments(crown, int(rng.integers(8, 16))) if _chance(rng, 0.4) else crown)
    return s


def _poplar(rng: np.random.Generator) -> Strokes:
    h, w = _u(rng, 200, 260), _u(rng, 28, 45)
    stub = _u(rng, 20, 40)
    s = _trunk(rng, stub, _u(rng, 3, 6))
    t = np.linspace(0, 1, 30)
    half = w * np.sin(np.pi * t ** _u(rng, 0.6, 0.9)) ** 0.8
    ys = -stub - h + h * t
    outline = np.concatenate([np.stack([-half, ys], 1), np.stack([half, ys], 1)[::-1]])
    s.append(_outline(rng, outline, 0.2))
    if _chance(rng, 0.5):
        for _ in range(int(rng.integers(2, 5))):
            x, y = _u(rng, -w * 0.4, w * 0.4), -stub - h * _u(rng, 0.2, 0.8)
            s.append(line((x, y), (x + 1, y - h * 0.15)))
    return s


def _winter(rng: np.random.Generator) -> Strokes:
    h = _u(rng, 70, 130)
    s = _trunk(rng, h, _u(rng, 4, 10))

    def fork(x: float, y: float, angle: float, length: float, depth: int) -> None:
        a = math.radians(angle)
        x2, y2 = x + length * math.cos(a), y - length * math.sin(a)
        s.append(line((x, y), (x2, y2)))
        if depth > 0:
            for _ in range(int(rng.integers(2, 4))):
                fork(x2, y2, angle + _u(rng, -45, 45), length * _u(rng, 0.55, 0.8), depth - 1)

    if _chance(rng, 0.5):  # the trunk fans out at its top into a few limbs
        for angle in np.linspace(50, 130, int(rng.integers(2, 4))):
            fork(0, -h, float(angle) + _u(rng, -10, 10), _u(rng, 50, 75), int(rng.integers(2, 4)))
        return s
    # a leader goes on up through the crown, limbs forking off it at a few heights
    leader = _u(rng, 0.8, 1.3) * h
    s.append(line((0, -h), (_u(rng, -6, 6), -h - leader)))
    for k in range(int(rng.integers(2, 5))):
        y = -h - leader * (0.1 + 0.75 * k / 4 + _u(rng, -0.05, 0.05))
        for side in (-1, 1):
            if _chance(rng, 0.85):
                angle = 90 - side * _u(rng, 25, 60)
                fork(0, y, angle, _u(rng, 30, 55) * (1 - 0.15 * k), int(rng.integers(1, 3)))
    return s


def _palm(rng: np.random.Generator) -> Strokes:
    h = _u(rng, 180, 240)
    bend = _u(rng, -50, 50)
    t = np.linspace(0, 1, 16)
    xs = bend * t**2
    ys = -h * t
    half = _u(rng, 4, 8)
    if _chance(rng, 0.7):
        s = [np.stack([xs - half, ys], 1), np.stack([xs + half * 0.7, ys], 1)]
        if _chance(rng, 0.4):  # the trunk's rings
            s += [
                line((x - half, y), (x + half * 0.7, y - 3))
                for x, y in zip(xs[1::2], ys[1::2], strict=True)
            ]
    else:
        s = [np.stack([xs, ys], 1)]
    tx, ty = bend, -h
    n = int(rng.integers(5, 9))
    style = int(rng.integers(3))
    for k in range(n):
        a = math.radians(180 * (k + 0.5) / n + _u(rng, -10, 10))
        reach = _u(rng, 70, 110)
        end = (tx - reach * math.cos(a), ty + _u(rng, 10, 60) * (1.2 - math.sin(a)))
        mid = (tx - reach * 0.5 * math.cos(a), ty - _u(rng, 20, 45) * math.sin(a) - 10)
        frond = curve((tx, ty), mid, end, 20)
        s.append(frond)
        if style == 1:  # leaflets hanging off each frond
            for p in frond[5::4]:
                s.append(line(tuple(p), (p[0] + 3 * np.sign(end[0] - tx), p[1] + 12)))
        elif style == 2:  # each frond a long leaf
            back = curve((tx, ty), (mid[0], mid[1] + 18), end, 20)
            s.append(back)
    if _chance(rng, 0.4):  # coconuts
        s += [_circle(tx + dx, ty + 8, 5, 10) for dx in (-7, 5)]
    return s


# --------------------------------------------------------------------- palms as people draw them
# a trunk (curved or straight, one line or two, often ringed) and 3-8 fronds from its top;
# each form draws every frond the same way.  Strokes as above: the base near (0, 0), up -y.


def _palm_trunk(rng: np.random.Generator) -> tuple[Strokes, tuple[float, float]]:
    """A palm's trunk and its top: curved (most) or straight, one line or two, tapering, and
    often ringed (short strokes across it, the mark people use to say "palm")."""
    h = _u(rng, 170, 250)
    bend = _u(rng, -70, 70) if _chance(rng, 0.7) else _u(rng, -8, 8)
    t = np.linspace(0, 1, 16)
    xs, ys = bend * t**2, -h * t
    half = _u(rng, 5, 11) * (1 - 0.45 * t)
    if _chance(rng, 0.25):  # one line, a quick doodle; rings as ticks across it
        s = [np.stack([xs, ys], 1)]
        if _chance(rng, 0.35):
            ticks = zip(xs[2:-1:2], ys[2:-1:2], strict=True)
            s += [line((x - 5, y + 1), (x + 5, y - 1)) for x, y in ticks]
        return s, (bend, -h)
    s = [np.stack([xs - half, ys], 1), np.stack([xs + half, ys], 1)]
    if _chance(rng, 0.6):  # rings: short arcs or chevrons from side to side
        every = int(rng.integers(1, 3))
        sag = _u(rng, -4, 4)
        for x, y, w in zip(xs[1:-1:every], ys[1:-1:every], half[1:-1:every], strict=True):
            s.append(line((x - w, y), (x, y + sag), (x + w, y)))
    return s, (bend, -h)


def _frond_axis(
    rng: np.random.Generator, top: tuple[float, float], k: int, n: int, burst: bool
) -> tuple[np.ndarray, np.ndarray, float]:
    """The ``k``-th of ``n`` fronds: where it ends, the point its midline bows through, and
    its length.  Fronds fan out sideways from the top, the outer ones drooping below it and
    none quite upright (people draw a palm's fronds hanging); a burst's spikes go all round
    but straight down."""
    spread = _u(rng, 280, 320) if burst else _u(rng, 200, 250)
    off = (k + 0.5) / n * 2 - 1  # -1 .. 1 across the fan
    if not burst:  # keep clear of upright: at least a third of the half fan off vertical
        off = math.copysign(0.35 + 0.65 * abs(off), off) if n > 1 else _u(rng, -1, 1)
    a = math.radians(90 + off * spread / 2 + _u(rng, -6, 6))
    reach = _u(rng, 55, 95) * (1.0 - 0.25 * math.sin(a))  # the upright ones a bit shorter
    if burst:
        reach *= _u(rng, 0.6, 0.85)
    tip = np.array(top) + reach * np.array([math.cos(a), -math.sin(a)])
    droop = 0.0 if burst else reach * _u(rng, 0.2, 0.45) * abs(math.cos(a))
    tip[1] += droop
    mid = (np.array(top) + tip) / 2 + np.array([0.0, -droop * 0.9 - _u(rng, 4, 12)])
    return tip, mid, reach


def _normals(pts: Stroke) -> np.ndarray:
    """Unit normals to one side of a stroke's direction, one per point."""
    d = np.gradient(pts, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    return np.stack([d[:, 1], -d[:, 0]], 1)


def _leaf(top: tuple[float, float], mid: np.ndarray, tip: np.ndarray, width: float) -> Stroke:
    """A closed pointed leaf: out along one side of the midline to the tip and back along
    the other, widest a third of the way."""
    axis = curve(top, tuple(mid), tuple(tip), 24)
    s = np.linspace(0, 1, 24)
    w = width * np.sin(np.pi * s**0.7)[:, None] * _normals(axis)
    return np.concatenate([axis + w, (axis - w)[::-1]])


def _jagged_leaf(
    rng: np.random.Generator,
    top: tuple[float, float],
    mid: np.ndarray,
    tip: np.ndarray,
    width: float,
) -> Stroke:
    """A leaf whose edges are zigzags (the leaflets drawn as teeth), closed at the tip."""
    teeth = int(rng.integers(3, 6))
    axis = curve(top, tuple(mid), tuple(tip), 2 * teeth + 1)
    s = np.linspace(0, 1, 2 * teeth + 1)
    saw = np.where(np.arange(2 * teeth + 1) % 2 == 1, 1.0, 0.2)
    w = (width * np.sin(np.pi * s**0.8) * saw)[:, None] * _normals(axis)
    return np.concatenate([axis + w, (axis - w)[::-1]])


def _palm_fronds(rng: np.random.Generator, form: str, top: tuple[float, float]) -> Strokes:
    # a burst of fewer than six spikes reads as a cross or a windmill, not a palm
    n = int(rng.integers(6, 9)) if form == "burst" else int(rng.integers(3, 9))
    width = _u(rng, 8, 16)
    rib = _chance(rng, 0.4)
    s: Strokes = []
    for k in range(n):
        tip, mid, reach = _frond_axis(rng, top, k, n, form == "burst")
        if form == "leaf":
            s.append(_leaf(top, mid, tip, width * reach / 80))
            if rib:  # the midrib drawn in
                s.append(curve(top, tuple(mid), tuple(tip), 16))
        elif form == "arc":
            s.append(curve(top, tuple(mid + (0, -reach * 0.1)), tuple(tip), 24))
        elif form == "jagged":
            s.append(_jagged_leaf(rng, top, mid, tip, width * 1.3 * reach / 80))
        else:  # burst: straight spikes, as narrow triangles or single lines
            if rib:
                s.append(line(top, tuple(tip)))
            else:
                d = tip - np.array(top)
                nrm = np.array([d[1], -d[0]]) / max(float(np.hypot(*d)), 1e-9) * width * 0.45
                s.append(line(tuple(np.array(top) + nrm), tuple(tip), tuple(np.array(top) - nrm)))
    return s


def _coconuts(rng: np.random.Generator, top: tuple[float, float]) -> Strokes:
    """Two to four small circles hanging just under the fronds."""
    r = _u(rng, 4, 7)
    n = int(rng.integers(2, 5))
    return [
        _circle(top[0] + (k - (n - 1) / 2) * r * 1.9, top[1] + r * _u(rng, 0.9, 1.6), r, 14)
        for k in range(n)
    ]


def _palm_ground(rng: np.random.Generator) -> Strokes:
    """Where the palm stands, when drawn: a ground line, or an island's mound over the sea."""
    w = _u(rng, 60, 110)
    if _chance(rng, 0.5):
        return [line((-w, _u(rng, 0, 3)), (w * _u(rng, 0.6, 1.1), _u(rng, -2, 4)))]
    mound = arc(0, 8, w, _u(rng, 12, 22), 180, 360, 30)
    s = [mound]
    if _chance(rng, 0.6):  # the sea it rises from
        xs = np.linspace(-w * 1.4, w * 1.4, 40)
        s.append(np.stack([xs, 10 + 3 * np.sin(xs / 7)], 1))
    return s


def _people_palm(rng: np.random.Generator, form: str) -> Strokes:
    """A palm the way people draw one, its fronds of one ``form`` of :data:`PALM_FORMS`."""
    s, top = _palm_trunk(rng)
    s += _palm_fronds(rng, form, top)
    if _chance(rng, 0.35):
        s += _coconuts(rng, top)
    if _chance(rng, 0.35):
        s += _palm_ground(rng)
    return s


def _bonsai(rng: np.random.Generator) -> Strokes:
    pw, ph = _u(rng, 80, 120), _u(rng, 22, 35)
    s = []
    if _chance(rng, 0.85):  # the pot
        s.append(_closed((-pw / 2, -ph), (pw / 2, -ph), (pw * 0.4, 0), (-pw * 0.4, 0)))
        base = -ph
    else:
        base = 0.0
    h = _u(rng, 70, 110)
    lean = _u(rng, 30, 60) * (1 if _chance(rng, 0.5) else -1)
    t = np.linspace(0, 1, 12)
    xs = lean * np.sin(t * math.pi * 0.8)
    ys = base - h * t
    half = _u(rng, 5, 9)
    s += [
        np.stack([xs - half * (1 - 0.5 * t), ys], 1),
        np.stack([xs + half * (1 - 0.5 * t), ys], 1),
    ]
    for k in range(int(rng.integers(2, 5))):  # flat pads of foliage
        f = _u(rng, 0.4, 1.0)
        x, y = float(np.interp(f, t, xs)), float(np.interp(f, t, ys))
        side = 1 if k % 2 else -1
        px = x + side * _u(rng, 15, 45) if k else x
        py = y - _u(rng, 5, 20)
        if k:
            s.append(line((x, y), (px, py)))
        pad = bumpy(px, py, _u(rng, 25, 45), _u(rng, 10, 16), int(rng.integers(4, 7)), 0.25)
        s.append(_outline(rng, pad, 0.1))
    return s


# --------------------------------------------------------------------- broadleaf trees as people draw them
# measured on people's drawings of "a tree" (eval.drawing_stats, benchmarks/probes/people_stats.py):
# a crown of big loops, about three quarters as tall as wide and often open where the trunk
# comes in; a trunk two lines about a quarter of the crown's width, flaring at its base and
# about 40% of the tree's height; few strokes, most of them open; the drawing near the middle
# of the page.  Units: the crown is 100 wide; the trunk's base at (0, 0), up is -y.


@dataclass(frozen=True)
class _Crown:
    """A people's tree's proportions: the crown's height over its width, the trunk's width
    at the crown over the crown's width, and the trunk's height over the crown's."""

    aspect: tuple[float, float]
    trunk_width: tuple[float, float]
    trunk_height: tuple[float, float]


_PEOPLE_CROWNS = {
    "oak": _Crown(aspect=(0.55, 0.8), trunk_width=(0.18, 0.3), trunk_height=(0.6, 1.0)),
    "maple": _Crown(aspect=(0.75, 1.0), trunk_width=(0.14, 0.26), trunk_height=(0.6, 1.0)),
    "cherry": _Crown(aspect=(0.42, 0.58), trunk_width=(0.15, 0.26), trunk_height=(0.5, 0.8)),
}

#: How often a broadleaf's seed draws the people's tree instead of the species' own drawer.
_PEOPLE_SHARE = {"oak": 0.45, "maple": 0.45, "cherry": 0.35}


def _scallops(base: Stroke, loops: int, depth: float, rng: np.random.Generator) -> Stroke:
    """A chain of ``loops`` bulges of relative ``depth`` along ``base`` (a path going
    clockwise on the page round the crown, so its outward side is to the left of its
    direction of travel): the crown's loops."""
    s = np.linspace(0, 1, len(base))
    # anchors at jittered equal steps, so that no loop is much smaller than another
    cuts = np.sort(rng.uniform(0.05, 0.95, loops - 1))
    cuts = 0.5 * np.concatenate([[0.0], cuts, [1.0]]) + 0.5 * np.linspace(0, 1, loops + 1)
    t = np.linspace(0, 1, loops * 14)
    path = np.stack([np.interp(t, s, base[:, i]) for i in range(2)], axis=1)
    seg = np.clip(np.searchsorted(cuts, t, side="right") - 1, 0, loops - 1)
    local = (t - cuts[seg]) / (cuts[seg + 1] - cuts[seg])
    bulge = depth * np.diff(cuts)[seg] * _path_length(base) * np.sin(np.pi * local)
    d = np.gradient(path, axis=0)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)
    outward = np.stack([d[:, 1], -d[:, 0]], 1)
    return path + bulge[:, None] * outward


def _path_length(pts: Stroke) -> float:
    return float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())


def _crown_base(kind: str, rx: float, ry: float, cy: float, join: float) -> Stroke:
    """The crown's outline before its loops, from the left trunk top clockwise over the top
    to the right one (``join``: the trunk's half-width where it meets the crown, a quarter
    of ``ry`` above the ellipse's bottom)."""
    start = math.degrees(math.atan2(0.75, -join / rx))  # between 90 (bottom) and 180
    a = np.radians(np.linspace(start, 540 - start, 90))
    x, y = rx * np.cos(a), cy + ry * np.sin(a)
    if kind == "mushroom":  # a dome over a flat underside
        y = np.minimum(y, cy + ry * 0.3)
    elif kind == "flat":  # a wide, flat-topped crown
        y = np.maximum(y, cy - ry * 0.7)
    return np.stack([x, y], 1)


def _people_crown(rng: np.random.Generator, rx: float, ry: float, cy: float, join: float) -> Stroke:
    kind = str(rng.choice(["cloud", "cloud", "cloud", "mushroom", "mushroom", "flat"]))
    base = _crown_base(kind, rx, ry, cy, join)
    loops = int(rng.integers(4, 10))
    return _scallops(base, loops, _u(rng, 0.22, 0.42), rng)


def _people_trunk(
    rng: np.random.Generator, top_left: np.ndarray, top_right: np.ndarray
) -> tuple[Stroke, Stroke]:
    """The trunk's two lines from the ground up to where the crown begins, flaring at the
    base."""
    join = (top_right[0] - top_left[0]) / 2
    mid = (top_right[0] + top_left[0]) / 2
    flare = join * (_u(rng, 0.2, 0.9) if _chance(rng, 0.7) else 0.0)
    t = np.linspace(0, 1, 12)
    widen = flare * (1 - t) ** 3  # wide at the base, quickly narrowing
    xs = mid * t  # the base under the middle, the top where the crown opens
    left = np.stack([xs - join - widen, top_left[1] * t], 1)
    right = np.stack([xs + join + widen, top_right[1] * t], 1)
    return left, right


def _roots(rng: np.random.Generator, base: float) -> Strokes:
    """A few root strokes spreading from the trunk's base."""
    out = []
    for _ in range(int(rng.integers(2, 6))):
        x = _u(rng, -base, base)
        reach = _u(rng, 8, 22) * (1 if x > 0 else -1)
        out.append(curve((x, -2), (x + reach * 0.6, 1), (x + reach, _u(rng, 3, 8)), 8))
    return out


def _sun(rng: np.random.Generator, x: float, y: float) -> Strokes:
    r = _u(rng, 9, 15)
    s = [_circle(x, y, r, 24)]
    n = int(rng.integers(6, 11))
    for k in range(n):
        a = 2 * math.pi * k / n + _u(rng, -0.1, 0.1)
        c, si = math.cos(a), math.sin(a)
        s.append(line((x + (r + 3) * c, y + (r + 3) * si), (x + (r + 11) * c, y + (r + 11) * si)))
    return s


def _cloud(rng: np.random.Generator, x: float, y: float) -> Strokes:
    w = _u(rng, 22, 35)
    base = np.stack([np.linspace(x - w, x + w, 20), np.full(20, y)], 1)  # left to right
    arcs = _scallops(base, int(rng.integers(3, 5)), _u(rng, 0.35, 0.5), rng)
    return [np.concatenate([arcs, arcs[:1]])]


def _beside(rng: np.random.Generator, rx: float, height: float) -> Strokes:
    """What people draw beside a tree (crown half-width ``rx``, ``height`` tall): a ground
    line or a hill, grass, a sun or a cloud."""
    width = rx * 1.3
    s: Strokes = []
    if _chance(rng, 0.18):
        w = width * _u(rng, 0.5, 0.9)
        s.append(line((-w, _u(rng, -1, 2)), (w * _u(rng, 0.6, 1.1), _u(rng, -2, 3))))
    elif _chance(rng, 0.08):  # the tree on a hill
        s.append(arc(0, 6, width * _u(rng, 0.7, 1.0), _u(rng, 10, 20), 180, 360, 30))
    if _chance(rng, 0.1):  # tufts of grass
        for x in rng.uniform(-width * 0.8, width * 0.8, int(rng.integers(2, 6))):
            s.append(
                line(
                    (x - 4, 0),
                    (x - 2, -_u(rng, 5, 10)),
                    (x, 0),
                    (x + 2, -_u(rng, 5, 10)),
                    (x + 4, 0),
                )
            )
    side = 1 if _chance(rng, 0.5) else -1
    if _chance(rng, 0.08):
        s += _sun(rng, side * rx * _u(rng, 1.5, 1.9), -height * _u(rng, 0.85, 1.0))
    elif _chance(rng, 0.06):
        s += _cloud(rng, side * rx * _u(rng, 1.4, 1.8), -height * _u(rng, 0.95, 1.1))
    return s


def _inside(
    rng: np.random.Generator, join: float, h: float, rx: float, ry: float, cy: float
) -> Strokes:
    """What people draw inside: limbs up from the trunk, little loops for leaves, a knot."""
    s: Strokes = []
    if _chance(rng, 0.3):
        for side in (-1, 1):
            s.append(
                curve(
                    (side * join * 0.5, -h),
                    (side * join, -h - ry * 0.3),
                    (side * rx * _u(rng, 0.25, 0.5), cy - ry * _u(rng, 0.0, 0.3)),
                    10,
                )
            )
    if _chance(rng, 0.15):  # curls for leaves, scattered (two level ones read as eyes)
        for _ in range(int(rng.integers(3, 7))):
            x, y = rx * _u(rng, -0.65, 0.65), cy + ry * _u(rng, -0.55, 0.35)
            r, a0 = _u(rng, 4, 8), _u(rng, 0, 360)
            s.append(arc(x, y, r, r * 0.8, a0, a0 + _u(rng, 160, 220), 12))
    if _chance(rng, 0.12):  # a knot hole in the trunk
        s.append(_circle(_u(rng, -0.3, 0.3) * join, -h * _u(rng, 0.4, 0.7), _u(rng, 2.5, 5), 12))
    return s


def _people_tree(rng: np.random.Generator, species: str) -> Strokes:
    """A broadleaf tree the way people draw "a tree" (proportions per species)."""
    shape = _PEOPLE_CROWNS[species]
    rx = 50.0
    ry = rx * _u(rng, *shape.aspect) * 0.9  # the loops add about a tenth
    join = rx * _u(rng, *shape.trunk_width)
    h = 2 * ry * _u(rng, *shape.trunk_height)
    cy = -h - ry * 0.75
    crown = _people_crown(rng, rx, ry, cy, join)
    left, right = _people_trunk(rng, crown[0], crown[-1])
    if _chance(rng, 0.35):  # trunk and crown in one stroke, up one side and down the other
        s = [np.concatenate([left, crown, right[::-1]])]
    else:
        s = [left, right, _outline(rng, crown, 0.3)]
    if _chance(rng, 0.35):
        s += _roots(rng, join * 1.4)
    elif _chance(rng, 0.3):  # the trunk's base closed with a line
        s.append(line(tuple(left[0]), tuple(right[0])))
    if species == "cherry" and _chance(rng, 0.5):  # blossoms
        for _ in range(int(rng.integers(4, 10))):
            a, rr = _u(rng, 0, 2 * math.pi), math.sqrt(_u(rng, 0, 0.6))
            s.append(_circle(rx * rr * math.cos(a), cy + ry * rr * math.sin(a), _u(rng, 2.5, 4), 8))
    s += _inside(rng, join, h, rx, ry, cy)
    if _chance(rng, 0.45):  # hasty: shaky strokes
        s = [jag(st, rng, amp=_u(rng, 0.4, 1.0), step=_u(rng, 3, 6)) for st in s]
    return s + _beside(rng, rx, h + 2 * ry)


_TREES = _by_name(
    _maple, _pine, _bonsai, _palm, _cherry, _fir, _willow, _oak, _birch, _poplar, _winter
)

#: The species :func:`tree_doodle` draws: the project's eleven (``weberpenn.species.SPECIES``).
TREE_SPECIES: tuple[str, ...] = tuple(_TREES)

#: How :func:`palm_doodle` draws a palm's fronds: each a closed pointed leaf, a single
#: drooping arc, a leaf with zigzag edges, or a straight spike of a star burst.
PALM_FORMS: tuple[str, ...] = ("leaf", "arc", "jagged", "burst")


# --------------------------------------------------------------------- the hand and the page


@dataclass(frozen=True)
class _Hand:
    """How one doodle is drawn."""

    tool: str  # pen, marker, phone (a finger) or mouse
    width: float  # line width, page pixels
    wobble: float  # sideways wobble, page pixels
    ink: int  # 0 black to about 110 pencil grey


_WIDTHS = {"pen": (2.0, 3.5), "marker": (3.5, 6.0), "phone": (6.0, 9.0), "mouse": (2.0, 4.0)}


def _hand(rng: np.random.Generator) -> _Hand:
    tool = str(rng.choice(["pen", "marker", "phone", "mouse"], p=[0.35, 0.25, 0.2, 0.2]))
    return _Hand(
        tool=tool,
        width=_u(rng, *_WIDTHS[tool]),
        wobble=_u(rng, 0.2, 0.9) * (2.0 if tool == "phone" else 1.0),
        ink=int(rng.integers(0, 40)) if _chance(rng, 0.8) else int(rng.integers(40, 110)),
    )


def _page(strokes: Strokes, rng: np.random.Generator, fill: tuple[float, float]) -> np.ndarray:
    """The strokes fitted to a random box (longest side ``fill`` of the page), tilted a
    little, drawn by a random hand, all ink inside the page."""
    return _ink(*_laid_out(strokes, rng, fill))


def _laid_out(
    strokes: Strokes, rng: np.random.Generator, fill: tuple[float, float], place: str = "anywhere"
) -> tuple[Strokes, _Hand]:
    """The strokes as the hand draws them on the page, in page pixels, and the hand; the
    drawing's box goes anywhere on the page (``place`` ``"anywhere"``), near its middle
    (``"centred"``, as people mostly draw) or in a corner (``"corner"``)."""
    hand = _hand(rng)
    pts = np.concatenate(strokes)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, extent = (lo + hi) / 2, np.maximum(hi - lo, 1e-6)
    side = _u(rng, *fill) * SIZE
    scale = side / extent.max() * np.array([_u(rng, 0.92, 1.08), _u(rng, 0.92, 1.08)])
    tilt = math.radians(_u(rng, -5, 5))
    rot = np.array([[math.cos(tilt), -math.sin(tilt)], [math.sin(tilt), math.cos(tilt)]])
    placed = [((st - centre) * scale) @ rot.T for st in strokes]
    drawn = []
    for st in placed:
        if hand.tool == "mouse":
            drawn.append(jag(st, rng, amp=_u(rng, 0.3, 0.9), step=_u(rng, 3.0, 6.0)))
        else:
            drawn.append(wobble(st, rng, amp=hand.wobble, step=4.0) if len(st) > 1 else st)
    allpts = np.concatenate(drawn)
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    pad = hand.width / 2 + 3
    # shrink anything the wobble pushed past the page, then place the box at random
    shrink = min(1.0, (SIZE - 2 * pad) / max(float((hi - lo).max()), 1e-6))
    drawn = [(st - (lo + hi) / 2) * shrink for st in drawn]
    half = (hi - lo) * shrink / 2
    room = SIZE / 2 - pad - half
    if place == "anywhere":
        offset = SIZE / 2 + np.array([_u(rng, -room[0], room[0]), _u(rng, -room[1], room[1])])
    elif place == "centred":
        offset = SIZE / 2 + room * rng.uniform(-0.25, 0.25, 2)
    else:  # a corner
        offset = SIZE / 2 + room * rng.choice([-1.0, 1.0], 2) * rng.uniform(0.75, 1.0, 2)
    return [st + offset for st in drawn], hand


def _ink(drawn: Strokes, hand: _Hand) -> np.ndarray:
    """The laid-out strokes inked by the hand: aliased for the mouse, else antialiased."""
    ss = 1 if hand.tool == "mouse" else 2  # the mouse draws aliased pixels
    im = Image.new("L", (SIZE * ss, SIZE * ss), 255)
    d = ImageDraw.Draw(im)
    width = max(1, round(hand.width * ss))
    for st in drawn:
        xy = [tuple(p) for p in st * ss]
        d.line(xy, fill=hand.ink, width=width, joint="curve")
        if width >= 3:  # round ends, as a pen or a finger leaves them
            for x, y in (xy[0], xy[-1]):
                r = width / 2 - 0.5
                d.ellipse((x - r, y - r, x + r, y + r), fill=hand.ink)
    if ss > 1:
        im = im.resize((SIZE, SIZE), Image.Resampling.BOX)
    return np.asarray(im, dtype=np.uint8)


def _rng(what: str, seed: int) -> np.random.Generator:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
    return np.random.default_rng([zlib.crc32(what.encode()), int(seed)])


def nontree_doodle(kind: str, seed: int) -> np.ndarray:
    """A doodle of something that is not a tree: a ``(256, 256)`` uint8 image, 255 paper."""
    if not isinstance(kind, str) or kind not in _NONTREES:
        raise ValueError(f"unknown doodle kind {kind!r}; one of {', '.join(NONTREE_KINDS)}")
    rng = _rng("nontree:" + kind, seed)
    return _page(_NONTREES[kind](rng), rng, (0.4, 0.9))


def palm_doodle(form: str, seed: int) -> np.ndarray:
    """A palm as people draw one, its fronds of ``form`` (one of :data:`PALM_FORMS`): a
    ``(256, 256)`` uint8 image, 255 paper."""
    if not isinstance(form, str) or form not in PALM_FORMS:
        raise ValueError(f"unknown palm form {form!r}; one of {', '.join(PALM_FORMS)}")
    rng = _rng("palm:" + form, seed)
    return _page(_people_palm(rng, form), rng, (0.5, 0.92))


def _variety(species: str, seed: int) -> str | None:
    """Which drawing of ``species`` a seed gets besides the species' own: a palm form,
    ``"people"`` (a broadleaf as people draw "a tree"), or None for the species' own drawer.  Drawn from a generator of its own, so a seed that
    keeps the species' own drawer keeps its bytes from before the varieties came."""
    rng = _rng("variety:" + species, seed)
    if species == "palm" and _chance(rng, 0.5):
        return PALM_FORMS[int(rng.integers(len(PALM_FORMS)))]
    if species in _PEOPLE_SHARE and _chance(rng, _PEOPLE_SHARE[species]):
        return "people"
    return None


def _tree_strokes(
    species: str, seed: int
) -> tuple[Strokes, np.random.Generator, tuple[float, float], str]:
    """A tree of ``species``'s strokes as drawn (before the page), the generator that goes
    on to lay them out and ink them, and how big and where on the page they go."""
    if not isinstance(species, str) or species not in _TREES:
        raise ValueError(f"unknown tree species {species!r}; one of {', '.join(TREE_SPECIES)}")
    rng = _rng("tree:" + species, seed)
    variety = _variety(species, seed)
    if variety in PALM_FORMS:
        return _people_palm(rng, variety), rng, (0.5, 0.92), "anywhere"
    if variety == "people":
        strokes = _people_tree(rng, species)
        if _chance(rng, 0.1):  # drawn small in a corner of the page
            return strokes, rng, (0.3, 0.5), "corner"
        return strokes, rng, (0.6, 0.92), "centred"
    strokes = _TREES[species](rng)
    if species != "bonsai" and _chance(rng, 0.1):  # a line for the ground
        w = _u(rng, 30, 80)
        strokes.append(line((-w, _u(rng, 0, 3)), (w * _u(rng, 0.6, 1.2), _u(rng, -2, 4))))
    return strokes, rng, (0.5, 0.92), "anywhere"


def tree_doodle(species: str, seed: int) -> np.ndarray:
    """A doodle of a tree of ``species`` as a person would draw one and name it: a
    ``(256, 256)`` uint8 image, 255 paper."""
    return _ink(*_laid_out(*_tree_strokes(species, seed)))


def tree_doodle_strokes(species: str, seed: int) -> list[np.ndarray]:
    """The strokes of ``tree_doodle(species, seed)`` as the hand drew them on its page:
    ``(n, 2)`` arrays of page pixels, x right, y down (for measuring a drawing's strokes,
    :func:`eval.drawing_stats.stroke_stats`)."""
    return _laid_out(*_tree_strokes(species, seed))[0]
