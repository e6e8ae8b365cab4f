"""What one refinement evaluation costs per species, stage by stage.

    .venv/bin/python benchmarks/eval_cost.py [--trees 3] [--size 128] [--repeats 3]

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
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from refine.objective import METRICS, framed, make_target  # noqa: E402
from refine.search import RefineSettings  # noqa: E402
from render.sketch import SketchRenderer  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402

STAGES = ("grow", "mesh", "scene", "sketch", "frame", "loss", "view only")
COUNTED = STAGES[:-1]  # a new point's evaluation; "view only" is the yaw-only move


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def measure(name: str, trees: int, size: int, repeats: int, metric: str) -> dict:
    rows = []
    for i in range(trees):
        p = species.sample(name, i)
        other = SketchRenderer(build_mesh(grow(species.sample(name, i + 100)))).sketch(0.0, size)
        target = make_target(framed(other, size), size, metric)
        t = {}
        t["grow"], sk = _best(lambda p=p: grow(p), repeats)
        t["mesh"], mesh = _best(lambda sk=sk: build_mesh(sk, species=name), repeats)
        t["scene"], rend = _best(lambda mesh=mesh: SketchRenderer(mesh), repeats)
        t["sketch"], img = _best(lambda rend=rend: rend.sketch(0.0, size), repeats)
        t["frame"], fr = _best(lambda img=img: framed(img, size), repeats)
        t["loss"], _ = _best(
            lambda fr=fr, tg=target: tg.distance(make_target(fr, size, metric)), repeats
        )
        t["view only"], _ = _best(lambda rend=rend: rend.sketch(37.0, size), repeats)
        t["tris"] = len(mesh.branches.faces) + len(mesh.leaves.faces)
        rows.append(t)
    out = {k: statistics.median(r[k] for r in rows) for k in (*STAGES, "tris")}
    out["total"] = sum(out[k] for k in COUNTED)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trees", type=int, default=3)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--species", nargs="*", default=list(species.SPECIES))
    ap.add_argument("--metric", choices=METRICS, default=RefineSettings().metric)
    args = ap.parse_args()
    SketchRenderer(build_mesh(grow(species.sample("palm", 0)))).sketch(0.0, args.size)  # warm-up
    print(
        "| species | triangles | "
        + " | ".join(f"{s} ms" for s in STAGES)
        + " | evaluation ms | largest stage |"
    )
    print("|---|---:|" + "---:|" * len(STAGES) + "---:|---|")
    for name in args.species:
        r = measure(name, args.trees, args.size, args.repeats, args.metric)
        top = max(COUNTED, key=lambda s: r[s])
        cells = " | ".join(f"{1000 * r[s]:.0f}" for s in STAGES)
        print(
            f"| {name} | {int(r['tris'])} | {cells} | {1000 * r['total']:.0f} | "
            f"{top} ({r[top] / r['total']:.0%}) |",
            flush=True,
        )


if __name__ == "__main__":
    main()
