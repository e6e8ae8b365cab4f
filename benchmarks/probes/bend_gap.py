"""Probe: how much of the first estimate's mesh error is the trunk's bend?

    .venv/bin/python benchmarks/probes/bend_gap.py 3_palm_3.json 0 30 60 90

For one published tree drawn (SG, 256 px) at each angle: the network's estimate of the
trunk's bend (``curve[0]``) against the truth's, the estimate's mesh error (normalised max
Hausdorff, 4000 samples, the tree's own frame as the rotation sweep measures the network
alone) and the same error with the truth's bend (``curve[0]`` and ``curveBack[0]``, nothing
else) set into the estimate.  The palm and the bonsai are the species whose bend is free.
"""

from __future__ import annotations

import argparse

from eval.hausdorff import hausdorff
from eval.paper import PUBLISHED_DIR
from render.sketch import SketchRenderer
from treesketch import Pipeline
from treesketch.estimators import SeededEstimator, TSNEstimator
from weberpenn import TreeParams, build_mesh, grow
from weberpenn.params import load_params
from weberpenn.species import TRUNK_BEND


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tree", help="a file of tests/data/treesketchnet_test_params")
    ap.add_argument("angles", type=float, nargs="+")
    args = ap.parse_args(argv)
    gt = load_params(PUBLISHED_DIR / args.tree)
    pipe = Pipeline(SeededEstimator(TSNEstimator.load(), int(gt["seed"]))).with_settings(
        refine=False
    )
    truth_mesh = build_mesh(grow(gt))
    truth, drawer = truth_mesh.combined(), SketchRenderer(truth_mesh)

    def mesh_error(params: TreeParams) -> float:
        return hausdorff(build_mesh(grow(params)).combined(), truth, 4000).max_norm

    print(f"{args.tree}: the truth's bend {gt['curve'][0]:.1f} degrees")
    for yaw in args.angles:
        est = pipe.estimate(drawer.sketch(yaw % 360.0, size=256)).params
        values = est.to_dict()
        for key, index in TRUNK_BEND:
            vector = list(values[key])
            vector[index] = float(gt[key][index])
            values[key] = vector
        print(
            f"{yaw:5.0f} deg: bend read {est['curve'][0]:7.1f}; mesh error {mesh_error(est):.3f},"
            f" with the truth's bend {mesh_error(TreeParams(values)):.3f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
