"""``--set KEY=VALUE`` for the benchmarks that run the pipeline: one ``RefineSettings``
field from the command line."""

from __future__ import annotations

import argparse
import dataclasses
from typing import Any

from refine.search import RefineSettings

__all__ = ["add_set_option", "setting"]


def setting(text: str) -> tuple[str, Any]:
    """``--set KEY=VALUE``: one RefineSettings field, VALUE read as its default's type."""
    key, sep, value = text.partition("=")
    fields = {f.name: f for f in dataclasses.fields(RefineSettings)}
    if not sep or key not in fields:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected KEY=VALUE with KEY one of {', '.join(fields)}"
        )
    kind = type(getattr(RefineSettings(), key))
    if kind is bool:
        if value.lower() not in ("true", "false"):
            raise argparse.ArgumentTypeError(f"{key} takes true or false, got {value!r}")
        return key, value.lower() == "true"
    if kind is tuple:  # e.g. hold=scaleV,rSplits2 (empty: none)
        return key, tuple(v.strip() for v in value.split(",") if v.strip())
    if kind not in (int, float, str):
        raise argparse.ArgumentTypeError(f"{key} cannot be set from the command line")
    try:
        return key, kind(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{key} takes a {kind.__name__}, got {value!r}") from None


def add_set_option(ap: argparse.ArgumentParser, help: str) -> None:
    """``--set KEY=VALUE`` (repeatable) on ``ap``: ``args.set``, a list of (field, value)."""
    ap.add_argument(
        "--set", type=setting, action="append", default=[], metavar="KEY=VALUE", help=help
    )
