"""docs/follow.png: does the tree follow the drawing? (issue 48)

24 drawings (held-out people's tree drawings, ``eval.people``, and the paper's five as
published, ``benchmarks/bench_drawings.py``'s ``paper_drawings``) through the default
pipeline; for each: the prepared drawing, both outlines overlaid (``eval.envelope``: the
drawing's in red, the returned tree's in blue, over the tree's sketch, with the first
estimate's and the returned tree's overlap) and the 3D tree at the drawn view.

    PYTHONPATH=$PWD nice -n 5 .venv/bin/python scripts/make_follow_png.py [--people 19]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from docs_png import write_palette_png
from PIL import Image, ImageDraw

from benchmarks.bench_drawings import paper_drawings
from eval.envelope import envelope_overlap
from eval.people import people_drawings
from refine.envelope import outlines_rgb
from render.sketch import SketchRenderer
from treesketch import Pipeline

ROOT = Path(__file__).resolve().parents[1]
CAP = 14  # pixels of caption above each row


def cases(people: int) -> list[tuple[str, np.ndarray]]:
    held = people_drawings("held", ("strokes",), ("tree",))[:people]
    out = [(f"people {i}", d.image()) for i, d in enumerate(held)]
    return out + [(n.replace("paper/", "paper "), img) for n, img in paper_drawings()[::2]]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--people", type=int, default=19)
    ap.add_argument("--columns", type=int, default=4)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "follow.png")
    args = ap.parse_args(argv)
    pipe = Pipeline("tsn")
    s, cols = args.size, args.columns
    todo = cases(args.people)
    rows = -(-len(todo) // cols)
    sheet = Image.new("RGB", (3 * s * cols, rows * (s + CAP)), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (name, img) in enumerate(todo):
        res = pipe.run(img)
        o0 = envelope_overlap(res.input_sketch, res.sketch_before)
        o1 = envelope_overlap(res.input_sketch, res.sketch_after)
        tree = SketchRenderer(res.tree_mesh).colour(res.yaw, 256, supersample=2)
        panels = [
            np.repeat(np.asarray(res.input_sketch)[..., None], 3, axis=2),
            outlines_rgb(res.input_sketch, res.sketch_after),
            np.asarray(tree, np.uint8),
        ]
        x, y = (k % cols) * 3 * s, (k // cols) * (s + CAP)
        for j, p in enumerate(panels):
            im = Image.fromarray(np.asarray(p, np.uint8)).convert("RGB").resize((s, s))
            sheet.paste(im, (x + j * s, y + CAP))
        draw.text((x + 2, y + 1), f"{name}: {res.species}", fill=(0, 0, 0))
        draw.text((x + s + 2, y + 1), f"overlap {o0:.2f} -> {o1:.2f}", fill=(0, 0, 160))
        print(f"{name}: {res.species} overlap {o0:.3f} -> {o1:.3f}", flush=True)
    write_palette_png(sheet, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
