"""Which free values can refinement see?  Sketch distance vs mesh change, per value.

For N test-split trees per species of a dataset built by ``render.dataset`` (one view per
tree, cycling front/left/back/right: the sketches ``bench_refine.py`` uses): start from the ground truth, move ONE free unit-cube
coordinate of ``refine.objective.SearchSpace`` by ``--step`` (up, or down near the top),
and measure

* the sketch distance from the ground truth's sketch at that view (what refinement sees),
* the symmetric Hausdorff distance (max and mean) of the moved tree's mesh to the ground
  truth's, divided by the ground-truth bounding-box diagonal (what the user gets).

A value whose ratio mesh change / sketch change is high moves the tree a lot for little
sketch evidence: refinement trades it for pixel noise (``refine.search.DEFAULT_HOLD``).
A value with both changes exactly 0 does not act on that tree at all
(``SearchSpace.live`` drops those).

    nice -n 10 .venv/bin/python benchmarks/probes/key_sensitivity.py --data /work/data/ds_v1 \
        --per-species 3 --json /work/data/key_sensitivity.json
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from benchmarks.bench_refine import pick_rows
from eval.hausdorff import bbox_diagonal, hausdorff
from refine.objective import SearchSpace, SketchObjective, framed, make_target
from refine.search import RefineSettings
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, load_params, species


def measure(data: Path, per_species: int, step: float, samples: int) -> list[dict]:
    out = []
    for row in pick_rows(data, per_species):
        name, tree, view = row["species"], row["tree_id"], row["view"]
        gt = load_params(data / row["params"])
        gt_mesh = build_mesh(grow(gt), species=name)
        gt_c, diag = gt_mesh.combined(), bbox_diagonal(gt_mesh.bounds())
        yaw = float(row["yaw"])
        sketch = SketchRenderer(gt_mesh).sketch(yaw, RefineSettings().size)
        space = SearchSpace.create(name, gt, search_yaw=False, yaw=yaw)
        size = RefineSettings().size
        obj = SketchObjective(make_target(framed(sketch, size), size), space)
        x0 = space.from_params(gt)
        for i, u in enumerate(space.dims):
            x = x0.copy()
            x[i] = x[i] + step if x[i] + step <= 1.0 else x[i] - step
            moved = build_mesh(grow(space.to_params(x)), species=name)
            h = hausdorff(moved.combined(), gt_c, samples, diag)
            out.append(
                {
                    "species": name,
                    "tree_id": tree,
                    "view": view,
                    "value": u.label,
                    "sketch": obj(x),
                    "mesh_max": h.max_norm,
                    "mesh_mean": h.mean_norm,
                }
            )
        print(f"  {tree} ({view}): {len(space.dims)} values", flush=True)
    return out


def _ratios(records: list[dict]) -> dict[str, list[tuple[str, float, float, float]]]:
    """Per species: (value, mean sketch distance, mean mesh max, mesh / sketch) per value."""
    by: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in records:
        by[(r["species"], r["value"])].append(r)
    out: dict[str, list[tuple[str, float, float, float]]] = defaultdict(list)
    for (name, value), rs in by.items():
        d = float(np.mean([r["sketch"] for r in rs]))
        m = float(np.mean([r["mesh_max"] for r in rs]))
        out[name].append((value, d, m, m / (d + 1e-3)))
    return {k: sorted(v, key=lambda t: -t[3]) for k, v in out.items()}


def markdown(records: list[dict]) -> str:
    """Every value, and a summary: values with no effect, the four with most mesh change."""
    ratios = _ratios(records)
    lines = [
        "| species | value | sketch distance | mesh max | mesh / sketch |",
        "|---|---|---:|---:|---:|",
    ]
    summary = [
        "| species | free values | no effect at all | most mesh per sketch |",
        "|---|---:|---|---|",
    ]
    for name in (s for s in species.SPECIES if s in ratios):
        rows = ratios[name]
        lines += [f"| {name} | {v} | {d:.4f} | {m:.4f} | {q:.2f} |" for v, d, m, q in rows]
        dead = [v for v, d, m, _ in rows if d <= 1e-6 and m <= 1e-6]
        top = [f"{v} {q:.2f}" for v, d, m, q in rows if v not in dead][:4]
        summary.append(f"| {name} | {len(rows)} | {', '.join(dead) or '-'} | {', '.join(top)} |")
    return "\n".join(lines + [""] + summary)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=Path("/work/data/ds_v1"))
    ap.add_argument("--per-species", type=int, default=3)
    ap.add_argument("--step", type=float, default=0.25, help="unit-cube move of one value")
    ap.add_argument("--samples", type=int, default=3000, help="Hausdorff samples per side")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--markdown", type=Path, default=None, help="only print a --json file")
    args = ap.parse_args()
    if args.markdown is not None:
        print(markdown(json.loads(args.markdown.read_text())))
        return
    if not 0.0 < args.step <= 1.0:
        ap.error("--step must be in (0, 1]")
    records = measure(args.data, args.per_species, args.step, args.samples)
    if args.json is not None:
        tmp = args.json.with_suffix(".tmp")
        tmp.write_text(json.dumps(records, indent=1))
        tmp.replace(args.json)
    print(markdown(records))


if __name__ == "__main__":
    main()
