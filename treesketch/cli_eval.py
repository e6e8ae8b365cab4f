"""`treesketch eval ...` commands: `eval tsn` (cli_eval_tsn), `eval rotation`, `eval all`."""

from __future__ import annotations

import typer

from . import cli_eval_tsn

eval_app = typer.Typer(help="Evaluate: 1-RMSE tables, Hausdorff distance, rotation sweep, reports.",
                       no_args_is_help=True)


def register(app: typer.Typer) -> None:
    """Add the `eval` command group to the main app."""
    cli_eval_tsn.register(eval_app)
    app.add_typer(eval_app, name="eval")
