"""Drawings by people TreeSketch never learned from, and what it makes of each: docs/people.png.

    nice -n 10 .venv/bin/python scripts/make_people_png.py [--out docs/people.png] [--budget 40]

48 drawings of held-out authors (``eval.people``, part ``held``: never trained, fitted or
calibrated on), taken in the folders' order, not picked: 24 trees (8 from each source) and
24 other things (3 of each of 8 kinds, from every source that has them).  Each runs through
the whole ``Pipeline`` at the default settings; a cell shows the drawing, the tree's colour
render at the drawn view and what the page would say: the species, or the question "is this
a tree?" when the drawing is warned.  A tree reads right when it is not warned and is not
read as a palm, bonsai or pine (a person's "tree" is none of these unless drawn as one); any
other thing reads right when it is warned.  ``--json`` writes each result's summary.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from eval.people import PeopleDrawing, people_drawings
from weberpenn.fileio import atomic_target, atomic_write

ROOT = Path(__file__).resolve().parents[1]
ODD_FOR_A_TREE = ("palm", "bonsai", "pine")
OTHER_KINDS = (
    ("strokes", "bicycle"), ("strokes", "guitar"), ("strokes", "fish"), ("strokes", "house"),
    ("mouse224", "person"), ("mouse224", "house"), ("quickdraw28", "flower"),
    ("quickdraw28", "cat"),
)  # fmt: skip
PER_ROW, TILE, LABEL = 4, 150, 34  # a cell: the drawing and the tree, side by side


def chosen() -> list[PeopleDrawing]:
    """The 48 drawings, in the folders' order."""
    held = people_drawings(part="held", per_kind=8)
    trees = [d for d in held if d.is_tree]
    others = []
    for source, kind in OTHER_KINDS:
        others += [d for d in held if d.source == source and d.kind == kind][:3]
    return trees + others


def _tile(img: np.ndarray) -> Image.Image:
    im = Image.fromarray(np.asarray(img)).convert("RGB")
    im.thumbnail((TILE, TILE))
    tile = Image.new("RGB", (TILE, TILE), (255, 255, 255))
    tile.paste(im, ((TILE - im.size[0]) // 2, (TILE - im.size[1]) // 2))
    return tile


def main(argv: list[str] | None = None) -> int:
    from render.sketch import SketchRenderer
    from treesketch import Pipeline, RefineSettings, load_sketch

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "people.png")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    pipe = Pipeline("tsn", RefineSettings(budget=args.budget))
    drawings = chosen()
    cell_w, cell_h = 2 * TILE, TILE + LABEL
    sheet = Image.new("RGB", (PER_ROW * cell_w, -(-len(drawings) // PER_ROW) * cell_h), "white")
    d = ImageDraw.Draw(sheet)
    font = ImageFont.load_default(size=12)
    results = []
    for i, dr in enumerate(drawings):
        img = load_sketch(dr.image())
        res = pipe.run(img)
        colour = SketchRenderer(res.tree_mesh, species=res.species).colour(res.yaw, 256)
        warned = res.warning is not None
        right = (not warned and res.species not in ODD_FOR_A_TREE) if dr.is_tree else warned
        x, y = (i % PER_ROW) * cell_w, (i // PER_ROW) * cell_h
        sheet.paste(_tile(img), (x, y))
        sheet.paste(_tile(colour), (x + TILE, y))
        said = "is this a tree?" if warned else res.species
        d.text((x + 4, y + TILE + 2), f"{dr.source} {dr.kind}", fill="black", font=font)
        d.text(
            (x + 4, y + TILE + 17),
            f"-> {said}",
            fill=(0, 110, 0) if right else (190, 0, 0),
            font=font,
        )
        d.rectangle((x, y, x + cell_w - 1, y + cell_h - 1), outline=(200, 200, 200))
        summary = {"drawing": dr.name, "kind": dr.kind, "warned": warned, "right": right}
        results.append({**summary, "species": res.species, "confidence": res.confidence})
        print(f"{dr.name}: {said} ({'right' if right else 'wrong'})", flush=True)
    with atomic_target(args.out) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)
    trees = [r for r in results if r["kind"] == "tree"]
    others = [r for r in results if r["kind"] != "tree"]
    print(
        f"trees read right {sum(r['right'] for r in trees)} of {len(trees)}; other things "
        f"warned {sum(r['right'] for r in others)} of {len(others)}; wrote {args.out}"
    )
    if args.json is not None:
        atomic_write(args.json, json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
