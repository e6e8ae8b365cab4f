"""Fixtures of the page tests (``tests/test_web*.py``); their helpers are in
``web_helpers.py``."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """A real server with one worker and the palm test estimator, one per test module (so
    a module's jobs are its own); its base URL.  A module may define its own."""
    from web_helpers import palm_service

    with palm_service(tmp_path_factory.mktemp("web")) as url:
        yield url


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    """Debian's chromium through Playwright."""
    from web_helpers import chromium

    with chromium() as b:
        yield b


@pytest.fixture
def page(browser: Any, server: str) -> Iterator[Any]:
    """The drawing page on a desktop screen, held to the server (see ``guarded_context``)."""
    from web_helpers import DESKTOP, guarded_context, open_page

    with guarded_context(browser, server, **DESKTOP) as ctx:
        yield open_page(ctx, server)
