"""Probe: is the network's first estimate worse for a tree drawn at a yaw it was not
trained at?

The shipped network was trained on sketches from the four square-on views (front, left,
back, right: yaw 0/90/180/270). For fresh trees of every species (seeds from ``--first-seed``,
none in a dataset or benchmark), each SG-drawn at square-on yaws and at yaws between them,
this prints the first estimate's values error (the RMSE of the normalised encoding over
all its values; ``treesketch eval tsn`` scores 1 minus it per head) and its mesh error
(the estimate grown with the truth's seed key, not turned: the rotation sweep's "alone"),
per group of yaws.

    .venv/bin/python benchmarks/probes/yaw_gap.py [--per-species 3] [--checkpoint PT] [--json F]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from eval.hausdorff import hausdorff
from render.sketch import SketchRenderer
from treesketch import Pipeline
from tsn import encoding
from tsn.predict import load_model
from weberpenn import build_mesh, grow, species

SQUARE = (0.0, 90.0, 180.0, 270.0)
BETWEEN = (30.0, 45.0, 60.0, 135.0, 210.0, 300.0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-species", type=int, default=3)
    ap.add_argument("--first-seed", type=int, default=20000)
    ap.add_argument("--checkpoint", default=None)
    ap.add_argument("--species", default=",".join(species.SPECIES))
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    pipe = Pipeline("tsn" if args.checkpoint is None else args.checkpoint)
    norm = load_model(args.checkpoint).normaliser
    rows = []
    t0 = time.perf_counter()
    for name in args.species.split(","):
        for k in range(args.per_species):
            seed = args.first_seed + k
            gt = species.sample(name, seed=seed)
            mesh = build_mesh(grow(gt), species=name)
            truth = norm.normalise(encoding.encode(gt))
            r = SketchRenderer(mesh, species=name)
            for yaw in SQUARE + BETWEEN:
                est = pipe.estimate(r.sketch(yaw, size=256))
                err = norm.normalise(encoding.encode(est.params)) - truth
                # grown with the truth's own seed key, as the rotation sweep grows its trees
                same_seed = est.params.replace(seed=gt["seed"])
                h = hausdorff(build_mesh(grow(same_seed)).combined(), mesh.combined(), args.samples)
                rows.append(
                    {"species": name, "seed": seed, "yaw": yaw, "square": yaw in SQUARE,
                     "rmse": float(np.sqrt(np.mean(err**2))), "mesh": h.max_norm,
                     "species_est": est.species}
                )  # fmt: skip
            print(f"{name}{seed} done {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    for group, keep in (("square-on", True), ("between", False)):
        g = [r for r in rows if r["square"] == keep]
        print(
            f"{group:10s} n={len(g):3d} values rmse {statistics.mean(r['rmse'] for r in g):.4f}"
            f"  mesh {statistics.mean(r['mesh'] for r in g):.4f}"
            f"  species right {sum(r['species'] == r['species_est'] for r in g)}/{len(g)}"
        )
    for name in args.species.split(","):
        parts = []
        for keep in (True, False):
            g = [r for r in rows if r["species"] == name and r["square"] == keep]
            rmse, mesh = (statistics.mean(r[k] for r in g) for k in ("rmse", "mesh"))
            parts.append(f"{rmse:.4f}/{mesh:.4f}")
        print(f"  {name:8s} square-on {parts[0]}  between {parts[1]}  (values rmse/mesh)")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
