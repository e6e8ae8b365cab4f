"""The page's interactive loop in a real browser (Debian's chromium through Playwright):
the first tree shown while the refinement runs, the sliders and "another variant", the
example gallery, the job in the address and the recent jobs, the 3D view's tools,
undo/redo and brush size from the keyboard, and a phone scrolled to the result.  A real
server with one worker (a fixed palm as the first estimate); the tests that only shape
or look at a finished tree open a shared job by its link (``finished_job``), those about
making one (the first tree, the link and the recent jobs, the phone's scroll) make
their own."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from web_helpers import (
    INK,
    JOB_TIMEOUT,
    PHONE,
    draw_with_mouse,
    edit_count,
    guarded_context,
    make_tree,
    open_job,
    open_page,
    picture_loaded,
    view_pixels,
    wait_edit,
)

pytestmark = pytest.mark.slow


def _height(page: Any) -> float:
    return float(page.inner_text("#height-readout").split()[0])


def test_the_first_tree_is_shown_before_the_refinement_ends(page: Any) -> None:
    draw_with_mouse(page)
    page.fill("#budget", "1000")
    page.click("#submit")
    page.wait_for_selector("body[data-preview]", timeout=JOB_TIMEOUT)
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    assert page.get_attribute("body", "data-state") == "running"
    assert picture_loaded(page, "#before") > 0
    assert _height(page) > 0
    text = page.inner_text("#status")
    if text.startswith("Refining"):  # "n of N trees": never past the plan
        n, _, rest = text.removeprefix("Refining: ").partition(" of ")
        assert int(n) <= int(rest.split()[0])
    page.click("#cancel")
    page.wait_for_selector("body[data-state=cancelled]", timeout=10_000)


def test_sliders_variant_and_the_edited_download(
    context: Any, server: str, finished_job: Any
) -> None:
    page = context.new_page()
    open_job(page, server, finished_job())
    before = view_pixels(page)
    h0 = _height(page)
    assert page.get_attribute("body", "data-edits") is None
    # height, typed in as a person drags: the tree is regrown that tall
    page.evaluate(
        """(h) => { const s = document.getElementById('c-height');
        s.value = String(h); s.dispatchEvent(new Event('input')); }""",
        round(h0 * 1.5, 1),
    )
    wait_edit(page, 0)
    assert _height(page) == pytest.approx(h0 * 1.5, rel=0.03)
    # crown width from the keyboard
    n = edit_count(page)
    page.focus("#c-crown_width")
    for _ in range(8):
        page.keyboard.press("ArrowRight")
    wait_edit(page, n)
    assert page.input_value("#c-crown_width") == "1.4"
    # bare branches, then another variant
    n = edit_count(page)
    page.uncheck("#c-leafy")
    wait_edit(page, n)
    seed = page.input_value("#c-seed")
    n = edit_count(page)
    page.click("#variant")
    wait_edit(page, n)
    assert page.input_value("#c-seed") != seed
    after = view_pixels(page)
    assert np.abs(after - before).sum(axis=2).__gt__(40).mean() > 0.01, "the tree did not change"
    assert page.inner_text("#view-note") == "edited"
    # the download is the edited tree's
    with page.expect_download() as dl:
        page.click("#dl-json")
    import json

    params = json.loads(Path(dl.value.path()).read_text())
    assert params["leaves"] == 0 and str(params["seed"]) == page.input_value("#c-seed")
    # reset: the drawing's tree again
    n = edit_count(page)
    page.click("#reset-controls")
    wait_edit(page, n)
    assert page.inner_text("#view-note") == ""
    assert _height(page) == pytest.approx(h0, rel=0.01)


def test_gallery_loads_an_example(page: Any) -> None:
    page.wait_for_selector("#gallery .example")
    # every example drawing the service offers (the repository's examples/hand/*.png)
    drawings = list((Path(__file__).resolve().parents[1] / "examples" / "hand").glob("*.png"))
    assert page.locator("#gallery .example").count() == len(drawings) >= 12
    assert page.evaluate(INK) == 0
    page.locator("#gallery .example").first.click()
    page.wait_for_function(f"({INK})() > 500")
    assert "Example" in page.inner_text("#status")
    page.keyboard.press("Control+z")  # the example is one step: undone at once
    page.keyboard.press("Control+z")
    assert page.evaluate(INK) == 0


def test_permalink_reload_and_recent_jobs(page: Any, server: str) -> None:
    make_tree(page)
    job = page.get_attribute("body", "data-job")
    assert f"job={job}" in page.url
    page.wait_for_selector(f"#recent a[href*='{job}']")
    assert "palm" in page.inner_text("#recent").lower()
    page.reload()
    page.wait_for_selector("body[data-state=done]", timeout=30_000)
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    assert page.get_attribute("body", "data-job") == job
    assert page.inner_text("#species").lower() == "palm"
    page.wait_for_selector(f"#recent a[href*='{job}']")
    # a shared link in a fresh page restores it too
    other = page.context.new_page()
    other.goto(f"{server}/?job={job}")
    other.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    assert other.inner_text("#species").lower() == "palm"


def test_view_tools(context: Any, server: str, finished_job: Any) -> None:
    page = context.new_page()
    open_job(page, server, finished_job())
    assert page.inner_text("#height-readout").endswith(" m") and _height(page) > 1
    framed = view_pixels(page)
    page.uncheck("#ground")
    bare = view_pixels(page)
    assert (np.abs(bare - framed).sum(axis=2) > 40).mean() > 0.005, "the ground did not go"
    page.check("#ground")
    box = page.locator("#view canvas").bounding_box()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.9, box["y"] + box["height"] * 0.3, steps=10)
    page.mouse.up()
    turned = view_pixels(page)
    assert (np.abs(turned - framed).sum(axis=2) > 40).mean() > 0.01
    page.click("#reset-view")
    back = view_pixels(page)
    assert (np.abs(back - framed).sum(axis=2) > 40).mean() < 0.002


def test_keyboard_undo_redo_brush_and_upload(page: Any) -> None:
    page.click("#pen")
    draw_with_mouse(page)
    full = page.evaluate(INK)
    page.locator("body").focus()
    page.keyboard.press("Control+z")
    fewer = page.evaluate(INK)
    assert 0 < fewer < full
    page.keyboard.press("Control+Shift+z")
    # (a redraw antialiases a little differently from strokes drawn as they came)
    assert page.evaluate(INK) == pytest.approx(full, rel=0.05)
    full = page.evaluate(INK)
    page.click("#clear")
    assert page.evaluate(INK) == 0
    page.keyboard.press("Control+z")  # Clear is undone like a stroke
    assert page.evaluate(INK) == full
    page.click("#clear")
    # a wider brush draws more ink
    inks = []
    for width in ("3", "30"):
        page.fill("#brush", width)
        page.dispatch_event("#brush", "input")
        page.click("#clear")
        box = page.locator("#pad").bounding_box()
        page.mouse.move(box["x"] + 50, box["y"] + 250)
        page.mouse.down()
        page.mouse.move(box["x"] + 400, box["y"] + 250, steps=10)
        page.mouse.up()
        inks.append(page.evaluate(INK))
    assert inks[1] > 5 * inks[0]
    # Upload is reached and opened from the keyboard
    page.focus("#clear")
    for _ in range(10):
        if page.evaluate("document.activeElement.id") == "upload":
            break
        page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.id") == "upload"
    page.evaluate(
        "document.getElementById('file').addEventListener('click', () => { window.opened = true; })"
    )
    page.keyboard.press("Enter")  # opens the file picker (the native input is hidden)
    page.wait_for_function("window.opened === true", timeout=5_000)


def test_a_phone_scrolls_to_the_result(browser: Any, server: str) -> None:
    with guarded_context(browser, server, **PHONE) as ctx:
        pg = open_page(ctx, server)
        make_tree(pg)
        pg.wait_for_function("window.scrollY > 300", timeout=10_000)
        top = pg.evaluate("document.getElementById('result-panel').getBoundingClientRect().top")
        assert -50 < top < 300
        assert pg.evaluate("document.scrollingElement.scrollWidth") <= 390
