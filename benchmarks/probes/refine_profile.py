"""Where does a refinement's time go? cProfile of the default pipeline on people's drawings.

Runs ``Pipeline("tsn")`` (default settings) on ``--people`` held-out people's tree drawings
from ``--from`` (``bench_drawings.py --part follow``'s cases; one run first, unprofiled, to
load the network and compile the rasteriser) and prints the seconds per drawing and the
functions by cumulative time.

    .venv/bin/python benchmarks/probes/refine_profile.py --people 6 --from 20 --top 45 [--sort tottime]
    .venv/bin/python benchmarks/probes/refine_profile.py --people 6 --from 20 --repeats
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from benchmarks.bench_drawings import follow_cases
from treesketch import Pipeline, RefineSettings


def count_repeats(pipe: Pipeline, images: list) -> None:
    """Runs ``pipe`` on ``images`` with every start of a tree's growth (``growing``: whole
    trees and the liveness probes' first levels) counted by its values and seed."""
    import collections
    import importlib
    import json

    grow = importlib.import_module("weberpenn.grow")
    seen: collections.Counter[str] = collections.Counter()
    real = grow.growing

    def counted(params, seed=0):  # noqa: ANN001, ANN202 - the generator it stands in for
        key = json.dumps(dict(grow.validate(params)), sort_keys=True, default=str)
        seen[f"{key}/{seed}"] += 1
        return (yield from real(params, seed))

    grow.growing = counted
    try:
        for img in images:
            pipe.run(img)
    finally:
        grow.growing = real
    total = sum(seen.values())
    print(f"{total} trees grown, {total - len(seen)} of them again with the same values")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=6)
    ap.add_argument("--from", dest="start", type=int, default=20)
    ap.add_argument("--top", type=int, default=45)
    ap.add_argument("--sort", default="cumulative", choices=["cumulative", "tottime"])
    ap.add_argument(
        "--repeats",
        action="store_true",
        help="instead: count the trees grown more than once with the same values",
    )
    args = ap.parse_args()
    cases = follow_cases(
        argparse.Namespace(
            only="people", people=args.people, people_from=args.start, pairs=0, hand=False
        )
    )
    pipe = Pipeline("tsn", RefineSettings())
    pipe.run(cases[0][1])
    if args.repeats:
        count_repeats(pipe, [img for _, img in cases])
        return
    profile = cProfile.Profile()
    t = time.perf_counter()
    profile.enable()
    for _, img in cases:
        pipe.run(img)
    profile.disable()
    print(f"{(time.perf_counter() - t) / len(cases):.2f} s per drawing (profiled)")
    pstats.Stats(profile).sort_stats(args.sort).print_stats(args.top)


if __name__ == "__main__":
    main()
