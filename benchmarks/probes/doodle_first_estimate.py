"""What the pipeline's first estimate makes of the code-made doodles of eval/doodles.py.

Per species of ``TREE_SPECIES``, ``tree_doodle(species, seed)`` for seeds 0 to ``--trees``-1:
how often the species comes back right and how often the "is this a tree?" warning is
given; per kind of ``NONTREE_KINDS``, ``nontree_doodle(kind, seed)`` for seeds 0 to
``--others``-1: how often the warning is given (it should be, every time).  No refinement
(``RefineSettings(refine=False)``): the estimate, its species and its warning.

    PYTHONPATH=$PWD nice -n 10 .venv/bin/python benchmarks/probes/doodle_first_estimate.py \\
        [--trees 20] [--others 6] [--json FILE] [--checkpoint CK]
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from pathlib import Path

from eval.doodles import NONTREE_KINDS, TREE_SPECIES, nontree_doodle, tree_doodle
from treesketch import Pipeline, RefineSettings


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trees", type=int, default=20, help="doodles per species")
    ap.add_argument("--others", type=int, default=6, help="doodles per kind of non-tree")
    ap.add_argument("--json", type=Path, default=None, help="also write every result")
    ap.add_argument(
        "--checkpoint", default=None, help="a TSN checkpoint (default: the shipped one)"
    )
    args = ap.parse_args()
    if not (1 <= args.trees <= 1000 and 0 <= args.others <= 1000):
        ap.error("--trees must be 1 to 1000 and --others 0 to 1000")
    pipe = Pipeline(args.checkpoint or "tsn", RefineSettings(refine=False))
    jobs = [("tree", sp, s) for sp in TREE_SPECIES for s in range(args.trees)]
    jobs += [("nontree", k, s) for k in NONTREE_KINDS for s in range(args.others)]
    rows = []
    for what, name, seed in jobs:
        img = tree_doodle(name, seed) if what == "tree" else nontree_doodle(name, seed)
        t = time.perf_counter()
        res = pipe.run(img)
        rows.append({"what": what, "name": name, "seed": seed, "species": res.species,
                     "warning": bool(res.warning), "confidence": res.confidence,
                     "s": time.perf_counter() - t})  # fmt: skip
    print("| doodles of | right | warned | read as (most often) |")
    print("|---|---:|---:|---|")
    for sp in TREE_SPECIES:
        mine = [r for r in rows if r["what"] == "tree" and r["name"] == sp]
        seen = Counter(r["species"] for r in mine).most_common(3)
        right = sum(r["species"] == sp for r in mine)
        warned = sum(r["warning"] for r in mine)
        read = ", ".join(f"{s} {n}" for s, n in seen)
        print(f"| {sp} | {right} / {len(mine)} | {warned} / {len(mine)} | {read} |")
    trees = [r for r in rows if r["what"] == "tree"]
    others = [r for r in rows if r["what"] == "nontree"]
    print(f"trees: right {sum(r['species'] == r['name'] for r in trees)} / {len(trees)}, "
          f"warned {sum(r['warning'] for r in trees)} / {len(trees)}")  # fmt: skip
    if others:
        by = {k: [r["warning"] for r in others if r["name"] == k] for k in NONTREE_KINDS}
        print(f"not trees: warned {sum(r['warning'] for r in others)} / {len(others)} (" +
              ", ".join(f"{k} {sum(v)}/{len(v)}" for k, v in by.items()) + ")")  # fmt: skip
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=0), encoding="utf-8")


if __name__ == "__main__":
    main()
