"""Probe: at a swept angle of the rotation sweep, is the refined tree's sketch distance
above the ground truth's own (the search stopped short) or below it (the distance points
elsewhere)?

    .venv/bin/python benchmarks/probes/search_gap.py 3_palm_3.json 0 30 60 [--turn 90] [--budget 24]

For one published tree, drawn as the report draws it at each angle (and ``--turn`` degrees
further round), refined as the report refines it (the truth's seed key, ``--budget``, no
time limit): the sketch distance the search minimises for the ground truth itself at the
drawn view, for the first estimate at the drawn view, and for the refined tree at the view
it found, with the mesh errors (normalised max Hausdorff, 4000 samples) of the first
estimate and the refined tree.
"""

from __future__ import annotations

import argparse

import numpy as np

from eval.hausdorff import hausdorff, rotate_about_trunk
from eval.paper import PUBLISHED_DIR
from refine.objective import PreparedDrawing
from render.sketch import SketchRenderer, sketch_mesh
from treesketch import Pipeline
from treesketch.estimators import SeededEstimator, TSNEstimator
from treesketch.pipeline import prepare_input
from weberpenn import build_mesh, grow
from weberpenn.params import load_params


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tree", help="a file of tests/data/treesketchnet_test_params")
    ap.add_argument("angles", type=float, nargs="+")
    ap.add_argument("--turn", type=float, action="append", default=[])
    ap.add_argument("--budget", type=int, default=24)
    args = ap.parse_args(argv)
    gt = load_params(PUBLISHED_DIR / args.tree)
    pipe = Pipeline(SeededEstimator(TSNEstimator.load(), int(gt["seed"]))).with_settings(
        refine=True, budget=args.budget, time_limit=None
    )
    cfg = pipe.settings
    truth_mesh = build_mesh(grow(gt))
    truth, drawer = truth_mesh.combined(), SketchRenderer(truth_mesh)

    def fast(params):  # the refinement's own way of drawing a candidate
        return SketchRenderer(sketch_mesh(grow(params), cfg.size, None), engine="raster")

    def mesh_error(params, turn: float) -> float:
        m = rotate_about_trunk(build_mesh(grow(params)), turn)
        return hausdorff(m.combined(), truth, 4000).max_norm

    truth_fast = fast(gt)
    turns = (0.0, *args.turn)
    for yaw in args.angles:
        imgs = [drawer.sketch((yaw + t) % 360.0, size=256) for t in turns]
        drawings = [
            PreparedDrawing.create(prepare_input(i), cfg.size, cfg.metric, pipe.embedder)
            for i in imgs
        ]

        def loss(r: SketchRenderer, at: float, drawings=drawings) -> float:
            return float(
                np.mean([d.distance(r.sketch((at + t) % 360.0, cfg.size))
                         for d, t in zip(drawings, turns, strict=True)])
            )  # fmt: skip

        run = pipe.run(
            imgs[0] if len(imgs) == 1 else [imgs[0], *zip(imgs[1:], args.turn, strict=True)]
        )
        est = run.estimate.params
        print(
            f"{yaw:5.0f} deg: truth {loss(truth_fast, yaw):.3f}; first estimate "
            f"{loss(fast(est), yaw):.3f} (mesh {mesh_error(est, 0.0):.3f}); refined at "
            f"{run.yaw:.1f} deg {run.losses['after']:.3f} "
            f"(mesh {mesh_error(run.params, (yaw - run.yaw) % 360.0):.3f})",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
