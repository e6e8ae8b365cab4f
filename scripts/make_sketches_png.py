"""Make docs/sketches.png and examples/sketch_maple.png.

    .venv/bin/python scripts/make_sketches_png.py [--seed 1] [--tile 200]

docs/sketches.png: one row per species (one tree, ``species.sample(name, seed)``): the
colour render (front) and the sketches of the four views front, left, back, right.
examples/sketch_maple.png: a 256x256 front sketch of the maple drawn with seed 100000,
which is not a tree of the default dataset (its per-tree seeds come from
``render.dataset.tree_seed``), used by ``make demo``.
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from render.sketch import VIEWS, SketchRenderer
from weberpenn.fileio import atomic_write

ROOT = Path(__file__).resolve().parents[1]

EXAMPLE_SEED = 100000


def _tree(name: str, seed: int):  # noqa: ANN202 - a TreeMesh
    from render.dataset import mesher_in_use
    from weberpenn import grow, species

    build_mesh, _ = mesher_in_use()
    tm = build_mesh(grow(species.sample(name, seed=seed)))
    if getattr(tm, "species", None) is None:
        tm.species = name
    return tm


def _png(img: Image.Image) -> bytes:
    buf = io.BytesIO()
    img.save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def make_grid(seed: int, tile: int) -> Image.Image:
    from weberpenn import species

    views = ["front", "left", "back", "right"]
    label_h = 18
    cols = 1 + len(views)
    grid = Image.new("RGB", (cols * tile, len(species.SPECIES) * (tile + label_h)), "white")
    draw = ImageDraw.Draw(grid)
    for r, name in enumerate(species.SPECIES):
        rend = SketchRenderer(_tree(name, seed))
        y = r * (tile + label_h)
        tiles = [rend.colour("front", tile)] + [
            np.stack([rend.sketch(v, tile)] * 3, axis=-1) for v in views
        ]
        labels = [f"{name} (seed {seed}) colour"] + [f"{v} ({VIEWS[v]:.0f} deg)" for v in views]
        for c, (im, lab) in enumerate(zip(tiles, labels, strict=True)):
            grid.paste(Image.fromarray(im), (c * tile, y + label_h))
            draw.text((c * tile + 4, y + 3), lab, fill=(60, 60, 60))
        for c in range(1, cols):
            draw.line(
                [(c * tile, y + label_h), (c * tile, y + label_h + tile)], fill=(200, 200, 200)
            )
    return grid


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tile", type=int, default=200)
    ap.add_argument("--out", default=str(ROOT / "docs" / "sketches.png"))
    ap.add_argument("--example", default=str(ROOT / "examples" / "sketch_maple.png"))
    args = ap.parse_args()
    grid = make_grid(args.seed, args.tile)
    atomic_write(Path(args.out), _png(grid))
    print(f"wrote {args.out} ({Path(args.out).stat().st_size // 1024} KB)")
    ex = SketchRenderer(_tree("maple", EXAMPLE_SEED)).sketch("front", 256)
    atomic_write(Path(args.example), _png(Image.fromarray(ex)))
    print(f"wrote {args.example} (maple, seed {EXAMPLE_SEED}, front, 256 px)")


if __name__ == "__main__":
    main()
