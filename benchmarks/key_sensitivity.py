"""Which free values can refinement see?  Sketch distance vs mesh change, per value.

For N test-split trees per species of a dataset built by ``render.dataset`` (one view per
tree, cycling front/left/back/right): start from the ground truth, move ONE free unit-cube
coordinate of ``refine.objective.SearchSpace`` by ``--step`` (up, or down near the top),
and measure

* the sketch distance from the ground truth's sketch at that view (what refinement sees),
* the symmetric Hausdorff distance (max and mean) of the moved tree's mesh to the ground
  truth's, divided by the ground-truth bounding-box diagonal (what the user gets).

A value whose ratio mesh change / sketch change is high moves the tree a lot for little
sketch evidence: refinement trades it for pixel noise (``refine.search.DEFAULT_HOLD``).
A value with both changes exactly 0 does not act on that tree at all
(``SearchSpace.live`` drops those).

    nice -n 10 .venv/bin/python benchmarks/key_sensitivity.py --data /work/data/ds_v1 \
        --per-species 3 --json /work/data/key_sensitivity.json
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from eval.hausdorff import bbox_diagonal, hausdorff  # noqa: E402
from refine.objective import SearchSpace, SketchObjective, SketchTarget  # noqa: E402
from render.dataset import read_manifest  # noqa: E402
from render.sketch import SketchRenderer  # noqa: E402
from treesketch.pipeline import SEARCH_SIZE  # noqa: E402
from weberpenn import build_mesh, grow, load_params, species  # noqa: E402

VIEW_ORDER = ("front", "left", "back", "right")


def measure(data: Path, per_species: int, step: float, samples: int) -> list[dict]:
    rows = read_manifest(data, split="test")
    out = []
    for name in species.SPECIES:
        mine = [r for r in rows if r["species"] == name]
        for k, tree in enumerate(sorted({r["tree_id"] for r in mine})[:per_species]):
            view = VIEW_ORDER[k % 4]
            row = next(r for r in mine if r["tree_id"] == tree and r["view"] == view)
            gt = load_params(data / row["params"])
            gt_mesh = build_mesh(grow(gt), species=name)
            gt_c, diag = gt_mesh.combined(), bbox_diagonal(gt_mesh.bounds())
            yaw = float(row["yaw"])
            sketch = SketchRenderer(gt_mesh).sketch(yaw, SEARCH_SIZE)
            space = SearchSpace.create(name, gt, search_yaw=False, yaw=yaw)
            obj = SketchObjective(SketchTarget.from_image(sketch, SEARCH_SIZE), space)
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


def markdown(records: list[dict]) -> str:
    by: dict[tuple[str, str], list[dict]] = defaultdict(list)
    for r in records:
        by[(r["species"], r["value"])].append(r)
    lines = [
        "| species | value | sketch distance | mesh max | mesh / sketch |",
        "|---|---|---:|---:|---:|",
    ]
    for name in species.SPECIES:
        stats = []
        for (s, value), rs in by.items():
            if s != name:
                continue
            d = float(np.mean([r["sketch"] for r in rs]))
            m = float(np.mean([r["mesh_max"] for r in rs]))
            stats.append((value, d, m, m / (d + 1e-3)))
        for value, d, m, ratio in sorted(stats, key=lambda t: -t[3]):
            lines.append(f"| {name} | {value} | {d:.4f} | {m:.4f} | {ratio:.2f} |")
    return "\n".join(lines)


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
