"""The drawing page in a real browser: Debian's chromium driven by Playwright (no browser
download), against a real server with one worker process (a fixed palm as the first
estimate, tiny budgets)."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from web_helpers import (
    INK,
    PHONE,
    draw_with_mouse,
    guarded_context,
    open_page,
    picture_loaded,
    view_pixels,
)

pytestmark = pytest.mark.slow


def test_draw_submit_view_and_download(page: Any, tmp_path: Path) -> None:
    draw_with_mouse(page)
    assert page.evaluate(INK) > 3000
    page.fill("#budget", "3")
    page.click("#submit")
    # (the best tree so far is loaded while the job runs: wait for the result's)
    page.wait_for_selector("body[data-state=done]", timeout=180_000)
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    assert page.get_attribute("body", "data-meshes") == "2"
    assert page.inner_text("#species").lower() == "palm"
    assert "%" in page.inner_text("#confidence")
    assert page.evaluate("document.getElementById('progress').value") == 1

    # the 3D view shows the tree: non-background pixels in its middle (the ground disc,
    # sized to the tree's width, hidden: the palm's fronds follow the drawn crown, about
    # as wide as the palm is tall, and the disc under them is wider still)
    page.uncheck("#ground")
    shot = view_pixels(page)
    h, w = shot.shape[:2]
    middle = shot[h // 4 : 3 * h // 4, w // 4 : 3 * w // 4]
    background = np.array([0xE8, 0xEE, 0xF0])
    tree = np.abs(middle - background).sum(axis=2) > 40
    assert tree.mean() > 0.02, f"only {tree.mean():.3%} of the view's middle shows the tree"
    inner = shot[4:-4, 4:-4]  # the element's screenshot has a white rim
    ys, xs = np.nonzero(np.abs(inner - background).sum(axis=2) > 40)
    assert np.ptp(ys) > np.ptp(xs), "the palm should stand (taller than wide), not lie"

    for img in ("#before", "#after"):
        assert picture_loaded(page, img) > 0, img

    with page.expect_download() as dl:
        page.click("#dl-glb")
    path = tmp_path / "tree.glb"
    dl.value.save_as(path)
    import trimesh

    data = path.read_bytes()
    assert data[:4] == b"glTF"
    scene = trimesh.load(io.BytesIO(data), file_type="glb")
    assert len(scene.geometry) == 2


def test_cancel_from_the_page(page: Any) -> None:
    draw_with_mouse(page)
    page.fill("#budget", "1000")
    page.click("#submit")
    page.wait_for_function(
        "document.getElementById('status').textContent.startsWith('Refining')", timeout=120_000
    )
    page.click("#cancel")
    page.wait_for_selector("body[data-state=cancelled]", timeout=10_000)
    assert page.inner_text("#status") == "Cancelled."
    assert not page.is_disabled("#submit")


def test_undo_clear_and_eraser(page: Any) -> None:
    draw_with_mouse(page)
    full = page.evaluate(INK)
    page.click("#undo")
    assert 0 < page.evaluate(INK) < full
    page.click("#eraser")
    box = page.locator("#pad").bounding_box()
    page.mouse.move(box["x"] + 5, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] - 5, box["y"] + box["height"] / 2, steps=20)
    page.mouse.up()
    erased = page.evaluate(INK)
    page.click("#clear")
    assert page.evaluate(INK) == 0
    assert erased < full
    page.click("#pen")
    page.click("#submit")  # an empty page is refused on the page itself
    assert "empty" in page.inner_text("#status")


def test_phone_sized_screen(browser: Any, server: str) -> None:
    with guarded_context(browser, server, **PHONE) as ctx:
        pg = open_page(ctx, server)
        box = pg.locator("#pad").bounding_box()
        assert 300 < box["width"] <= 390
        assert pg.evaluate("document.scrollingElement.scrollWidth") <= 390  # no sideways scroll
        # a touch draws too
        pg.touchscreen.tap(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        assert pg.evaluate(INK) > 0
