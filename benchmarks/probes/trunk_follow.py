"""Does the returned tree keep the drawn trunk and crown base (issue 48)?

Reads ``bench_drawings.py --part follow --json RUN`` runs (each with its ``.npz``; several
files of one run are read together, e.g. the two halves of people's drawings) and reads
each drawing's outline and its returned tree's (``refine.start.profile_of`` on
``input_sketch`` and ``sketch_after``, the current code's reading for every run, so runs
of two codes compare on one rule).  Printed per run: the crown base's error (the tree's
minus the drawn, as a share of the height: median and mean of its size); of the drawings
whose trunk is read, the tree's trunk width over the drawn one (median), how many are
within 1.5 times it and how many under half of it; and how many returned trees have a
trunk ratio under 0.005 (``ratio``: a 10 m tree's trunk 5 cm across or less, too thin to
see under its crown).

    .venv/bin/python benchmarks/probes/trunk_follow.py A0.json+A50.json B0.json+B50.json
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from refine.start import profile_of

THIN = 0.005  # a trunk ratio under this: too thin to see
SEEN = 0.03  # a drawn trunk read at least this wide (of the height): one to compare


def load(spec: str) -> tuple[list[dict], dict[str, np.ndarray]]:
    records: list[dict] = []
    sketches: dict[str, np.ndarray] = {}
    for part in spec.split("+"):
        path = Path(part)
        records += json.loads(path.read_text())["records"]
        with np.load(path.with_suffix(".npz")) as z:
            sketches.update({k: z[k] for k in z.files})
    return records, sketches


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="RUN.json, or parts joined with +")
    ap.add_argument("--set", default="people", help="people, paper or pairs")
    args = ap.parse_args()
    for spec in args.runs:
        records, sketches = load(spec)
        base_err, trunk_ratio, thin = [], [], 0
        for r in records:
            if not r["name"].startswith(args.set + "/"):
                continue
            drawn = profile_of(sketches[r["name"] + "/input_sketch"])
            tree = profile_of(sketches[r["name"] + "/sketch_after"])
            if drawn is None or tree is None:
                continue
            base_err.append(abs(tree.crown_base - drawn.crown_base))
            if drawn.trunk >= SEEN:
                trunk_ratio.append(max(tree.trunk, 1e-3) / drawn.trunk)
            thin += float(r["params"]["ratio"]) < THIN
        t = np.log(np.array(trunk_ratio))
        print(
            f"{spec}: {len(base_err)} drawings; crown base error median "
            f"{np.median(base_err):.3f} mean {np.mean(base_err):.3f}; trunk width tree/drawn "
            f"median {np.exp(np.median(t)):.2f} over {len(t)}, within 1.5x "
            f"{int((abs(t) < np.log(1.5)).sum())}, under half {int((t < np.log(0.5)).sum())}; "
            f"trunk ratio under {THIN}: {thin}"
        )


if __name__ == "__main__":
    main()
