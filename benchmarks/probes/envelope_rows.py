"""Where up the tree do the returned trees' outlines miss the drawn ones?

From ``bench_drawings.py --part follow`` runs (their JSON and the sketches beside it in
``.npz``): each drawing's envelope (``eval.envelope``) and its returned tree's, the rows
of both split into ``--bins`` bands of the height (0 the bottom), and per band the pixels
a row the tree has too many (outside the drawn envelope) and too few (the drawn envelope
it leaves out), summed over the drawings.

    .venv/bin/python benchmarks/probes/envelope_rows.py RUN.json [RUN2.json] [--bins 20]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT)]


def main() -> None:
    from eval.envelope import envelope

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", type=Path, nargs="+")
    ap.add_argument("--bins", type=int, default=20)
    args = ap.parse_args()
    extra, miss, rows = np.zeros(args.bins), np.zeros(args.bins), np.zeros(args.bins)
    for run in args.runs:
        sketches = np.load(run.with_suffix(".npz"))
        for rec in json.loads(run.read_text())["records"]:
            drawn = envelope(sketches[f"{rec['name']}/input_sketch"])
            tree = envelope(sketches[f"{rec['name']}/sketch_after"])
            used = np.flatnonzero((drawn | tree).any(axis=1))
            top, bottom = int(used[0]), int(used[-1])
            band = np.minimum(
                args.bins - 1,
                ((bottom - np.arange(top, bottom + 1)) * args.bins) // (bottom - top + 1),
            )
            np.add.at(extra, band, (tree & ~drawn)[top : bottom + 1].sum(axis=1))
            np.add.at(miss, band, (drawn & ~tree)[top : bottom + 1].sum(axis=1))
            np.add.at(rows, band, 1)
    print("height (0 the bottom)   too many px/row   too few px/row")
    for k in range(args.bins):
        lo, hi = k / args.bins, (k + 1) / args.bins
        print(f"{lo:.2f}-{hi:.2f}   {extra[k] / rows[k]:15.2f}   {miss[k] / rows[k]:14.2f}")


if __name__ == "__main__":
    main()
