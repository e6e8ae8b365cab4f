"""What one refinement evaluation costs per species, stage by stage.

    .venv/bin/python benchmarks/eval_cost.py [--trees 3] [--size 128] [--repeats 3] [--clock cpu]

One evaluation of ``refine.objective.SketchObjective`` at a new point is: grow the
skeleton, build the mesh, build the mitsuba scene (``render.sketch.SketchRenderer``),
render the sketch at ``--size``, frame it as the target was framed
(``refine.objective.framed``) and compare it with the target in the search's metric
(``--metric``, default the search's own: ``make_target`` + ``.distance``), exactly as
``SketchObjective.loss_of_sketch`` does.  A second sketch of the same scene
(another yaw) shows what a view-only move costs.  For ``species.sample(name, i)``,
``i < --trees``, each stage is timed ``--repeats`` times (best kept, as other jobs share
the machine); the table gives the median over trees of each stage in milliseconds, the
triangle count, and the share of the largest stage.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time

from refine.objective import METRICS, framed, make_target
from refine.search import RefineSettings
from render.sketch import SketchRenderer, sketch_mesh
from weberpenn import build_mesh, grow, species

STAGES = ("grow", "mesh", "scene", "sketch", "frame", "loss", "view only")
COUNTED = STAGES[:-1]  # a new point's evaluation; "view only" is the yaw-only move


# "cpu" (process time, all threads) is steadier than wall time on a shared machine:
# the fast path is single-threaded (CPU ~ an idle machine's wall time), mitsuba's BVH
# build uses every Dr.Jit thread (CPU up to threads x its wall time)
CLOCKS = {"wall": time.perf_counter, "cpu": time.process_time}


def _best(fn, repeats: int, clock=time.perf_counter) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = clock()
        out = fn()
        best = min(best, clock() - t0)
    return best, out


def _stages(p, name: str, size: int, repeats: int, metric: str, target, fast: bool, clock) -> dict:
    def best(fn):
        return _best(fn, repeats, clock)

    t = {}
    t["grow"], sk = best(lambda: grow(p))
    if fast:
        t["mesh"], mesh = best(lambda: sketch_mesh(sk, size, name))
        t["scene"], rend = best(lambda: SketchRenderer(mesh, engine="raster"))
    else:
        t["mesh"], mesh = best(lambda: build_mesh(sk, species=name))
        t["scene"], rend = best(lambda: SketchRenderer(mesh))
    t["sketch"], img = best(lambda: rend.sketch(0.0, size))
    t["frame"], fr = best(lambda: framed(img, size))
    t["loss"], t["distance"] = best(lambda: target.distance(make_target(fr, size, metric)))
    t["view only"], _ = best(lambda: rend.sketch(37.0, size))
    t["tris"] = mesh.n_faces
    return t


def measure(name: str, trees: int, size: int, repeats: int, metric: str, clock) -> dict:
    """Median over trees of each stage, for the full path and the fast path."""
    rows: dict[bool, list[dict]] = {False: [], True: []}
    for i in range(trees):
        p = species.sample(name, i)
        other = SketchRenderer(build_mesh(grow(species.sample(name, i + 100)))).sketch(0.0, size)
        target = make_target(framed(other, size), size, metric)
        for fast in (False, True):
            rows[fast].append(_stages(p, name, size, repeats, metric, target, fast, clock))
    # what the search sees: the candidate's distance to the target, fast vs full path
    pairs = zip(rows[False], rows[True], strict=True)
    out: dict = {"delta": max(abs(a["distance"] - b["distance"]) for a, b in pairs)}
    for fast, rs in rows.items():
        r = {k: statistics.median(x[k] for x in rs) for k in (*STAGES, "tris")}
        r["total"] = sum(r[k] for k in COUNTED)
        out[fast] = r
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trees", type=int, default=3)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--species", nargs="*", default=list(species.SPECIES))
    ap.add_argument("--metric", choices=METRICS, default=RefineSettings().metric)
    ap.add_argument("--clock", choices=sorted(CLOCKS), default="wall")
    args = ap.parse_args()
    SketchRenderer(build_mesh(grow(species.sample("palm", 0)))).sketch(0.0, args.size)  # warm-up
    full_rows, fast_rows = [], []
    for name in args.species:
        r = measure(name, args.trees, args.size, args.repeats, args.metric, CLOCKS[args.clock])
        full, fast = r[False], r[True]
        top = max(COUNTED, key=lambda s: full[s])
        cells = " | ".join(f"{1000 * full[s]:.0f}" for s in STAGES)
        full_rows.append(
            f"| {name} | {int(full['tris'])} | {cells} | {1000 * full['total']:.0f} | "
            f"{top} ({full[top] / full['total']:.0%}) |"
        )
        cells = " | ".join(f"{1000 * fast[s]:.0f}" for s in STAGES)
        fast_rows.append(
            f"| {name} | {int(fast['tris'])} | {cells} | {1000 * fast['total']:.0f} | "
            f"{1000 * full['total']:.0f} | {full['total'] / fast['total']:.1f}x | "
            f"{r['delta']:.4f} |"
        )
        print(
            f"{name}: full {1000 * full['total']:.0f} ms, fast {1000 * fast['total']:.0f} ms",
            file=sys.stderr,
            flush=True,
        )
    for title, last, rows in (
        ("Full path (before: build_mesh + mitsuba scene)", ("largest stage",), full_rows),
        (
            "Fast path (after: sketch_mesh + raster), same trees, same run",
            ("before ms", "speed-up", "distance change"),
            fast_rows,
        ),
    ):
        cols = ["triangles", *(f"{s} ms" for s in STAGES), "evaluation ms", *last]
        print(f"\n{title}\n\n| species | " + " | ".join(cols) + " |")
        print("|---|" + "---:|" * (len(cols) - 1) + ("---|" if len(last) == 1 else "---:|"))
        print("\n".join(rows))


if __name__ == "__main__":
    main()
