"""Browser helpers for the page tests and docs/web.png: Debian's chromium through
Playwright (no browser download), a context held to the server, and a tree drawn with
mouse strokes and submitted.  The page tests' ``server`` and ``browser`` fixtures are in
``conftest.py``."""

from __future__ import annotations

import contextlib
import io
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
# software WebGL (SwiftShader) so the 3D view renders on a machine without a GPU
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"]
JOB_TIMEOUT = 180_000  # ms a tiny-budget job may take on a busy machine
DESKTOP = {"viewport": {"width": 1200, "height": 900}}
PHONE = {"viewport": {"width": 390, "height": 844}, "has_touch": True}
# the pad's dark pixels (a JavaScript function for page.evaluate)
INK = """() => {
  const c = document.getElementById('pad');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let n = 0;
  for (let i = 0; i < d.length; i += 4) if (d[i] < 128) n++;
  return n;
}"""


@contextlib.contextmanager
def palm_service(data: Path, estimator: str = "service_helpers:palm_estimator") -> Iterator[str]:
    """A real server on ``data`` with one worker and a palm test estimator (no network
    to load); yields its base URL."""
    from treesketch.service import ServiceConfig, create_app
    from treesketch.service.inprocess import serve

    config = ServiceConfig(data=data, workers=1, estimator=estimator)
    with serve(create_app(config)) as url:
        yield url


@contextlib.contextmanager
def chromium() -> Iterator[Any]:
    """Debian's chromium through Playwright (never a downloaded browser)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()


@contextlib.contextmanager
def guarded_context(
    browser: Any, server: str, console: bool = False, **options: Any
) -> Iterator[Any]:
    """A browser context (``options`` as for ``new_context``) that may talk to ``server``
    only: on leaving, a request elsewhere (a CDN) or a page error fails the test, and with
    ``console`` a console error too."""
    ctx = browser.new_context(accept_downloads=True, **options)
    outside: list[str] = []
    errors: list[str] = []

    def guard(route: Any) -> None:
        if route.request.url.startswith(server):
            route.continue_()
        else:
            outside.append(route.request.url)
            route.abort()

    ctx.route("**/*", guard)
    ctx.on("weberror", lambda e: errors.append(str(e.error)))
    if console:
        ctx.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    try:
        yield ctx
    finally:
        ctx.close()
    assert not outside, f"the page fetched from outside the server: {outside}"
    assert not errors, errors


def open_page(ctx: Any, server: str, ready: str = "") -> Any:
    """A new page of ``ctx`` on the drawing page, once its budget is filled in (and the
    ``ready`` selector, e.g. ``body[data-species=ready]``, shows)."""
    pg = ctx.new_page()
    pg.goto(server + "/")
    if ready:
        pg.wait_for_selector(ready)
    pg.wait_for_function("document.getElementById('budget').value !== ''")
    return pg


def open_job(page: Any, server: str, job: str, ready: str = "") -> Any:
    """``page`` on the link of the finished ``job`` (a shared one, ``finished_job`` in
    ``conftest.py``), once its tree is shown and editable (and ``ready`` shows); the job
    as the API gives it.  ``page`` a new one of a new context (the ``context`` fixture):
    nothing of another test's visit (its edits, its pad, its recent jobs) is kept, and
    the job itself is never changed by the page (an edit is a new tree, ``POST
    /trees``)."""
    page.goto(f"{server}/?job={job}")
    if ready:
        page.wait_for_selector(ready)
    page.wait_for_selector("body[data-edit=ready]", timeout=30_000)
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)
    return page.evaluate("async (id) => (await fetch(`/jobs/${id}`)).json()", job)


def make_tree(page: Any, budget: int = 2) -> None:
    """Draw ``tree_strokes``, submit with ``budget`` and wait until the result is shown
    and editable."""
    draw_with_mouse(page)
    page.fill("#budget", str(budget))
    page.click("#submit")
    page.wait_for_selector("body[data-state=done]", timeout=JOB_TIMEOUT)
    page.wait_for_selector("body[data-edit=ready]", timeout=30_000)
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)


def edit_count(page: Any) -> int:
    """How many edited trees the page has shown (``data-edits``)."""
    return int(page.get_attribute("body", "data-edits") or 0)


def wait_edit(page: Any, n: int) -> None:
    """Wait until more than ``n`` edited trees were shown and the one shown is the
    controls' last position: keys pressed in a row can send two requests, and the first's
    tree alone raises the count."""
    page.wait_for_function(
        f"Number(document.body.dataset.edits || 0) > {n}"
        " && document.body.dataset.editQueue === 'idle'",
        timeout=30_000,
    )
    page.wait_for_selector("body[data-model=loaded]", timeout=30_000)


def painted(page: Any) -> None:
    """Wait until the browser has drawn two more frames: what a change of the page's
    layout sets off (the 3D view resized, drawn again) has been painted by then."""
    page.evaluate("() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)))")


def picture_loaded(page: Any, selector: str, timeout: int = 30_000) -> int:
    """Wait until the <img> at ``selector`` has finished loading and return its natural
    width: the page sets ``src`` when the job is done, and the browser fetches the picture
    after that, so reading ``naturalWidth`` at once races the fetch. A picture that failed
    to load (complete, width 0) fails at once rather than waiting out the timeout."""
    done = page.wait_for_function(
        f"(() => {{ const im = document.querySelector({selector!r});"
        " return im && im.getAttribute('src') && im.complete ? im.naturalWidth + 1 : 0; })()",
        timeout=timeout,
    )
    return int(done.json_value()) - 1


def view_pixels(page: Any) -> Any:
    """The 3D view's canvas as an (h, w, 3) int array."""
    import numpy as np
    from PIL import Image

    shot = page.locator("#view canvas").screenshot()
    return np.asarray(Image.open(io.BytesIO(shot)))[..., :3].astype(int)


def tree_strokes(size: int = 512) -> list[list[tuple[float, float]]]:
    """Strokes of a broadleaf tree in pad pixels: a lobed crown outline, the trunk as two
    lines, a few branches inside the crown (like the paper's hand-drawn sketches)."""
    s = size / 512
    cx, cy, rx, ry = 256 * s, 190 * s, 170 * s, 135 * s
    crown = []
    for i in range(73):
        t = 2 * math.pi * i / 72
        lobe = 1 + 0.08 * math.sin(7 * t)
        crown.append((cx + rx * lobe * math.cos(t), cy + ry * lobe * math.sin(t)))
    trunk_l = [(238 * s, 490 * s), (242 * s, 400 * s), (246 * s, 300 * s)]
    trunk_r = [(276 * s, 490 * s), (272 * s, 400 * s), (266 * s, 300 * s)]
    branches = [
        [(246 * s, 300 * s), (200 * s, 230 * s), (150 * s, 170 * s)],
        [(266 * s, 300 * s), (310 * s, 220 * s), (360 * s, 160 * s)],
        [(256 * s, 300 * s), (256 * s, 200 * s), (258 * s, 90 * s)],
        [(205 * s, 235 * s), (170 * s, 250 * s)],
        [(310 * s, 225 * s), (350 * s, 240 * s)],
    ]
    return [crown, trunk_l, trunk_r, *branches]


def draw_with_mouse(page: Any, selector: str = "#pad") -> None:
    """Draw ``tree_strokes`` on the canvas with real mouse events, one move to each of a
    stroke's points: the pad joins the points it is given with straight lines, so moves
    in between (``steps``) draw the same lines, and each costs a round trip to the
    browser and a redraw of the pad (three steps a point took 5.5 s a drawing, one 1.9 s,
    for the same ink within 0.1%)."""
    box = page.locator(selector).bounding_box()
    k = box["width"] / 512
    for stroke in tree_strokes():
        x0, y0 = stroke[0]
        page.mouse.move(box["x"] + x0 * k, box["y"] + y0 * k)
        page.mouse.down()
        for x, y in stroke[1:]:
            page.mouse.move(box["x"] + x * k, box["y"] + y * k)
        page.mouse.up()
