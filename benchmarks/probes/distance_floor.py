"""Probe: how far in 3D are trees that fit the drawings as well as the truth does?

    .venv/bin/python benchmarks/probes/distance_floor.py [--views front,side] [--budget 40] [--only palm,bonsai]
    .venv/bin/python benchmarks/probes/distance_floor.py --drawings 2 [--first-seed 950] [--views front]

For each of the paper's 15 published trees, drawn (SG, 256 px) from the front, or from the
front and the side as ``bench_gt15.py`` draws them (``--drawings N``: instead, ``N`` fresh
trees per species drawn in the held-out styles at a random view, and with ``side`` from 90
degrees further round, as ``bench_drawings.py --part refine`` draws them; the search from
the truth is then given the drawing's view): the sketch distance the refinement
minimises (the mean over the views) for the truth itself, seen from its own view; then two
searches of the pipeline's settings over the truth's species' free values and the view,
one from the network's first estimate (as the pipeline runs) and one from the truth
itself.  For each: the sketch distance it ends at and the mesh error (normalised max
Hausdorff, the tree turned back by the view it found, ``--samples`` per side) of the
tree it ends at, and of every best-so-far tree whose distance is at or below the truth's.

A search from the truth that ends below the truth's own distance has found a tree the
drawings prefer to the truth; its mesh error is what the drawings cannot tell apart, a
floor under any search that minimises this distance.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from eval.hausdorff import hausdorff, rotate_about_trunk
from refine import refine
from refine.objective import OtherView, PreparedDrawing
from render.sketch import SketchRenderer
from treesketch import Pipeline
from treesketch.estimators import SeededEstimator, TSNEstimator
from treesketch.pipeline import prepare_input
from treesketch.views import fuse_estimates
from weberpenn import TreeParams, build_mesh, grow, load_params, species

ROOT = Path(__file__).resolve().parents[2]
GT_DIR = ROOT / "tests" / "data" / "treesketchnet_test_params"
VIEWS = {"front": 0.0, "side": 90.0}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--views", default="front,side", help="front, or front,side")
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--samples", type=int, default=4000)
    ap.add_argument("--only", default="", help="species to run (default: all 15 trees)")
    ap.add_argument("--drawings", type=int, default=0, help="N held-out-style trees per species")
    ap.add_argument("--first-seed", type=int, default=950, help="with --drawings")
    args = ap.parse_args(argv)
    names = [n.strip() for n in args.views.split(",")]
    if names[0] != "front" or any(n not in VIEWS for n in names):
        raise SystemExit(f"--views: front, then side, got {args.views!r}")
    wanted = {species.canonical(s) for s in args.only.split(",") if s.strip()}
    inner = TSNEstimator.load()
    print(
        f"views {','.join(names)}, budget {args.budget}: distance (mesh error); "
        "'<= truth': best-so-far trees at or below the truth's distance, their mesh errors"
    )
    print(
        "| tree | truth's distance | from the estimate | from the truth | "
        "from the truth, <= truth: n, median / max mesh | seconds |"
    )
    print("|---|---:|---|---|---|---:|")
    rows = []
    cases = (
        drawn_cases(args.drawings, args.first_seed, names, wanted)
        if args.drawings
        else published_cases(names, wanted)
    )
    for label, name, gt, imgs, yaws in cases:
        t0 = time.perf_counter()
        # a drawing's random view is not among the search's start views: the search from
        # the truth is given it, so that it starts at the truth itself
        known = yaws[0] if args.drawings else None
        row = one_tree(name, gt, imgs, yaws, inner, args.budget, args.samples, known)
        rows.append(row)
        d_truth, d_est, e_est, d_gt, e_gt, below = row
        below_text = (
            f"{len(below)}: {float(np.median(below)):.3f} / {max(below):.3f}" if below else "0"
        )
        print(
            f"| {label} | {d_truth:.3f} | {d_est:.3f} ({e_est:.3f}) | "
            f"{d_gt:.3f} ({e_gt:.3f}) | {below_text} | "
            f"{time.perf_counter() - t0:.0f} |",
            flush=True,
        )
    if rows:
        a = np.array([r[:5] for r in rows])
        print(
            f"| mean | {a[:, 0].mean():.3f} | {a[:, 1].mean():.3f} ({a[:, 2].mean():.4f}) | "
            f"{a[:, 3].mean():.3f} ({a[:, 4].mean():.4f}) | | |"
        )
        print(
            f"from the estimate: ends at or below the truth's distance on "
            f"{int((a[:, 1] <= a[:, 0]).sum())} of {len(rows)}; from the truth: ends below "
            f"it on {int((a[:, 3] < a[:, 0]).sum())} of {len(rows)}, mean mesh error "
            f"{a[:, 4].mean():.4f}"
        )
    return 0


Case = tuple[str, str, TreeParams, list[np.ndarray], list[float]]


def published_cases(names: list[str], wanted: set[str]) -> Iterator[Case]:
    """(label, species, truth, drawings, their yaws) for the 15 published trees, SG."""
    files = sorted(GT_DIR.glob("*.json"), key=lambda p: int(p.stem.split("_", 1)[0]))
    for path in files:
        name = species.canonical(path.stem.split("_", 1)[1])
        if wanted and name not in wanted:
            continue
        gt = load_params(path)
        drawer = SketchRenderer(build_mesh(grow(gt), species=name), species=name)
        yaws = [VIEWS[n] for n in names]
        yield path.stem, name, gt, [prepare_input(drawer.sketch(y, 256)) for y in yaws], yaws


def drawn_cases(
    per_species: int, first_seed: int, names: list[str], wanted: set[str]
) -> Iterator[Case]:
    """The same for ``bench_drawings``' held-out-style drawings (the side 90 degrees round)."""
    from benchmarks.bench_drawings import tree_drawings

    for d in tree_drawings(first_seed, per_species, len(names) > 1, sorted(wanted) or None):
        imgs = [d["image"]] + ([d["side"]] if len(names) > 1 else [])
        yaws = [d["yaw"], d["yaw"] + 90.0][: len(imgs)]
        label = f"{d['name']} ({d['style']})"
        yield label, d["species"], d["params"], [prepare_input(i) for i in imgs], yaws


def one_tree(
    name: str,
    gt: TreeParams,
    imgs: list[np.ndarray],
    yaws: list[float],
    inner: TSNEstimator,
    budget: int,
    samples: int,
    truth_yaw: float | None = None,
) -> tuple:
    """(truth's distance, the estimate's search: distance, mesh error, the truth's search:
    distance, mesh error, mesh errors of its best-so-far trees at or below the truth's)."""
    gt_mesh = build_mesh(grow(gt), species=name)
    truth = gt_mesh.combined()
    pipe = Pipeline(SeededEstimator(inner, int(gt["seed"]))).with_settings(
        refine=True, budget=budget, time_limit=None
    )
    cfg = pipe.settings
    drawings = [PreparedDrawing.create(i, cfg.size, cfg.metric, pipe.embedder) for i in imgs]
    others = [OtherView(d, y - yaws[0]) for d, y in zip(drawings[1:], yaws[1:], strict=True)]

    def mesh_error(params: TreeParams, yaw: float) -> float:
        m = rotate_about_trunk(build_mesh(grow(params), species=name), yaws[0] - yaw)
        return hausdorff(m.combined(), truth, samples).max_norm

    def search(start: TreeParams, evaluations: int, yaw: float | None = None):
        bests: list[tuple[TreeParams, float, float]] = []
        r = refine(
            drawings[0],
            start,
            cfg.replace(budget=evaluations),
            species=name,
            yaw=yaw,
            embedder=pipe.embedder,
            views=others,
            on_best=lambda p, y, d, _w: bests.append((p, y, d)),
        )
        return r, bests

    own, _ = search(gt, 1, yaw=yaws[0])  # the truth's distance at its own view
    d_truth = own.loss_before
    est = fuse_estimates([pipe.estimator.estimate(i) for i in imgs])
    from_est, _ = search(est.params_for(name), budget)
    from_gt, bests = search(gt, budget, yaw=truth_yaw)
    below = [mesh_error(p, y) for p, y, d in bests if d <= d_truth]
    return (
        d_truth,
        from_est.loss_after,
        mesh_error(from_est.params, from_est.yaw),
        from_gt.loss_after,
        mesh_error(from_gt.params, from_gt.yaw),
        below,
    )


if __name__ == "__main__":
    raise SystemExit(main())
