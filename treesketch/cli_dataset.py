"""`treesketch dataset ...`: build the synthetic sketch dataset (see render/dataset.py)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import NoReturn

import typer

from .cli_common import (
    address_option,
    comma_list,
    executor_from,
    executor_option,
    fail,
    workers_option,
)

dataset_app = typer.Typer(
    name="dataset",
    help="Synthetic sketch datasets (species x trees x views).",
    no_args_is_help=True,
)


def _bad_parameter(message: str) -> NoReturn:
    raise typer.BadParameter(message)


@dataset_app.command("build")
def build(
    out: Path = typer.Option(..., "--out", help="Output folder (created; resumed if it exists)."),
    trees_per_species: int = typer.Option(
        250, "--trees-per-species", min=1, max=100_000, help="Trees per species."
    ),
    views: str = typer.Option(
        "front,back,left,right",
        "--views",
        help="Comma-separated views: front, back, left, right, or yaws in degrees in [0, 360) "
        "(45,135,225,315: the views between the axes).",
    ),
    species: str = typer.Option(
        "maple,pine,bonsai,palm,cherry", "--species", help="Comma-separated species."
    ),
    size: int = typer.Option(256, "--size", min=32, max=2048, help="Sketch size in pixels."),
    styles: str = typer.Option(
        "sg",
        "--styles",
        help="Comma-separated drawing styles: sg (the paper's chain), pen, cloud, scribble, "
        "pencil, felt, bare, doodle. With sg and others, every view is drawn in sg and in "
        "--styles-per-view of the others (a seeded choice per view).",
    ),
    styles_per_view: int = typer.Option(
        1, "--styles-per-view", min=1, max=16, help="Other styles drawn per view besides sg."
    ),
    workers: int = workers_option(),
    executor: str = executor_option("the trees"),
    address: str | None = address_option(),
    seed: int = typer.Option(0, "--seed", min=0, help="Dataset seed (same seed, same dataset)."),
    val_fraction: float = typer.Option(0.1, "--val-fraction", min=0.0, max=0.9),
    test_fraction: float = typer.Option(0.1, "--test-fraction", min=0.0, max=0.9),
    only_split: str | None = typer.Option(
        None,
        "--only-split",
        help="Build only this split's trees (train, val or test): the same files as the "
        "full build, e.g. the paper's SG test split to score a network on.",
    ),
    progress: bool | None = typer.Option(
        None, "--progress/--no-progress", help="Progress bar (default: on a terminal)."
    ),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Log more."),
) -> None:
    """Sample, grow, mesh and render every tree; write sketches, parameters, renders and a
    manifest with a train/val/test split by tree.  Re-running resumes."""
    from render.dataset import DatasetConfig, DatasetError, build_dataset

    logging.basicConfig(
        level=logging.INFO if verbose else logging.WARNING,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        cfg = DatasetConfig(
            out=str(out),
            trees_per_species=trees_per_species,
            species=comma_list(species, "species"),
            views=comma_list(views, "view"),
            size=size,
            seed=seed,
            val_fraction=val_fraction,
            test_fraction=test_fraction,
            styles=comma_list(styles, "style"),
            styles_per_view=styles_per_view,
        )
    except DatasetError as exc:
        raise typer.BadParameter(str(exc)) from None
    with executor_from(executor, workers, address, bad=_bad_parameter) as runner:
        try:
            summary = build_dataset(cfg, progress=progress, executor=runner, only_split=only_split)
        except DatasetError as exc:
            fail(str(exc))
    typer.echo(summary.text())


def register(app: typer.Typer) -> None:
    """Add ``treesketch dataset`` to the main app."""
    app.add_typer(dataset_app, name="dataset")
