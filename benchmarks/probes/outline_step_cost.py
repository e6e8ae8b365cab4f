"""What does the outline step after the search cost the 3D tree (issue 48)?

Each held-out-style drawing (``bench_drawings.py --part refine``'s: one tree per species
from ``--first-seed``, ``--per-species`` each, in the renderer's other styles) is run
through the default pipeline twice, with the outline step (``refine.start.polish``) and
without it (``refine.start.POLISH_EVALS`` 0), and prints per drawing and in all: the mesh
error against the ground truth (normalised max Hausdorff, each tree turned into the
drawing's view), the envelope overlap of the drawing and the returned tree's sketch
(``eval.envelope``), the search's distance and the outline step's, the drawing's
``ShapeTarget.inside_ink`` (how much of its crown's inside is drawn), and the overlap of
the drawing and the ground truth's own sketch at the drawn view (how far an outline can
follow a drawing in these styles and still be the drawn tree's).  ``--people N`` adds
the first N held-out people's tree drawings (overlaps and distances only: no truth).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/outline_step_cost.py \
        [--first-seed 950 --per-species 1] [--people 0] [--json OUT]
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

import refine.start
from benchmarks.bench_drawings import tree_drawings
from eval.envelope import envelope_overlap
from eval.hausdorff import bbox_diagonal, hausdorff, rotate_about_trunk
from eval.people import people_drawings
from refine.objective import PreparedDrawing
from refine.start import cheap_sketches
from treesketch import Pipeline
from treesketch.steps import as_drawn, prepare_input
from weberpenn import build_mesh, grow, species


def inside(img: np.ndarray) -> float:
    """The drawing's ``inside_ink`` as the refinement sees it."""
    return PreparedDrawing.create(prepare_input(img), 128).shape.inside_ink


def run(pipe: Pipeline, img: np.ndarray, step: bool, truth: tuple | None, yaw: float) -> dict:
    """One pipeline run with the outline step on or off."""
    evals = refine.start.POLISH_EVALS
    refine.start.POLISH_EVALS = evals if step else 0
    try:
        res = pipe.run(img)
    finally:
        refine.start.POLISH_EVALS = evals
    r = res.refinement
    out = {
        "species": res.species,
        "overlap": envelope_overlap(res.input_sketch, res.sketch_after),
        "distance": res.losses["after"],
        "search_distance": None if r is None or math.isnan(r.search_loss) else r.search_loss,
    }
    if truth is not None:
        m = rotate_about_trunk(res.tree_mesh, yaw - res.yaw).combined()
        out["mesh_error"] = hausdorff(m, *truth).max_norm
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--first-seed", type=int, default=950)
    ap.add_argument("--per-species", type=int, default=1)
    ap.add_argument("--people", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    pipe = Pipeline("tsn")
    rows = []
    drawings = sorted(
        tree_drawings(args.first_seed, args.per_species, False, None),
        key=lambda d: (d["seed"], species.SPECIES.index(d["species"])),
    )
    for d in drawings:
        gt = build_mesh(grow(d["params"]), species=d["species"])
        truth = (gt.combined(), 2000, bbox_diagonal(gt.bounds()))
        own = cheap_sketches(d["params"], d["species"], 256, [d["yaw"]])[0]
        row = {
            "name": d["name"],
            "style": d["style"],
            "truth_overlap": envelope_overlap(as_drawn(prepare_input(d["image"])), as_drawn(own)),
            "inside_ink": inside(d["image"]),
            "on": run(pipe, d["image"], True, truth, d["yaw"]),
            "off": run(pipe, d["image"], False, truth, d["yaw"]),
        }
        rows.append(row)
        on, off = row["on"], row["off"]
        print(
            f"{d['name']:>10} {d['style']:>8}: mesh {on['mesh_error']:.3f} (off "
            f"{off['mesh_error']:.3f}), overlap {on['overlap']:.3f} (off {off['overlap']:.3f},"
            f" the truth's {row['truth_overlap']:.3f})",
            flush=True,
        )
    for i, p in enumerate(people_drawings("held", ("strokes",), ("tree",))[: args.people]):
        img = np.asarray(p.image())
        row = {"name": f"people/{i:02d}-{p.key}", "inside_ink": inside(img)}
        row["on"] = run(pipe, img, True, None, 0.0)
        row["off"] = run(pipe, img, False, None, 0.0)
        rows.append(row)
        print(
            f"{row['name']:>24}: overlap {row['on']['overlap']:.3f} "
            f"(off {row['off']['overlap']:.3f})",
            flush=True,
        )
    drawn = [r for r in rows if "truth_overlap" in r]
    if drawn:
        for k in ("on", "off"):
            e = [r[k]["mesh_error"] for r in drawn]
            o = [r[k]["overlap"] for r in drawn]
            print(
                f"held-out style, outline step {k:>3}: mesh error mean {np.mean(e):.4f} median "
                f"{np.median(e):.4f}; overlap median {np.median(o):.3f} ({len(e)} drawings)"
            )
        t = [r["truth_overlap"] for r in drawn]
        print(f"the truth's own overlap: median {np.median(t):.3f}, mean {np.mean(t):.3f}")
        i = [r["inside_ink"] for r in drawn]
        print(f"inside ink: median {np.median(i):.3f}, 10th percentile {np.percentile(i, 10):.3f}")
    people = [r for r in rows if r["name"].startswith("people/")]
    if people:
        for k in ("on", "off"):
            o = [r[k]["overlap"] for r in people]
            print(f"people, outline step {k:>3}: overlap median {np.median(o):.4f}")
        i = [r["inside_ink"] for r in people]
        print(
            f"people's inside ink: median {np.median(i):.3f}, 90th percentile {np.percentile(i, 90):.3f}"
        )
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
