"""The paper's tables in one place: what ``treesketch eval paper`` writes to ``reports/``.

* 1-RMSE per head of the network on the SG test split (the paper's definition,
  :func:`eval.report.score_backend`), beside the paper's EfficientNet-B7 figures, and
  species identification (:func:`eval.report.species_accuracy`);
* the 15 ground-truth trees published with the paper: each one's front sketch, the first
  estimate alone and estimate + refinement, the Hausdorff family (symmetric max and mean,
  the paper's vertex-to-surface wording both ways) beside the seed floor;
* the rotation sweep (:func:`eval.rotation.rotation_sweep`) of the first published tree of
  each species, without and with refinement, and refined from two sketches 90 degrees
  apart; the published trees refined from their front and side sketches too, and the
  whole family of 3D errors (:data:`eval.hausdorff.FAMILY`);
* every number stamped (:class:`eval.stamp.Stamp`): README, each CSV row, each plot.

Every estimate grows with the ground truth's ``seed`` key (the seed is not predicted; the
paper grows its predictions with the ground truth's seed), so the pipelines come from
``pipeline_for(seed)``, handed in by the caller (``eval`` does not know the front door).
Refinement runs with a budget and no time limit: the numbers do not depend on the
machine's speed, only the seconds do.
"""

from __future__ import annotations

import csv
import io
import json
import math
import shutil
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn import TreeParams, build_mesh, grow, load_params
from weberpenn import species as wp_species
from weberpenn.fileio import atomic_write

from .hausdorff import FAMILY, Distance, bbox_diagonal, hausdorff, rotate_about_trunk
from .metrics import PAPER_ONE_MINUS_RMSE, Scores, format_table
from .report import PAPER_HAUSDORFF_MEAN, PAPER_ROTATION_RANGE, score_backend, species_accuracy
from .rotation import CSV_FIELDS, SweepResult, rotation_sweep, yaw_angles
from .scoring import Scorer, progress_bar
from .stamp import Stamp

ROOT = Path(__file__).resolve().parents[1]
PUBLISHED_DIR = ROOT / "tests" / "data" / "treesketchnet_test_params"
PAPER_SPECIES = ("maple", "pine", "bonsai", "palm", "cherry")
SKETCH_SIZE = 256  # the published trees' sketches, as bench_gt15 draws them


@dataclass(frozen=True)
class PaperSizes:
    """How much work the report does (``QUICK`` for a check, ``FULL`` for the record)."""

    name: str
    trees_per_species: int  # dataset plan; 250 is the paper's (25 SG test trees each)
    refine_budget: int  # tree evaluations per published tree
    rotation_step: float  # degrees
    rotation_budget: int  # tree evaluations per sweep angle (the refined sweep)
    samples: int  # Hausdorff samples per direction

    def check(self) -> PaperSizes:
        if self.trees_per_species < 10:
            raise ValueError("trees_per_species must be >= 10 (one test tree per species)")
        if self.refine_budget < 1 or self.rotation_budget < 1:
            raise ValueError("refinement budgets must be >= 1")
        if self.samples < 100:
            raise ValueError(f"samples must be >= 100, got {self.samples}")
        yaw_angles(self.rotation_step)  # raises on a step that does not divide 360
        return self


QUICK = PaperSizes("quick", 10, 4, 120.0, 2, 1000)
# the refined sweep needs a budget that tries 8 start views (a third of it: refine.search)
FULL = PaperSizes("full", 250, 40, 30.0, 24, 10_000)


def published_trees(folder: Path = PUBLISHED_DIR) -> list[tuple[str, str, TreeParams]]:
    """(file name, species, parameters) of the 15 published trees, in the paper's order."""
    files = sorted(folder.glob("*.json"), key=lambda p: int(p.stem.split("_", 1)[0]))
    if not files:
        raise ValueError(f"no published ground-truth trees in {folder.name}/")
    return [(f.name, wp_species.canonical(f.stem.split("_", 1)[1]), load_params(f)) for f in files]


@dataclass
class PublishedResult:
    file: str
    species: str
    species_estimate: str
    species_refined: str
    alone: Distance
    refined: Distance
    floor: Distance  # the ground truth against itself grown with the next seed
    loss_before: float
    loss_after: float
    yaw_found: float
    seconds: float
    # refined from two drawings: the front sketch and the side (90 degrees round)
    two_views: Distance | None = None
    species_two_views: str = ""
    loss_two_views: float = math.nan
    seconds_two_views: float = math.nan


def score_published(
    trees: Sequence[tuple[str, str, TreeParams]],
    pipeline_for: Callable[[int], Any],
    budget: int,
    samples: int,
    bar: bool = True,
) -> list[PublishedResult]:
    """Front sketch of each tree -> first estimate alone and estimate + refinement; the
    front and side (90 degrees round) sketches together -> estimate + refinement."""
    from render.sketch import SketchRenderer

    out = []
    for name, sp, gt in progress_bar(trees, "published trees", len(trees), bar):
        seed = int(gt["seed"])
        gt_mesh = build_mesh(grow(gt), species=sp)
        drawer = SketchRenderer(gt_mesh, species=sp)
        img, side = drawer.sketch(0, SKETCH_SIZE), drawer.sketch(90, SKETCH_SIZE)
        pipe = pipeline_for(seed).with_settings(refine=True, budget=int(budget), time_limit=None)
        t0 = time.perf_counter()
        run = pipe.run(img)
        seconds = time.perf_counter() - t0
        est = run.estimate
        # the combined branch + leaf mesh only (the paper's figure; the per-part
        # distances would triple the cost), normalised by the ground truth's diagonal
        gt_comb, diag = gt_mesh.combined(), bbox_diagonal(gt_mesh.bounds())

        def dist(mesh: Any, gt_comb: Any = gt_comb, diag: float = diag) -> Distance:
            return hausdorff(mesh.combined(), gt_comb, samples, diag)

        alone = dist(build_mesh(grow(est.params), species=est.species))
        # the refined tree matches the sketch at the yaw it found: turn it into the
        # ground truth's frame (the sketch is the front view)
        refined = dist(rotate_about_trunk(run.tree_mesh, -run.yaw))
        # the seed floor: the ground truth grown with the next seed
        floor = dist(build_mesh(grow(gt, seed=seed + 1), species=sp))
        t0 = time.perf_counter()
        both = pipe.run([img, (side, 90.0)])
        seconds_both = time.perf_counter() - t0
        # the first drawing is the front: its yaw turns the tree into the truth's frame
        two = dist(rotate_about_trunk(both.tree_mesh, -both.yaw))
        out.append(
            PublishedResult(
                name,
                sp,
                est.species,
                run.species,
                alone,
                refined,
                floor,
                float(run.losses["before"]),
                float(run.losses["after"]),
                float(run.yaw),
                seconds,
                two,
                both.species,
                float(both.losses["after"]),
                seconds_both,
            )  # fmt: skip
        )
    return out


def sweep_both(
    trees: Sequence[tuple[str, str, TreeParams]],
    pipeline_for: Callable[[int], Any],
    sizes: PaperSizes,
    bar: bool = True,
    executor: Any = None,
) -> dict[str, dict[str, Any]]:
    """The rotation sweep of the first published tree of each species, the first estimate
    alone, refined, and refined from two sketches (the swept one and the side, 90 degrees
    further round): ``{species: {"file", "alone", "refined", "two views": SweepResult}}``."""
    first: dict[str, tuple[str, TreeParams]] = {}
    for name, sp, gt in trees:
        first.setdefault(sp, (name, gt))
    out: dict[str, dict[str, Any]] = {}
    for sp, (name, gt) in first.items():
        seed = int(gt["seed"])
        base = pipeline_for(seed)
        refined = base.with_settings(
            refine=True, budget=int(sizes.rotation_budget), time_limit=None
        )
        # (pipeline, other views' turns): the front sketch alone, or with the side's
        runs = {"alone": (base.with_settings(refine=False), ()), "refined": (refined, ()),
                "two views": (refined, (90.0,))}  # fmt: skip
        out[sp] = {"file": name}
        for label, (pipe, turns) in runs.items():
            n = len(yaw_angles(sizes.rotation_step))
            pbar = progress_bar(range(n), f"rotation {sp} ({label})", n, bar)
            it = iter(pbar)
            out[sp][label] = rotation_sweep(
                gt, pipe, step=sizes.rotation_step, size=SKETCH_SIZE, samples=sizes.samples,
                seed=seed, progress=lambda i, total, it=it: next(it, None), executor=executor,
                turns=turns,
            )  # fmt: skip
            if hasattr(pbar, "close"):
                pbar.close()
    return out


# ------------------------------------------------------------------------------- writing
def _csv(rows: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    # every row's columns (a run that did not happen for one row leaves its cells empty)
    names = list(dict.fromkeys(k for r in rows for k in r))
    w = csv.DictWriter(buf, fieldnames=names, restval="", lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    return buf.getvalue()


def _fmt(x: float, d: int = 4) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{d}f}"


def _mean(values: Sequence[float]) -> float:
    ok = [v for v in values if math.isfinite(v)]
    return float(np.mean(ok)) if ok else float("nan")


def _footer(fig: Any, stamp: Stamp) -> None:
    fig.text(0.01, 0.005, stamp.short(), fontsize=6, color="0.35", ha="left", va="bottom")


def _plot_sweeps(sp: str, res: Mapping[str, Any], sizes: PaperSizes, stamp: Stamp, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 3.0))
    styles = {"alone": ("C0", "o", "network alone"),
              "refined": ("C3", "s", f"+ refinement ({sizes.rotation_budget} evaluations)"),
              "two views": ("C2", "^", "+ refinement, two sketches (+90)")}  # fmt: skip
    for label, (colour, marker, text) in styles.items():
        if label not in res:
            continue
        r: SweepResult = res[label]
        x = np.array([row.angle for row in r.rows])
        y = r.values()
        ax.plot(
            x, y, color=colour, marker=marker, ms=4, lw=1, label=f"{text}, mean {_fmt(_mean(y), 3)}"
        )
    ax.axhspan(*PAPER_ROTATION_RANGE, color="0.85", label="paper's range (0.029-0.040)")
    ax.set_xlim(-5, 360)
    ax.set_xticks(range(0, 361, 45))
    ax.set_ylim(bottom=0)
    ax.set_xlabel("yaw of the sketch (degrees)")
    ax.set_ylabel("max Hausdorff / GT diagonal")
    ax.set_title(f"rotation sweep: {sp} ({res['file']})", fontsize=10)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # off the curves
    ax.grid(alpha=0.3)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    _footer(fig, stamp)
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=80, format="png"))
    plt.close(fig)


def _plot_published(results: Sequence[PublishedResult], budget: int, stamp: Stamp, path: Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9.0, 3.2))
    x = np.arange(len(results))
    w = 0.21
    bars = [
        ([r.alone.max_norm for r in results], "network alone", "C0"),
        ([r.refined.max_norm for r in results], f"+ refinement ({budget})", "C3"),
        ([r.two_views.max_norm if r.two_views else math.nan for r in results],
         "+ refinement, front + side sketches", "C2"),
        ([r.floor.max_norm for r in results], "seed floor", "0.6"),
    ]  # fmt: skip
    for i, (values, text, colour) in enumerate(bars):
        ax.bar(x + (i - 1.5) * w, values, w, label=text, color=colour)
    ax.axhline(PAPER_HAUSDORFF_MEAN, color="k", ls="--", lw=0.8, label="paper's mean (0.031)")
    ax.set_xticks(x, [r.file.removesuffix(".json") for r in results], rotation=60, fontsize=6)
    ax.set_ylabel("max Hausdorff / GT diagonal")
    ax.set_title("the 15 published trees (front sketch; front + side)", fontsize=10)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # off the bars
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    _footer(fig, stamp)
    atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=80, format="png"))
    plt.close(fig)


@dataclass
class PaperResults:
    scores: Scores
    accuracy: dict[str, Any]
    n_sketches: int
    n_trees: int
    published: list[PublishedResult]
    sweeps: dict[str, dict[str, Any]]
    seconds: float = 0.0


def compute(
    data: Path,
    scorer: Scorer,
    pipeline_for: Callable[[int], Any],
    sizes: PaperSizes,
    bar: bool = True,
    executor: Any = None,
) -> PaperResults:
    """Every number of the report (``data``: a dataset with the SG test split)."""
    from render.dataset import read_manifest

    t0 = time.perf_counter()
    rows = read_manifest(data, split="test", styles=("sg",))
    if not rows:
        raise ValueError(f"{data.name}: no SG test sketches")
    scores = score_backend(scorer, data, rows, bar=bar)
    accuracy = species_accuracy(pipeline_for(0), data, rows, bar)
    trees = published_trees()
    published = score_published(trees, pipeline_for, sizes.refine_budget, sizes.samples, bar)
    sweeps = sweep_both(trees, pipeline_for, sizes, bar, executor)
    n_trees = len({r["tree_id"] for r in rows})
    return PaperResults(scores, accuracy, len(rows), n_trees, published, sweeps,
                        time.perf_counter() - t0)  # fmt: skip


def write(out: Path, res: PaperResults, sizes: PaperSizes, stamp: Stamp, command: str) -> Path:
    """Write ``out`` (README.md, CSVs, PNGs, results.json) whole: everything goes to a
    sibling folder first and replaces ``out`` at the end, so a failure leaves the old
    report and no stale file of an older one survives."""
    out = Path(out)
    if out.exists() and any(out.iterdir()) and not (out / "README.md").is_file():
        raise ValueError(f"--out {out.name}: a non-empty folder that is not a report; refusing")
    tmp = out.with_name(f".{out.name}.new")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    col = stamp.columns()
    ours = {**res.scores.heads, "overall": res.scores.overall}
    atomic_write(tmp / "one_minus_rmse.csv", _csv([
        {"model": "ours", **{h: ours[h] for h in PAPER_ONE_MINUS_RMSE}, **col},
        {"model": "paper EfficientNet-B7", **PAPER_ONE_MINUS_RMSE, **col},
    ]))  # fmt: skip
    acc = res.accuracy
    atomic_write(tmp / "species_accuracy.csv", _csv(
        [{"species": sp, "accuracy": v, **col} for sp, v in acc["per_species"].items()]
        + [{"species": "all", "accuracy": acc["overall"], **col}]
    ))  # fmt: skip
    pub_rows = []
    for p in res.published:
        d = {"file": p.file, "species": p.species, "species_estimate": p.species_estimate,
             "species_refined": p.species_refined}  # fmt: skip
        runs = (("alone", p.alone), ("refined", p.refined), ("two_views", p.two_views),
                ("floor", p.floor))  # fmt: skip
        for label, dist in runs:
            if dist is None:
                continue
            d |= {f"{label}_max": dist.max_norm, f"{label}_mean": dist.mean_norm,
                  f"{label}_pred_to_gt_vertex": dist.pred_to_gt_vertex,
                  f"{label}_gt_to_pred_vertex": dist.gt_to_pred_vertex,
                  **{f"{label}_{k}": v for k, v in dist.family().items() if k != "max_norm"}}  # fmt: skip
        d |= {"loss_before": p.loss_before, "loss_after": p.loss_after,
              "yaw_found": p.yaw_found, "seconds": p.seconds,
              "species_two_views": p.species_two_views, "loss_two_views": p.loss_two_views,
              "seconds_two_views": p.seconds_two_views, **col}  # fmt: skip
        pub_rows.append(d)
    atomic_write(tmp / "published_trees.csv", _csv(pub_rows))
    _plot_published(res.published, sizes.refine_budget, stamp, tmp / "published_trees.png")
    rot_rows = []
    for sp, r in res.sweeps.items():
        for label in (k for k in ("alone", "refined", "two views") if k in r):
            for row in r[label].rows:
                rot_rows.append({"species": sp, "tree": r["file"], "run": label,
                                 **{k: asdict(row)[k] for k in CSV_FIELDS}, **col})  # fmt: skip
        _plot_sweeps(sp, r, sizes, stamp, tmp / f"rotation_{sp}.png")
    atomic_write(tmp / "rotation.csv", _csv(rot_rows))
    atomic_write(tmp / "README.md", markdown(res, sizes, stamp, command))
    atomic_write(tmp / "results.json", json.dumps({
        "stamp": asdict(stamp), "sizes": asdict(sizes), "command": command,
        "one_minus_rmse": {**res.scores.heads, "overall": res.scores.overall},
        "species_accuracy": res.accuracy, "published": [
            {k: (v.to_dict() if isinstance(v, Distance) else v) for k, v in asdict(p).items()}
            for p in res.published], "seconds": res.seconds,
    }, indent=1, default=float) + "\n")  # fmt: skip
    old = out.with_name(f".{out.name}.old")
    shutil.rmtree(old, ignore_errors=True)
    if out.exists():
        out.rename(old)
    tmp.rename(out)
    shutil.rmtree(old, ignore_errors=True)
    return out / "README.md"


def markdown(res: PaperResults, sizes: PaperSizes, stamp: Stamp, command: str) -> str:
    """The report's README: the headline against the paper, then each table."""
    parts = [
        _headline_md(res, sizes, stamp, command),
        _heads_md(res, sizes),
        _species_md(res),
        _published_md(res.published, sizes),
        _family_md(res.published),
        _rotation_md(res, sizes),
    ]
    return "\n".join(line for part in parts for line in part)


def _headline_md(res: PaperResults, sizes: PaperSizes, stamp: Stamp, command: str) -> list[str]:
    """The title, the stamp and the headline table (ours against the paper's)."""
    pub = res.published
    alone = _mean([p.alone.max_norm for p in pub])
    refined = _mean([p.refined.max_norm for p in pub])
    better = sum(p.refined.max_norm < p.alone.max_norm for p in pub)
    twos = [p for p in pub if p.two_views is not None]
    two = _mean([p.two_views.max_norm for p in twos])
    better_two = sum(p.two_views.max_norm < p.alone.max_norm for p in twos)
    acc = res.accuracy
    return [
        "# TreeSketch: the paper's tables for the shipped network",
        "",
        f"Regenerate with `{command}` (sizes: **{sizes.name}**; it took "
        f"{res.seconds / 60:.1f} min of computing after the data was built). Every number "
        "below, every CSV row and every plot carries this stamp; a test fails when the "
        "checkpoint's sha256 is not the shipped one's.",
        "",
        stamp.markdown(),
        "",
        "## Headline",
        "",
        "| quantity | paper (EfficientNet-B7) | ours |",
        "|---|---|---|",
        f"| 1-RMSE overall, SG test sketches | {PAPER_ONE_MINUS_RMSE['overall']:.4f} | "
        f"{res.scores.overall:.4f} |",
        f"| species identification (paper: Algorithm 1; ours: the checkpoint's classifier) "
        f"| 98% (target) | {acc['overall']:.1%} |",
        f"| mean max Hausdorff, 15 published trees, network alone | {PAPER_HAUSDORFF_MEAN} | "
        f"{_fmt(alone)} |",
        f"| the same, + refinement ({sizes.refine_budget} evaluations) | - | {_fmt(refined)} "
        f"(better on {better} of {len(pub)}) |",
        f"| the same from two sketches (front + side, 90 degrees round) | - | {_fmt(two)} "
        f"(better than the network alone on {better_two} of {len(twos)}) |",
        f"| rotation sweep, per-tree means (alone / refined) | {PAPER_ROTATION_RANGE[0]}-"
        f"{PAPER_ROTATION_RANGE[1]} | "
        + " · ".join(
            f"{sp} {_fmt(r['alone'].summary().get('mean', math.nan), 3)} / "
            f"{_fmt(r['refined'].summary().get('mean', math.nan), 3)}"
            + (
                f" / two sketches {_fmt(r['two views'].summary().get('mean', math.nan), 3)}"
                if "two views" in r
                else ""
            )  # fmt: skip
            for sp, r in res.sweeps.items()
        )
        + " |",
        "",
        *(
            [
                "**Quick sizes**: a check of the machinery, not the record. The refinement "
                "budgets are too small to search the view, so a refined tree at a turned "
                "sketch is often measured in the wrong orientation; read the full report "
                "(`make reports`) for the refined numbers.",
                "",
            ]
            if sizes.name == "quick"
            else []
        ),
    ]


def _heads_md(res: PaperResults, sizes: PaperSizes) -> list[str]:
    """1-RMSE per head on the SG test split, ours and the paper's."""
    return [
        "## 1-RMSE per head (SG test split)",
        "",
        f"{res.n_sketches} SG sketches of {res.n_trees} test trees of the paper's five species "
        f"(seeded dataset plan of {sizes.trees_per_species} trees per species; 250 is the "
        "paper's, 25 test trees each). 1 - RMSE of each head's normalised target matrix, "
        "network output for the sketch alone; overall = mean of the six heads. "
        "CSV: [one_minus_rmse.csv](one_minus_rmse.csv).",
        "",
        format_table({"ours": res.scores, "paper: EfficientNet-B7": PAPER_ONE_MINUS_RMSE}),
        "",
    ]


def _species_md(res: PaperResults) -> list[str]:
    """The first estimate's species accuracy, per species."""
    acc = res.accuracy
    return [
        "## Species identification",
        "",
        f"The first estimate's species (the checkpoint's calibrated classifier; the paper "
        f"used Algorithm 1) for each of the {acc['n']} sketches. "
        "CSV: [species_accuracy.csv](species_accuracy.csv).",
        "",
        "| species | accuracy |",
        "|---|---|",
        *[f"| {sp} | {v:.1%} |" for sp, v in acc["per_species"].items()],
        "",
    ]


def _published_md(pub: list[PublishedResult], sizes: PaperSizes) -> list[str]:
    """The 15 published trees: one row each, then the means per species."""
    L = [
        "## The 15 published trees",
        "",
        "Each tree's front sketch (256 px), the network's estimate alone and refined "
        f"({sizes.refine_budget} tree evaluations, the view searched); both grown with the "
        "ground truth's seed. Distances divided by the ground truth's bounding-box diagonal: "
        "**max** / **mean** symmetric Hausdorff (combined branch + leaf mesh, "
        f"{sizes.samples} samples per direction), **p->g / g->p** the paper's wording (largest "
        "vertex-to-surface distance each way). **Seed floor**: the ground truth against itself "
        "grown with the next seed, what the generator's remaining randomness costs. "
        "CSV: [published_trees.csv](published_trees.csv).",
        "",
        "![the 15 published trees](published_trees.png)",
        "",
        "| tree | species (estimate -> refined) | alone max / mean | refined max / mean "
        "| two sketches max / mean | alone p->g / g->p | refined p->g / g->p | seed floor max "
        "| sketch loss |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p in pub:
        t = p.two_views
        L.append(
            f"| {p.file} | {p.species} ({p.species_estimate} -> {p.species_refined}) "
            f"| {_fmt(p.alone.max_norm)} / {_fmt(p.alone.mean_norm)} "
            f"| {_fmt(p.refined.max_norm)} / {_fmt(p.refined.mean_norm)} "
            f"| {_fmt(t.max_norm if t else math.nan)} / {_fmt(t.mean_norm if t else math.nan)} "
            f"| {_fmt(p.alone.pred_to_gt_vertex)} / {_fmt(p.alone.gt_to_pred_vertex)} "
            f"| {_fmt(p.refined.pred_to_gt_vertex)} / {_fmt(p.refined.gt_to_pred_vertex)} "
            f"| {_fmt(p.floor.max_norm)} | {_fmt(p.loss_before)} -> {_fmt(p.loss_after)} |"
        )
    L += [
        "",
        "| species | trees | alone max | refined max | two sketches max | seed floor max |",
        "|---|---|---|---|---|---|",
    ]
    groups = {
        sp: [p for p in pub if p.species == sp] for sp in dict.fromkeys(p.species for p in pub)
    }
    for sp, ps in [*groups.items(), ("all", pub)]:
        L.append(
            f"| {sp} | {len(ps)} | {_fmt(_mean([p.alone.max_norm for p in ps]))} "
            f"| {_fmt(_mean([p.refined.max_norm for p in ps]))} "
            f"| {_fmt(_mean([p.two_views.max_norm for p in ps if p.two_views]))} "
            f"| {_fmt(_mean([p.floor.max_norm for p in ps]))} |"
        )
    return L


def _family_md(pub: list[PublishedResult]) -> list[str]:
    """The same meshes' whole family of 3D error figures (``eval.hausdorff.FAMILY``)."""
    L = [
        "",
        "### The 3D error as the field reports it",
        "",
        "The same meshes (combined branch + leaf), the whole family of figures, mean over the "
        "15 trees (`eval.hausdorff.FAMILY`): ours is the symmetric max over the ground "
        "truth's diagonal; MeshLab's one-sided Hausdorff filter reports the largest distance "
        "from the sampled mesh's vertices to the other surface over the sampled mesh's "
        "diagonal; Metro the symmetric max over the diagonal of both meshes' box. The "
        "paper's 0.031 does not say which of these it is.",
        "",
        "| figure | network alone | refined | two sketches | seed floor |",
        "|---|---|---|---|---|",
    ]
    for key, words in FAMILY.items():

        def m(get: Callable[[PublishedResult], Distance | None], key: str = key) -> str:
            vals = [getattr(d, key) for d in map(get, pub) if d is not None]
            return _fmt(_mean(vals))

        L.append(
            f"| {words} | {m(lambda p: p.alone)} | {m(lambda p: p.refined)} "
            f"| {m(lambda p: p.two_views)} | {m(lambda p: p.floor)} |"
        )
    return L


def _rotation_md(res: PaperResults, sizes: PaperSizes) -> list[str]:
    """The rotation sweep of each species' first published tree, and its pictures."""
    L = [
        "",
        "## Rotation sweep",
        "",
        f"The first published tree of each species turned about its trunk every "
        f"{sizes.rotation_step:g} degrees; at each yaw its sketch, the network's estimate "
        f"alone and refined ({sizes.rotation_budget} evaluations per angle), the max "
        "Hausdorff distance to the ground truth (the paper: about 0.03 at every angle). "
        "CSV: [rotation.csv](rotation.csv).",
        "",
        "Two sketches: at each yaw the sketch and the one 90 degrees further round, refined "
        "together. max/median: the worst angle over the median angle (1 = the error does "
        "not depend on the side drawn).",
        "",
        "| species | tree | angles | alone mean (min-max) | refined mean (min-max) "
        "| two sketches mean (min-max) | max/median alone / refined / two |",
        "|---|---|---|---|---|---|---|",
    ]

    def span(r: SweepResult | None) -> str:
        if r is None:
            return "n/a"
        a = r.summary()
        return (
            f"{_fmt(a.get('mean', math.nan))} ({_fmt(a.get('min', math.nan))}-"
            f"{_fmt(a.get('max', math.nan))})"
        )

    def ratio(r: SweepResult | None) -> str:
        v = np.asarray([] if r is None else r.values(), float)
        v = v[np.isfinite(v)]
        return "n/a" if not len(v) or np.median(v) <= 0 else f"{v.max() / np.median(v):.2f}"

    for sp, r in res.sweeps.items():
        two_r = r.get("two views")
        L.append(
            f"| {sp} | {r['file']} | {r['alone'].summary().get('n', 0)} "
            f"| {span(r['alone'])} | {span(r['refined'])} | {span(two_r)} "
            f"| {ratio(r['alone'])} / {ratio(r['refined'])} / {ratio(two_r)} |"
        )
    L.append("")
    L += [f"![rotation {sp}](rotation_{sp}.png)\n" for sp in res.sweeps]
    return L
