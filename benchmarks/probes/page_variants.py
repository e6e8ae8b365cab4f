"""Probe: does the reader frame a drawing the same when the page around it changes?

Each drawing of ``examples/hand`` is put on a page as people send it (graph paper, a
caption under it, a title over it, a frame drawn round it, a heavy JPEG, a phone photo's
uneven light and blur, a coloured sky and grass, a flat shadow ellipse or a hill's arc
under the trunk) and read as the pipeline reads it (``treesketch.steps.prepare_input``).
Each variant is compared with the same page without the change (the same size and place,
so only what was added differs): the share of either picture's ink within a pixel of the
other's (the lesser; 1.0: the same tree, framed the same).  Prints a table, one row a
drawing, and each variant's median.

    .venv/bin/python benchmarks/probes/page_variants.py [--drawings oak,palm,...] \\
        [--set render.reader.CAPTION_MARKS=1000000]
"""

from __future__ import annotations

import argparse
import io
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFilter, ImageFont

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

Pair = tuple[Image.Image, Image.Image]  # (the page without the change, with it)


def _taller(im: Image.Image) -> Image.Image:
    w, h = im.size
    page = Image.new("RGB", (w, h + h // 3), "white")
    page.paste(im, (0, h // 6))
    return page


def _base(im: Image.Image) -> tuple[int, float]:
    """The drawing's lowest ink row and the middle of the ink there."""
    ink = np.asarray(im.convert("L")) < 128
    yb = int(np.flatnonzero(ink.any(axis=1))[-1])
    xs = np.flatnonzero(ink[yb - 3 : yb + 1].any(axis=0))
    return yb, float(xs[0] + xs[-1]) / 2


def grid(im: Image.Image) -> Pair:
    a = np.asarray(im).copy()
    lines = np.zeros(a.shape[:2], bool)
    lines[::24], lines[:, ::24] = True, True
    a[lines & (a.mean(axis=2) > 200)] = (150, 190, 235)
    return im, Image.fromarray(a)


def _written(im: Image.Image, under: str, over: str) -> Pair:
    plain, page = _taller(im), _taller(im)
    w, h = im.size
    font = ImageFont.load_default(size=max(12, h // 14))
    d = ImageDraw.Draw(page)
    d.text((w // 3, h + h // 6 + 6), under, fill=(20, 20, 20), font=font)
    if over:
        d.text((w // 4, 2), over, fill=(20, 20, 20), font=font)
    return plain, page


def caption(im: Image.Image) -> Pair:
    return _written(im, "My tree", "")


def title(im: Image.Image) -> Pair:
    return _written(im, "Anna 7", "TREE")


def border(im: Image.Image) -> Pair:
    w, h = im.size
    plain = Image.new("RGB", (w * 5 // 4, h * 5 // 4), "white")
    plain.paste(im, (w // 8, h // 8))
    page = plain.copy()
    d = ImageDraw.Draw(page)
    rng = np.random.default_rng(1)
    W, H = page.size
    corners = [(28, 26), (W - 24, 30), (W - 22, H - 26), (26, H - 24)]
    for p, q in zip(corners, corners[1:] + corners[:1], strict=True):
        s = 0.04  # each stroke stops short of the corners
        p2 = (p[0] + (q[0] - p[0]) * s, p[1] + (q[1] - p[1]) * s)
        q2 = (q[0] + (p[0] - q[0]) * s, q[1] + (p[1] - q[1]) * s)
        pts = [
            (p2[0] + (q2[0] - p2[0]) * k / 20 + rng.normal(0, 1.5),
             p2[1] + (q2[1] - p2[1]) * k / 20 + rng.normal(0, 1.5))
            for k in range(21)
        ]  # fmt: skip
        d.line(pts, fill=(0, 0, 0), width=3)
    return plain, page


def jpeg(im: Image.Image) -> Pair:
    b = io.BytesIO()
    im.save(b, "JPEG", quality=8)
    return im, Image.open(io.BytesIO(b.getvalue())).convert("RGB")


def photo(im: Image.Image) -> Pair:
    a = np.asarray(im.convert("L"), float)
    h, w = a.shape
    yy, xx = np.mgrid[0:h, 0:w]
    b = a * (0.65 + 0.3 * xx / w + 0.05 * yy / h) + np.random.default_rng(0).normal(0, 6, a.shape)
    page = Image.fromarray(np.clip(b, 0, 255).astype(np.uint8)).filter(
        ImageFilter.GaussianBlur(1.2)
    )
    return im, page.convert("RGB")


def coloured(im: Image.Image) -> Pair:
    a = np.asarray(im).astype(float)
    ink = a.mean(axis=2) < 128
    yb, _ = _base(im)
    fill = np.zeros_like(a)
    fill[:] = (150, 200, 250)
    fill[yb - int(0.02 * a.shape[0]) :] = (90, 170, 70)
    return im, Image.fromarray(np.where(ink[..., None], a, fill).astype(np.uint8))


def shadow(im: Image.Image) -> Pair:
    page = im.copy()
    yb, xc = _base(im)
    w, h = im.size
    ImageDraw.Draw(page).ellipse(
        (xc - w * 0.25, yb - h * 0.03, xc + w * 0.25, yb + h * 0.03), outline=(0, 0, 0), width=3
    )
    return im, page


def hill(im: Image.Image) -> Pair:
    page = im.copy()
    yb, xc = _base(im)
    w, h = im.size
    ImageDraw.Draw(page).arc(
        (xc - w * 0.45, yb - h * 0.02, xc + w * 0.45, yb + h * 0.3),
        180,
        360,
        fill=(0, 0, 0),
        width=3,
    )
    return im, page


VARIANTS: dict[str, Callable[[Image.Image], Pair]] = {
    "grid": grid,
    "caption": caption,
    "title": title,
    "border": border,
    "jpeg q8": jpeg,
    "photo": photo,
    "coloured": coloured,
    "shadow": shadow,
    "hill": hill,
}


def within_a_pixel(a: np.ndarray, b: np.ndarray) -> float:
    """The share of either picture's ink within a pixel of the other's (the lesser)."""
    from scipy import ndimage

    ia, ib = a < 128, b < 128
    return float(
        min(
            (ia & ndimage.binary_dilation(ib)).sum() / max(1, ia.sum()),
            (ib & ndimage.binary_dilation(ia)).sum() / max(1, ib.sum()),
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drawings", default="", help="names in examples/hand (default: all)")
    ap.add_argument("--set", nargs="*", default=[], help="MODULE.NAME=VALUE to change first")
    args = ap.parse_args()
    import importlib

    from render.reader import SketchError, read_sketch
    from treesketch.steps import prepare_input

    for item in args.set:
        target, value = item.split("=", 1)
        mod, name = target.rsplit(".", 1)
        setattr(importlib.import_module(mod), name, float(value))
    hand = ROOT / "examples" / "hand"
    names = (
        args.drawings.split(",") if args.drawings else sorted(p.stem for p in hand.glob("*.png"))
    )

    def read(page: Image.Image) -> np.ndarray | None:
        try:
            return prepare_input(read_sketch(page))
        except SketchError:
            return None

    scores: dict[str, list[float]] = {v: [] for v in VARIANTS}
    print("| drawing | " + " | ".join(VARIANTS) + " |")
    print("|---|" + "---:|" * len(VARIANTS))
    for name in names:
        im = Image.open(hand / f"{name}.png").convert("RGB")
        row = []
        for v, make in VARIANTS.items():
            plain, page = make(im)
            a, b = read(plain), read(page)
            s = 0.0 if a is None or b is None else within_a_pixel(a, b)
            scores[v].append(s)
            row.append(f"{s:.2f}")
        print(f"| {name} | " + " | ".join(row) + " |", flush=True)
    print("| **median** | " + " | ".join(f"**{np.median(s):.2f}**" for s in scores.values()) + " |")


if __name__ == "__main__":
    main()
