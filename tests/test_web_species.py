"""The page's species in a real browser (Debian's chromium through Playwright): the picker
lists every species and the one picked reaches the job; the result names its species in
words and shows its candidates as thumbnails; clicking one (or pressing Enter on it)
switches the 3D view, the controls and the downloads to that candidate's tree.  A real
server with one worker (a fixed palm as the first estimate, tiny budgets); any console
error, page error or request outside the server fails the test.  The picker's test makes
its job in the page (the pick must reach it); the others only read and shape a finished
one, and open a shared job by its link (``finished_job``)."""

from __future__ import annotations

import io
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from web_helpers import (
    DESKTOP,
    PHONE,
    edit_count,
    guarded_context,
    make_tree,
    open_job,
    open_page,
    view_pixels,
    wait_edit,
)

from weberpenn import species

pytestmark = pytest.mark.slow
READY = "body[data-species=ready]"


@pytest.fixture
def context(browser: Any, server: str) -> Iterator[Any]:
    with guarded_context(browser, server, console=True, **DESKTOP) as ctx:
        yield ctx


@pytest.fixture
def page(context: Any, server: str) -> Any:
    return open_page(context, server, READY)


def _make_tree(page: Any, pick: str | None = None) -> dict:
    """Draw, submit (the species ``pick``, or let it decide) and wait for the result on
    show; returns the finished job as the API gives it."""
    if pick is not None:
        page.select_option("#species-pick", pick)
    make_tree(page)
    return page.evaluate("async (id) => (await fetch(`/jobs/${id}`)).json()", _job(page))


def _job(page: Any) -> str:
    return page.get_attribute("body", "data-job")


def _loads(page: Any) -> int:
    return int(page.get_attribute("body", "data-loads") or 0)


def test_the_picker_lists_every_species_and_the_pick_reaches_the_job(page: Any) -> None:
    options = page.eval_on_selector_all(
        "#species-pick option", "os => os.map(o => [o.value, o.textContent])"
    )
    assert options[0] == ["", "Let it decide"]
    assert page.input_value("#species-pick") == ""  # the drawing decides by default
    assert sorted(v for v, _ in options[1:]) == sorted(species.SPECIES)
    assert {v: t for v, t in options[1:]} == {s: species.display_name(s) for s in species.SPECIES}
    labels = [t for _, t in options[1:]]
    assert labels == sorted(labels, key=str.lower)  # found by name

    job = _make_tree(page, pick="fir")  # the estimator says palm; the person means a fir
    assert job["result"]["species"] == "fir"
    assert page.text_content("#species") == species.display_name("fir")
    assert page.get_attribute("body", "data-shown") == "fir"
    # a species picked by hand is not a verdict on the drawing
    assert page.inner_text("#species-text").startswith("You picked this species: fir")
    assert page.inner_text("#confidence") == "picked by you"
    first = page.locator("#candidates .candidate").first
    assert first.get_attribute("data-species") == "fir"
    assert first.get_attribute("aria-pressed") == "true"


def test_candidates_switch_the_tree_the_controls_and_the_downloads(
    context: Any, server: str, finished_job: Any
) -> None:
    page = context.new_page()
    job = open_job(page, server, finished_job(), READY)
    result = job["result"]
    assert result["species"] == "palm"
    text = page.inner_text("#species-text")
    said = f"It is {result['species_text']}."
    if result["warning"]:  # a drawing that may be no tree: the question leads
        said = (
            "Is this a tree? The drawing does not look much like one. "
            f"If it is, the closest is {result['species_text']}."
        )
    assert text == said and "palm" in text
    cands = page.locator("#candidates .candidate")
    assert cands.count() == 3
    for i, c in enumerate(result["candidates"][:3]):
        thumb = cands.nth(i)
        assert thumb.get_attribute("data-species") == c["species"]
        assert c["name"] in thumb.inner_text()
        p = c["probability"]
        assert (f"{round(p * 100)}%" if p == 0 or p >= 0.005 else "<1%") in thumb.inner_text()
        page.wait_for_function(
            "(i) => document.querySelectorAll('#candidates img')[i].naturalWidth > 0", arg=i
        )
        assert thumb.get_attribute("aria-pressed") == ("true" if i == 0 else "false")
    before = view_pixels(page)
    h0 = page.inner_text("#height-readout")

    # the second candidate, from the keyboard: a new GLB, its species, its controls
    other = result["candidates"][1]
    n = _loads(page)
    cands.nth(1).focus()
    page.keyboard.press("Enter")
    page.wait_for_function(f"Number(document.body.dataset.loads) > {n}", timeout=30_000)
    page.wait_for_selector("body[data-model=loaded]")
    assert page.get_attribute("body", "data-shown") == other["species"]
    assert page.text_content("#species") == species.display_name(other["species"])
    assert cands.nth(1).get_attribute("aria-pressed") == "true"
    assert cands.nth(0).get_attribute("aria-pressed") == "false"
    after = view_pixels(page)
    assert (np.abs(after - before).sum(axis=2) > 40).mean() > 0.01, "the tree did not change"
    assert page.inner_text("#height-readout") != h0
    page.wait_for_selector("body[data-edit=ready]")
    assert "disabled" in (page.get_attribute("#dl-preset", "class") or "")

    # the downloads are the candidate's tree
    with page.expect_download() as dl:
        page.click("#dl-json")
    got = json.loads(Path(dl.value.path()).read_text())
    assert got == other["params"]
    with page.expect_download() as dl:
        page.click("#dl-glb")
    glb = Path(dl.value.path()).read_bytes()
    assert glb[:4] == b"glTF"
    import trimesh

    assert len(trimesh.load(io.BytesIO(glb), file_type="glb").geometry) >= 1
    job_glb = page.evaluate(
        "async (id) => (await (await fetch(`/jobs/${id}/tree.glb`)).arrayBuffer()).byteLength",
        job["id"],
    )
    assert len(glb) != job_glb

    # the controls now shape the candidate's tree
    edits = edit_count(page)
    page.uncheck("#c-leafy")
    wait_edit(page, edits)
    with page.expect_download() as dl:
        page.click("#dl-json")
    edited = json.loads(Path(dl.value.path()).read_text())
    assert edited["leaves"] == 0 and edited["shape"] == other["params"]["shape"]
    assert page.get_attribute("body", "data-shown") == other["species"]

    # and back to the drawing's own tree: its species, its files
    n = _loads(page)
    cands.nth(0).click()
    page.wait_for_function(f"Number(document.body.dataset.loads) > {n}", timeout=30_000)
    page.wait_for_selector("body[data-edit=ready]")
    assert page.inner_text("#species").lower() == "palm"
    assert "disabled" not in (page.get_attribute("#dl-preset", "class") or "")
    assert page.get_attribute("#dl-glb", "href").endswith(f"/jobs/{job['id']}/tree.glb")


def test_a_phone_shows_and_switches_the_candidates(
    browser: Any, server: str, finished_job: Any
) -> None:
    with guarded_context(browser, server, console=True, **PHONE) as ctx:
        pg = ctx.new_page()
        job = open_job(pg, server, finished_job(), READY)
        cands = pg.locator("#candidates .candidate")
        assert cands.count() == 3
        # all three in one layout: on a phone the page may still be scrolling smoothly,
        # so boxes read one after another can sit at different heights
        boxes = cands.evaluate_all(
            "els => els.map(e => { const r = e.getBoundingClientRect();"
            " return {x: r.x, y: r.y, width: r.width}; })"
        )
        assert all(b["width"] >= 80 and b["x"] + b["width"] <= 390 for b in boxes)
        assert len({round(b["y"]) for b in boxes}) == 1  # one row
        assert pg.evaluate("document.scrollingElement.scrollWidth") <= 390  # no sideways scroll
        n = _loads(pg)
        cands.nth(2).tap()
        pg.wait_for_function(f"Number(document.body.dataset.loads) > {n}", timeout=30_000)
        assert pg.get_attribute("body", "data-shown") == job["result"]["candidates"][2]["species"]


def test_a_slider_past_the_generators_limits_stops_at_the_most_it_grows(
    context: Any, server: str, finished_job: Any
) -> None:
    page = context.new_page()
    open_job(page, server, finished_job(species="fir"), READY)
    n = edit_count(page)
    # three times the branches of a fir: more leaves than the generator grows
    page.evaluate(
        """() => { const s = document.getElementById('c-branch_count');
        s.value = s.max; s.dispatchEvent(new Event('input')); }"""
    )
    wait_edit(page, n)
    status = page.inner_text("#edit-status")
    assert "Refused" not in status and "branch count held at" in status, status
    held = float(page.input_value("#c-branch_count"))
    assert 1.0 <= held < float(page.get_attribute("#c-branch_count", "max"))
