"""Level of detail per species: triangles, GLB size, distance to the full mesh, sketch change.

    .venv/bin/python benchmarks/bench_lod.py [--trees 3] [--budgets 50000,20000,5000]
        [--samples 20000] [--write]

For each species and seeds 0..trees-1: the full tree (lod0, the reference, measured in
the same run) and ``weberpenn.lod.lod(tree, budget)`` for each budget.  Per LOD: branch
and leaf triangles, the textured GLB's size (``weberpenn.export.glb_bytes``), the
symmetric Hausdorff distance of the LOD to the full mesh (``eval.hausdorff``, branches
and leaves together, max and mean as % of the full tree's bounding-box diagonal), the
seconds ``lod`` took, and the share of pixels whose sketch (``render.sketch``, front
view, 256 px) differs from the full tree's sketch: what refinement would see if it
rendered that LOD instead.  Medians over the trees.  ``--write`` replaces this
benchmark's section of ``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import datetime as dt  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from benchmarks.lib.results_md import cpu_name, write_section  # noqa: E402
from eval.hausdorff import bbox_diagonal, hausdorff  # noqa: E402
from render.sketch import SketchRenderer  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402
from weberpenn.export import glb_bytes  # noqa: E402
from weberpenn.lod import lod  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SECTION = "## Level of detail"
SKETCH_SIZE = 256


def measure(name: str, seed: int, budgets: list[int], samples: int) -> list[dict]:
    full = build_mesh(grow(species.sample(name, seed)), species=name)
    diag = bbox_diagonal(full.bounds())
    full_c = full.combined()
    ref_sketch = SketchRenderer(full).sketch(0.0, SKETCH_SIZE)
    rows = []
    for budget in [None, *budgets]:
        t0 = time.perf_counter()
        m = full if budget is None else lod(full, budget)
        secs = time.perf_counter() - t0
        h = hausdorff(m.combined(), full_c, samples, diag) if budget is not None else None
        sk = ref_sketch if budget is None else SketchRenderer(m).sketch(0.0, SKETCH_SIZE)
        changed = float(np.mean(np.abs(sk.astype(int) - ref_sketch.astype(int)) > 64))
        rows.append(
            {
                "species": name,
                "seed": seed,
                "lod": "full" if budget is None else f"<= {budget:,}",
                "branch": len(m.branches.faces),
                "leaf": len(m.leaves.faces),
                "glb_mb": len(glb_bytes(m)) / 1e6,
                "h_max": 0.0 if h is None else 100 * h.max_norm,
                "h_mean": 0.0 if h is None else 100 * h.mean_norm,
                "secs": secs,
                "changed": 100 * changed,
                "decimated": bool(m.meta.get("lod", {}).get("decimated", False)),
            }
        )
    return rows


def markdown(rows: list[dict], args: argparse.Namespace, budgets: list[int]) -> str:
    now = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    cmd = (
        f"`.venv/bin/python benchmarks/bench_lod.py --trees {args.trees} "
        f"--budgets {','.join(map(str, budgets))} --samples {args.samples} --write`"
    )
    out = [
        SECTION,
        "",
        f"{cmd} ({now}; {cpu_name()}, {os.cpu_count()} cores, no GPU, one thread). Per species, "
        f"median over seeds 0..{args.trees - 1}; the full tree is the reference, measured in "
        "the same run. Triangles; textured GLB size; symmetric Hausdorff distance of the LOD "
        "to the full mesh (`eval.hausdorff`, "
        f"{args.samples} samples, % of the full tree's bounding-box diagonal); seconds "
        "`lod()` took; % of pixels of the front-view 256 px sketch that change against the "
        "full tree's sketch (what refinement would see from that LOD); whether quadric "
        "decimation was needed (after coarser tubes and fewer, rectangular leaves).",
        "",
        "| species | LOD | branch tris | leaf tris | GLB MB | Hausdorff max % | mean % "
        "| lod s | sketch px changed % | decimated |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    keys = []
    for r in rows:
        if (r["species"], r["lod"]) not in keys:
            keys.append((r["species"], r["lod"]))
    for name, level in keys:
        sel = [r for r in rows if r["species"] == name and r["lod"] == level]

        def med(k: str, sel: list[dict] = sel) -> float:
            return statistics.median(r[k] for r in sel)

        dec = sum(r["decimated"] for r in sel)
        out.append(
            f"| {name} | {level} | {med('branch'):,.0f} | {med('leaf'):,.0f} | "
            f"{med('glb_mb'):.2f} | {med('h_max'):.2f} | {med('h_mean'):.3f} | "
            f"{med('secs'):.2f} | {med('changed'):.2f} | {dec}/{len(sel)} |"
        )
    out += [
        "",
        "Every LOD that drops detail changes the sketch (second-last column), so refinement "
        "keeps rendering the full mesh; `--max-faces` / `lod()` are for what is exported.",
    ]
    return "\n".join(out) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trees", type=int, default=3, help="trees per species (seeds 0..N-1)")
    ap.add_argument("--budgets", default="50000,20000,5000", help="triangle budgets")
    ap.add_argument("--samples", type=int, default=20000, help="Hausdorff samples")
    ap.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    args = ap.parse_args()
    try:
        budgets = [int(b) for b in args.budgets.split(",")]
    except ValueError:
        ap.error(f"--budgets {args.budgets!r}: triangle counts separated by commas")
    if args.trees < 1:
        ap.error("--trees must be at least 1")
    rows = []
    for name in species.SPECIES:
        for seed in range(args.trees):
            rows += measure(name, seed, budgets, args.samples)
            print(f"{name} seed {seed} done", flush=True)
    text = markdown(rows, args, budgets)
    print(text)
    if args.write:
        write_section(text)


if __name__ == "__main__":
    main()
