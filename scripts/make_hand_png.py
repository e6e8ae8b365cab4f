"""Hand-style drawings outside the training styles, and what the pipeline makes of them.

    .venv/bin/python scripts/make_hand_png.py --inputs-only   # examples/hand/*.png, species.json
    nice -n 10 .venv/bin/python scripts/make_hand_png.py      # ... and docs/hand.png

Each drawing is written here as strokes (polylines in page pixels), drawn with PIL at about
4 px with a little seeded wobble, the way a person draws: a lollipop tree, stacked
triangles, a leaning bonsai, a palm, a wide cherry, a scribbled bush, a ballpoint tree on
lined paper, a pencil tree on grey paper, a small tree in the corner of a big page, a
weeping tree, a bare winter tree, a child's cloud tree; and twelve of the trees people draw
most, the way they draw them (issue 27): a zigzag Christmas tree, a finger-drawn lollipop on
a phone, a palm whose fronds are single lines, a bare tree of uneven forks, a weeping willow,
an oak, a poplar, a birch, a child's crayon tree, a tree in four finger strokes, a fir of
three drooping tiers, a jaggy tree drawn with a mouse.  None uses ``render.styles``: they are
inputs made outside the training styles.  ``examples/hand/species.json`` names, per drawing,
the species a person would name (and others they fairly could).  ``docs/hand.png`` shows, per
drawing: the input, the normalised input (``Pipeline`` sees this), the refined tree's sketch
and its colour render, labelled with the species, the final distance and any warning.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from eval.strokes import Stroke, arc, branches, bumpy, curve, jag, line, wobble
from weberpenn.fileio import atomic_target, atomic_write

ROOT = Path(__file__).resolve().parents[1]

EXAMPLES = ROOT / "examples" / "hand"


# --------------------------------------------------------------------- the drawings
# each: rng -> (page size (w, h), paper grey or RGB, [(stroke, width, ink colour)])

Page = tuple[tuple[int, int], tuple[int, int, int], list[tuple[Stroke, float, tuple]]]
BLACK, GRAPHITE, BLUE = (20, 20, 20), (70, 70, 75), (30, 40, 140)
WHITE = (255, 255, 255)


def lollipop(rng: np.random.Generator) -> Page:
    s = [line((256, 490), (258, 300)), line((276, 490), (272, 300))]
    s += [arc(262, 185, 125, 120, 100, 440, 90)]
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def conifer(rng: np.random.Generator) -> Page:
    s = [line((246, 500), (246, 440)), line((266, 500), (266, 440))]
    for k, (top, base, half) in enumerate(((40, 200, 90), (120, 320, 140), (220, 440, 190))):
        s.append(line((256 - half, base), (256, top), (256 + half, base), (256 - half, base)))
        del k
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def bonsai(rng: np.random.Generator) -> Page:
    pot = line((150, 430), (362, 430), (340, 490), (172, 490), (150, 430))
    trunk_l = line((230, 430), (215, 360), (250, 290), (300, 240), (320, 180))
    trunk_r = line((262, 430), (245, 365), (278, 300), (322, 250), (332, 180))
    pads = [
        bumpy(330, 150, 70, 35, 6, 0.25),
        bumpy(200, 270, 60, 28, 5, 0.25),
        bumpy(370, 250, 50, 24, 5, 0.25),
    ]
    limbs = [line((262, 300), (215, 275)), line((315, 245), (355, 250))]
    return (512, 512), WHITE, [(p, 4, BLACK) for p in [pot, trunk_l, trunk_r, *pads, *limbs]]


def palm(rng: np.random.Generator) -> Page:
    t = np.linspace(0, 1, 20)
    xs = 220 + 70 * t**2
    ys = 495 - 365 * t
    s = [np.stack([xs - 8, ys], 1), np.stack([xs + 8, ys], 1)]
    tx, ty = 290.0, 128.0
    # fronds arch up and out from the crown and droop at their tips
    for side, reach, rise, drop in (
        (-1, 200, 35, 110), (-1, 160, 45, 55), (-1, 110, 55, 10), (1, 200, 35, 115),
        (1, 160, 45, 60), (1, 110, 55, 15), (-1, 90, 10, 120), (1, 90, 10, 120),
    ):  # fmt: skip
        frond = line(
            (tx, ty), (tx + side * reach * 0.45, ty - rise), (tx + side * reach, ty + drop)
        )
        s.append(frond)
        dense = wobble(frond, rng, 0.0, step=4.0)
        for f in np.linspace(0.25, 0.95, 6):  # leaflets hanging off the frond
            x, y = dense[int(f * (len(dense) - 1))]
            s.append(line((x, y), (x + side * 8, y + 22)))
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def cherry(rng: np.random.Generator) -> Page:
    s = [line((240, 500), (245, 380), (200, 300)), line((270, 500), (268, 380), (320, 300))]
    s += [line((245, 380), (256, 290)), line((222, 330), (150, 280)), line((300, 330), (370, 285))]
    s += [bumpy(256, 230, 225, 95, 11, 0.18)]
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def bush(rng: np.random.Generator) -> Page:
    t = np.linspace(0, 40 * math.pi, 900)
    r = 1 + 0.15 * rng.standard_normal(900).cumsum() / 30
    xs = 256 + 150 * np.sin(t * 0.13) * r + 40 * np.cos(t)
    ys = 260 + 90 * np.cos(t * 0.11) * r + 40 * np.sin(t)
    s = [np.stack([xs, ys], 1), line((246, 480), (250, 340)), line((266, 480), (264, 340))]
    return (512, 512), WHITE, [(p, 3, BLACK) for p in s]


def ballpoint(rng: np.random.Generator) -> Page:
    sub = np.random.default_rng(7)
    s = [line((250, 500), (252, 330)), line((270, 500), (268, 330))]
    s += branches(260, 330, 90, 90, 4, sub)
    paper: list[tuple[Stroke, float, tuple]] = [
        (line((0, y), (512, y)), 1, (150, 185, 230)) for y in range(40, 512, 32)
    ]
    paper.append((line((60, 0), (60, 512)), 1, (230, 120, 120)))
    return (512, 512), (250, 250, 245), paper + [(p, 2.5, BLUE) for p in s]


def grey_paper(rng: np.random.Generator) -> Page:
    s = [line((245, 490), (248, 330), (210, 250)), line((268, 490), (265, 330), (305, 250))]
    s += [line((255, 330), (258, 230))]
    s += [bumpy(256, 190, 170, 140, 9, 0.15)]
    return (512, 512), (150, 150, 145), [(p, 4, (45, 45, 50)) for p in s]


def corner(rng: np.random.Generator) -> Page:
    off = np.array([60.0, 620.0])
    s = [
        line((100, 270), (102, 170)),
        line((114, 270), (112, 170)),
        bumpy(107, 110, 75, 70, 8, 0.2),
    ]
    return (1200, 900), WHITE, [(p * 0.9 + off, 4, BLACK) for p in s]


def weeping(rng: np.random.Generator) -> Page:
    s = [line((246, 500), (250, 200)), line((268, 500), (264, 200))]
    s += [arc(257, 200, 170, 110, 180, 360)]
    for x0 in np.linspace(100, 414, 12):
        t = np.linspace(0, 1, 12)
        side = np.sign(x0 - 257)
        s.append(np.stack([x0 + side * 25 * np.sin(t * 2), 200 - 60 * (1 - t) + 250 * t**1.3], 1))
    return (512, 512), WHITE, [(p, 3.5, BLACK) for p in s]


def winter(rng: np.random.Generator) -> Page:
    sub = np.random.default_rng(3)
    s = [line((246, 500), (250, 350)), line((268, 500), (264, 350))]
    s += branches(257, 350, 90, 110, 5, sub)
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def cloud_tree(rng: np.random.Generator) -> Page:
    trunk = line((225, 500), (235, 330), (280, 330), (290, 500), (225, 500))
    crown = bumpy(257, 200, 185, 140, 7, 0.3)
    return (512, 512), WHITE, [(trunk, 5, BLACK), (crown, 5, BLACK)]


# ---- twelve more (issue 27): the trees people draw most, and how they draw them on a phone,
# with a mouse or a crayon.  Appended after the first twelve, so those keep their seeds and
# bytes.


def christmas_tree(rng: np.random.Generator) -> Page:
    # one zigzag outline: out to a tip, back in, out again, four times down each side
    tiers = ((150, 70, 40), (250, 110, 60), (350, 150, 85), (440, 195, 0))
    left: list[tuple[float, float]] = [(256, 35)]
    for y, half, back in tiers:
        left += [(256 - half, y)] + ([(256 - back, y - 8)] if back else [])
    right = [(512 - x, y) for x, y in reversed(left)]
    outline = line(*left, *right)
    trunk = line((236, 440), (236, 495), (276, 495), (276, 440))
    return (512, 512), WHITE, [(outline, 4, BLACK), (trunk, 4, BLACK)]


def phone_lollipop(rng: np.random.Generator) -> Page:
    # a finger on a phone: one thick wobbly loop that overshoots its start, one thick stick
    loop = arc(262, 190, 130, 140, 80, 80 + 380, 90)
    loop = wobble(loop, rng, amp=3.5, step=10.0)
    stick = wobble(line((252, 495), (256, 400), (262, 325)), rng, amp=2.5, step=10.0)
    return (512, 512), WHITE, [(stick, 16, BLACK), (loop, 14, BLACK)]


def palm_lines(rng: np.random.Generator) -> Page:
    # a curved trunk and each frond one swept line, no leaflets: the palm that came out as a
    # cherry (its fronds' hull looks like a filled crown)
    t = np.linspace(0, 1, 24)
    xs = 300 - 90 * t + 60 * t**2
    ys = 495 - 330 * t
    s = [np.stack([xs - 9 + 4 * t, ys], 1), np.stack([xs + 9 - 4 * t, ys], 1)]
    tx, ty = float(xs[-1]), float(ys[-1]) - 4
    for dx, lift, dy in (
        (-190, 60, 95), (-150, 80, 20), (-70, 95, -45), (60, 100, -50),
        (150, 85, 15), (195, 55, 100), (-110, 10, 150), (115, 10, 145),
    ):  # fmt: skip
        s.append(curve((tx, ty), (tx + 0.45 * dx, ty - lift), (tx + dx, ty + dy)))
    return (512, 512), WHITE, [(p, 4, BLACK) for p in s]


def _limbs(
    x: float, y: float, angle: float, length: float, depth: int, rng: np.random.Generator
) -> list[tuple[Stroke, float]]:
    """Uneven forks of two or three, the limbs thinner as they go: a bare tree's crown."""
    a = math.radians(angle)
    x2, y2 = x + length * math.cos(a), y - length * math.sin(a)
    out = [(line((x, y), (x2, y2)), 1.5 + 1.2 * depth)]
    if depth > 0:
        for k in range(int(rng.integers(2, 4))):
            turn = angle + rng.uniform(-48, 48) + (k - 1) * 12
            out += _limbs(x2, y2, turn, length * rng.uniform(0.55, 0.8), depth - 1, rng)
    return out


def bare_winter(rng: np.random.Generator) -> Page:
    sub = np.random.default_rng(11)
    trunk = [line((238, 498), (244, 400), (236, 330)), line((274, 498), (268, 400), (272, 330))]
    limbs = [(p, 4.0) for p in trunk]
    for angle, length in ((128, 95), (92, 120), (55, 100)):
        limbs += _limbs(254, 335, angle, length, 3, sub)
    return (512, 512), WHITE, [(p, w, BLACK) for p, w in limbs]


def willow(rng: np.random.Generator) -> Page:
    # limbs arch up and out like a fountain; long wavy strands hang from them to the ground
    s = [line((244, 498), (250, 330), (248, 150)), line((266, 498), (262, 330), (264, 150))]
    arches = []
    for k in range(3):  # each limb rises over the middle and falls outwards, both sides
        ctrl, end = (236 - 30 * k, 35 + 35 * k), (105 - 30 * k, 215 + 20 * k)
        arches.append(curve((256, 150), ctrl, end))
        arches.append(curve((256, 150), (512 - ctrl[0], ctrl[1]), (512 - end[0], end[1])))
    s += arches
    for a in arches:
        for f in (0.45, 0.65, 0.85, 1.0):
            x, y = a[int(f * (len(a) - 1))]
            drop = np.linspace(0, 1, 14)
            length = rng.uniform(170, 250) * (0.6 + 0.4 * f)
            sway = rng.uniform(-10, 10)
            s.append(np.stack([x + sway * np.sin(drop * 5), y + length * drop], 1))
    return (512, 512), WHITE, [(p, 3.5, BLACK) for p in s]


def oak(rng: np.random.Generator) -> Page:
    # a wide, lumpy crown of uneven lobes on a short, thick trunk with flared roots
    a = np.radians(np.linspace(200, 200 + 360, 260))
    lobes = 1 + 0.13 * np.abs(np.sin(a * 4.5)) + 0.06 * np.abs(np.sin(a * 7 + 1.0))
    crown = np.stack([256 + 225 * lobes * np.cos(a), 215 + 125 * lobes * np.sin(a)], 1)
    crown = crown[(crown[:, 1] < 320) | (np.abs(crown[:, 0] - 256) > 60)]
    trunk = [
        line((180, 498), (215, 470), (222, 395), (215, 335)),
        line((335, 498), (295, 470), (290, 395), (300, 335)),
    ]
    limbs = [
        line((222, 360), (160, 290)),
        line((292, 360), (360, 280)),
        line((256, 350), (252, 260)),
    ]
    return (512, 512), WHITE, [(crown, 5, BLACK)] + [(p, 5, BLACK) for p in trunk + limbs]


def poplar(rng: np.random.Generator) -> Page:
    # a tall narrow flame of a crown on a short trunk, a few upright strokes inside
    t = np.linspace(0, 1, 40)
    half = 62 * np.sin(np.pi * t**0.8) ** 0.9
    ys = 25 + 405 * t
    outline = np.concatenate(
        [np.stack([256 - half, ys], 1), np.stack([256 + half, ys], 1)[::-1]], axis=0
    )
    s = [outline, line((248, 498), (249, 425)), line((264, 498), (263, 425))]
    s += [line((x, y0), (x + 2, y0 - 70)) for x, y0 in ((236, 330), (270, 260), (250, 180))]
    return (512, 512), WHITE, [(p, 3.5, BLACK) for p in s]


def birch(rng: np.random.Generator) -> Page:
    # a slender white trunk marked with dashes, thin limbs and a light, broken crown
    t = np.linspace(0, 1, 20)
    xs = 256 + 18 * np.sin(t * 2.4)
    ys = 498 - 370 * t
    s: list[tuple[Stroke, float]] = [
        (np.stack([xs - 8 + 3 * t, ys], 1), 3.0),
        (np.stack([xs + 8 - 3 * t, ys], 1), 3.0),
    ]
    for y in (470, 430, 395, 350, 305, 262, 220):
        x = float(np.interp(498 - y, 498 - ys[::-1], xs[::-1]))
        s.append((line((x - 6, y), (x + 4, y - 3)), 4.0))
    s += [(line((263, 300), (330, 230)), 2.5), (line((252, 260), (190, 200)), 2.5)]
    for cx, cy, rx, ry in ((256, 110, 75, 60), (185, 190, 55, 40), (335, 205, 60, 42)):
        clump = bumpy(cx, cy, rx, ry, 6, 0.3, rng.uniform(0, 60), rng.uniform(250, 310))
        s.append((clump, 2.5))
    return (512, 512), WHITE, [(p, w, GRAPHITE) for p, w in s]


def child_tree(rng: np.random.Generator) -> Page:
    # crayon: a brown rectangle trunk and a green round crown scribbled in
    brown, green = (100, 60, 25), (30, 120, 40)
    trunk = line((222, 498), (222, 330), (290, 330), (290, 498), (222, 498))
    ring = arc(256, 200, 170, 150, 0, 370, 80)
    t = np.linspace(0, 1, 220)
    zig = np.stack([256 + 150 * np.sin(t * 2 * np.pi * 9), 85 + 230 * t], 1)
    zig[:, 0] = 256 + (zig[:, 0] - 256) * np.sqrt(np.clip(1 - ((zig[:, 1] - 200) / 150) ** 2, 0, 1))
    return (512, 512), WHITE, [(trunk, 7, brown), (ring, 6, green), (zig, 3, green)]


def phone_doodle(rng: np.random.Generator) -> Page:
    # four thick finger strokes: the trunk, an egg of a crown, two limbs
    trunk = wobble(line((256, 498), (252, 400), (256, 300)), rng, amp=2.0, step=12.0)
    crown = wobble(arc(256, 190, 140, 170, 95, 95 + 355, 70), rng, amp=4.0, step=12.0)
    limbs = [
        wobble(line((254, 350), (190, 250)), rng, amp=2.0, step=12.0),
        wobble(line((256, 330), (330, 240)), rng, amp=2.0, step=12.0),
    ]
    return (
        (512, 512),
        WHITE,
        [(trunk, 18, BLACK), (crown, 15, BLACK)] + [(p, 13, BLACK) for p in limbs],
    )


def fir_tiers(rng: np.random.Generator) -> Page:
    # three triangles with drooping sides and a scalloped hem, each tucked under the one
    # above, in pencil
    s = []
    for top, base, half in ((30, 185, 85), (125, 320, 135), (240, 445, 185)):
        side = np.linspace(0, 1, 12)[:, None]
        sag = 12 * np.sin(np.pi * side)
        left = np.hstack([256 - half * side + sag * 0.5, top + (base - top) * side + sag])
        hem = arc(256, base, half, 10, 180, 0, 30)
        hem[:, 1] = base - 8 * np.abs(np.sin(np.radians(np.linspace(0, 540, 30))))
        right = left[::-1].copy()
        right[:, 0] = 512 - right[:, 0]
        s.append(np.concatenate([left, hem, right], axis=0))
    s += [line((246, 498), (246, 445)), line((266, 498), (266, 445))]
    return (512, 512), WHITE, [(p, 3.5, GRAPHITE) for p in s]


def mouse_tree(rng: np.random.Generator) -> Page:
    # a mouse in a paint program: straight jaggy segments, the crown left open at the trunk
    a = np.radians(np.linspace(105, 105 + 330, 14))
    crown = np.stack([256 + 150 * np.cos(a), 185 + 160 * np.sin(a)], 1)
    crown += rng.normal(0, 10, crown.shape)  # each click a little off the round
    crown[np.argmin(crown[:, 1]), 1] -= 25  # a peak where the mouse slipped up
    s = [jag(crown, rng, amp=2.5, step=6.0)]
    s += [jag(line((240, 500), (242, 335)), rng, 1.8, 7.0)]
    s += [jag(line((270, 500), (268, 335)), rng, 1.8, 7.0)]
    return (512, 512), WHITE, [(p, 3, BLACK) for p in s]


class Drawing(NamedTuple):
    make: Callable[[np.random.Generator], Page]
    what: str
    species: str  # the species a person would name (one of weberpenn.species.SPECIES)
    also: tuple[str, ...]  # others a person could fairly name for the same drawing


# the order is the seed (1000 + index): append new drawings, never insert or reorder
DRAWINGS: dict[str, Drawing] = {
    "lollipop": Drawing(lollipop, "a lollipop: a stick and a circle", "oak", ("maple",)),
    "conifer": Drawing(conifer, "stacked triangles", "fir", ("pine",)),
    "bonsai": Drawing(bonsai, "a leaning bonsai in a pot", "bonsai", ()),
    "palm": Drawing(palm, "a palm with fronds", "palm", ()),
    "cherry": Drawing(cherry, "a cherry with a wide crown", "cherry", ("oak",)),
    "bush": Drawing(bush, "a scribbled bush", "oak", ("maple",)),
    "ballpoint": Drawing(ballpoint, "ballpoint on lined paper", "winter", ()),
    "grey_paper": Drawing(grey_paper, "pencil on grey paper", "maple", ("oak",)),
    "corner": Drawing(corner, "small, in a corner of a big page", "maple", ("oak",)),
    "weeping": Drawing(weeping, "a weeping tree", "willow", ()),
    "winter": Drawing(winter, "a bare winter tree", "winter", ()),
    "cloud_tree": Drawing(cloud_tree, "a child's cloud tree", "oak", ("maple",)),
    "christmas_tree": Drawing(
        christmas_tree, "a Christmas tree: a zigzag triangle", "fir", ("pine",)
    ),
    "phone_lollipop": Drawing(phone_lollipop, "a lollipop by finger on a phone", "oak", ("maple",)),
    "palm_lines": Drawing(palm_lines, "a palm, each frond one line", "palm", ()),
    "bare_winter": Drawing(bare_winter, "a bare tree, uneven forks", "winter", ()),
    "willow": Drawing(willow, "a weeping willow, strands to the ground", "willow", ()),
    "oak": Drawing(oak, "an oak: wide lumpy crown, thick trunk", "oak", ()),
    "poplar": Drawing(poplar, "a poplar: a tall narrow flame", "poplar", ()),
    "birch": Drawing(birch, "a birch: marked trunk, light crown", "birch", ()),
    "child_tree": Drawing(child_tree, "a child's crayon tree", "oak", ("maple",)),
    "phone_doodle": Drawing(phone_doodle, "a tree in four finger strokes", "maple", ("oak",)),
    "fir_tiers": Drawing(fir_tiers, "a fir: three drooping tiers", "fir", ("pine",)),
    "mouse_tree": Drawing(mouse_tree, "a tree drawn with a mouse", "maple", ("oak",)),
}


def render_page(page: Page, rng: np.random.Generator) -> Image.Image:
    (w, h), paper, strokes = page
    im = Image.new("RGB", (w, h), paper)
    d = ImageDraw.Draw(im)
    for pts, width, ink in strokes:
        jit = wobble(pts, rng, amp=1.2 if width > 1 else 0.3)
        d.line([tuple(p) for p in jit], fill=ink, width=max(1, round(width)), joint="curve")
    return im


def species_table() -> dict[str, dict]:
    """Per drawing: what it is, the species a person would name, the others they could."""
    return {
        name: {"what": d.what, "species": d.species, "also": list(d.also)}
        for name, d in DRAWINGS.items()
    }


def make_inputs(out: Path) -> list[Path]:
    """Write every drawing to ``out``/NAME.png (seeded: the same bytes every run) and the
    species a person would name for each to ``out``/species.json (a benchmark scores them
    on it)."""
    atomic_write(out / "species.json", json.dumps(species_table(), indent=1) + "\n")
    paths = []
    for k, (name, drawing) in enumerate(DRAWINGS.items()):
        rng = np.random.default_rng(1000 + k)
        im = render_page(drawing.make(rng), rng)
        if im.size[0] > 600:  # the big page stays big, but in grey to stay small on disk
            im = im.convert("L")
        path = out / f"{name}.png"
        with atomic_target(path) as tmp:
            im.save(tmp, format="PNG", optimize=True)
        paths.append(path)
    return paths


def _tile(img: np.ndarray, size: int) -> Image.Image:
    im = Image.fromarray(img).convert("RGB")
    im.thumbnail((size, size))
    tile = Image.new("RGB", (size, size), (255, 255, 255))
    tile.paste(im, ((size - im.size[0]) // 2, (size - im.size[1]) // 2))
    return tile


def make_figure(paths: list[Path], target: Path, budget: int) -> list[dict]:
    from render.sketch import SketchRenderer
    from treesketch import Pipeline, RefineSettings, load_sketch

    pipe = Pipeline("tsn", RefineSettings(budget=budget))
    tile, label_h, head = 200, 44, 26
    font = ImageFont.load_default(size=13)
    big = ImageFont.load_default(size=16)
    cols = ("input", "normalised input", "refined tree's sketch", "colour render")
    sheet = Image.new("RGB", (4 * tile, head + len(paths) * (tile + label_h)), "white")
    d = ImageDraw.Draw(sheet)
    for c, title in enumerate(cols):
        d.text((c * tile + 8, 5), title, fill="black", font=big)
    rows = []
    for i, path in enumerate(paths):
        res = pipe.run(path)
        colour = SketchRenderer(res.tree_mesh, species=res.species).colour(res.yaw, 256)
        imgs = [load_sketch(path), res.input_sketch, res.sketch_after, colour]
        y = head + i * (tile + label_h)
        for c, img in enumerate(imgs):
            sheet.paste(_tile(np.asarray(img), tile), (c * tile, y))
        d.rectangle((0, y, 4 * tile - 1, y + tile + label_h - 1), outline=(180, 180, 180))
        drawing = DRAWINGS[path.stem]
        right = res.species == drawing.species or res.species in drawing.also
        line1 = (
            f"{path.stem} ({drawing.what}; a person says {drawing.species}): "
            f"{res.species_text or res.species}"
        )
        line2 = (
            f"{'right' if right else 'WRONG'}; distance {res.losses['before']:.3f} -> "
            f"{res.losses['after']:.3f}; "
            + ("warning: is this a tree?" if res.warning else "no warning")
        )
        d.text((6, y + tile + 4), line1, fill="black", font=font)
        d.text(
            (6, y + tile + 22),
            line2,
            fill=(190, 0, 0) if res.warning or not right else (0, 110, 0),
            font=font,
        )
        rows.append(
            {"drawing": path.stem, "person": drawing.species, "right": right, **res.summary()}
        )
        rows[-1].pop("params", None)
        print(line1, "|", line2, flush=True)
    with atomic_target(target) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)
    n_right = sum(r["right"] for r in rows)
    print(f"species as a person names it: {n_right} of {len(rows)} right", flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inputs-only", action="store_true", help="only write examples/hand")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "hand.png")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--json", type=Path, default=None, help="also write each result's summary")
    args = ap.parse_args(argv)
    paths = make_inputs(EXAMPLES)
    if args.inputs_only:
        print("\n".join(f"{p} {p.stat().st_size} bytes" for p in paths))
        return 0
    rows = make_figure(paths, args.out, args.budget)
    if args.json is not None:
        atomic_write(args.json, json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
