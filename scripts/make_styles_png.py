"""Make docs/styles.png: every drawing style side by side for one tree of each species.

    .venv/bin/python scripts/make_styles_png.py [--seed 1] [--tile 200] [--style-seed 0]

One row per species (the tree ``species.sample(name, seed)``, front view), one column per
style of :data:`render.styles.STYLES`, each drawn with ``rng = default_rng(style_seed)``.
"""

from __future__ import annotations

import argparse
import io
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from render.dataset import mesher_in_use
from render.sketch import SketchRenderer
from render.styles import STYLES, Silhouettes, draw
from weberpenn.fileio import atomic_write

ROOT = Path(__file__).resolve().parents[1]

BLURB = {
    "sg": "paper's SG chain",
    "pen": "pen outline",
    "cloud": "architect's cloud",
    "scribble": "scribbled foliage",
    "pencil": "pencil, textured paper",
    "felt": "felt tip",
    "bare": "bare (winter) tree",
    "doodle": "quick doodle",
}
# the doodle's modes (polyline, lollipop, zigzag, loops, strokes) vary by seed: two columns
EXTRA = [("doodle", 5, "another doodle")]


def make_grid(seed: int, tile: int, style_seed: int) -> Image.Image:
    from weberpenn import grow, species

    build_mesh, _ = mesher_in_use()
    label_h, side_w = 18, 70
    names = [(st, style_seed, f"{st}: {BLURB.get(st, '')}") for st in STYLES]
    names += [(st, style_seed + k, text) for st, k, text in EXTRA]
    grid = Image.new(
        "RGB", (side_w + len(names) * tile, label_h + len(species.SPECIES) * tile), "white"
    )
    draw_ = ImageDraw.Draw(grid)
    for c, (_, _, text) in enumerate(names):
        draw_.text((side_w + c * tile + 4, 3), text, fill=(40, 40, 40))
    for r, name in enumerate(species.SPECIES):
        tree = build_mesh(grow(species.sample(name, seed=seed)))
        parts = SketchRenderer(tree, species=name).parts("front", 256)
        sil = Silhouettes.from_parts(parts, species.doodle_foliage(name))
        y = label_h + r * tile
        draw_.text((4, y + tile // 2 - 6), name, fill=(40, 40, 40))
        for c, (st, st_seed, _) in enumerate(names):
            img = draw(st, sil, np.random.default_rng(st_seed), 256)
            tile_im = Image.fromarray(img).resize((tile, tile), Image.Resampling.LANCZOS)
            grid.paste(tile_im.convert("RGB"), (side_w + c * tile, y))
            if c:
                x = side_w + c * tile
                draw_.line([(x, y), (x, y + tile)], fill=(200, 200, 200))
    return grid


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1, help="tree seed of every species")
    ap.add_argument("--style-seed", type=int, default=0, help="seed of the styles' choices")
    ap.add_argument("--tile", type=int, default=150)
    ap.add_argument("--out", default=str(ROOT / "docs" / "styles.png"))
    args = ap.parse_args()
    grid = make_grid(args.seed, args.tile, args.style_seed)
    buf = io.BytesIO()
    grid.save(buf, format="PNG", optimize=True)
    atomic_write(args.out, buf.getvalue())
    print(f"wrote {args.out} ({len(buf.getvalue()) // 1024} KB)")


if __name__ == "__main__":
    main()
