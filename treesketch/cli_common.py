"""What the commands share: the one error path (``fail``), the options several take
(``--data`` a dataset, ``--checkpoint`` a TSN checkpoint), and, for the commands whose
pieces run on an executor, their options (``--executor``, ``--workers``, ``--address``)
and the executor they ask for (``executor_from``)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any, NoReturn

import typer

__all__ = [
    "address_option",
    "checkpoint_option",
    "dataset_option",
    "executor_from",
    "executor_option",
    "fail",
    "workers_option",
]


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: MESSAGE`` on stderr and exit with ``code`` (no traceback)."""
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


def dataset_option() -> Any:
    """``--data``, required: a dataset folder."""
    return typer.Option(..., "--data", help="Dataset folder (treesketch dataset build).")


def checkpoint_option() -> Any:
    """``--checkpoint``: a TSN checkpoint, None for the shipped one."""
    return typer.Option(None, "--checkpoint", help="TSN checkpoint (default: the shipped one).")


@contextlib.contextmanager
def executor_from(
    kind: str, workers: int, address: str | None, bad: Callable[[str], NoReturn] = fail
) -> Iterator[Any]:
    """The executor of ``--executor/--workers/--address`` (None: in-process), closed when
    the block ends; a combination that makes none goes to ``bad`` (default: ``fail``)."""
    from .executor import ExecutorError, from_options

    try:
        runner = from_options(kind, workers, address)
    except ExecutorError as e:
        bad(str(e))
    try:
        yield runner
    finally:
        if runner is not None:
            runner.close()


def executor_option(pieces: str) -> Any:
    """``--executor``: where ``pieces`` (e.g. "trees", "the angles") run."""
    return typer.Option(
        "local", "--executor", help=f"Where {pieces} run: local (this machine) or ray."
    )


def workers_option() -> Any:
    return typer.Option(
        1, "--workers", min=1, max=64, help="Worker processes (local) or CPUs of a local Ray."
    )


def address_option() -> Any:
    return typer.Option(
        None,
        "--address",
        help="Ray cluster to use (auto, HOST:PORT, ray://HOST:PORT); "
        "without it --executor ray starts a local Ray for the run.",
    )
