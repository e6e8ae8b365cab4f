"""`treesketch eval all`: one markdown report with every number the paper reports, ours beside.

Sections: 1-RMSE per head (every test sketch; one row per backbone given), Hausdorff distance
TSN alone vs TSN + refinement per species (front-view sketch of ``per_species`` held-out
trees each), the seed floor, species identification accuracy, the rotation sweep for one
held-out tree per species, and the paper's published numbers.

The first estimates and refinements come from a pipeline handed in (``treesketch.Pipeline``
or anything with ``estimate(sketch)``, ``run(sketch)`` and ``with_settings(**changes)``);
the 1-RMSE table from :class:`eval.scoring.Scorer` objects.  So the report is tested with
stand-ins and run with a TSN checkpoint.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn import TreeParams, build_mesh, grow

from .hausdorff import (
    DEFAULT_SAMPLES,
    PARTS,
    Distance,
    aligned_tree_hausdorff,
    rotate_about_trunk,
    seed_floor,
    tree_hausdorff,
)
from .metrics import PAPER_ONE_MINUS_RMSE, Scores, format_hardest, format_table, one_minus_rmse
from .rotation import plot_cases, plot_sweep, rotation_sweep, write_csv
from .scoring import Scorer, dataset_sketch, progress_bar

PAPER_HAUSDORFF_MEAN = 0.031  # EfficientNet-B7, 15 SG test trees
PAPER_ROTATION_RANGE = (0.029, 0.040)

HAUSDORFF_DEFINITION = (
    "Symmetric Hausdorff distance (MeshLab/pymeshlab `get_hausdorff_distance`, run in both "
    "directions): each direction samples all vertices plus points spread uniformly over the "
    "faces ({samples} samples per direction) of one mesh and takes each sample's distance to "
    "the closest point on the other mesh's surface, with no sample discarded (maxdist = the "
    "diagonal of both bounding boxes together). **max** = the larger of the two directional "
    "maxima (the classical Hausdorff distance); **mean** = the mean of the two directional "
    "means. Both are divided by the diagonal of the ground-truth tree's bounding box. Both "
    "trees are grown with the same seed (0) from their parameter dictionaries; 'combined' is "
    "branches and leaves as one mesh. The paper does not state its normalisation; its 0.031 "
    "is the Metro/HDD value from MeshLab, which we read as the normalised maximum."
)


def _test_trees(data: Path, split: str) -> tuple[list[dict], dict[str, list[dict]]]:
    from render.dataset import read_manifest

    rows = read_manifest(data, split=split)
    if not rows:
        raise ValueError(f"{data}: the {split!r} split is empty")
    trees: dict[str, dict] = {}
    for r in rows:
        trees.setdefault(r["tree_id"], r)
        if r["view"] == "front":
            trees[r["tree_id"]] = r
    by_species: dict[str, list[dict]] = {}
    for r in sorted(trees.values(), key=lambda r: r["tree_id"]):
        by_species.setdefault(r["species"], []).append(r)
    return rows, by_species


def _params(data: Path, row: Mapping) -> TreeParams:
    return TreeParams(json.loads((data / row["params"]).read_text(encoding="utf-8")))


def score_backend(
    backend: Scorer, data: Path, rows: Sequence[Mapping], batch: int = 32, bar: bool = True
) -> Scores:
    """1-RMSE of ``backend`` over the given manifest rows (all their sketches)."""
    preds, targets = [], []
    cache: dict[str, TreeParams] = {}
    starts = range(0, len(rows), batch)
    for s in progress_bar(starts, f"1-RMSE {backend.name}", len(starts), bar):
        chunk = rows[s : s + batch]
        imgs = np.stack([dataset_sketch(data / r["sketch"]) for r in chunk])
        preds.append(np.asarray(backend.predict_normalised(imgs), dtype=np.float64))
        ps = [cache.setdefault(r["params"], _params(data, r)) for r in chunk]
        targets.append(np.asarray(backend.normalise_targets(ps), dtype=np.float64))
    return one_minus_rmse(np.concatenate(preds), np.concatenate(targets))


@dataclass
class TreeResult:
    species: str
    tree_id: str
    tsn: dict[str, Distance]
    refined: dict[str, Distance] | None
    loss_before: float = float("nan")
    loss_after: float = float("nan")
    refine_seconds: float = 0.0
    # combined max distance (normalised) after the best turn about the trunk
    tsn_aligned: float = float("nan")
    refined_aligned: float = float("nan")


def hausdorff_trees(
    pipeline: Any,
    data: Path,
    by_species: Mapping[str, list[dict]],
    per_species: int,
    samples: int,
    bar: bool = True,
    aligned: bool = True,
    name: str = "",
) -> list[TreeResult]:
    """The pipeline's first estimate alone and, when its settings refine, estimate +
    refinement on the front sketch of ``per_species`` trees each (``aligned``: also the
    distance after the best turn about the trunk)."""
    jobs = [r for sp in by_species for r in by_species[sp][:per_species]]
    refining = bool(pipeline.settings.refine)
    out = []
    for r in progress_bar(jobs, f"Hausdorff ({name}, +refine)", len(jobs), bar):
        gt = _params(data, r)
        gt_mesh = build_mesh(grow(gt))
        img = dataset_sketch(data / r["sketch"])
        t0 = time.perf_counter()
        run = pipeline.run(img) if refining else None
        seconds = time.perf_counter() - t0
        pred = run.estimate.params if run is not None else pipeline.estimate(img).params
        pred_mesh = build_mesh(grow(pred))
        tsn_d = tree_hausdorff(pred_mesh, gt_mesh, samples)
        res = TreeResult(r["species"], r["tree_id"], tsn_d, None)
        if aligned:
            res.tsn_aligned = aligned_tree_hausdorff(pred_mesh, gt_mesh, samples)[1].max_norm
        if run is not None:
            res.refine_seconds = seconds
            # the refined tree matches the sketch at the yaw it found: turn it into the
            # ground truth's frame (the sketch was drawn at the row's yaw)
            turned = rotate_about_trunk(
                build_mesh(grow(run.params)), float(r.get("yaw", 0.0)) - run.yaw
            )
            res.refined = tree_hausdorff(turned, gt_mesh, samples)
            if aligned:
                res.refined_aligned = aligned_tree_hausdorff(turned, gt_mesh, samples)[1].max_norm
            res.loss_before, res.loss_after = run.losses["before"], run.losses["after"]
        out.append(res)
    return out


def species_accuracy(
    pipeline: Any, data: Path, rows: Sequence[Mapping], bar: bool = True
) -> dict[str, Any]:
    """Fraction of test sketches whose first estimate names the right species."""
    hits: dict[str, list[bool]] = {}
    for r in progress_bar(rows, "species identification", len(rows), bar):
        got = pipeline.estimate(dataset_sketch(data / r["sketch"])).species
        hits.setdefault(r["species"], []).append(got == r["species"])
    per = {sp: float(np.mean(v)) for sp, v in hits.items()}
    n = sum(len(v) for v in hits.values())
    return {"overall": float(sum(sum(v) for v in hits.values()) / n), "per_species": per, "n": n}


def _fmt(x: float, d: int = 4) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{d}f}"


def _mean(vals: list[float]) -> float:
    v = [x for x in vals if math.isfinite(x)]
    return float(np.mean(v)) if v else float("nan")


def hausdorff_table(
    results: list[TreeResult], floors: Mapping[str, dict[str, Distance]], name: str = "TSN"
) -> str:
    """Per species (and all): mean normalised max / mean distance, model vs model + refine."""
    lines = [
        f"| species | trees | {name} max | +refine max | {name} mean | +refine mean |"
        f" seed floor max | branches max ({name} / +refine) | leaves max ({name} / +refine) |"
        f" aligned max ({name} / +refine) |",
        "|---" * 10 + "|",
    ]
    groups = {
        sp: [r for r in results if r.species == sp]
        for sp in dict.fromkeys(r.species for r in results)
    }
    groups["all"] = results
    for sp, rs in groups.items():

        def m(kind: str, part: str, key: str, rs=rs) -> float:
            vals = [
                getattr(getattr(r, kind)[part], key) for r in rs if getattr(r, kind) is not None
            ]
            return _mean(vals)

        fl = (
            _mean([f["combined"].max_norm for f in floors.values()])
            if sp == "all"
            else (floors[sp]["combined"].max_norm if sp in floors else float("nan"))
        )
        lines.append(
            f"| {sp} | {len(rs)} | {_fmt(m('tsn', 'combined', 'max_norm'))} | "
            f"{_fmt(m('refined', 'combined', 'max_norm'))} | {_fmt(m('tsn', 'combined', 'mean_norm'))} | "
            f"{_fmt(m('refined', 'combined', 'mean_norm'))} | {_fmt(fl)} | "
            f"{_fmt(m('tsn', 'branches', 'max_norm'))} / {_fmt(m('refined', 'branches', 'max_norm'))} | "
            f"{_fmt(m('tsn', 'leaves', 'max_norm'))} / {_fmt(m('refined', 'leaves', 'max_norm'))} |"
            f" {_fmt(_mean([r.tsn_aligned for r in rs]))} /"
            f" {_fmt(_mean([r.refined_aligned for r in rs]))} |"
        )
    return "\n".join(lines)


def build_report(
    data: str | Path,
    out: str | Path,
    pipeline: Any,
    backend: Scorer,
    extra_backends: Sequence[Scorer] = (),
    per_species: int = 3,
    refine_budget: int = 40,
    rotation_step: float = 5.0,
    rotation_refine_budget: int = 0,
    rotation_species: Sequence[str] | None = None,
    rotation_size: int = 256,
    samples: int = DEFAULT_SAMPLES,
    split: str = "test",
    max_sketches: int | None = None,
    bar: bool = True,
    command: str = "",
    executor: Any = None,
) -> Path:
    """Compute everything and write ``OUT/README.md`` (+ PNG/CSV files); returns its path.

    ``pipeline`` makes the first estimates and refinements (its settings, with the budgets
    given here and no time limit, so the numbers do not depend on the machine's speed);
    ``backend`` and ``extra_backends`` score the 1-RMSE table; ``executor``
    (``treesketch.executor``) spreads the rotation sweeps' angles over workers, each with
    its own copy of the pipeline."""
    t_start = time.perf_counter()
    data, out = Path(data), Path(out)
    if not data.is_dir():
        raise ValueError(f"--data {data}: no such dataset directory")
    if per_species < 1:
        raise ValueError(f"per_species must be >= 1, got {per_species}")
    out.mkdir(parents=True, exist_ok=True)
    rows, by_species = _test_trees(data, split)
    if max_sketches is not None and len(rows) > max_sketches:
        pick = np.linspace(0, len(rows) - 1, max_sketches).round().astype(int)
        rows = [rows[i] for i in pick]

    scores = {backend.name: score_backend(backend, data, rows, bar=bar)}
    for b in extra_backends:
        scores[b.name] = score_backend(b, data, rows, bar=bar)
    if refine_budget > 0:
        refining = pipeline.with_settings(refine=True, budget=int(refine_budget), time_limit=None)
    else:
        refining = pipeline.with_settings(refine=False)
    trees = hausdorff_trees(
        refining, data, by_species, per_species, samples, bar, name=backend.name
    )
    floors = {}
    for sp in progress_bar(list(by_species), "seed floor", len(by_species), bar):
        floors[sp] = seed_floor(_params(data, by_species[sp][0]), samples=samples)
    acc = species_accuracy(pipeline, data, rows, bar)
    if rotation_refine_budget > 0:
        sweeping = pipeline.with_settings(
            refine=True, budget=int(rotation_refine_budget), time_limit=None
        )
    else:
        sweeping = pipeline.with_settings(refine=False)

    sweeps = _rotation_sweeps(
        data, out, by_species, sweeping, rotation_species, split, rotation_step,
        rotation_size, samples, bar, executor,
    )  # fmt: skip

    md = _markdown(
        backend, scores, trees, floors, acc, sweeps, rows, per_species, refine_budget,
        rotation_step, rotation_refine_budget, samples, split, command,
        time.perf_counter() - t_start,
    )  # fmt: skip
    from weberpenn.fileio import atomic_write

    path = out / "README.md"
    atomic_write(path, md)
    atomic_write(out / "results.json", _results_json(scores, trees, floors, acc, sweeps))
    return path


def _rotation_sweeps(
    data: Path,
    out: Path,
    by_species: Mapping[str, list[dict]],
    sweeping: Any,
    rotation_species: Sequence[str] | None,
    split: str,
    rotation_step: float,
    rotation_size: int,
    samples: int,
    bar: bool,
    executor: Any,
) -> dict[str, tuple[str, dict]]:
    """Each species' first test tree turned about its trunk (``eval.rotation``): its CSV
    and pictures into ``out``; per species the tree's id and the sweep's summary."""
    sweeps: dict[str, tuple[str, dict]] = {}
    for sp in rotation_species if rotation_species is not None else list(by_species):
        if sp not in by_species:
            raise ValueError(f"no {split} tree of species {sp!r} for the rotation sweep")
        r = by_species[sp][0]
        n = int(round(360 / rotation_step))
        pbar = progress_bar(range(n), f"rotation sweep {sp}", n, bar)
        it = iter(pbar)

        def tick(i: int, total: int, it=it) -> None:
            next(it, None)

        res = rotation_sweep(
            _params(data, r),
            sweeping,
            step=rotation_step,
            size=rotation_size,
            samples=samples,
            progress=tick,
            executor=executor,
        )
        if hasattr(pbar, "close"):
            pbar.close()
        write_csv(res.rows, out / f"rotation_{sp}.csv")
        plot_sweep(res, out / f"rotation_{sp}.png", title=f"{sp} ({r['tree_id']})")
        plot_cases(res, out / f"rotation_cases_{sp}.png")
        sweeps[sp] = (r["tree_id"], res.summary())
    return sweeps


def _results_json(
    scores: Mapping[str, Scores],
    trees: Sequence[Any],
    floors: Mapping[str, Any],
    acc: Any,
    sweeps: Mapping[str, tuple[str, dict]],
) -> str:
    """The report's numbers as JSON (``results.json``)."""
    return json.dumps(
        {
            "one_minus_rmse": {
                k: {**s.heads, "overall": s.overall, "n": s.n} for k, s in scores.items()
            },
            "hausdorff": [
                {
                    "species": t.species,
                    "tree_id": t.tree_id,
                    "tsn": {p: t.tsn[p].to_dict() for p in PARTS},
                    "refined": {p: t.refined[p].to_dict() for p in PARTS} if t.refined else None,
                    "loss_before": t.loss_before,
                    "loss_after": t.loss_after,
                    "aligned_max_norm": {"tsn": t.tsn_aligned, "refined": t.refined_aligned},
                }
                for t in trees
            ],
            "seed_floor": {sp: {p: f[p].to_dict() for p in PARTS} for sp, f in floors.items()},
            "species_accuracy": acc,
            "rotation": {sp: {"tree_id": tid, **s} for sp, (tid, s) in sweeps.items()},
        },
        indent=1,
        default=float,
    )


def _comparison_note(backend: Scorer, scores: Mapping[str, Scores]) -> str:
    """What the rows of the 1-RMSE table are, said plainly (backbones vs baselines)."""
    others = [n for n in scores if n != backend.name]
    baselines = [n for n in others if n == "NNS baseline" or "baseline" in n.lower()]
    backbones = [n for n in others if n not in baselines]
    if backbones:
        text = (
            "Backbone comparison: " + ", ".join(f"**{n}**" for n in backbones) + " trained the "
            f"same way as **{backend.name}**, scored on the same sketches."
        )
    else:
        text = (
            "Backbone comparison: **no second backbone was evaluated** in this report, so "
            "the table cannot say what the pretrained EfficientNet-Lite0 buys over another "
            "network."
        )
    if baselines:
        text += (
            " " + ", ".join(f"**{n}**" for n in baselines) + " is not a network: it returns "
            "the parameters of the closest training sketch, the floor a learned model must beat."
        )
    return text


def _markdown(
    backend, scores, trees, floors, acc, sweeps, rows, per_species, refine_budget,
    rotation_step, rotation_refine_budget, samples, split, command, seconds,
) -> str:  # fmt: skip
    all_tsn = _mean([t.tsn["combined"].max_norm for t in trees])
    all_ref = _mean([t.refined["combined"].max_norm for t in trees if t.refined])
    rot_means = [s["mean"] for _, s in sweeps.values() if s.get("n")]
    L = [
        "# TreeSketch evaluation report",
        "",
        f"Model: **{backend.name}** {json.dumps(backend.info) if backend.info else ''}".rstrip(),
        f"Data: {split} split, {len(rows)} sketches (1-RMSE, species identification); "
        f"{per_species} tree(s) per species (front view) for the Hausdorff table; "
        f"refinement budget {refine_budget} evaluations; rotation step {rotation_step} deg "
        f"(refinement budget {rotation_refine_budget}); {samples} Hausdorff samples per direction.",
    ]
    if command:
        L += ["", f"Produced by `{command}` in {seconds / 60:.1f} min."]
    if backend.info.get("kind") == "baseline":
        L += [
            "",
            f"**No TSN checkpoint was evaluated here**: the model is the {backend.name} "
            "(the nearest training sketch's parameters, no network), standing in where the "
            "paper's rows are a trained network. Every number below is the baseline's.",
        ]
    L += [
        "",
        "## Headline: ours beside the paper",
        "",
        "| quantity | paper (EfficientNet-B7) | ours |",
        "|---|---|---|",
        f"| 1-RMSE overall | {PAPER_ONE_MINUS_RMSE['overall']:.4f} | {scores[backend.name].overall:.4f} |",
        f"| mean Hausdorff ({backend.name}) | {PAPER_HAUSDORFF_MEAN} | {_fmt(all_tsn)} |",
        f"| mean Hausdorff ({backend.name} + refinement) | - | {_fmt(all_ref)} |",
        f"| Hausdorff across rotation sweep (per-tree means) | {PAPER_ROTATION_RANGE[0]}-{PAPER_ROTATION_RANGE[1]} | "
        + (f"{min(rot_means):.4f}-{max(rot_means):.4f}" if rot_means else "n/a")
        + " |",
        f"| species identification accuracy | - | {acc['overall']:.3f} (n={acc['n']}) |",
        "",
        "## 1-RMSE per head (normalised values, as the paper)",
        "",
        "1 - RMSE over every sample, row and column of each head's normalised target matrix; "
        "overall = mean of the six heads.",
        "",
        format_table({**scores, "paper: EfficientNet-B7": PAPER_ONE_MINUS_RMSE}),
        "",
        _comparison_note(backend, scores),
        "",
        f"Hardest keys for {backend.name} (largest normalised RMSE):",
        "",
        format_hardest(scores[backend.name], 10),
        "",
        f"## Hausdorff distance: {backend.name} alone vs {backend.name} + refinement",
        "",
        "Definition: " + HAUSDORFF_DEFINITION.format(samples=samples),
        "",
        "Values are means over trees of the normalised **max** (and mean) distance; the seed "
        "floor is the distance between the same ground-truth parameters grown with seeds 0 "
        "and 1 (what remains random in the generator). The refined tree is turned about its "
        "trunk into the ground truth's frame (by the sketch's yaw minus the yaw refinement "
        "found). *Aligned max*: the combined max distance after turning the estimate about "
        "its trunk to its best fit (15 degree steps): a single sketch cannot say which way "
        "the tree faces in depth, so this is the shape error without the orientation.",
        "",
        hausdorff_table(trees, floors, backend.name),
        "",
    ]
    if any(t.refined for t in trees):
        better = sum(
            t.refined["combined"].max_norm < t.tsn["combined"].max_norm for t in trees if t.refined
        )
        better_al = sum(t.refined_aligned < t.tsn_aligned for t in trees if t.refined)
        L += [
            f"Refinement lowered the combined max distance on {better} of {len(trees)} trees "
            f"(the aligned max on {better_al}); "
            f"sketch loss {_mean([t.loss_before for t in trees]):.4f} -> "
            f"{_mean([t.loss_after for t in trees]):.4f}, "
            f"{_mean([t.refine_seconds for t in trees]):.1f} s per tree.",
            "",
        ]
    L += ["## Species identification", "", "| species | accuracy |", "|---|---|"]
    L += [f"| {sp} | {v:.3f} |" for sp, v in acc["per_species"].items()]
    L += ["", "## Rotation sweep", ""]
    if sweeps:
        L += [
            "One held-out tree per species, its sketch rendered every "
            f"{rotation_step} degrees of yaw; normalised max Hausdorff distance of the "
            "prediction at each angle (paper: about 0.03 at every angle).",
            "",
            "| species | tree | angles | mean | min | max | std |",
            "|---|---|---|---|---|---|---|",
        ]
        for sp, (tid, s) in sweeps.items():
            L.append(
                f"| {sp} | {tid} | {s.get('n', 0)} | {_fmt(s.get('mean', math.nan))} | "
                f"{_fmt(s.get('min', math.nan))} | {_fmt(s.get('max', math.nan))} | "
                f"{_fmt(s.get('std', math.nan))} |"
            )
        L.append("")
        for sp in sweeps:
            L += [
                f"![rotation {sp}](rotation_{sp}.png)",
                "",
                f"Worst, median and best angle ({sp}): ![cases {sp}](rotation_cases_{sp}.png)",
                "",
            ]
    else:
        L += ["(not run)", ""]
    return "\n".join(L)
