"""Make docs/doodles.png: the code-made doodles of eval/doodles.py, trees and not trees.

    .venv/bin/python scripts/make_doodles_png.py [--seeds 6] [--tile 100]

Top: ``tree_doodle(species, seed)`` for every species of ``TREE_SPECIES``; below:
``nontree_doodle(kind, seed)`` for every kind of ``NONTREE_KINDS``; seeds 0 to N-1 left to
right, two species or kinds to a row.
"""

from __future__ import annotations

import argparse
import io
from collections.abc import Callable
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from eval.doodles import NONTREE_KINDS, TREE_SPECIES, nontree_doodle, tree_doodle
from weberpenn.fileio import atomic_write

ROOT = Path(__file__).resolve().parents[1]

GAP, HEAD = 16, 28


def _section(
    title: str,
    names: tuple[str, ...],
    make: Callable[[str, int], np.ndarray],
    seeds: int,
    tile: int,
) -> Image.Image:
    rows = (len(names) + 1) // 2
    group = seeds * tile
    im = Image.new("L", (2 * group + GAP, HEAD + rows * tile), 255)
    d = ImageDraw.Draw(im)
    d.text((4, 6), title, fill=0)
    for i, name in enumerate(names):
        x0, y0 = (i % 2) * (group + GAP), HEAD + (i // 2) * tile
        for seed in range(seeds):
            img = Image.fromarray(make(name, seed)).resize((tile, tile), Image.Resampling.BOX)
            im.paste(img, (x0 + seed * tile, y0))
            d.rectangle(
                (x0 + seed * tile, y0, x0 + (seed + 1) * tile - 1, y0 + tile - 1), outline=200
            )
        d.rectangle((x0 + 1, y0 + 1, x0 + 7 * len(name) + 4, y0 + 13), fill=235)
        d.text((x0 + 3, y0 + 1), name, fill=0)
    return im


def make_sheet(seeds: int, tile: int) -> Image.Image:
    trees = _section(
        "tree_doodle(species, seed): the trees people draw, each species as people draw it",
        TREE_SPECIES, tree_doodle, seeds, tile,
    )  # fmt: skip
    others = _section(
        "nontree_doodle(kind, seed): what is not a tree (for the 'is this a tree?' warning)",
        NONTREE_KINDS, nontree_doodle, seeds, tile,
    )  # fmt: skip
    sheet = Image.new("L", (trees.width, trees.height + GAP + others.height), 255)
    sheet.paste(trees, (0, 0))
    sheet.paste(others, (0, trees.height + GAP))
    return sheet


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6, help="doodles per species or kind")
    ap.add_argument("--tile", type=int, default=100)
    ap.add_argument("--out", default=str(ROOT / "docs" / "doodles.png"))
    args = ap.parse_args()
    if not 1 <= args.seeds <= 20 or not 32 <= args.tile <= 256:
        ap.error("--seeds must be 1 to 20 and --tile 32 to 256")
    buf = io.BytesIO()
    make_sheet(args.seeds, args.tile).save(buf, format="PNG", optimize=True)
    atomic_write(args.out, buf.getvalue())
    print(f"wrote {args.out} ({len(buf.getvalue()) // 1024} KB)")


if __name__ == "__main__":
    main()
