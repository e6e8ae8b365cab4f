"""How near do the code-made pairs' drawn trees themselves come to their own drawings?

``bench_drawings.py --part follow --only pairs`` scores the returned tree's envelope
overlap with each drawing of a pair (front, side).  The doodle style draws a crown's
outline in broken strokes, so a drawn envelope can be a part of the tree's.  This probe
scores, on the same drawings, the tree that was drawn (the ground truth, at the drawn
views, framed as drawn): the overlap a tree exactly like the drawn one gets.  With a
run's JSON (and its ``.npz`` of prepared drawings), also the returned tree's outline
against the drawn tree's own at each view (does a narrow side stay narrow, measured on
the tree rather than on its strokes).

    .venv/bin/python benchmarks/bench_drawings.py --part follow --only pairs --pairs 3 \\
        --json RUN.json
    .venv/bin/python benchmarks/probes/pairs_truth.py RUN.json
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
    ap.add_argument("run", type=Path, help="a pairs run's JSON (its .npz beside it)")
    args = ap.parse_args(argv)

    from bench_drawings import tree_drawings

    from eval.envelope import envelope_overlap
    from render.sketch import SketchRenderer
    from treesketch.steps import SKETCH_SIZE, as_drawn
    from weberpenn import TreeParams, build_mesh, grow

    run = json.loads(args.run.read_text())
    drawn = np.load(args.run.with_suffix(".npz"))
    returned = {r["name"]: r for r in run["records"] if r["name"].startswith("pairs/")}
    a = run["args"]
    if not returned:
        raise SystemExit(f"{args.run} holds no pairs")

    def sketches(params: TreeParams, species: str, yaws: list[float]) -> list[np.ndarray]:
        r = SketchRenderer(build_mesh(grow(params)), species=species)
        return [as_drawn(r.sketch(y % 360.0, SKETCH_SIZE)) for y in yaws]

    rows = []
    for d in tree_drawings(int(a["first_seed"]), int(a["pairs"]), side=True, style="doodle"):
        name = f"pairs/{d['name']}"
        if name not in returned:
            continue
        keys = [f"{name}/input_sketch", f"{name}/view2/input_sketch"]
        truth = sketches(d["params"], d["species"], [d["yaw"], d["yaw"] + 90.0])
        own = [envelope_overlap(drawn[k], t) for k, t in zip(keys, truth, strict=True)]
        rec = returned[name]
        got = sketches(TreeParams(rec["params"]), rec["species"], [rec["yaw"], rec["yaw"] + 90.0])
        vs_truth = [envelope_overlap(t, g) for t, g in zip(truth, got, strict=True)]
        rows.append((name, own, rec["view_overlaps_after"], vs_truth))
        print(
            f"{name:>20}  drawn tree {own[0]:.3f} {own[1]:.3f}  returned "
            f"{rec['view_overlaps_after'][0]:.3f} {rec['view_overlaps_after'][1]:.3f}  "
            f"returned against the drawn tree {vs_truth[0]:.3f} {vs_truth[1]:.3f}",
            flush=True,
        )
    for i, view in enumerate(("fronts", "sides")):
        med = [statistics.median(r[j][i] for r in rows) for j in (1, 2, 3)]
        print(
            f"{view}, {len(rows)} pairs, medians: the drawn tree against its drawing "
            f"{med[0]:.4f}, the returned tree against the drawing {med[1]:.4f}, "
            f"the returned tree against the drawn tree {med[2]:.4f}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
