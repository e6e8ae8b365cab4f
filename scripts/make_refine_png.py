"""docs/refine.png: one held-out sketch per species: the input, the first estimate's
sketch (TSN, or the perturbed ground truth with ``--estimator perturbed``), the refined
tree's sketch, and the ground truth's sketch and colour render.

    .venv/bin/python scripts/make_refine_png.py --data /work/data/ds_v1 --out docs/refine.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from benchmarks.bench_refine import KnownStart, perturbed, pick_rows
from render.reader import read_sketch
from render.sketch import SketchRenderer
from treesketch import Pipeline, RefineSettings, load_estimator
from weberpenn import build_mesh, grow, load_params, species
from weberpenn.fileio import atomic_write

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str] | None = None) -> int:
    from PIL import Image, ImageDraw

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("/work/data/ds_v1"))
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "refine.png")
    ap.add_argument("--estimator", choices=("tsn", "perturbed"), default="tsn")
    ap.add_argument("--budget", type=int, default=RefineSettings().budget)
    ap.add_argument("--size", type=int, default=160)
    args = ap.parse_args(argv)

    inner = load_estimator("tsn") if args.estimator == "tsn" else None
    settings = RefineSettings(budget=args.budget)
    s = args.size
    first = "TSN" if inner is not None else "perturbed GT"
    titles = ["input sketch", first, "refined", "ground truth", "GT render"]
    cap = 16
    sheet = Image.new("RGB", (s * len(titles), cap + s * len(species.SPECIES)), "white")
    draw = ImageDraw.Draw(sheet)
    for j, t in enumerate(titles):
        draw.text((j * s + 4, 2), t, fill=(0, 0, 0))
    rows = pick_rows(args.data, 1)
    for i, row in enumerate(rows):
        name = row["species"]
        img = read_sketch(args.data / row["sketch"])
        gt = load_params(args.data / row["params"])
        if inner is None:
            est = KnownStart(None, perturbed(name, gt, 0.25, i), name)
        else:
            est = KnownStart(inner)
        run = Pipeline(est, settings).run(img)
        r, start, guessed = run.refinement, run.estimate.params, run.species
        gt_r = SketchRenderer(build_mesh(grow(gt), species=name))
        panels = [
            img,
            SketchRenderer(build_mesh(grow(start), species=guessed)).sketch(r.start_yaw, 256),
            SketchRenderer(build_mesh(grow(r.params), species=guessed)).sketch(r.yaw, 256),
            gt_r.sketch(row["yaw"], 256),
            gt_r.colour(row["yaw"], 256, supersample=2),
        ]
        y = cap + i * s
        for j, p in enumerate(panels):
            im = Image.fromarray(np.asarray(p, np.uint8)).convert("RGB").resize((s, s))
            sheet.paste(im, (j * s, y))
        draw.text((4, y + 2), f"{name} {row['view']}", fill=(200, 0, 0))
        draw.text((s + 4, y + s - 12), f"loss {r.loss_before:.3f}", fill=(0, 0, 160))
        draw.text((2 * s + 4, y + s - 12), f"loss {r.loss_after:.3f}", fill=(0, 0, 160))
        print(f"{name}: {r.loss_before:.4f} -> {r.loss_after:.4f} ({r.evaluations} ev)", flush=True)
    atomic_write(args.out, lambda tmp: sheet.save(tmp, format="PNG", optimize=True))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
