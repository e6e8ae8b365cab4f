"""Distance against parameter step: how far the tree moves when one value moves a little.

    .venv/bin/python benchmarks/step_curve.py --out step.json [--species maple pine]
    .venv/bin/python benchmarks/step_curve.py --table before.json after.json

For each species, the point ``x`` is ``species.sample(name, 0)`` in the unit cube of the
species' free continuous unfixed values (``refine.objective.SearchSpace``, no yaw).  For
every dimension ``k`` and step ``d`` in ``--deltas`` the tree at ``x`` and at
``x + d e_k`` (``x - d e_k`` where that leaves the cube) are grown with seed 0 and
compared by ``eval.hausdorff.hausdorff`` (symmetric max, normalised by the diagonal of
the tree at ``x``).  A generator whose random draws follow the tree's structure moves
the tree a little for a small step; one whose draws are reshuffled by a small change
jumps to another tree (up to the seed floor) however small the step.  The seed floor is
the same parameters at ``x`` grown with seeds 0 and 1.

To keep the run short, both trees are meshed coarsely (``resU`` 1, ``bevelRes`` 0: the
same skeleton, four-sided tubes) and every vertex of each is measured to the other's
surface (``samples=1``: vertices only, plus one face point).

``--table`` prints Markdown: per species and step, the median and the fraction of
dimensions whose distance is above half the seed floor (a jump), for each JSON given.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from eval.hausdorff import bbox_diagonal, hausdorff  # noqa: E402
from refine.objective import SearchSpace  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402
from weberpenn.fileio import atomic_write  # noqa: E402

DELTAS = (0.001, 0.003, 0.01, 0.03, 0.1)


def _mesh(params, seed: int = 0):
    return build_mesh(grow(params.replace(resU=1, bevelRes=0), seed=seed)).combined()


def run_species(name: str, deltas: tuple[float, ...]) -> dict:
    base = species.sample(name, 0)
    space = SearchSpace.create(name, base, search_yaw=False)
    x = space.from_params(base)
    p0 = space.to_params(x)
    m0 = _mesh(p0)
    diag = bbox_diagonal(m0.vertices)
    floor = hausdorff(_mesh(p0, seed=1), m0, samples=1, diagonal=diag).max_norm
    rows = {}
    for k, label in enumerate(space.labels):
        out = []
        for d in deltas:
            y = x.copy()
            y[k] = x[k] + d if x[k] + d <= 1.0 else x[k] - d
            out.append(hausdorff(_mesh(space.to_params(y)), m0, samples=1, diagonal=diag).max_norm)
        rows[label] = out
        print(f"{name:7s} {label:18s} " + " ".join(f"{v:.4f}" for v in out), flush=True)
    return {"seed_floor": floor, "deltas": list(deltas), "keys": rows}


def table(paths: list[str]) -> str:
    runs = [(Path(p).stem, json.loads(Path(p).read_text())) for p in paths]
    deltas = runs[0][1]["deltas"]
    head = "| species | run | seed floor | " + " | ".join(f"d={d:g}" for d in deltas) + " |"
    lines = [
        "Median over the species' dimensions of the normalised max distance (fraction of "
        "dimensions above half the seed floor in brackets).",
        "",
        head,
        "|---|---|---:|" + "---:|" * len(deltas),
    ]
    for sp in runs[0][1]["species"]:
        for label, run in runs:
            r = run["species"].get(sp)
            if r is None:
                continue
            cells = []
            for j in range(len(deltas)):
                vals = [v[j] for v in r["keys"].values()]
                jump = np.mean([v > 0.5 * r["seed_floor"] for v in vals])
                cells.append(f"{statistics.median(vals):.4f} ({jump:.0%})")
            lines.append(f"| {sp} | {label} | {r['seed_floor']:.4f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def per_key(paths: list[str], delta: float) -> str:
    runs = [(Path(p).stem, json.loads(Path(p).read_text())) for p in paths]
    j = runs[0][1]["deltas"].index(delta)
    lines = [
        "| species | key | " + " | ".join(label for label, _ in runs) + " |",
        "|---|---|" + "---:|" * len(runs),
    ]
    for sp, r0 in runs[0][1]["species"].items():
        for key in r0["keys"]:
            vals = [run["species"][sp]["keys"][key][j] for _, run in runs]
            lines.append(f"| {sp} | {key} | " + " | ".join(f"{v:.4f}" for v in vals) + " |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--species", nargs="*", default=list(species.SPECIES))
    ap.add_argument("--deltas", nargs="*", type=float, default=list(DELTAS))
    ap.add_argument("--out", type=Path)
    ap.add_argument("--table", nargs="*", help="JSON files to compare (Markdown to stdout)")
    ap.add_argument("--per-key", type=float, help="with --table: one row per key at this step")
    args = ap.parse_args()
    if args.table:
        print(table(args.table))
        if args.per_key is not None:
            print()
            print(per_key(args.table, args.per_key))
        return
    if args.out is None:
        ap.error("--out is required unless --table is given")
    t0 = time.perf_counter()
    res = {"species": {}, "deltas": list(args.deltas)}
    for name in args.species:
        res["species"][name] = run_species(name, tuple(args.deltas))
        res["species"][name]["seconds"] = time.perf_counter() - t0
    atomic_write(args.out, json.dumps(res, indent=1))
    print(f"wrote {args.out} in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
