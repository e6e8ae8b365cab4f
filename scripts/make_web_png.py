"""docs/web.png: a real screenshot of the page after a drawing was turned into a tree;
docs/side.png: the page in "Draw from this side" mode (the 3D view turned, the tree's
outline from there faint behind the pad, a second drawing begun over it);
docs/edit.png: that tree in the 3D view, then after each of four edits with the sliders;
docs/web_phone.png: the same job opened by its link on a phone-sized screen (390 x 844,
touch): the drawing brought back on the pad, and the result scrolled to, side by side.

Starts the service (the shipped TSN checkpoint, one worker) in this process, draws a tree
with mouse strokes in headless Debian chromium (Playwright), submits it and waits for the
result, then saves the screenshot; then turns the 3D view, presses "Draw from this side", draws
the start of a second drawing and saves that screenshot; then moves four controls one
after the other (each on top of the last) and puts the 3D view after each side by side.

    PYTHONPATH=$PWD .venv/bin/python scripts/make_web_png.py --out docs/web.png \
        --side-out docs/side.png --edit-out docs/edit.png --phone-out docs/web_phone.png

``PYTHONPATH=$PWD`` is needed even in the main checkout: the mouse strokes and the browser
are the page tests' own (``tests.web_helpers``), and tests/ is no installed package.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from tests.web_helpers import CHROMIUM, CHROMIUM_ARGS, draw_with_mouse, tree_strokes
from treesketch.service import ServiceConfig, create_app
from treesketch.service.inprocess import serve
from weberpenn.fileio import atomic_target

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=int, default=None, help="default: the page's")
    ap.add_argument("--estimator", default="tsn")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "web.png")
    ap.add_argument("--side-out", type=Path, default=ROOT / "docs" / "side.png")
    ap.add_argument("--edit-out", type=Path, default=ROOT / "docs" / "edit.png")
    ap.add_argument("--phone-out", type=Path, default=ROOT / "docs" / "web_phone.png")
    args = ap.parse_args()

    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="web-png-") as d:
        app = create_app(ServiceConfig(data=Path(d), workers=1, estimator=args.estimator))
        with serve(app) as url, sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1200, "height": 1000})
            page.goto(url + "/")
            page.wait_for_function("document.getElementById('budget').value !== ''")
            draw_with_mouse(page)
            if args.budget is not None:
                page.fill("#budget", str(args.budget))
            page.click("#submit")
            page.wait_for_selector("body[data-state=done]", timeout=600_000)
            page.wait_for_selector("body[data-edit=ready]", timeout=60_000)
            page.wait_for_selector("body[data-model=loaded]", timeout=60_000)
            page.wait_for_timeout(500)
            with atomic_target(args.out) as tmp:
                page.screenshot(path=str(tmp), full_page=True, type="png")
            print(page.inner_text("#species"), page.inner_text("#confidence"))
            print(page.inner_text("#status"))
            job = page.get_attribute("body", "data-job")
            side(page, args.side_out)
            edits(page, args.edit_out)
            phone(browser, url, job, args.phone_out)
            browser.close()
    print(f"wrote {args.out}, {args.side_out}, {args.edit_out} and {args.phone_out}")


def phone(browser, url: str, job: str, out: Path) -> None:
    """The job opened by its link on a phone: the top of the page (the drawing back on the
    pad) and the result (scrolled to), side by side."""
    import io

    from PIL import Image

    ctx = browser.new_context(
        viewport={"width": 390, "height": 844}, has_touch=True, device_scale_factor=2
    )
    page = ctx.new_page()
    page.goto(f"{url}/?job={job}")
    page.wait_for_selector("body[data-edit=ready]", timeout=60_000)
    page.wait_for_selector("body[data-model=loaded]", timeout=60_000)
    page.wait_for_selector("body[data-pad=restored]", timeout=60_000)
    page.wait_for_timeout(300)
    shots = [Image.open(io.BytesIO(page.screenshot(type="png")))]
    page.evaluate("document.getElementById('result-panel').scrollIntoView()")
    page.wait_for_timeout(500)
    shots.append(Image.open(io.BytesIO(page.screenshot(type="png"))))
    ctx.close()
    w, h = shots[0].size
    sheet = Image.new("RGB", (2 * w + 24, h), "white")
    for i, im in enumerate(shots):
        sheet.paste(im.convert("RGB"), (i * (w + 24), 0))
    with atomic_target(out) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)


def side(page, out: Path) -> None:
    """The 3D view turned about 60 degrees, "Draw from this side", the crown and trunk of
    a second drawing over the faint outline; then back to the first drawing."""
    page.evaluate("window.scrollTo(0, 0)")
    box = page.locator("#view canvas").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x - box["height"] / 6, y, steps=8)  # a drag left: round to the right
    page.mouse.up()
    page.click("#draw-side")
    page.wait_for_selector("body[data-guide=loaded]", timeout=60_000)
    pad = page.locator("#pad").bounding_box()
    k = pad["width"] / 512
    for stroke in tree_strokes()[:3]:  # the crown outline and the trunk's two lines
        page.mouse.move(pad["x"] + stroke[0][0] * k, pad["y"] + stroke[0][1] * k)
        page.mouse.down()
        for px, py in stroke[1:]:
            page.mouse.move(pad["x"] + px * k, pad["y"] + py * k, steps=3)
        page.mouse.up()
    page.evaluate("window.scrollTo(0, 0)")
    page.wait_for_timeout(300)
    with atomic_target(out) as tmp:
        page.screenshot(
            path=str(tmp), type="png", clip={"x": 0, "y": 0, "width": 1200, "height": 900}
        )
    print(page.inner_text("#side-note"))
    page.click("#side-exit")
    page.click("#reset-view")


EDITS = (  # (control, value, caption): each on top of the ones before
    ("crown_width", 1.6, "crown width 1.6x"),
    ("branch_angle", 25, "branch angle +25 deg"),
    ("leafy", False, "bare"),
    ("seed", 12345, "another variant"),
)


def edits(page, out: Path) -> None:
    import io

    from PIL import Image, ImageDraw

    def shot(caption: str) -> Image.Image:
        page.wait_for_selector("body[data-model=loaded]")
        page.click("#reset-view")  # an edit keeps the camera; the picture frames each tree
        page.wait_for_timeout(300)
        im = Image.open(io.BytesIO(page.locator("#view canvas").screenshot())).convert("RGB")
        im = im.resize((320, round(320 * im.height / im.width)))
        height = page.inner_text("#height-readout")
        ImageDraw.Draw(im).text((6, 4), f"{caption} ({height})", fill=(20, 30, 20))
        return im

    panels = [shot(f"{page.inner_text('#species')} as drawn")]
    for name, value, caption in EDITS:
        n = int(page.get_attribute("body", "data-edits") or 0)
        if isinstance(value, bool):
            page.set_checked(f"#c-{name}", value)
        else:
            page.evaluate(
                """([id, v]) => { const s = document.getElementById(id);
                s.value = String(v); s.dispatchEvent(new Event('input')); }""",
                [f"c-{name}", value],
            )
        page.wait_for_function(f"Number(document.body.dataset.edits || 0) > {n}", timeout=60_000)
        panels.append(shot(caption))
    w, h = panels[0].size
    sheet = Image.new("RGB", (w * len(panels), h), "white")
    for i, im in enumerate(panels):
        sheet.paste(im, (i * w, 0))
    with atomic_target(out) as tmp:
        sheet.save(tmp, format="PNG", optimize=True)


if __name__ == "__main__":
    main()
