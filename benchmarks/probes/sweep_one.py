"""The rotation sweep of one published tree at the report's sizes, printed per angle.

    .venv/bin/python benchmarks/probes/sweep_one.py 3_palm_3.json [--turn 90] [--budget 24]

The same sweep ``make reports`` makes for the first published tree of each species
(``eval.paper.sweep_both``: every 30 degrees, the published tree's seed, 10 000 Hausdorff
samples, refined at ``--budget`` with no time limit), for one tree and one run: refined
from the swept sketch alone, or with ``--turn 90`` from it and the sketch 90 degrees
further round.  It prints the mean, the median, the worst angle over the median and the
normalised max distance at each angle, so a change to the refinement can be tried on one
tree in a few minutes instead of the whole report (run it in a worktree of each side).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from eval.paper import PUBLISHED_DIR
from eval.rotation import rotation_sweep
from treesketch import Pipeline
from treesketch.estimators import SeededEstimator, TSNEstimator
from weberpenn.params import load_params


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tree", help="a file of tests/data/treesketchnet_test_params")
    ap.add_argument("--turn", type=float, action="append", default=[])
    ap.add_argument("--budget", type=int, default=24)
    ap.add_argument("--step", type=float, default=30.0)
    args = ap.parse_args(argv)
    gt = load_params(PUBLISHED_DIR / args.tree)
    seed = int(gt["seed"])
    pipe = Pipeline(SeededEstimator(TSNEstimator.load(), seed)).with_settings(
        refine=True, budget=args.budget, time_limit=None
    )
    t = time.perf_counter()
    res = rotation_sweep(
        gt, pipe, step=args.step, size=256, samples=10_000, seed=seed, turns=tuple(args.turn)
    )
    v = res.values()
    print(
        f"{args.tree}: mean {v.mean():.4f}, median {np.median(v):.4f}, worst/median "
        f"{v.max() / np.median(v):.2f} ({time.perf_counter() - t:.0f} s)"
    )
    print("  ".join(f"{r.angle:.0f}: {x:.3f}" for r, x in zip(res.rows, v, strict=True)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
