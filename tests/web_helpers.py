"""Browser helpers for the page tests and docs/web.png: Debian's chromium through
Playwright (no browser download), and a tree drawn with mouse strokes."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
# software WebGL (SwiftShader) so the 3D view renders on a machine without a GPU
CHROMIUM_ARGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox"]


@contextlib.contextmanager
def palm_service(data: Path, estimator: str = "service_helpers:palm_estimator") -> Iterator[str]:
    """A real server on ``data`` with one worker and a palm test estimator (no network
    to load); yields its base URL."""
    from service_helpers import serve

    from treesketch.service import ServiceConfig, create_app

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
    """Draw ``tree_strokes`` on the canvas with real mouse events."""
    box = page.locator(selector).bounding_box()
    k = box["width"] / 512
    for stroke in tree_strokes():
        x0, y0 = stroke[0]
        page.mouse.move(box["x"] + x0 * k, box["y"] + y0 * k)
        page.mouse.down()
        for x, y in stroke[1:]:
            page.mouse.move(box["x"] + x * k, box["y"] + y * k, steps=3)
        page.mouse.up()
