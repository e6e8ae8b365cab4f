"""What every command shares: the one error path (``fail``) and the options of the commands
whose pieces run on an executor (``--executor``, ``--workers``, ``--address``)."""

from __future__ import annotations

from typing import Any, NoReturn

import typer

__all__ = ["address_option", "executor_option", "fail", "workers_option"]


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: MESSAGE`` on stderr and exit with ``code`` (no traceback)."""
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


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
