"""What the commands share: the one error path (``fail``), the one reading of a
comma-separated value (``comma_list``), the options several take (``--data`` a dataset,
``--checkpoint`` a TSN checkpoint, ``--styles`` the drawing styles a dataset's sketches are
kept in; ``--preset``, ``--max-faces`` and ``--textures`` of an exported tree), and, for
the commands whose pieces run on an executor, their options (``--executor``,
``--workers``, ``--address``) and the executor they ask for (``executor_from``)."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any, NoReturn

import typer

__all__ = [
    "address_option",
    "checkpoint_option",
    "comma_list",
    "dataset_option",
    "executor_from",
    "executor_option",
    "fail",
    "max_faces_option",
    "preset_option",
    "styles_kept",
    "styles_option",
    "textures_option",
    "workers_option",
]


def fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: MESSAGE`` on stderr and exit with ``code`` (no traceback)."""
    typer.secho(f"error: {message}", fg=typer.colors.RED, err=True)
    raise typer.Exit(code)


def comma_list(text: str, what: str) -> tuple[str, ...]:
    """The items of a comma-separated value, stripped and lower-cased; none at all is a
    usage error naming ``what`` (e.g. "style")."""
    items = tuple(x.strip().lower() for x in text.split(",") if x.strip())
    if not items:
        raise typer.BadParameter(f"give at least one {what} (comma-separated)")
    return items


def dataset_option() -> Any:
    """``--data``, required: a dataset folder."""
    return typer.Option(..., "--data", help="Dataset folder (treesketch dataset build).")


def checkpoint_option() -> Any:
    """``--checkpoint``: a TSN checkpoint, None for the shipped one."""
    return typer.Option(None, "--checkpoint", help="TSN checkpoint (default: the shipped one).")


def styles_option(use: str, more: str = "") -> Any:
    """``--styles``: ``use`` (e.g. "score") only the dataset's sketches drawn in these
    styles (None: every sketch); ``more`` ends the help."""
    return typer.Option(
        None,
        "--styles",
        help=f"Comma-separated drawing styles (e.g. sg): {use} only the sketches drawn in "
        f"them (default: every sketch){more}.",
    )


def styles_kept(text: str | None) -> tuple[str, ...] | None:
    """The styles a ``--styles`` value keeps; None keeps every sketch."""
    return None if text is None else comma_list(text, "style")


def preset_option() -> Any:
    """``--preset``: also write the tree's Sapling preset."""
    return typer.Option(
        None,
        "--preset",
        help="Also write a Sapling preset (.py) that Blender's Sapling 'Import Preset' loads "
        "(all levels and leaves; `treesketch grow --params` on it gives back the same tree).",
    )


def max_faces_option() -> Any:
    """``--max-faces``: a triangle budget for the exported tree; its range is checked by
    ``weberpenn.lod.check_budget``, the one check every exporter uses."""
    return typer.Option(
        None,
        "--max-faces",
        help="Keep the exported tree under this many triangles (coarser tubes, fewer and "
        "lighter leaves, then decimation).",
    )


def textures_option() -> Any:
    """``--textures/--no-textures`` of the exported tree."""
    return typer.Option(
        True,
        "--textures/--no-textures",
        help="Bark and leaf textures (made by the project, embedded in GLB, PNGs beside OBJ) "
        "or flat species colours.",
    )


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
