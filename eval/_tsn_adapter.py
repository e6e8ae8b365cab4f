"""Adapter from a TSN checkpoint (``tsn.predict`` / ``tsn.encoding``) to ``eval.report.Backend``."""

from __future__ import annotations

from pathlib import Path


def backend(checkpoint: str | Path | None = None, name: str | None = None):
    try:
        from tsn import predict as _predict  # noqa: F401
    except ImportError as e:  # pragma: no cover - only before tsn lands
        raise RuntimeError(
            f"tsn.predict is not available ({e}); cannot evaluate a checkpoint"
        ) from e
    raise RuntimeError("tsn adapter not wired yet")
