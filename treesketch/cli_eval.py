"""`treesketch eval ...` commands: `eval tsn` (cli_eval_tsn), `eval rotation`, `eval all`,
`eval paper` (cli_eval_paper)."""

from __future__ import annotations

import math
import shlex
import sys
from pathlib import Path

import typer

from . import cli_eval_paper, cli_eval_tsn
from .cli_common import (
    address_option,
    checkpoint_option,
    comma_list,
    dataset_option,
    executor_from,
    executor_option,
    fail,
    workers_option,
)

eval_app = typer.Typer(
    help="Evaluate: 1-RMSE tables, Hausdorff distance, rotation sweep, reports.",
    no_args_is_help=True,
)


@eval_app.command("rotation")
def rotation(
    params: Path = typer.Option(
        ..., "--params", help="Ground-truth parameter JSON (the tree to turn)."
    ),
    out: Path = typer.Option(
        ..., "--out", help="Output folder (CSV, plot, worst/median/best picture)."
    ),
    step: float = typer.Option(5.0, "--step", help="Yaw step in degrees (must divide 360)."),
    refine: bool = typer.Option(False, "--refine/--no-refine", help="Refine each prediction."),
    budget: int = typer.Option(
        20, "--budget", help="Refinement budget (tree evaluations) per angle."
    ),
    checkpoint: Path | None = checkpoint_option(),
    size: int = typer.Option(256, "--size", help="Sketch size in pixels."),
    samples: int = typer.Option(10_000, "--samples", help="Hausdorff samples per direction."),
    seed: int | None = typer.Option(
        None,
        "--seed",
        min=0,
        help="Seed key both trees are grown with, the estimates' too (default: the ground "
        "truth's own, as the paper grows its predictions).",
    ),
    turn: list[float] = typer.Option(
        [],
        "--turn",
        help="Also draw the tree from this many degrees further round at every angle and "
        "give the pipeline both drawings (--turn 90: front and side); repeatable.",
    ),
    executor: str = executor_option("the angles"),
    workers: int = workers_option(),
    address: str | None = address_option(),
) -> None:
    """Turn a tree about its trunk, predict from each view's sketch, Hausdorff at each angle."""
    from tqdm.auto import tqdm

    from eval.rotation import plot_cases, plot_sweep, rotation_sweep, write_csv, yaw_angles
    from weberpenn import ParamError, load_params

    try:
        gt = load_params(params)
        n = len(yaw_angles(step))
        if budget < 1:
            raise ValueError(f"--budget must be >= 1, got {budget}")
        if len(turn) > 3 or not all(math.isfinite(t) for t in turn):
            raise ValueError(f"--turn: at most 3 finite angles in degrees, got {turn}")
    except (ParamError, ValueError, OSError) as e:
        fail(str(e))
    from .estimators import SeededEstimator, load_estimator
    from .pipeline import Pipeline, RefineSettings

    seed = int(gt["seed"]) if seed is None else seed
    try:
        settings = RefineSettings(refine=refine, budget=budget, time_limit=None)
        # the estimates carry the sweep's seed key, so a refinement searches the trees
        # the sweep measures
        estimator = SeededEstimator(load_estimator("tsn", checkpoint=checkpoint), seed)
        pipeline = Pipeline(estimator, settings)
    except ValueError as e:
        fail(str(e))
    with (
        executor_from(executor, workers, address) as runner,
        tqdm(total=n, desc="rotation sweep", dynamic_ncols=True) as bar,
    ):
        res = rotation_sweep(
            gt,
            pipeline,
            step=step,
            size=size,
            samples=samples,
            seed=seed,
            progress=lambda i, total: bar.update(i - bar.n),
            executor=runner,
            turns=tuple(turn),
        )
    out.mkdir(parents=True, exist_ok=True)
    write_csv(res.rows, out / "rotation.csv")
    plot_sweep(res, out / "rotation.png")
    plot_cases(res, out / "rotation_cases.png")
    s = res.summary()
    typer.echo(
        f"{len(res.rows)} angles; normalised max Hausdorff mean {s.get('mean', float('nan')):.4f}"
        f" (min {s.get('min', float('nan')):.4f}, max {s.get('max', float('nan')):.4f}); "
        f"wrote {out / 'rotation.csv'}, rotation.png, rotation_cases.png"
    )


@eval_app.command("all")
def all_(
    data: Path = dataset_option(),
    out: Path = typer.Option(Path("reports"), "--out", help="Report folder."),
    checkpoint: Path | None = checkpoint_option(),
    refine_budget: int = typer.Option(
        40, "--refine-budget", help="Refinement budget per tree (0: none)."
    ),
    per_species: int = typer.Option(
        3, "--per-species", help="Held-out trees per species for Hausdorff."
    ),
    rotation_step: float = typer.Option(
        5.0, "--rotation-step", help="Yaw step of the rotation sweep."
    ),
    rotation_budget: int = typer.Option(
        0, "--rotation-budget", help="Refinement budget per sweep angle."
    ),
    rotation_species: str = typer.Option(
        "all", "--rotation-species", help="'all', 'none' or comma list."
    ),
    samples: int = typer.Option(10_000, "--samples", help="Hausdorff samples per direction."),
    max_sketches: int | None = typer.Option(
        None, "--max-sketches", help="Cap the 1-RMSE sketches."
    ),
    backbone: list[str] = typer.Option(
        [], "--compare", help="Another checkpoint for the 1-RMSE table, as NAME=PATH (repeatable)."
    ),
    model: str = typer.Option(
        "tsn",
        "--model",
        help="'tsn' (the checkpoint) or 'nns' (nearest-neighbour baseline, no network).",
    ),
    nns: bool = typer.Option(
        True, "--nns/--no-nns", help="With --model tsn: add the nearest-neighbour baseline row."
    ),
    executor: str = executor_option("the rotation sweeps' angles"),
    workers: int = workers_option(),
    address: str | None = address_option(),
) -> None:
    """Write the full evaluation report (markdown + PNGs) to --out."""
    from eval.baseline import NNSIndex
    from eval.report import build_report
    from eval.scoring import tsn_scorer

    from .estimators import NNSEstimator, TSNEstimator
    from .pipeline import Pipeline

    extras = []
    if model not in ("tsn", "nns"):
        fail(f"--model must be 'tsn' or 'nns', got {model!r}")
    spread = executor.strip().lower() != "local" or workers != 1 or address is not None
    if spread and model != "tsn":
        fail("--executor/--workers/--address spread the sweeps of --model tsn only")
    if rotation_species == "all":
        rot = None
    elif rotation_species == "none":
        rot = []
    else:
        rot = list(comma_list(rotation_species, "species"))
    try:
        for spec in backbone:  # checked before anything is loaded
            name, sep, path = spec.partition("=")
            if not sep or not name or not path:
                raise ValueError(f"--compare expects NAME=PATH, got {spec!r}")
        if model == "tsn":
            estimator = TSNEstimator.load(checkpoint)
            main = tsn_scorer(estimator.model)
            if nns:  # scored on TSN's own normaliser, so the rows compare
                index = NNSIndex.fit(data)
                extras.append(index.scorer(reference=main.normalise_targets))
        else:
            index = NNSIndex.fit(data)
            estimator, main = NNSEstimator(index), index.scorer()
        for spec in backbone:
            name, _, path = spec.partition("=")
            extras.append(tsn_scorer(TSNEstimator.load(Path(path)).model, name=name))
        pipeline = Pipeline(estimator)
    except (RuntimeError, ValueError, OSError) as e:  # DatasetError is a ValueError
        fail(str(e))
    with executor_from(executor, workers, address) as runner:
        try:
            path = build_report(
                data,
                out,
                pipeline,
                main,
                extras,
                per_species=per_species,
                refine_budget=refine_budget,
                rotation_step=rotation_step,
                rotation_refine_budget=rotation_budget,
                rotation_species=rot,
                samples=samples,
                max_sketches=max_sketches,
                command="treesketch " + " ".join(shlex.quote(a) for a in sys.argv[1:]),
                executor=runner,
            )
        except ValueError as e:
            fail(str(e))
    typer.echo(f"wrote {path}")


def register(app: typer.Typer) -> None:
    """Add the `eval` command group to the main app."""
    cli_eval_tsn.register(eval_app)
    cli_eval_paper.register(eval_app)
    app.add_typer(eval_app, name="eval")
