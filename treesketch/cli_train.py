"""`treesketch train`: train the TSN regressor on a dataset (see ``tsn.train``)."""

from __future__ import annotations

from pathlib import Path

import typer

from .cli_common import dataset_option, fail, styles_kept, styles_option


def train_cmd(
    data: Path = dataset_option(),
    out: Path = typer.Option(..., "--out", help="Checkpoint to write, e.g. checkpoints/NAME.pt."),
    backbone: str = typer.Option("lite0", "--backbone", help="lite0 (pretrained) or resnet_small."),
    size: int = typer.Option(128, "--size", help="Input size in pixels (multiple of 32)."),
    epochs: int = typer.Option(30, "--epochs", help="Training epochs."),
    batch: int = typer.Option(64, "--batch", help="Batch size."),
    lr: float = typer.Option(1e-3, "--lr", help="Adam learning rate (cosine decay to lr/100)."),
    copies: int = typer.Option(3, "--copies", help="Augmented copies cached per sketch."),
    cut: int | None = typer.Option(
        None, "--cut", help="Frozen (cached) backbone stages; default per backbone."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of augmentation, shuffling and init."),
    work: Path | None = typer.Option(
        None,
        "--work",
        help="Folder for feature cache, state, log.csv, loss.png (default OUT.work).",
    ),
    threads: int | None = typer.Option(None, "--threads", help="torch CPU threads."),
    max_sketches: int | None = typer.Option(
        None, "--max-sketches", help="Use only the first N sketches of each split (quick runs)."
    ),
    resume: bool = typer.Option(False, "--resume", help="Continue an interrupted run."),
    more_data: list[Path] = typer.Option(
        [],
        "--more-data",
        help="Another dataset (built with another --seed) whose every split is added to the "
        "training trees; repeatable. Validation stays --data's val split.",
    ),
    loss: str = typer.Option(
        "mse", "--loss", help="mse: sum of per-head MSE (paper); rmse: sum of per-head RMSE."
    ),
    styles: str | None = styles_option("train and validate on", "; leave one out to test on it"),
    cache: Path | None = typer.Option(
        None,
        "--cache",
        help="Folder of the feature caches (default: the work folder); runs on the same "
        "dataset that keep other --styles can share it.",
    ),
    init: Path | None = typer.Option(
        None,
        "--init",
        help="Checkpoint to fine-tune from (same --backbone and --size); keeps its normaliser.",
    ),
    normalise: bool = typer.Option(
        True,
        "--normalise/--raw",
        help="Feed every sketch through the drawing normaliser first, as predict does "
        "(--raw: the dataset's pixels as they are).",
    ),
) -> None:
    """Train TSN: cached frozen early layers, fine-tuned last layers and six heads."""
    from tsn.train import TrainConfig, TrainError, train

    cfg = TrainConfig(
        data=str(data),
        out=str(out),
        backbone=backbone,
        size=size,
        epochs=epochs,
        batch=batch,
        lr=lr,
        copies=copies,
        cut=cut,
        seed=seed,
        work=str(work) if work else None,
        threads=threads,
        max_sketches=max_sketches,
        resume=resume,
        loss=loss,
        more_data=tuple(str(d) for d in more_data),
        styles=styles_kept(styles),
        init=str(init) if init else None,
        cache=str(cache) if cache else None,
        normalise=normalise,
    )
    try:
        cfg.check()
        res = train(cfg, log=lambda s: typer.echo(s))
    except (TrainError, ValueError, OSError) as e:
        fail(str(e))
        return
    typer.echo(
        f"best val 1-RMSE {res['best_val_overall']:.4f} at epoch {res['best_epoch']}; "
        f"checkpoint {res['out']}; log {res['work']}/log.csv ({res['seconds']:.0f} s)"
    )


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("train")(train_cmd)
