"""The page shows the drawing's outline (red) over the tree's (blue) once a job is done
(``GET /jobs/{id}/outlines.png``), on a desktop and on a phone, and does without it
quietly when the picture cannot load.  Debian's chromium through Playwright against a
real server (conftest's: one worker, a fixed palm as the first estimate, tiny budgets).
``TREESKETCH_SHOTS=DIR`` keeps screenshots of the result there."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
from web_helpers import PHONE, guarded_context, make_tree, open_page, picture_loaded

pytestmark = pytest.mark.slow

CAPTION = "your drawing's outline (red) over the tree's (blue)"
SHOTS = os.environ.get("TREESKETCH_SHOTS")


def _shot(page: Any, name: str) -> None:
    if SHOTS:
        Path(SHOTS).mkdir(parents=True, exist_ok=True)
        page.locator("#result-panel").screenshot(path=str(Path(SHOTS) / name))


def _outlines_shown(page: Any) -> dict:
    """Wait until the outlines picture has loaded; what the page shows of it."""
    page.wait_for_selector("body[data-outlines='1']", timeout=30_000)
    return page.evaluate(
        """() => {
          const im = document.querySelector('#outlines figure img');
          const box = im.getBoundingClientRect();
          return {
            natural: im.naturalWidth, width: box.width, right: box.right,
            src: im.getAttribute('src'),
            caption: document.querySelector('#outlines figcaption').textContent,
            panel: !document.getElementById('outlines-panel').hidden,
            job: document.body.dataset.job,
          };
        }"""
    )


def test_the_outlines_show_after_a_job(page: Any) -> None:
    make_tree(page)
    shown = _outlines_shown(page)
    assert shown["natural"] == 256 and shown["width"] > 100, shown
    assert shown["panel"] and shown["caption"] == CAPTION, shown
    assert shown["src"] == f"/jobs/{shown['job']}/outlines.png?view=1"
    assert page.is_visible("#outlines img")
    _shot(page, "web_outlines.png")
    # a new job replaces it with its own
    make_tree(page)
    again = _outlines_shown(page)
    assert again["job"] != shown["job"] and again["src"].startswith(f"/jobs/{again['job']}/")
    assert page.locator("#outlines figure").count() == 1


def test_a_picture_that_cannot_load_is_left_out(browser: Any, server: str) -> None:
    with guarded_context(browser, server) as ctx:
        page = open_page(ctx, server)
        page.route("**/outlines.png*", lambda route: route.fulfill(status=404, body="{}"))
        make_tree(page)
        # the figure is dropped (no broken-image icon), the panel stays hidden
        page.wait_for_function("document.querySelectorAll('#outlines figure').length === 0")
        assert not page.is_visible("#outlines-panel")
        assert page.get_attribute("body", "data-outlines") is None
        # the rest of the result is there
        assert page.inner_text("#species").lower() == "palm"
        assert picture_loaded(page, "#after") > 0
        assert "disabled" not in (page.get_attribute("#dl-glb", "class") or "")


def test_the_outlines_fit_a_phone(browser: Any, server: str) -> None:
    with guarded_context(browser, server, **PHONE) as ctx:
        page = open_page(ctx, server)
        make_tree(page)
        shown = _outlines_shown(page)
        assert shown["natural"] == 256 and shown["right"] <= 390, shown
        assert page.evaluate("document.scrollingElement.scrollWidth") <= 390  # no sideways scroll
        page.locator("#outlines").scroll_into_view_if_needed()
        _shot(page, "web_phone_outlines.png")
