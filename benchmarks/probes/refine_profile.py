"""Where does a refinement's time go? cProfile of the default pipeline on people's drawings.

Runs ``Pipeline("tsn")`` (default settings) on ``--people`` held-out people's tree drawings
from ``--from`` (``bench_drawings.py --part follow``'s cases; one run first, unprofiled, to
load the network and compile the rasteriser) and prints the seconds per drawing and the
functions by cumulative time.

    .venv/bin/python benchmarks/probes/refine_profile.py --people 6 --from 20 --top 45
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import time

from benchmarks.bench_drawings import follow_cases
from treesketch import Pipeline, RefineSettings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=6)
    ap.add_argument("--from", dest="start", type=int, default=20)
    ap.add_argument("--top", type=int, default=45)
    args = ap.parse_args()
    cases = follow_cases(
        argparse.Namespace(
            only="people", people=args.people, people_from=args.start, pairs=0, hand=False
        )
    )
    pipe = Pipeline("tsn", RefineSettings())
    pipe.run(cases[0][1])
    profile = cProfile.Profile()
    t = time.perf_counter()
    profile.enable()
    for _, img in cases:
        pipe.run(img)
    profile.disable()
    print(f"{(time.perf_counter() - t) / len(cases):.2f} s per drawing (profiled)")
    pstats.Stats(profile).sort_stats("cumulative").print_stats(args.top)


if __name__ == "__main__":
    main()
