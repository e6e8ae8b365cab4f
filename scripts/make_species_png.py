"""Make docs/species.png: five species x three seeds, front view, flat-shaded colour renders.

    .venv/bin/python scripts/make_species_png.py [--seeds 0,1,2] [--tile 220]

Each tile is ``build_mesh(grow(species.sample(name, seed)))`` rendered by
``render.sketch.SketchRenderer.colour`` (mitsuba; bark and leaf colours per species),
framed per tree, with the tree's height and triangle count in the label.
"""

from __future__ import annotations

import argparse
import io
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from render.sketch import SketchRenderer  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402


def make_grid(seeds: list[int], tile: int) -> Image.Image:
    label_h = 30
    rows, cols = len(seeds), len(species.SPECIES)
    grid = Image.new("RGB", (cols * tile, rows * (tile + label_h)), "white")
    draw = ImageDraw.Draw(grid)
    for c, name in enumerate(species.SPECIES):
        for r, seed in enumerate(seeds):
            tm = build_mesh(grow(species.sample(name, seed)), species=name)
            img = np.asarray(SketchRenderer(tm).colour("front", tile))
            x, y = c * tile, r * (tile + label_h)
            grid.paste(Image.fromarray(img), (x, y + label_h))
            lo, hi = tm.bounds()
            tris = len(tm.branches.faces) + len(tm.leaves.faces)
            draw.text((x + 4, y + 2), f"{name} seed {seed}", fill=(30, 30, 30))
            draw.text(
                (x + 4, y + 15),
                f"h {hi[2] - lo[2]:.1f}  {tris // 1000}k tris",
                fill=(110, 110, 110),
            )
        if c:
            draw.line([(c * tile, 0), (c * tile, grid.height)], fill=(210, 210, 210))
    return grid


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="0,1,2", help="comma-separated sample seeds (rows)")
    ap.add_argument("--tile", type=int, default=220, help="tile size in pixels")
    ap.add_argument("--out", default=str(ROOT / "docs" / "species.png"))
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    grid = make_grid(seeds, args.tile)
    buf = io.BytesIO()
    grid.quantize(colors=128, method=Image.Quantize.MEDIANCUT).save(
        buf, format="PNG", optimize=True
    )
    out = Path(args.out)
    tmp = out.with_suffix(".png.tmp")
    tmp.write_bytes(buf.getvalue())
    tmp.replace(out)
    print(f"wrote {out} ({out.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main()
