"""How far the trees we grow stay below weberpenn.limits.

    .venv/bin/python benchmarks/probes/limits_margin.py [--trees 20] [--ref DIR]

Grows ``species.sample(name, i)`` for ``i < --trees`` and the 15 reference dictionaries
(``DIR``, default ``tests/data/treesketchnet_test_params``) and prints the
largest stems, control points, leaves, mesh vertices and triangles per species next to
the limits.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from weberpenn import grow, limits, load_params, species

ROOT = Path(__file__).resolve().parents[2]

COLS = ("stems", "points", "leaves", "vertices", "triangles")


def _stats(p) -> dict[str, int]:
    sk = grow(p)
    v, f = limits.mesh_size(np.diff(sk.offsets), sk.res_u, sk.bevel_res, sk.n_leaves, sk.leaf_shape)
    return dict(
        stems=sk.n_stems, points=len(sk.points), leaves=sk.n_leaves, vertices=v, triangles=f
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trees", type=int, default=20)
    ap.add_argument(
        "--ref",
        type=Path,
        default=ROOT / "tests" / "data" / "treesketchnet_test_params",
    )
    args = ap.parse_args()
    rows: dict[str, dict[str, int]] = {}

    def add(name: str, s: dict[str, int]) -> None:
        r = rows.setdefault(name, dict.fromkeys(COLS, 0))
        for k in COLS:
            r[k] = max(r[k], s[k])

    for name in species.SPECIES:
        for i in range(args.trees):
            add(name, _stats(species.sample(name, i)))
    for f in sorted(args.ref.glob("*.json")):
        add("15 reference files", _stats(load_params(f)))
    print("| largest of | " + " | ".join(COLS) + " |")
    print("|---|" + "---:|" * len(COLS))
    for name, r in rows.items():
        print(f"| {name} | " + " | ".join(f"{r[k]:,}" for k in COLS) + " |")
    lim = (
        limits.MAX_STEMS,
        None,
        limits.MAX_LEAVES,
        limits.MAX_MESH_VERTICES,
        limits.MAX_MESH_FACES,
    )
    print("| **limit** | " + " | ".join("-" if x is None else f"{x:,}" for x in lim) + " |")


if __name__ == "__main__":
    main()
