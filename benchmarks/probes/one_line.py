"""Probe: how thin are people's drawings? (``treesketch.pipeline.LINE_SPREAD``)

Reads the held part of people's drawings (``eval.people``, authors never fitted on) as the
pipeline does and measures each one's ``render.reader.line_spread`` (the ink's spread
across its longest axis over its reach; a straight line drawn by hand about 0.005).
Prints, per source and kind, how many are at or under ``--limit``, the thinnest trees,
the share of trees among the drawings that thin (the probability a drawing of one line is
a tree: ``treesketch.pipeline.LINE_TREES``), and which of them the network's detector had
left unwarned (what the rule adds to ``bench_species.py people``'s figures).

    .venv/bin/python benchmarks/probes/one_line.py [--limit 0.03] [--per-kind 400]
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def held_inks(per_kind: int) -> tuple[list, list]:
    """People's held-out drawings (``eval.people``) and, for each the pipeline reads, its
    (index, ink as the pipeline reads and frames it)."""
    from eval.people import SOURCES, people_drawings
    from render.reader import SketchError, ink_mask
    from treesketch.pipeline import load_sketch, prepare_input

    drawings = people_drawings(part="held", sources=SOURCES, per_kind=per_kind)
    inks = []
    for i, d in enumerate(drawings):
        try:
            inks.append((i, ink_mask(prepare_input(load_sketch(d.image())))))
        except SketchError:
            continue
    return drawings, inks


def detector_says(drawings: list, indices: list[int], label: Callable[[int], str]) -> None:
    """What the network's detector says of each of ``drawings[indices]`` (what a rule adds
    to ``bench_species.py people``, which measures the detector alone)."""
    from treesketch import Pipeline
    from treesketch.pipeline import TREE_PROBABILITY_LIMIT, load_sketch

    pipeline = Pipeline()
    for i in sorted(indices):
        d = drawings[i]
        p = pipeline.estimate(load_sketch(d.image())).tree_probability
        said = "unwarned before" if p is not None and p >= TREE_PROBABILITY_LIMIT else "warned"
        print(f"- {d.source}/{d.kind} {d.key}{label(i)}: detector P(tree) {p:.3f}, {said}")


def main() -> None:
    from render.reader import line_spread
    from treesketch.pipeline import LINE_SPREAD

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--limit", type=float, default=LINE_SPREAD)
    ap.add_argument("--per-kind", type=int, default=400)
    args = ap.parse_args()
    drawings, inks = held_inks(args.per_kind)
    rows = []
    for i, ink in inks:
        d = drawings[i]
        rows.append((d.source, d.kind, d.key, line_spread(ink), i))
    under = Counter((s, k) for s, k, _, v, _ in rows if v <= args.limit)
    total = Counter((s, k) for s, k, _, _, _ in rows)
    print(f"{len(rows)} held-out drawings; at or under {args.limit}:")
    for (s, k), n in sorted(total.items()):
        if under[(s, k)]:
            print(f"- {s}/{k}: {under[(s, k)]} of {n}")
    trees = sorted((v, f"{s}/{key}") for s, k, key, v, _ in rows if k == "tree")
    print("thinnest trees:", ", ".join(f"{name} {v:.3f}" for v, name in trees[:5]))
    thin = [k for _, k, _, v, _ in rows if v <= args.limit]
    n_trees = sum(k == "tree" for k in thin)
    print(f"trees among the drawings that thin: {n_trees} of {len(thin)}")
    # the thin drawings the detector had left unwarned: what the rule adds
    detector_says(drawings, [i for *_, v, i in rows if v <= args.limit], lambda i: "")


if __name__ == "__main__":
    main()
