"""Make docs/controls.png: what each control does, a row of trees per control.

    PYTHONPATH=$PWD .venv/bin/python scripts/make_controls_png.py [--species maple] [--tile 150]

Every row is one tree (``species.sample(species, seed)``; the trunk rows a single-trunk
species' tree, ``--trunk-species``, as a trunk that forks low leans little) edited by one control of
``weberpenn.controls.CONTROLS`` at five values across its range (the tree's own value in
the middle where it has one), grown by ``grow_with_controls`` and rendered in colour
(mitsuba), front view; the trees of a row share one framing so sizes compare.  The page's
"what do these do?" link shows it.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np
from docs_png import write_palette_png
from PIL import Image, ImageDraw

from render.camera import Framing
from render.sketch import SketchRenderer
from weberpenn import species
from weberpenn.controls import CONTROLS, Control, current, grow_with_controls

ROOT = Path(__file__).resolve().parents[1]

LABEL_W = 190


def row_values(c: Control, own: Any) -> list[Any]:
    """Five values of a control: its range's ends, the tree's own value in the middle."""
    if c.kind == "toggle":
        return [True, False]
    if c.kind == "choice":
        return [v for v, _ in c.choices if v in ("0", "1", "3", "5", "6")] + [own]
    if c.name == "seed":
        return [own, own + 1, own + 2, own + 3, own + 4]
    if c.name == "height":
        return [own * f for f in (0.5, 0.75, 1.0, 1.25, 1.5)]
    lo, hi = c.lo, c.hi
    mid = own
    return [lo, (lo + mid) / 2, mid, (mid + hi) / 2, hi]


def caption(c: Control, v: Any) -> str:
    if c.kind == "toggle":
        return "leafy" if v else "bare"
    if c.kind == "choice":
        return dict(c.choices)[v][:18]
    if c.name == "seed":
        return f"seed {v}"
    if c.name == "height":
        return f"{v:.1f} m"
    return f"{v:g}{c.unit}" if c.unit == "x" else f"{v:+g}{c.unit}"


TRUNK_ROWS = ("trunk_lean", "trunk_bend")  # shown on a single-trunk species (--trunk-species)


def make_grid(name: str, seed: int, tile: int, trunk_species: str) -> Image.Image:
    trees = {n: species.sample(n, seed) for n in {name, trunk_species}}
    owns = {n: current(t) for n, t in trees.items()}
    cols = 5
    cap = 16
    grid = Image.new("RGB", (LABEL_W + cols * tile, len(CONTROLS) * (tile + cap)), "white")
    draw = ImageDraw.Draw(grid)
    for r, c in enumerate(CONTROLS):
        row_species = trunk_species if c.name in TRUNK_ROWS else name
        base = trees[row_species]
        values = row_values(c, owns[row_species][c.name])
        meshes = [grow_with_controls(base, {c.name: v}, row_species)[1] for v in values]
        framing = Framing.from_parts(
            [m.branches.vertices for m in meshes]
            + [m.leaves.vertices for m in meshes if len(m.leaves.vertices)]
        )
        y = r * (tile + cap)
        side = ", side view" if c.name in TRUNK_ROWS else ""
        draw.text((6, y + 8), f"{c.label} ({row_species}{side})", fill=(20, 40, 25))
        for k, line in enumerate(_wrap(c.help, 30)[:5]):
            draw.text((6, y + 26 + 13 * k), line, fill=(90, 100, 95))
        for i, (v, m) in enumerate(zip(values, meshes, strict=True)):
            # a trunk bends across the front view's line of sight: seen from the side
            view = "left" if c.name in TRUNK_ROWS else "front"
            img = SketchRenderer(m, framing=framing, species=row_species).colour(view, tile)
            x = LABEL_W + i * tile
            grid.paste(Image.fromarray(np.asarray(img)), (x, y + cap))
            draw.text((x + 4, y + 2), caption(c, v), fill=(30, 30, 30))
        draw.line([(0, y), (grid.width, y)], fill=(200, 200, 200))
    return grid


def _wrap(text: str, width: int) -> list[str]:
    lines, line = [], ""
    for word in text.split():
        if len(line) + len(word) + 1 > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}".strip()
    return [*lines, line] if line else lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--species", default="maple", choices=species.SPECIES)
    ap.add_argument("--trunk-species", default="palm", choices=species.SPECIES)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--tile", type=int, default=150)
    ap.add_argument("--out", default=str(ROOT / "docs" / "controls.png"))
    args = ap.parse_args()
    grid = make_grid(args.species, args.seed, args.tile, args.trunk_species)
    write_palette_png(grid, args.out)


if __name__ == "__main__":
    main()
