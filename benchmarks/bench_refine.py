"""Benchmark: TSN alone vs TSN + refinement on held-out synthetic sketches.

For N test-split sketches per species (one view per tree, views cycling front/left/back/
right) of the dataset built by ``render.dataset``: the first estimate (TSN; or with
``--estimator nns`` the nearest training sketch's parameters, ``eval.baseline``; or with
``--estimator perturbed`` the ground truth moved by +-``--shift`` in every free unit-cube
coordinate), then ``refine.refine`` at the default budget and time limit, the view yaw
searched (``--known-yaw`` gives it the true one, an oracle).  Reports the sketch loss before/after, seconds, evaluations, and
the mesh error: the symmetric Hausdorff distance (max, and mean) to the ground-truth mesh
divided by the ground-truth bounding-box diagonal (``eval.hausdorff``).  Each estimate is
placed in the ground truth's frame by its own view: the refined tree is turned about the
trunk by (view yaw - found yaw), TSN alone -- which has no view estimate and shows its tree
as seen from the front -- by (view yaw - 0), so both face the way they say the sketch shows.
"gt frame" columns: TSN's tree NOT turned, i.e. given the sketch's true view (an oracle, and
one that only helps because the generator gives every tree of a species the same azimuth
pattern).
Also the "aligned" max distance: each tree turned about its trunk to its best fit
(``aligned_tree_hausdorff``), the shape error without the orientation a single sketch
cannot tell.

    nice -n 10 .venv/bin/python benchmarks/bench_refine.py --data /work/data/ds_v1 \
        --per-species 5 --json /work/data/bench_refine.json

``--executor ray [--address ADDR]`` (or ``--workers N`` local processes) spreads the cases;
each case is the same computation wherever it runs, but a refinement stopped by
``--time-limit`` rather than by ``--budget`` depends on the machine's speed.
"""

from __future__ import annotations

import argparse
import functools
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from eval.hausdorff import (
    aligned_tree_hausdorff,
    bbox_diagonal,
    hausdorff,
    rotate_about_trunk,
)
from refine.objective import SearchSpace
from render.dataset import read_manifest
from render.reader import read_sketch
from treesketch import Estimate, Pipeline, RefineSettings, load_estimator
from treesketch.executor import ExecutorError, from_options
from weberpenn import build_mesh, grow, load_params, species
from weberpenn.fileio import atomic_write

VIEW_ORDER = ("front", "left", "back", "right")


def pick_rows(data: Path, per_species: int, style: str = "sg") -> list[dict]:
    # a mixed-style dataset has one row per style of each view: keep one style
    rows = [r for r in read_manifest(data, split="test") if r.get("style", "sg") == style]
    out = []
    for name in species.SPECIES:
        trees = sorted({r["tree_id"] for r in rows if r["species"] == name})[:per_species]
        for i, tid in enumerate(trees):
            view = VIEW_ORDER[i % len(VIEW_ORDER)]
            out += [r for r in rows if r["tree_id"] == tid and r["view"] == view]
    return out


def perturbed(name: str, gt, shift: float, seed: int):
    sp = SearchSpace.create(name, gt, search_yaw=False)
    x = sp.from_params(gt)
    rng = np.random.default_rng(seed)
    return sp.to_params(np.clip(x + rng.choice([-shift, shift], size=x.shape), 0.0, 1.0))


class KnownStart:
    """An estimator that answers with a given tree (and, with the oracle, its view)."""

    def __init__(self, inner, tree=None, species_name: str = "", yaw: float | None = None):
        self.inner, self.tree, self.species_name, self.yaw = inner, tree, species_name, yaw
        self.name = "perturbed" if inner is None else inner.name

    def estimate(self, sketch: np.ndarray) -> Estimate:
        if self.inner is not None:
            e = self.inner.estimate(sketch)
            return Estimate(e.params, e.species, e.species_scores, self.yaw)
        return Estimate(self.tree, self.species_name, {self.species_name: 1.0}, self.yaw)


@dataclass(frozen=True)
class CaseWorker:
    """Worker factory (picklable) for an executor: one case is one held-out sketch,
    estimated, refined and measured.  The estimator travels with it (a TSN estimator
    reloads its checkpoint in the worker)."""

    data: str
    inner: Any
    settings: RefineSettings
    shift: float
    known_yaw: bool
    samples: int
    align_step: float

    def __call__(self) -> Callable[[tuple[int, dict]], dict]:
        return functools.partial(run_case, self)


def run_case(cfg: CaseWorker, case: tuple[int, dict]) -> dict:
    k, row = case
    data = Path(cfg.data)
    name = row["species"]
    img = read_sketch(data / row["sketch"])
    gt = load_params(data / row["params"])
    gt_mesh = build_mesh(grow(gt), species=name)
    known = float(row["yaw"]) if cfg.known_yaw else None
    if cfg.inner is None:
        est = KnownStart(None, perturbed(name, gt, cfg.shift, k), name, known)
    else:
        est = KnownStart(cfg.inner, yaw=known)
    run = Pipeline(est, cfg.settings).run(img)
    r, start, guessed = run.refinement, run.estimate.params, run.species
    view_yaw = float(row["yaw"])
    m0 = build_mesh(grow(start), species=guessed)
    m1 = rotate_about_trunk(build_mesh(grow(r.params), species=guessed), view_yaw - r.yaw)
    gt_c, diag = gt_mesh.combined(), bbox_diagonal(gt_mesh.bounds())
    m0_view = rotate_about_trunk(m0, view_yaw)  # TSN shows its tree as a front view
    h0 = hausdorff(m0_view.combined(), gt_c, cfg.samples, diag)  # branches + leaves
    h0_gt = hausdorff(m0.combined(), gt_c, cfg.samples, diag)
    h1 = hausdorff(m1.combined(), gt_c, cfg.samples, diag)
    # the same, each tree turned about its trunk to its best fit (shape alone)
    t0, a0 = aligned_tree_hausdorff(m0, gt_mesh, cfg.samples, cfg.align_step)
    t1, a1 = aligned_tree_hausdorff(m1, gt_mesh, cfg.samples, cfg.align_step)
    return {
        "tree_id": row["tree_id"],
        "view": row["view"],
        "species": name,
        "species_pred": guessed,
        "loss_before": r.loss_before,
        "loss_after": r.loss_after,
        "seconds": r.seconds,
        "evaluations": r.evaluations,
        "stopped_by": r.stopped_by,
        "yaw_view": view_yaw,
        "yaw_found": r.yaw,
        "haus_max_before": h0.max_norm,
        "haus_max_after": h1.max_norm,
        "haus_mean_before": h0.mean_norm,
        "haus_mean_after": h1.mean_norm,
        "haus_max_before_gt_frame": h0_gt.max_norm,
        "haus_mean_before_gt_frame": h0_gt.mean_norm,
        "aligned_max_before": a0.max_norm,
        "aligned_max_after": a1.max_norm,
        "aligned_turn_before": t0,
        "aligned_turn_after": t1,
        "params_start": start.to_dict(),
        "params_refined": r.params.to_dict(),
    }


def case_line(rec: dict) -> str:
    return (
        f"{rec['tree_id']:>12} {rec['view']:>5} loss {rec['loss_before']:.4f}->"
        f"{rec['loss_after']:.4f} {rec['seconds']:5.1f}s {rec['evaluations']:3d} ev  haus max "
        f"{rec['haus_max_before']:.4f}->{rec['haus_max_after']:.4f} (gt frame "
        f"{rec['haus_max_before_gt_frame']:.4f}) mean {rec['haus_mean_before']:.4f}->"
        f"{rec['haus_mean_after']:.4f} aligned max {rec['aligned_max_before']:.4f}->"
        f"{rec['aligned_max_after']:.4f}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("/work/data/ds_v1"))
    ap.add_argument("--per-species", type=int, default=5)
    ap.add_argument("--style", default="sg", help="drawing style of a mixed-style dataset")
    ap.add_argument("--budget", type=int, default=RefineSettings().budget)
    ap.add_argument("--time-limit", type=float, default=RefineSettings().time_limit)
    ap.add_argument("--estimator", choices=("tsn", "nns", "perturbed"), default="tsn")
    ap.add_argument(
        "--known-yaw",
        action="store_true",
        help="give refinement the sketch's true view yaw (an oracle; default: searched)",
    )
    ap.add_argument("--shift", type=float, default=0.25)
    ap.add_argument("--species", default=None, help="comma list (default: all five)")
    ap.add_argument(
        "--hold",
        default=None,
        help="comma list of keys not searched (default: refine.search.DEFAULT_HOLD; '' for none)",
    )
    ap.add_argument(
        "--markdown", type=Path, default=None, help="only print the tables of a --json file"
    )
    ap.add_argument("--samples", type=int, default=10_000, help="Hausdorff samples per side")
    ap.add_argument("--algorithm", default=RefineSettings.algorithm, help="cobyla, bobyqa or sbplx")
    ap.add_argument(
        "--align-step", type=float, default=15.0, help="turns tried for the aligned distance"
    )
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--executor", default="local", help="where the cases run: local or ray")
    ap.add_argument("--workers", type=int, default=1, help="local processes or local Ray CPUs")
    ap.add_argument("--address", default=None, help="Ray cluster (auto, HOST:PORT)")
    args = ap.parse_args(argv)
    if args.markdown is not None:
        recs = json.loads(args.markdown.read_text())["records"]
        print(markdown(recs, summarise(recs)))
        return 0

    inner = None
    if args.estimator in ("tsn", "nns"):
        inner = load_estimator(args.estimator, data=args.data)
    settings = RefineSettings(
        budget=args.budget,
        time_limit=args.time_limit,
        algorithm=args.algorithm,
        search_yaw=not args.known_yaw,
    )
    if args.hold is not None:
        settings = settings.replace(hold=tuple(k for k in args.hold.split(",") if k))
    try:
        settings.validate()  # a bad option fails here, not in every case
    except ValueError as exc:
        ap.error(str(exc))
    only = None if args.species is None else set(args.species.split(","))
    cases = [
        (k, row)
        for k, row in enumerate(pick_rows(args.data, args.per_species, args.style))
        if only is None or row["species"] in only
    ]
    worker = CaseWorker(
        str(args.data), inner, settings, args.shift, args.known_yaw, args.samples, args.align_step
    )
    try:
        runner = from_options(args.executor, args.workers, args.address)
    except ExecutorError as exc:
        ap.error(str(exc))
    records_by_k: dict[int, dict] = {}
    try:
        outcomes = (
            ((i, worker()(case), None) for i, case in enumerate(cases))
            if runner is None
            else ((o.index, o.value, o.error) for o in runner.run(worker, cases))
        )
        for i, rec, error in outcomes:
            if error is not None:  # reported, not retried: the rest of the run goes on
                print(f"{cases[i][1]['tree_id']:>12} failed: {error.splitlines()[0]}", flush=True)
                continue
            records_by_k[cases[i][0]] = rec
            print(case_line(rec), flush=True)
    finally:
        if runner is not None:
            runner.close()
    records = [records_by_k[k] for k in sorted(records_by_k)]
    summary = summarise(records)
    print(json.dumps(summary, indent=1))
    if args.json is not None:
        atomic_write(
            args.json,
            json.dumps(
                {
                    "args": vars(args) | {"data": str(args.data), "json": str(args.json)},
                    "summary": summary,
                    "records": records,
                },
                indent=1,
            ),
        )
    return 0


def markdown(records: list[dict], summary: dict) -> str:
    """Per-sketch table and per-species means (for RESULTS.md)."""
    lines = [
        "| sketch | view | loss before -> after | s | evals | yaw view / found |"
        " Hausdorff max before -> after | TSN in gt frame | aligned max before -> after |",
        "|---|---|---|---:|---:|---|---|---:|---|",
    ]
    for r in records:
        lines.append(
            f"| {r['tree_id']} | {r['view']} | {r['loss_before']:.4f} -> {r['loss_after']:.4f} |"
            f" {r['seconds']:.1f} | {r['evaluations']} | {r['yaw_view']:.0f} / "
            f"{r['yaw_found']:.0f} | {r['haus_max_before']:.4f} -> {r['haus_max_after']:.4f} |"
            f" {r.get('haus_max_before_gt_frame', float('nan')):.4f} |"
            f" {r['aligned_max_before']:.4f} -> {r['aligned_max_after']:.4f} |"
        )
    lines += [
        "",
        "| species | n | loss before -> after | Hausdorff max before -> after (improved) |"
        " TSN in gt frame (refined better) | aligned max before -> after (improved) |"
        " s mean / max |",
        "|---|---:|---|---|---|---|---|",
    ]
    groups: dict[str, list[dict]] = {}
    for r in records:
        groups.setdefault(r["species"], []).append(r)
    groups["all"] = records
    for sp, rs in groups.items():
        s = summarise(rs)
        hb, ha = s["haus_max_before_mean"], s["haus_max_after_mean"]
        ab, aa = s["aligned_max_before_mean"], s["aligned_max_after_mean"]
        lines.append(
            f"| {sp} | {s['n']} | {s['loss_before_mean']:.4f} -> {s['loss_after_mean']:.4f} |"
            f" {hb:.4f} -> {ha:.4f} ({s['haus_max_improved_frac']:.0%}) |"
            f" {s.get('haus_max_before_gt_frame_mean', float('nan')):.4f}"
            f" ({s.get('haus_max_improved_frac_vs_gt_frame', float('nan')):.0%}) |"
            f" {ab:.4f} -> {aa:.4f} ({s['aligned_max_improved_frac']:.0%}) |"
            f" {s['seconds_mean']:.1f} / {s['seconds_max']:.1f} |"
        )
    return "\n".join(lines)


def _column(records: list[dict], key: str) -> np.ndarray | None:
    """``key`` of every record, or None when a record lacks it (older JSON files)."""
    if not all(key in r for r in records):
        return None
    return np.array([r[key] for r in records])


def summarise(records: list[dict]) -> dict:
    n = len(records)
    if n == 0:
        return {"n": 0}
    lb = np.array([r["loss_before"] for r in records])
    la = np.array([r["loss_after"] for r in records])
    hb = np.array([r["haus_max_before"] for r in records])
    ha = np.array([r["haus_max_after"] for r in records])
    mb = np.array([r["haus_mean_before"] for r in records])
    ma = np.array([r["haus_mean_after"] for r in records])
    sec = np.array([r["seconds"] for r in records])
    ab = np.array([r["aligned_max_before"] for r in records])
    aa = np.array([r["aligned_max_after"] for r in records])
    return {
        "n": n,
        "loss_never_worse": bool(np.all(la <= lb + 1e-12)),
        "loss_fell_frac": float(np.mean(la < lb)),
        "loss_before_mean": float(lb.mean()),
        "loss_after_mean": float(la.mean()),
        "haus_max_improved_frac": float(np.mean(ha < hb)),
        "haus_max_before_mean": float(hb.mean()),
        "haus_max_after_mean": float(ha.mean()),
        "haus_mean_improved_frac": float(np.mean(ma < mb)),
        "haus_mean_before_mean": float(mb.mean()),
        "haus_mean_after_mean": float(ma.mean()),
        **(
            {
                "haus_max_improved_frac_vs_gt_frame": float(np.mean(ha < hg)),
                "haus_max_before_gt_frame_mean": float(hg.mean()),
            }
            if (hg := _column(records, "haus_max_before_gt_frame")) is not None
            else {}
        ),
        "aligned_max_improved_frac": float(np.mean(aa < ab)),
        "aligned_max_before_mean": float(ab.mean()),
        "aligned_max_after_mean": float(aa.mean()),
        "seconds_mean": float(sec.mean()),
        "seconds_max": float(sec.max()),
        "evaluations_mean": float(np.mean([r["evaluations"] for r in records])),
    }


if __name__ == "__main__":
    raise SystemExit(main())
