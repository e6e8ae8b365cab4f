"""What the time limit buys: one refinement with the fast sketch and with the full one.

    .venv/bin/python benchmarks/probes/refine_speed.py [--time-limit 15] [--species cherry bonsai maple]

For each species: the truth is ``species.sample(name, 1)`` seen from the front (its full
128 px sketch), the start is another tree of the species (``species.sample(name, 2)``),
and ``refine`` runs under ``--time-limit`` seconds (budget 10,000, so time stops it)
twice, with ``RefineSettings(fast_sketch=True)`` and ``False``.  Reported: evaluations,
evaluations per second, the sketch distance before and after (both measured by the
objective the run used), and the distance of the result to the target measured the
same way for both, on the full sketch (``metric_distance``).
"""

from __future__ import annotations

import argparse

from refine.objective import metric_distance
from refine.search import RefineSettings, refine
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, species


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--time-limit", type=float, default=15.0)
    ap.add_argument("--species", nargs="*", default=["cherry", "bonsai", "maple"])
    args = ap.parse_args()
    print(
        "| species | sketch | evaluations | per second | distance before | after "
        "| result on the full sketch | stopped by |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---|")
    for name in args.species:
        truth = build_mesh(grow(species.sample(name, 1)), species=name)
        target = SketchRenderer(truth).sketch(0.0, 128)
        start = species.sample(name, 2)
        for fast in (True, False):
            cfg = RefineSettings(budget=10_000, time_limit=args.time_limit, fast_sketch=fast)
            r = refine(target, start, cfg, species=name)
            got = SketchRenderer(build_mesh(grow(r.params), species=name)).sketch(r.yaw, 128)
            print(
                f"| {name} | {'fast' if fast else 'full'} | {r.evaluations} | "
                f"{r.evaluations / r.seconds:.1f} | {r.loss_before:.4f} | {r.loss_after:.4f} | "
                f"{metric_distance(target, got, 128):.4f} | {r.stopped_by} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
