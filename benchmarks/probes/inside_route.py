"""Which drawings does the stroke-width cap of ``ShapeTarget.inside_ink`` touch?

``inside_ink`` counts a line no wider than ``refine.shape.INSIDE_STROKE`` and leaves out a
band along the outline as much wider as a line is wider than that; a drawing whose
lines are all as narrow as that (``render.reader.stroke_width`` at the search's 128 px) has
the same share as without the cap, and the refinement takes it down the same road (a
drawing of outlines under ``refine.start.LINES_INSIDE``, one that shows its inside at or
above it). Per set: the median and widest stroke, how many drawings are wider than the
cap (only those can change), and how many read as showing their inside, with the cap and
without it (the band as wide either way; a pair's two drawings go one road, by their
mean: the pairs' row counts pairs). Sets: people's held-out trees of each folder (the
first ``--people`` of each), the paper's ten, the code-made doodle pairs (``--pairs`` a
species, seeds 950+), the held-out-style drawings of the mesh-error figure (one a species
at seed 950, three at 952+), and with ``--published`` the renderer's sketches of the
paper's 15 trees every 15 degrees (the reports' views).

    .venv/bin/python benchmarks/probes/inside_route.py --people 143 --published
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def reading(img: Any) -> tuple[float, float, float]:
    """(stroke width at 128 px, inside_ink, the share without the cap) of a drawing as
    the refinement prepares it."""
    from bench_drawings import seen_shape

    from refine.shape import INSIDE_STROKE
    from render.reader import stroke_width

    shape = seen_shape(img)
    width = stroke_width(shape.image < 0.5)
    capped = shape.inside_ink
    return width, capped, capped / min(1.0, INSIDE_STROKE * shape.size / width)


def drawing_sets(people: int, pairs: int, published: bool) -> dict[str, list[Any]]:
    import bench_drawings as bd

    from eval.people import people_drawings

    sets: dict[str, list[Any]] = {}
    for source in ("strokes", "mouse224", "quickdraw28"):
        held = people_drawings("held", (source,), ("tree",))[:people]
        sets[f"people {source}"] = [d.image() for d in held]
    sets["the paper's ten"] = [img for _, img in bd.paper_drawings()]
    both = bd.tree_drawings(950, pairs, side=True, style="doodle")
    sets["pairs, fronts"] = [d["image"] for d in both]
    sets["pairs, sides"] = [d["side"] for d in both]
    held = bd.tree_drawings(950, 1) + bd.tree_drawings(952, 3)
    sets["held-out style (44)"] = [d["image"] for d in held]
    if published:
        import bench_gt15

        from render.sketch import SketchRenderer
        from weberpenn import build_mesh, grow, load_params

        sketches = []
        for path in bench_gt15.gt_files(None):
            name = bench_gt15.species_of(path)
            r = SketchRenderer(build_mesh(grow(load_params(path)), species=name), species=name)
            sketches += [r.sketch(yaw, 256) for yaw in range(0, 360, 15)]
        sets["the paper's 15, every 15 degrees"] = sketches
    return sets


def main() -> None:
    from refine.shape import INSIDE_STROKE
    from refine.start import LINES_INSIDE

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--people", type=int, default=143, help="of each folder's held-out trees")
    ap.add_argument("--pairs", type=int, default=3, help="doodle pairs a species")
    ap.add_argument("--published", action="store_true", help="the paper's 15 too")
    args = ap.parse_args()
    cap = INSIDE_STROKE * 128
    print(f"cap {cap:.2f} px at 128; LINES_INSIDE {LINES_INSIDE}")
    print(
        "| set | drawings | stroke median | widest | wider than the cap "
        "| show their inside | ... without the cap |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    readings = {}
    for name, imgs in drawing_sets(args.people, args.pairs, args.published).items():
        r = readings[name] = np.array([reading(img) for img in imgs])
        row(name, len(r), r[:, 0], r[:, 1], r[:, 2], cap, LINES_INSIDE)
    fronts, sides = readings["pairs, fronts"], readings["pairs, sides"]
    both = np.maximum(fronts[:, 0], sides[:, 0])
    mean = [(fronts[:, k] + sides[:, k]) / 2 for k in (1, 2)]
    row("pairs, the two views' mean", len(both), both, *mean, cap, LINES_INSIDE)


def row(
    name: str, n: int, width: np.ndarray, capped: np.ndarray, uncapped: np.ndarray,
    cap: float, limit: float,
) -> None:  # fmt: skip
    print(
        f"| {name} | {n} | {np.median(width):.2f} | {width.max():.2f} | "
        f"{int(np.sum(width > cap))} | {int(np.sum(capped >= limit))} | "
        f"{int(np.sum(uncapped >= limit))} |",
        flush=True,
    )


if __name__ == "__main__":
    main()
