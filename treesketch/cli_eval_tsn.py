"""`treesketch eval tsn` (being written; see the issue tracker)."""

from __future__ import annotations

import typer


def register(eval_app: typer.Typer) -> None:
    """Add `eval tsn` to the eval group."""
    del eval_app
