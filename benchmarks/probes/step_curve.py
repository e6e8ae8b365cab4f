"""Distance against parameter step: how far the tree moves when one value moves a little.

    .venv/bin/python benchmarks/probes/step_curve.py --out step.json [--species maple pine]
        [--metric points|mesh] [--points 3]
    .venv/bin/python benchmarks/probes/step_curve.py --table before.json after.json

For each species, the point ``x`` is ``species.sample(name, i)`` (``i < --points``) in
the unit cube of the species' free continuous unfixed values
(``refine.objective.SearchSpace``, no yaw).  For every dimension ``k`` and step ``d`` in
``--deltas`` the tree at ``x`` and at ``x + d e_k`` (``x - d e_k`` where that leaves the
cube) are grown with seed 0 and compared (symmetric max distance, normalised by the
diagonal of the tree at ``x``; see ``--metric``).  A generator whose random draws follow the tree's structure moves
the tree a little for a small step; one whose draws are reshuffled by a small change
jumps to another tree (up to the seed floor) however small the step.  The seed floor is
the same parameters at ``x`` grown with seeds 0 and 1.

``--metric mesh``: both trees are meshed coarsely (``resU`` 1, ``bevelRes`` 0: the same
skeleton, four-sided tubes) and every vertex of each is measured to the other's surface
(``samples=1``: vertices only, plus one face point); minutes per species on 2 cores.
``--metric points`` (default): the symmetric Hausdorff distance between the two
skeletons' point sets (every stem control point and every leaf position, exact with
KD-trees), normalised by the diagonal of the tree at ``x``'s points; seconds per
species, and it moves exactly when stems or leaves move.

``--table`` prints Markdown: per species and step, the mean over dimensions and the
number of dimensions whose distance is a jump (above half the seed floor and 0.01), for
each JSON given; ``--per-key D`` adds one row per key at step ``D``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from eval.hausdorff import bbox_diagonal, hausdorff
from refine.objective import SearchSpace
from weberpenn import build_mesh, grow, species
from weberpenn.fileio import atomic_write

DELTAS = (0.001, 0.003, 0.01, 0.03, 0.1)


class _Mesh:
    """Coarse combined mesh; distance = eval.hausdorff's symmetric max (vertices)."""

    def __init__(self, params, seed: int = 0):
        p = params.replace(resU=1, bevelRes=0)
        self.mesh = build_mesh(grow(p, seed=seed)).combined()
        self.diag = bbox_diagonal(self.mesh.vertices)

    def distance(self, other: _Mesh, diag: float) -> float:
        return hausdorff(other.mesh, self.mesh, samples=1, diagonal=diag).max_norm


class _Points:
    """Skeleton point set (control points + leaf positions); exact point-set Hausdorff."""

    def __init__(self, params, seed: int = 0):
        sk = grow(params, seed=seed)
        self.pts = np.vstack([sk.points, sk.leaf_positions])
        self.tree = cKDTree(self.pts)
        self.diag = bbox_diagonal(self.pts)

    def distance(self, other: _Points, diag: float) -> float:
        d = max(self.tree.query(other.pts)[0].max(), other.tree.query(self.pts)[0].max())
        return float(d) / diag


def run_species(
    name: str, deltas: tuple[float, ...], metric: str = "points", points: int = 1
) -> dict:
    """Rows ``key#i`` for the base points ``species.sample(name, i)``, ``i < points``."""
    tree = _Points if metric == "points" else _Mesh
    rows = {}
    floors = []
    for i in range(points):
        base = species.sample(name, i)
        space = SearchSpace.create(name, base, search_yaw=False)
        x = space.from_params(base)
        p0 = space.to_params(x)
        m0 = tree(p0)
        diag = m0.diag
        floors.append(m0.distance(tree(p0, seed=1), diag))
        for k, label in enumerate(space.labels):
            out = []
            for d in deltas:
                y = x.copy()
                y[k] = x[k] + d if x[k] + d <= 1.0 else x[k] - d
                out.append(m0.distance(tree(space.to_params(y)), diag))
            rows[f"{label}#{i}"] = out
            print(f"{name:7s} {label:18s} #{i} " + " ".join(f"{v:.4f}" for v in out), flush=True)
    return {"seed_floor": float(np.mean(floors)), "deltas": list(deltas), "keys": rows}


def _jump(r: dict) -> float:
    """A distance this large is a jump to another realisation, not a small move."""
    return max(0.5 * r["seed_floor"], 0.01)


def table(paths: list[str]) -> str:
    runs = [(Path(p).stem, json.loads(Path(p).read_text())) for p in paths]
    deltas = runs[0][1]["deltas"]
    head = "| species | run | seed floor | " + " | ".join(f"d={d:g}" for d in deltas) + " |"
    lines = [
        "Mean over the species' dimensions of the normalised max distance; in brackets the "
        "number of dimensions (of all) whose distance is a jump (above half the seed floor "
        "and above 0.01).",
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
                jumps = sum(v > _jump(r) for v in vals)
                cells.append(f"{statistics.mean(vals):.4f} ({jumps}/{len(vals)})")
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
    ap.add_argument("--metric", choices=("points", "mesh"), default="points")
    ap.add_argument("--points", type=int, default=1, help="base points per species")
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
    res = {"species": {}, "deltas": list(args.deltas), "metric": args.metric}
    for name in args.species:
        res["species"][name] = run_species(name, tuple(args.deltas), args.metric, args.points)
        res["species"][name]["seconds"] = time.perf_counter() - t0
    atomic_write(args.out, json.dumps(res, indent=1))
    print(f"wrote {args.out} in {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
