"""A drawing on the pages people send it on: words written under or over it, a frame drawn
round it by hand; and how alike two readings of it are.

Each page comes with its plain twin (the same size, the drawing in the same place, nothing
added), so a reading of the two differs only by what was added
(``tests/test_drawings.py``, ``benchmarks/probes/page_variants.py``).
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageDraw, ImageFont

__all__ = ["bordered", "captioned", "within_a_pixel"]


def captioned(img: Image.Image, under: str, over: str = "") -> Image.Image:
    """``img`` on a page a third taller, ``under`` written below it and ``over`` above
    (either empty: nothing written there; both empty: the plain twin)."""
    w, h = img.size
    font = ImageFont.load_default(size=max(12, h // 14))
    page = Image.new("RGB", (w, h + h // 3), "white")
    page.paste(img.convert("RGB"), (0, h // 6))
    draw = ImageDraw.Draw(page)
    if under:
        draw.text((w // 3, h + h // 6 + 6), under, fill=(20, 20, 20), font=font)
    if over:
        draw.text((w // 4, 2), over, fill=(20, 20, 20), font=font)
    return page


def bordered(img: Image.Image, frame: bool = True, seed: int = 1) -> Image.Image:
    """``img`` on a page a quarter larger, centred, with a frame drawn round it by hand
    (four wobbly strokes stopping short of the corners; ``frame=False``: the plain
    twin)."""
    w, h = img.size
    page = Image.new("RGB", (w * 5 // 4, h * 5 // 4), "white")
    page.paste(img.convert("RGB"), (w // 8, h // 8))
    if not frame:
        return page
    draw = ImageDraw.Draw(page)
    rng = np.random.default_rng(seed)
    width, height = page.size
    corners = [(28, 26), (width - 24, 30), (width - 22, height - 26), (26, height - 24)]
    for p, q in zip(corners, corners[1:] + corners[:1], strict=True):
        a, b = np.asarray(p, float), np.asarray(q, float)
        a, b = a + 0.04 * (b - a), b + 0.04 * (a - b)  # short of the corners
        t = np.linspace(0.0, 1.0, 21)[:, None]
        pts = a + t * (b - a) + rng.normal(0.0, 1.5, (21, 2))
        draw.line([tuple(xy) for xy in pts], fill=(0, 0, 0), width=3)
    return page


def within_a_pixel(a: np.ndarray, b: np.ndarray) -> float:
    """The share of either ink mask's pixels within a pixel of the other's (the lesser;
    1.0: the same lines, moved by at most a pixel)."""
    from scipy import ndimage

    a, b = np.asarray(a, bool), np.asarray(b, bool)
    return float(
        min(
            (a & ndimage.binary_dilation(b)).sum() / max(1, a.sum()),
            (b & ndimage.binary_dilation(a)).sum() / max(1, b.sum()),
        )
    )
