"""docs/web.png: a real screenshot of the page after a drawing was turned into a tree.

Starts the service (the shipped TSN checkpoint, one worker) in this process, draws a tree
with mouse strokes in headless Debian chromium (Playwright), submits it and waits for the
3D view, then saves the screenshot.

    PYTHONPATH=$PWD .venv/bin/python scripts/make_web_png.py --budget 20 --out docs/web.png
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from service_helpers import serve  # noqa: E402
from web_helpers import CHROMIUM, CHROMIUM_ARGS, draw_with_mouse  # noqa: E402

from treesketch.service import ServiceConfig, create_app  # noqa: E402
from weberpenn.fileio import atomic_target  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--budget", type=int, default=20)
    ap.add_argument("--estimator", default="tsn")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "web.png")
    args = ap.parse_args()

    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="web-png-") as d:
        app = create_app(ServiceConfig(data=Path(d), workers=1, estimator=args.estimator))
        with serve(app) as url, sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            page = browser.new_page(viewport={"width": 1200, "height": 1000})
            page.goto(url + "/")
            draw_with_mouse(page)
            page.fill("#budget", str(args.budget))
            page.click("#submit")
            page.wait_for_selector("body[data-model=loaded]", timeout=600_000)
            page.wait_for_timeout(500)
            with atomic_target(args.out) as tmp:
                page.screenshot(path=str(tmp), full_page=True, type="png")
            print(page.inner_text("#species"), page.inner_text("#confidence"))
            print(page.inner_text("#status"))
            browser.close()
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
