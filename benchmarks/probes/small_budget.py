"""How long does a whole run take at a small refinement budget (the page's quick tries, the
Blender add-on's preview, the tests)?

Runs the default pipeline (``Pipeline("tsn", RefineSettings(budget=B))``) on each drawing
of ``--drawings`` (``examples/hand`` by default, the first ``--count``) at each budget,
after one run to warm up, and prints the mean seconds per run, each drawing's refinement
seconds, the species and the outline step's trees.  Run it in a worktree of each code in
turn (``PYTHONPATH=$PWD``) to compare two codes on one machine.

    .venv/bin/python benchmarks/probes/small_budget.py [--budgets 2,6] [--count 4]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from treesketch import Pipeline, RefineSettings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--drawings", type=Path, default=Path("examples/hand"))
    ap.add_argument("--count", type=int, default=4)
    ap.add_argument("--budgets", default="2,6", help="comma-separated budgets")
    args = ap.parse_args()
    drawings = sorted(args.drawings.glob("*.png"))[: args.count]
    if not drawings:
        raise SystemExit(f"no PNG drawings in {args.drawings}")
    for budget in (int(b) for b in args.budgets.split(",")):
        pipe = Pipeline("tsn", RefineSettings(budget=budget))
        pipe.run(str(drawings[0]))  # loads the network and compiles the rasteriser
        t0 = time.perf_counter()
        results = [pipe.run(str(d)) for d in drawings]
        per_run = (time.perf_counter() - t0) / len(drawings)
        refine = " ".join(f"{r.timings['refine']:.2f}" for r in results)
        outline = [r.refinement.outline_evaluations for r in results if r.refinement]
        species = " ".join(r.species for r in results)
        print(
            f"budget {budget}: {per_run:.2f} s a run; refinement {refine} s; outline step "
            f"trees {outline}; species {species}",
            flush=True,
        )


if __name__ == "__main__":
    main()
