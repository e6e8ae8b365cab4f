"""Benchmark the sketch renderer and the dataset builder.

    .venv/bin/python benchmarks/bench_render.py                 # both parts
    .venv/bin/python benchmarks/bench_render.py --skip-builder  # per-sketch timings only
    .venv/bin/python benchmarks/bench_render.py --markdown      # print a RESULTS.md section

Part 1 (one tree per species, already meshed): scene build once, then per view the
sketch (silhouette rays + edge chain) at 256 px, median of ``--repeats`` runs over the
four views, plus the colour render.  Part 2: ``build_dataset`` end to end with
``--workers`` processes on ``--trees-per-species`` trees x 4 views, and the time that
rate gives for the paper-size dataset (5 x 250 trees x 4 views = 5000 sketches).
Other processes share the CPUs; the load average is printed with the numbers.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time

from render.backend import init_mitsuba
from render.camera import VIEWS


def bench_sketch(size: int, repeats: int, seed: int) -> list[dict]:
    from render.dataset import mesher_in_use
    from render.edges import branch_sketch, foliage_sketch, thin_mask
    from render.sketch import SketchRenderer
    from weberpenn import grow, species

    build_mesh, _ = mesher_in_use()

    rows = []
    for sp in species.SPECIES:
        params = species.sample(sp, seed=seed)
        t0 = time.perf_counter()
        tree = build_mesh(grow(params))
        t1 = time.perf_counter()
        r = SketchRenderer(tree)
        t2 = time.perf_counter()
        r.sketch(0, size)  # warm-up (kernel compilation)
        times, ray_t, edge_t = [], [], []
        cfg = r.config
        for _ in range(repeats):
            for yaw in VIEWS.values():
                a = time.perf_counter()
                r.sketch(yaw, size)
                times.append(time.perf_counter() - a)
                a = time.perf_counter()
                cov = r.scene.coverage(
                    yaw, size, cfg.supersample, keep_hr=True, leaf_supersample=cfg.leaf_supersample
                )
                b = time.perf_counter()
                assert cov.branches_hr is not None
                bs = 1.0 - thin_mask(
                    cov.branches_hr, cfg.supersample, cfg.px(cfg.branch_thin_px, size)
                )
                branch_sketch(bs, cfg)
                foliage_sketch(1.0 - cov.leaves, cfg)
                c = time.perf_counter()
                ray_t.append(b - a)
                edge_t.append(c - b)
        a = time.perf_counter()
        r.colour(0, size)
        t_col = time.perf_counter() - a
        rows.append(
            {
                "species": sp,
                "faces": len(tree.branches.faces) + len(tree.leaves.faces),
                "grow_mesh_s": t1 - t0,
                "scene_s": t2 - t1,
                "sketch_ms": 1000 * statistics.median(times),
                "sketch_max_ms": 1000 * max(times),
                "rays_ms": 1000 * statistics.median(ray_t),
                "edges_ms": 1000 * statistics.median(edge_t),
                "colour_ms": 1000 * t_col,
            }
        )
    return rows


def bench_builder(trees: int, workers: int, size: int, out: str | None) -> dict:
    from render.dataset import DatasetConfig, build_dataset
    from treesketch.executor import LocalExecutor

    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix="bench_ds_")
        out = os.path.join(tmp.name, "ds")
    cfg = DatasetConfig(out=out, trees_per_species=trees, size=size)
    t0 = time.perf_counter()
    s = build_dataset(cfg, progress=False, executor=LocalExecutor(workers) if workers > 1 else None)
    dt = time.perf_counter() - t0
    n = s.built * len(cfg.views)
    res = {
        "trees": s.built,
        "failed": len(s.failed),
        "sketches": n,
        "seconds": dt,
        "sketches_per_s": n / dt if dt > 0 else 0.0,
        "paper_size_min": 5000 / (n / dt) / 60 if n else float("nan"),
        "workers": workers,
    }
    if tmp is not None:
        tmp.cleanup()
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--trees-per-species", type=int, default=10)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=None, help="builder output (default: a temp folder)")
    ap.add_argument("--skip-builder", action="store_true")
    ap.add_argument("--skip-sketch", action="store_true")
    ap.add_argument("--markdown", action="store_true", help="print a RESULTS.md section")
    args = ap.parse_args()

    backend = init_mitsuba()
    load = os.getloadavg()
    head = (
        f"machine: {platform.node()} {platform.machine()}, {os.cpu_count()} CPUs, "
        f"load average before {load[0]:.2f}; mitsuba {backend.variant}, "
        f"Dr.Jit threads {backend.threads}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}"
    )
    print(head)
    lines = []
    if not args.skip_sketch:
        rows = bench_sketch(args.size, args.repeats, args.seed)
        lines.append(
            "| species | faces | grow+mesh s | scene build s | sketch ms (median / max) "
            "| rays ms | edges ms | colour ms |"
        )
        lines.append("|---|---:|---:|---:|---:|---:|---:|---:|")
        for r in rows:
            lines.append(
                f"| {r['species']} | {r['faces']} | {r['grow_mesh_s']:.2f} | {r['scene_s']:.2f} "
                f"| {r['sketch_ms']:.1f} / {r['sketch_max_ms']:.1f} | {r['rays_ms']:.1f} "
                f"| {r['edges_ms']:.1f} | {r['colour_ms']:.0f} |"
            )
        mean = statistics.mean(r["sketch_ms"] for r in rows)
        lines.append(
            f"\nOne {args.size}px sketch of a meshed tree: {mean:.1f} ms on average over species "
            f"({1000 / mean:.0f} sketches/s per tree; target < 50 ms)."
        )
    if not args.skip_builder:
        b = bench_builder(args.trees_per_species, args.workers, args.size, args.out)
        lines.append(
            f"\nBuilder end to end, {b['workers']} workers: {b['trees']} trees "
            f"({b['failed']} failed), {b['sketches']} sketches in {b['seconds']:.1f} s = "
            f"{b['sketches_per_s']:.1f} sketches/s -> paper size (5000 sketches) in "
            f"{b['paper_size_min']:.1f} min (target < 10 min). "
            f"Load average after: {os.getloadavg()[0]:.2f}."
        )
    text = "\n".join(lines)
    print(text)
    if args.markdown:
        cmd = " ".join(["benchmarks/bench_render.py", *sys.argv[1:]])
        print(f"\n## Renderer and dataset builder\n\n`{cmd}`\n\n{head}\n\n{text}\n")


if __name__ == "__main__":
    main()
