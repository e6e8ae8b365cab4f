"""docs/follow.png: does the tree follow the drawing? (issue 48)

24 drawings (held-out people's tree drawings, ``eval.people``, and the paper's five as
published, ``benchmarks/bench_drawings.py``'s ``paper_drawings``) through the default
pipeline; for each: the prepared drawing, both outlines overlaid (``eval.envelope``: the
drawing's in red, the returned tree's in blue, over the tree's sketch, with the first
estimate's and the returned tree's overlap) and the 3D tree at the drawn view.

    PYTHONPATH=$PWD nice -n 5 .venv/bin/python scripts/make_follow_png.py [--people 19]
    # or from a run of benchmarks/bench_drawings.py --part follow --json F.json (its
    # sketches in F.npz, its trees regrown from their params): no pipeline run
    ... scripts/make_follow_png.py --from F.json
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
    out = [(f"people/{i:02d}", d.image()) for i, d in enumerate(held)]
    return out + paper_drawings()[::2]


def from_run(path: Path, people: int) -> list[dict]:
    """A follow run's first ``people`` people's drawings and the paper's five as
    published: their sketches, species, params and yaw."""
    import json

    recs = json.loads(path.read_text())["records"]
    sk = np.load(path.with_suffix(".npz"))
    keep = [r for r in recs if r["name"].startswith("people/")][:people]
    keep += [r for r in recs if r["name"].startswith("paper/") and "pencil" not in r["name"]]
    return [
        r | {k: sk[f"{r['name']}/{k}"] for k in ("input_sketch", "sketch_before", "sketch_after")}
        for r in keep
    ]


def tree_picture(params: dict, species: str, yaw: float) -> np.ndarray:
    from weberpenn import TreeParams, build_mesh, grow

    mesh = build_mesh(grow(TreeParams(params)), species=species)
    return SketchRenderer(mesh).colour(yaw, 256, supersample=2)


def run_all(people: int) -> list[dict]:
    """The pipeline on :func:`cases`: the same fields as :func:`from_run`."""
    pipe = Pipeline("tsn")
    out = []
    for name, img in cases(people):
        res = pipe.run(img)
        out.append(
            {
                "name": name,
                "species": res.species,
                "yaw": res.yaw,
                "params": res.params.to_dict(),
                "input_sketch": res.input_sketch,
                "sketch_before": res.sketch_before,
                "sketch_after": res.sketch_after,
            }
        )
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--people", type=int, default=19)
    ap.add_argument("--columns", type=int, default=4)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--from", dest="run", type=Path, default=None, help="a follow run's JSON")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "follow.png")
    args = ap.parse_args(argv)
    todo = from_run(args.run, args.people) if args.run else run_all(args.people)
    s, cols = args.size, args.columns
    rows = -(-len(todo) // cols)
    sheet = Image.new("RGB", (3 * s * cols, rows * (s + CAP)), "white")
    draw = ImageDraw.Draw(sheet)
    for k, r in enumerate(todo):
        o0 = envelope_overlap(r["input_sketch"], r["sketch_before"])
        o1 = envelope_overlap(r["input_sketch"], r["sketch_after"])
        panels = [
            np.repeat(np.asarray(r["input_sketch"])[..., None], 3, axis=2),
            outlines_rgb(r["input_sketch"], r["sketch_after"]),
            tree_picture(r["params"], r["species"], r["yaw"]),
        ]
        x, y = (k % cols) * 3 * s, (k // cols) * (s + CAP)
        for j, p in enumerate(panels):
            im = Image.fromarray(np.asarray(p, np.uint8)).convert("RGB").resize((s, s))
            sheet.paste(im, (x + j * s, y + CAP))
        label = r["name"].split("-")[0].replace("/", " ")
        draw.text((x + 2, y + 1), f"{label}: {r['species']}", fill=(0, 0, 0))
        draw.text((x + s + 2, y + 1), f"overlap {o0:.2f} -> {o1:.2f}", fill=(0, 0, 160))
        print(f"{label}: {r['species']} overlap {o0:.3f} -> {o1:.3f}", flush=True)
    write_palette_png(sheet, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
