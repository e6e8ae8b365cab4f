"""Probe: which of people's drawings are two straight lines? (``treesketch.pipeline.STRAIGHT_SHARE``)

Reads the held part of people's drawings (``eval.people``, authors never fitted on) as the
pipeline does and measures each one's ``render.reader.straight_share`` (the share of the
ink's centre line within reach of its two strongest straight lines: 1 for a cross, a
plus, an X, a T or a V).  Prints, per source and kind, how many reach ``--limit``, the
trees that come nearest it, the share of trees among the drawings that reach it (the
probability such a drawing is a tree: ``treesketch.pipeline.STRAIGHT_TREES``), and which
of them the network's detector had left unwarned (and which the one-line rule,
``treesketch.pipeline.LINE_SPREAD``, already asks).

    .venv/bin/python benchmarks/probes/two_lines.py [--limit 0.95] [--per-kind 400]
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks"), str(ROOT / "benchmarks" / "probes")]


def main() -> None:
    from one_line import detector_says, held_inks

    from render.reader import line_spread, straight_share
    from treesketch.pipeline import LINE_SPREAD, STRAIGHT_SHARE

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--limit", type=float, default=STRAIGHT_SHARE)
    ap.add_argument("--per-kind", type=int, default=400)
    ap.add_argument(
        "--doodles", type=int, default=40, help="code-made tree doodles a species (seeds 7000+)"
    )
    args = ap.parse_args()
    _doodles(args.doodles)
    drawings, inks = held_inks(args.per_kind)
    rows = []
    thin: dict[int, bool] = {}
    for i, ink in inks:
        d = drawings[i]
        rows.append((d.source, d.kind, d.key, straight_share(ink), i))
        # the one-line rule (LINE_SPREAD) comes first: say which these are
        thin[i] = line_spread(ink) <= LINE_SPREAD
    over = Counter((s, k) for s, k, _, v, _ in rows if v >= args.limit)
    total = Counter((s, k) for s, k, _, _, _ in rows)
    print(f"{len(rows)} held-out drawings; at or over {args.limit}:")
    for (s, k), n in sorted(total.items()):
        if over[(s, k)]:
            print(f"- {s}/{k}: {over[(s, k)]} of {n}")
    trees = sorted(((v, f"{s}/{key}") for s, k, key, v, _ in rows if k == "tree"), reverse=True)
    print("straightest trees:", ", ".join(f"{name} {v:.3f}" for v, name in trees[:5]))
    straight = [k for _, k, _, v, _ in rows if v >= args.limit]
    n_trees = sum(k == "tree" for k in straight)
    print(f"trees among the drawings that straight: {n_trees} of {len(straight)}")
    detector_says(
        drawings,
        [i for *_, v, i in rows if v >= args.limit],
        lambda i: " (one line)" if thin[i] else " (two lines)",
    )


def _doodles(per_species: int) -> None:
    """The straightest of the code-made tree doodles (``eval.doodles``, every species)."""
    from eval.doodles import TREE_SPECIES, tree_doodle
    from render.reader import SketchError, ink_mask, straight_share
    from treesketch.pipeline import prepare_input

    shares = []
    for species in TREE_SPECIES:
        for seed in range(7000, 7000 + per_species):
            try:
                img = prepare_input(tree_doodle(species, seed))
            except SketchError:
                continue
            shares.append((straight_share(ink_mask(img)), f"{species} {seed}"))
    shares.sort(reverse=True)
    top = ", ".join(f"{name} {v:.3f}" for v, name in shares[:3])
    print(f"{len(shares)} code-made tree doodles; the straightest: {top}")


if __name__ == "__main__":
    main()
