"""Hand-style drawings outside the training styles, and what the pipeline makes of them.

    .venv/bin/python scripts/make_hand_png.py --inputs-only   # examples/hand/*.png
    nice -n 10 .venv/bin/python scripts/make_hand_png.py      # ... and docs/hand.png

Each drawing is written here as strokes (polylines in page pixels), drawn with PIL at about
4 px with a little seeded wobble, the way a person draws: a lollipop tree, stacked
triangles, a leaning bonsai, a palm, a wide cherry, a scribbled bush, a ballpoint tree on
lined paper, a pencil tree on grey paper, a small tree in the corner of a big page, a
weeping tree, a bare winter tree, a child's cloud tree.  ``docs/hand.png`` shows, per
drawing: the input, the normalised input (``Pipeline`` sees this), the refined tree's sketch
and its colour render, labelled with the species, the final distance and any warning.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from weberpenn.fileio import atomic_target, atomic_write  # noqa: E402

Stroke = np.ndarray  # (n, 2) page pixels, x right, y down
EXAMPLES = ROOT / "examples" / "hand"


def wobble(pts: Stroke, rng: np.random.Generator, amp: float = 2.0, step: float = 6.0) -> Stroke:
    """The stroke resampled every ``step`` px with a smooth sideways wobble of ``amp`` px."""
    pts = np.asarray(pts, dtype=float)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    n = max(2, int(s[-1] / step) + 1)
    t = np.linspace(0.0, s[-1], n)
    out = np.stack([np.interp(t, s, pts[:, 0]), np.interp(t, s, pts[:, 1])], axis=1)
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
    cx: float, cy: float, rx: float, ry: float, bumps: int, depth: float, a0=0.0, a1=360.0
) -> Stroke:
    """A cloud outline: an ellipse with ``bumps`` scallops of relative ``depth``."""
    a = np.radians(np.linspace(a0, a1, bumps * 16))
    r = 1.0 + depth * np.abs(np.sin(a * bumps / 2))
    return np.stack([cx + rx * r * np.cos(a), cy + ry * r * np.sin(a)], axis=1)


def line(*pts: tuple[float, float]) -> Stroke:
    return np.array(pts, dtype=float)


def branches(
    x: float, y: float, angle: float, length: float, depth: int, rng: np.random.Generator
) -> list[Stroke]:
    """A recursive branching (angle in degrees, 90 = up)."""
    a = math.radians(angle)
    x2, y2 = x + length * math.cos(a), y - length * math.sin(a)
    out = [line((x, y), (x2, y2))]
    if depth > 0:
        for turn in (-1, 1):
            spread = turn * rng.uniform(20, 40)
            out += branches(x2, y2, angle + spread, length * rng.uniform(0.6, 0.8), depth - 1, rng)
    return out


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


DRAWINGS: dict[str, tuple[Callable[[np.random.Generator], Page], str]] = {
    "lollipop": (lollipop, "a lollipop: a stick and a circle"),
    "conifer": (conifer, "stacked triangles"),
    "bonsai": (bonsai, "a leaning bonsai in a pot"),
    "palm": (palm, "a palm with fronds"),
    "cherry": (cherry, "a cherry with a wide crown"),
    "bush": (bush, "a scribbled bush"),
    "ballpoint": (ballpoint, "ballpoint on lined paper"),
    "grey_paper": (grey_paper, "pencil on grey paper"),
    "corner": (corner, "small, in a corner of a big page"),
    "weeping": (weeping, "a weeping tree"),
    "winter": (winter, "a bare winter tree"),
    "cloud_tree": (cloud_tree, "a child's cloud tree"),
}


def render_page(page: Page, rng: np.random.Generator) -> Image.Image:
    (w, h), paper, strokes = page
    im = Image.new("RGB", (w, h), paper)
    d = ImageDraw.Draw(im)
    for pts, width, ink in strokes:
        jit = wobble(pts, rng, amp=1.2 if width > 1 else 0.3)
        d.line([tuple(p) for p in jit], fill=ink, width=max(1, round(width)), joint="curve")
    return im


def make_inputs(out: Path) -> list[Path]:
    """Write every drawing to ``out``/NAME.png (seeded: the same bytes every run)."""
    paths = []
    for k, (name, (make, _)) in enumerate(DRAWINGS.items()):
        rng = np.random.default_rng(1000 + k)
        im = render_page(make(rng), rng)
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
        desc = DRAWINGS[path.stem][1]
        tried = ", ".join(f"{s} {v:.2f}" for s, v in res.extras.get("tried", {}).items())
        line1 = (
            f"{path.stem} ({desc}): {res.species}, distance {res.losses['before']:.3f} -> "
            f"{res.losses['after']:.3f}, line {res.losses['ink_after']:.3f} (tried {tried})"
        )
        warn = "warning: low confidence (is this a tree?)" if res.warning else "no warning"
        d.text((6, y + tile + 4), line1, fill="black", font=font)
        d.text(
            (6, y + tile + 22), warn, fill=(190, 0, 0) if res.warning else (0, 110, 0), font=font
        )
        rows.append({"drawing": path.stem, **res.summary()})
        rows[-1].pop("params", None)
        print(line1, "|", warn, flush=True)
    with atomic_target(target) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)
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
