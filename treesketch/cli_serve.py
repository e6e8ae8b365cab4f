"""`treesketch serve`: the HTTP service (see treesketch/service.py)."""

from __future__ import annotations

import typer


def serve_command(
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
    port: int = typer.Option(8000, "--port", min=1, max=65535, help="Port to listen on."),
    budget: int = typer.Option(
        None, "--budget", min=1, help="Default refinement budget per request (default 100)."
    ),
) -> None:
    """Serve POST /predict (sketch image -> parameters, species, losses, GLB link),
    GET /trees/ID.glb and GET /health.

    Example: `treesketch serve --port 8000`, then
    `curl -F sketch=@examples/sketch_maple.png localhost:8000/predict`.
    """
    import uvicorn

    from .service import create_app

    uvicorn.run(create_app(default_budget=budget), host=host, port=port, log_level="info")


def register(app: typer.Typer) -> None:
    """Add this module's commands to the main app."""
    app.command("serve")(serve_command)
