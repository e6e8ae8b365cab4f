"""Two codes' mesh error on the same held-out-style drawings: is the difference more than noise?

Reads ``bench_drawings.py --part refine --json`` runs of two codes (each side may be
several runs, e.g. two sets of seeds, or a run split by ``--species``), pairs their
records by drawing and view count, and prints each code's mean and median mesh error
(``haus_after``), how many drawings the refinement improved (against ``haus_before``),
on how many the second code is better or worse (by more than 0.005), and a bootstrap
interval of the medians' difference (the pairs drawn again with replacement).

    .venv/bin/python benchmarks/probes/mesh_runs.py --a OLD1.json OLD2.json --b NEW1.json NEW2.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

NEAR = 0.005  # a difference under this is "the same"


def _records(paths: list[Path]) -> dict[tuple[str, int], dict]:
    out: dict[tuple[str, int], dict] = {}
    for path in paths:
        for r in json.loads(path.read_text())["records"]:
            out[(r["name"], int(r.get("views", 1)))] = r
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--a", type=Path, nargs="+", required=True, help="the first code's runs")
    ap.add_argument("--b", type=Path, nargs="+", required=True, help="the second code's runs")
    ap.add_argument("--draws", type=int, default=5000, help="bootstrap draws")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    a, b = _records(args.a), _records(args.b)
    for views in sorted({v for _, v in a} & {v for _, v in b}):
        keys = sorted(k for k in a if k in b and k[1] == views)
        if not keys:
            continue
        print(f"{len(keys)} drawings, {views} view(s) each")
        got = {}
        for label, runs in (("a", a), ("b", b)):
            after = np.array([runs[k]["haus_after"] for k in keys])
            before = np.array([runs[k]["haus_before"] for k in keys])
            got[label] = after
            print(
                f"  {label}: mean {after.mean():.4f}, median {np.median(after):.4f}, "
                f"improved {(after < before).sum()} of {len(keys)}"
            )
        x, y = got["a"], got["b"]
        rng = np.random.default_rng(args.seed)
        picks = rng.integers(0, len(keys), size=(args.draws, len(keys)))
        diff = np.median(y[picks], axis=1) - np.median(x[picks], axis=1)
        lo, hi = np.percentile(diff, [5, 95])
        print(
            f"  b better on {(y < x - NEAR).sum()}, worse on {(y > x + NEAR).sum()}; median "
            f"b - a {np.median(y) - np.median(x):+.4f}, 90 % bootstrap interval "
            f"{lo:+.4f} to {hi:+.4f}"
        )


if __name__ == "__main__":
    main()
