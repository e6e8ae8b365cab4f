"""The page's "Draw from this side" in a real browser (Debian's chromium through
Playwright): a tree made from one drawing, the 3D view turned, the tree's outline from
that side shown faintly behind the pad (and agreeing with what the 3D view shows: the
sign of the turn and the exported tree's face-view turn), a second drawing over it, and
the next job made from both drawings.  A real server with one worker whose first
estimate is a leaning palm seen from yaw 180 (no refinement: fast; the service tests
refine jobs of several drawings)."""

from __future__ import annotations

import io
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from web_helpers import DESKTOP, INK, draw_with_mouse, guarded_context, open_page, palm_service

pytestmark = pytest.mark.slow

JOB_TIMEOUT = 180_000  # ms
BACKGROUND = np.array([0xE8, 0xEE, 0xF0])  # the 3D view's


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    data = tmp_path_factory.mktemp("web-views")
    with palm_service(data, estimator="service_helpers:leaning_palm_estimator") as url:
        yield url


@pytest.fixture
def page(browser: Any, server: str) -> Iterator[Any]:
    """The drawing page (conftest's), held to the server, console errors failing too."""
    with guarded_context(browser, server, console=True, **DESKTOP) as ctx:
        yield open_page(ctx, server)


def lean(mask: np.ndarray) -> float:
    """How far the upper half of a tree (a mask) lies right of its base, in tree heights
    (negative: left)."""
    ys, xs = np.nonzero(mask)
    height = ys.max() - ys.min()
    base = xs[ys >= ys.max() - 3].mean()
    upper = ys < ys.min() + height * 0.5
    return float((xs[upper].mean() - base) / height)


def png_mask(data: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(data)).convert("L")) < 128


def view_mask(page: Any) -> np.ndarray:
    """The tree's pixels in the 3D view (the ground hidden)."""
    from PIL import Image

    shot = Image.open(io.BytesIO(page.locator("#view canvas").screenshot())).convert("RGB")
    inner = np.asarray(shot)[4:-4, 4:-4].astype(int)  # the element's screenshot has a rim
    return np.abs(inner - BACKGROUND).sum(axis=2) > 40


def make_tree(page: Any) -> dict:
    """Press "Make the tree" and wait for this job's tree; the job's JSON."""
    before = page.get_attribute("body", "data-job")
    page.click("#submit")
    page.wait_for_function(
        "(b) => document.body.dataset.job !== b && document.body.dataset.state === 'done'",
        arg=before,
        timeout=JOB_TIMEOUT,
    )
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    job_id = page.get_attribute("body", "data-job")
    return page.evaluate(f"fetch('/jobs/{job_id}').then((r) => r.json())")


def test_draw_from_another_side(page: Any, server: str) -> None:
    assert page.is_disabled("#draw-side")  # no tree yet
    draw_with_mouse(page)
    page.uncheck("#refine")
    first = make_tree(page)
    assert first["result"]["yaw"] == 180.0  # the exported tree is turned to face the drawing
    assert "views" not in first["result"]
    assert page.inner_text("#turn-readout") == "the front (0°)"
    page.wait_for_function("!document.getElementById('draw-side').disabled")

    # turn the view: a drag to the right by a quarter of the view's height turns the
    # camera a quarter turn (OrbitControls) round to its left
    page.uncheck("#ground")
    page.evaluate("window.scrollTo(0, 0)")  # the view whole on the screen, for the mouse
    box = page.locator("#view canvas").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + box["height"] / 4, y, steps=8)
    page.mouse.up()
    readout = page.inner_text("#turn-readout")
    assert readout.startswith("−") and abs(float(readout[1:-1]) - 90) < 3, readout
    shown = view_mask(page)

    # "Draw from this side", from the keyboard: the outline behind an empty pad
    page.focus("#draw-side")
    page.keyboard.press("Enter")
    page.wait_for_selector("body[data-guide=loaded]", timeout=30_000)
    turn = float(page.get_attribute("body", "data-turn"))
    assert abs(turn + 90) < 3 and page.is_visible("#guide") and page.is_visible("#side-bar")
    assert page.evaluate(INK) == 0  # the outline is not on the drawing
    assert page.evaluate("document.getElementById('guide').naturalWidth") == 512
    assert "−90" in page.inner_text("#side-note") or "−8" in page.inner_text("#side-note")
    src = page.get_attribute("#guide", "src")
    assert src == f"/jobs/{first['id']}/outline.png?turn={turn:g}&size=512", src

    # the outline shows what the 3D view shows from there: the palm leans the same way,
    # and the other side's outline leans the other way (so the check can tell them apart)
    def outline(t: float) -> np.ndarray:
        r = page.request.get(f"{server}/jobs/{first['id']}/outline.png?turn={t:g}&size=256")
        assert r.ok, r.text()
        return png_mask(r.body())

    here, there, seen = lean(outline(turn)), lean(outline(-turn)), lean(shown)
    print(
        f"lean in tree heights: 3D view {seen:+.3f}, outline at {turn:+g} {here:+.3f}, at {-turn:+g} {there:+.3f}"
    )
    assert (
        abs(here) > 0.06 and abs(there) > 0.06 and math.copysign(1, here) != math.copysign(1, there)
    ), (here, there)
    assert math.copysign(1, seen) == math.copysign(1, here), (seen, here, there)
    assert abs(seen - here) < 0.06, (seen, here)

    # draw that side over the outline; "Make the tree" sends both drawings
    draw_with_mouse(page)
    assert page.evaluate(INK) > 3000
    second = make_tree(page)
    assert second["id"] != first["id"]
    assert second["options"]["yaws"] == [pytest.approx(turn % 360)]
    views = second["result"]["views"]
    assert len(views) == 2 and views[1]["yaw"] == pytest.approx(turn % 360)
    assert not page.is_visible("#guide") and page.get_attribute("body", "data-mode") is None
    assert page.get_attribute("body", "data-views") == "2" and page.is_visible("#views-panel")
    assert page.locator("#views figure").count() == 2
    assert page.evaluate("document.querySelector('#views figure:nth-child(2) img').naturalWidth")
    assert "(2 drawings)" in page.inner_text("#recent")


def test_back_to_the_first_drawing_and_keyboard_turns(page: Any) -> None:
    draw_with_mouse(page)
    drawn = page.evaluate(INK)
    page.uncheck("#refine")
    make_tree(page)
    page.wait_for_function("!document.getElementById('draw-side').disabled")
    for _ in range(2):  # walk round to the right from the keyboard
        page.focus("#turn-right")
        page.keyboard.press("Enter")
    assert page.inner_text("#turn-readout") == "+30°"
    page.click("#draw-side")
    page.wait_for_selector("body[data-guide=loaded]", timeout=30_000)
    assert page.get_attribute("body", "data-turn") == "30"
    assert page.is_disabled("#draw-side")
    page.click("#submit")  # nothing drawn on this side yet: refused on the page
    assert "this side" in page.inner_text("#status")
    page.click("#side-exit")
    assert page.get_attribute("body", "data-mode") is None and not page.is_visible("#guide")
    assert page.evaluate(INK) == drawn  # the first drawing is back
    assert not page.is_disabled("#draw-side")
