"""`treesketch eval paper`: the paper's tables for the shipped network, written to reports/.

Builds the data it needs (the paper's SG test split, seeded, cached), scores the network
and the refinement (``eval.paper``) and replaces the report folder whole, stamped with the
commit, the checkpoint's sha256, the date and the machine (``eval.stamp``).  ``make
reports`` runs it; the test suite fails when reports/ names another checkpoint.
"""

from __future__ import annotations

from pathlib import Path

import typer

from .cli_common import (
    address_option,
    checkpoint_option,
    executor_from,
    executor_option,
    fail,
    workers_option,
)

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_CACHE = Path("out") / "paper_cache"
# what the lead runs after shipping a network (the tests' failure message says it too)
REGENERATE = "make reports"


def eval_paper(
    out: Path = typer.Option(Path("reports"), "--out", help="Report folder (replaced whole)."),
    quick: bool = typer.Option(
        False, "--quick", help="Small sizes (a few minutes on two cores) instead of the full set."
    ),
    cache: Path = typer.Option(
        DEFAULT_CACHE, "--cache", help="Where the generated test data is kept between runs."
    ),
    checkpoint: Path | None = checkpoint_option(),
    bar: bool = typer.Option(True, "--progress/--no-progress", help="Progress bars on stderr."),
    executor: str = executor_option("the rotation sweeps' angles and the dataset's trees"),
    workers: int = workers_option(),
    address: str | None = address_option(),
) -> None:
    """The paper's tables (1-RMSE, species, 15 published trees, rotation) into reports/."""
    from eval.paper import FULL, QUICK, compute, write
    from eval.stamp import make_stamp, portable_path
    from render.dataset import DatasetConfig, DatasetError, build_dataset

    from .estimators import SeededEstimator, TSNEstimator
    from .pipeline import Pipeline

    sizes = (QUICK if quick else FULL).check()
    if out.exists() and not out.is_dir():
        fail(f"--out {out}: exists and is not a folder")
    if checkpoint is not None and not checkpoint.is_file():
        fail(f"--checkpoint {checkpoint}: no such file")
    try:
        estimator = TSNEstimator.load(checkpoint)
    except (RuntimeError, ValueError, OSError) as e:
        fail(str(e))
    ckpt = Path(str(estimator.model.loaded.path))
    try:
        rel_out = portable_path(out, ROOT) if out.resolve().is_relative_to(ROOT) else None
        stamp = make_stamp(ckpt, ROOT, ignore=(rel_out,) if rel_out else ())
    except (RuntimeError, OSError) as e:
        fail(f"cannot stamp the report: {e}")
    command = "treesketch eval paper" + (" --quick" if quick else "")
    if checkpoint is not None:
        command += f" --checkpoint {portable_path(checkpoint, ROOT)}"
    if out != Path("reports"):
        command += f" --out {portable_path(out, ROOT)}"
    data = cache / f"sg_test_{sizes.trees_per_species}"
    with executor_from(executor, workers, address) as runner:
        try:
            cfg = DatasetConfig(out=str(data), trees_per_species=sizes.trees_per_species)
            summary = build_dataset(cfg, progress=bar, executor=runner, only_split="test")
            if summary.failed:
                failed = ", ".join(summary.failed)
                fail(f"{len(summary.failed)} test trees failed to build: {failed}")

            def pipeline_for(seed: int) -> Pipeline:
                return Pipeline(SeededEstimator(estimator, seed))

            from eval.scoring import tsn_scorer

            res = compute(data, tsn_scorer(estimator.model), pipeline_for, sizes, bar, runner)
            path = write(out, res, sizes, stamp, command)
        except (DatasetError, ValueError, OSError) as e:
            fail(str(e))
    typer.echo(f"wrote {path} ({res.seconds / 60:.1f} min; {stamp.short()})")


def register(eval_app: typer.Typer) -> None:
    """Add `eval paper` to the eval group."""
    eval_app.command("paper")(eval_paper)
