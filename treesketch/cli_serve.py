"""`treesketch serve`: the job service and its drawing page (see treesketch/service/)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from refine.search import DEFAULT_BUDGET

from .cli_common import fail

if TYPE_CHECKING:
    from fastapi import FastAPI

    from .service import ServiceConfig

LOCAL_HOSTS = ("127.0.0.1", "localhost", "::1")
ANY_ADDRESS = ("0.0.0.0", "::", "")


def served_names(host: str, allow: list[str]) -> tuple[str, ...]:
    """The names the server answers to (its Host check): the loopback names, the address
    it is bound to and ``--allow-host`` names; ``("*",)`` (no check) when it listens on
    every address and no name is given."""
    if host in ANY_ADDRESS and not allow:
        return ("*",)
    named = () if host in ANY_ADDRESS else (host,)
    return tuple(dict.fromkeys((*LOCAL_HOSTS, *named, *allow)))


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/treesketch`` (``~/.local/share/treesketch``)."""
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "treesketch"


def serve_command(
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
    port: int = typer.Option(8000, "--port", min=1, max=65535, help="Port to listen on."),
    data: Path = typer.Option(
        None, "--data", help="Folder for the job database and results (default: user data)."
    ),
    workers: int = typer.Option(
        None,
        "--workers",
        min=1,
        help="Worker processes, or Ray actors (default: one per core, or per cluster CPU).",
    ),
    estimator: str = typer.Option(
        "tsn", "--estimator", help="tsn, template, or a TSN checkpoint path."
    ),
    budget: int = typer.Option(
        DEFAULT_BUDGET, "--budget", min=1, max=1000, help="Default refinement budget of a job."
    ),
    max_queue: int = typer.Option(64, "--max-queue", min=1, help="Most jobs waiting."),
    retention_days: float = typer.Option(
        30.0, "--retention-days", min=0.0, help="Remove results older than this."
    ),
    retention_gb: float = typer.Option(
        2.0, "--retention-gb", min=0.0, help="Keep results under this total size."
    ),
    token: str = typer.Option(
        None,
        "--token",
        envvar="TREESKETCH_TOKEN",
        help="Require 'Authorization: Bearer TOKEN' on the API (the page: open /#token=TOKEN).",
    ),
    allow_host: list[str] = typer.Option(
        None,
        "--allow-host",
        help="Also answer to this name (repeatable): the public name behind a reverse proxy.",
    ),
    cors: list[str] = typer.Option(
        None, "--cors", help="Allow browser calls from this origin (repeatable); off by default."
    ),
    executor: str = typer.Option(
        "local", "--executor", help="local (worker processes) or ray (Ray actors)."
    ),
    address: str = typer.Option(
        None,
        "--address",
        help="With --executor ray: the cluster (auto, HOST:PORT); default a local Ray.",
    ),
) -> None:
    """Serve the job API and the drawing page at http://HOST:PORT/.

    Example: `treesketch serve --port 8000`, then open http://127.0.0.1:8000/ or
    `curl -F sketch=@examples/sketch_maple.png -F budget=20 localhost:8000/jobs`.
    On a Ray cluster: `treesketch serve --executor ray --address HEAD_IP:6379`.
    """
    from .service import ServiceConfig
    from .service.pool import default_workers

    executor = _checked_executor(executor, address)
    hosts = _checked_exposure(host, token, cors or [], allow_host or [])
    config = ServiceConfig(
        data=data or default_data_dir(),
        # on Ray, default to every CPU of the cluster (the pool counts them)
        workers=workers or (None if executor == "ray" else default_workers()),
        estimator=estimator,
        default_budget=budget,
        max_queue=max_queue,
        retention_days=retention_days,
        retention_bytes=int(retention_gb * 1024**3),
        token=token or None,
        cors=tuple(cors or ()),
        hosts=hosts,
        executor=executor,
        address=address,
    )
    if executor == "local":
        _serve_local(config, host, port)
    else:
        _serve_on_ray(config, host, port, workers)


def _checked_executor(executor: str, address: str | None) -> str:
    """``--executor`` normalised ('local' or 'ray'); ``--address`` only goes with ray."""
    executor = executor.strip().lower()
    if executor not in ("local", "ray"):
        raise typer.BadParameter(f"choose local or ray, got {executor!r}", param_hint="--executor")
    if address is not None and executor != "ray":
        raise typer.BadParameter(
            "is for the ray executor (add --executor ray)", param_hint="--address"
        )
    return executor


def _checked_exposure(
    host: str, token: str | None, cors: list[str], allow_host: list[str]
) -> tuple[str, ...]:
    """The names the server answers to; refuses CORS settings that would expose jobs
    (before anything starts) and warns of what makes the service reachable from
    elsewhere without a token or a Host check."""
    from .service.app import check_cors

    try:
        check_cors(tuple(cors), token or None)
    except ValueError as exc:
        fail(str(exc))
    if cors and not token:
        typer.echo(
            f"warning: without --token, pages at {', '.join(cors)} can read every job here",
            err=True,
        )
    if host not in LOCAL_HOSTS:
        typer.echo(
            f"warning: listening on {host}: other machines can reach this service"
            + ("" if token else "; set --token (or TREESKETCH_TOKEN) to require a token"),
            err=True,
        )
    hosts = served_names(host, allow_host)
    if hosts == ("*",):
        typer.echo(
            "warning: the Host check is off (every address); name this server with --allow-host",
            err=True,
        )
    return hosts


def _make_app(config: ServiceConfig) -> FastAPI:
    """The app, or a plain error (exit 2) when the data folder cannot be used: another
    server owns it (refused before any job is touched), it is no folder, or its
    database cannot be read."""
    from .service import create_app
    from .service.owner import DataOwner
    from .service.store import StoreError

    try:
        DataOwner(config.data).probe()
        return create_app(config)
    except StoreError as exc:
        fail(str(exc))


def _serve_local(config: ServiceConfig, host: str, port: int) -> None:
    """Serve with worker processes on this machine."""
    import uvicorn

    app = _make_app(config)
    typer.echo(f"data: {config.data}; workers: {config.workers}; estimator: {config.estimator}")
    uvicorn.run(app, host=host, port=port, log_level="info")


def _serve_on_ray(config: ServiceConfig, host: str, port: int, workers: int | None) -> None:
    """Serve with Ray actors: connect first, so a cluster nobody answers at is a plain
    error, not a failed start-up; the pool then uses this Ray, and a Ray started here
    is ended with the server."""
    import uvicorn

    app = _make_app(config)  # before Ray starts
    from .executor import ExecutorError, start_ray

    address = config.address
    try:
        owns = start_ray(address, workers if address is None else None)
    except ExecutorError as exc:
        raise typer.BadParameter(
            str(exc), param_hint="--address" if address else "--executor"
        ) from None
    import ray

    where = address or "a local Ray"
    count = workers or "one per CPU of the cluster"
    typer.echo(
        f"data: {config.data}; workers: {count} Ray actors on {where}; "
        f"estimator: {config.estimator}"
    )
    try:
        uvicorn.run(app, host=host, port=port, log_level="info")
    finally:
        if owns:
            ray.shutdown()


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("serve")(serve_command)
