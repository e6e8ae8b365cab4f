"""How near do the code-made pairs' drawn trees themselves come to their own drawings?

``bench_drawings.py --part follow --only pairs`` scores the returned tree's envelope
overlap with each drawing of a pair (front, side).  The doodle style draws a crown's
outline in broken strokes, so a drawn envelope can be a part of the tree's.  This probe
scores, on the same drawings (prepared as the pipeline prepares them), the tree that was
drawn (the ground truth, at the drawn views, framed as drawn): the overlap a tree exactly
like the drawn one gets.  Given a run's JSON, also the returned tree's outline against the
drawn tree's own at each view (does a narrow side stay narrow, measured on the tree rather
than on its strokes).

    .venv/bin/python benchmarks/bench_drawings.py --part follow --only pairs --pairs 3 \\
        --json RUN.json
    .venv/bin/python benchmarks/probes/pairs_truth.py --run RUN.json
    .venv/bin/python benchmarks/probes/pairs_truth.py --pairs 10 --first-seed 950
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--run", type=Path, default=None, help="a pairs run's JSON")
    ap.add_argument("--pairs", type=int, default=3, help="per species, without --run")
    ap.add_argument("--first-seed", type=int, default=950, help="without --run")
    args = ap.parse_args(argv)

    from bench_drawings import tree_drawings

    from eval.envelope import envelope_overlap
    from render.sketch import SketchRenderer
    from treesketch.steps import SKETCH_SIZE, as_drawn, prepare_input
    from weberpenn import TreeParams, build_mesh, grow

    returned: dict[str, dict] = {}
    first, per = args.first_seed, args.pairs
    if args.run is not None:
        run = json.loads(args.run.read_text())
        returned = {r["name"]: r for r in run["records"] if r["name"].startswith("pairs/")}
        if not returned:
            raise SystemExit(f"{args.run} holds no pairs")
        first, per = int(run["args"]["first_seed"]), int(run["args"]["pairs"])

    def sketches(params: TreeParams, species: str, yaw: float) -> list[np.ndarray]:
        r = SketchRenderer(build_mesh(grow(params)), species=species)
        return [as_drawn(r.sketch(y % 360.0, SKETCH_SIZE)) for y in (yaw, yaw + 90.0)]

    rows = []
    for d in tree_drawings(first, per, side=True, style="doodle"):
        name = f"pairs/{d['name']}"
        if args.run is not None and name not in returned:
            continue
        drawn = [as_drawn(prepare_input(img)) for img in (d["image"], d["side"])]
        truth = sketches(d["params"], d["species"], d["yaw"])
        own = [envelope_overlap(a, t) for a, t in zip(drawn, truth, strict=True)]
        line = f"{name:>20}  drawn tree {own[0]:.3f} {own[1]:.3f}"
        if name in returned:
            rec = returned[name]
            got = sketches(TreeParams(rec["params"]), rec["species"], rec["yaw"])
            after = rec["view_overlaps_after"]
            vs_truth = [envelope_overlap(t, g) for t, g in zip(truth, got, strict=True)]
            rows.append((name, own, after, vs_truth))
            line += f"  returned {after[0]:.3f} {after[1]:.3f}"
            line += f"  returned against the drawn tree {vs_truth[0]:.3f} {vs_truth[1]:.3f}"
        else:
            rows.append((name, own))
        print(line, flush=True)
    for i, view in enumerate(("fronts", "sides")):
        med = [statistics.median(r[j][i] for r in rows) for j in range(1, len(rows[0]))]
        line = (
            f"{view}, {len(rows)} pairs, medians: the drawn tree against its drawing {med[0]:.4f}"
        )
        if len(med) > 1:
            line += f", the returned tree against the drawing {med[1]:.4f}"
            line += f", the returned tree against the drawn tree {med[2]:.4f}"
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
