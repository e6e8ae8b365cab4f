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
from PIL import Image, ImageDraw, ImageFilter

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

from eval.pages import bordered, captioned, within_a_pixel  # noqa: E402

Pair = tuple[Image.Image, Image.Image]  # (the page without the change, with it)


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


def caption(im: Image.Image) -> Pair:
    return captioned(im, ""), captioned(im, "My tree")


def title(im: Image.Image) -> Pair:
    return captioned(im, ""), captioned(im, "Anna 7", "TREE")


def border(im: Image.Image) -> Pair:
    return bordered(im, frame=False), bordered(im)


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drawings", default="", help="names in examples/hand (default: all)")
    ap.add_argument("--set", nargs="*", default=[], help="MODULE.NAME=VALUE to change first")
    args = ap.parse_args()
    from outline_replay import set_constants

    from render.reader import SketchError, ink_mask, read_sketch
    from treesketch.steps import prepare_input

    set_constants(args.set)
    hand = ROOT / "examples" / "hand"
    names = (
        args.drawings.split(",") if args.drawings else sorted(p.stem for p in hand.glob("*.png"))
    )

    def read(page: Image.Image) -> np.ndarray | None:
        try:
            return ink_mask(prepare_input(read_sketch(page)))
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
