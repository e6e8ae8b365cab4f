"""Check: what does the reader leave out of the frame as not the tree (``tree_ink``)?

``render.reader.normalise_drawing`` frames a drawing on the tree, not on all its ink: a
ground line under the tree, a sun, a cloud or grass beside it are left out.  This probe
runs ``render.reader.tree_ink`` on drawings by people (``../shared/people_doodles``: an
evenly spaced ``--count`` of the stroke drawings, rasterised with 3 px lines, and as many
of the 224 px mouse drawings; never copied into the project) and on ``examples/hand``,
and reports how many lose ink to it and how much.  ``--sheet PATH`` writes a contact sheet
of the drawings that lose ink: each drawing with what is left out in red, then its
normalised picture, to look at whether only ground, grass, suns and clouds went.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/framing_on_tree.py --sheet /tmp/f.png
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from render.reader import ink_mask, normalise_drawing, read_sketch, tree_ink

ROOT = Path(__file__).resolve().parents[2]
PEOPLE = ROOT.parent / "shared" / "people_doodles"
TILE = 160


def stroke_drawings(count: int) -> list[tuple[str, np.ndarray]]:
    """``count`` evenly spaced tree drawings of ``strokes/tree.ndjson``, 3 px lines."""
    lines = (PEOPLE / "strokes" / "tree.ndjson").read_text(encoding="utf-8").splitlines()
    out = []
    for i in np.linspace(0, len(lines) - 1, count).astype(int):
        strokes = json.loads(lines[i])["strokes"]
        pts = np.array([p for s in strokes for p in s], float)
        w, h = (int(max(500, v + 10)) for v in pts.max(axis=0))
        im = Image.new("L", (w, h), 255)
        draw = ImageDraw.Draw(im)
        for s in strokes:
            draw.line([tuple(p) for p in s] * (2 if len(s) == 1 else 1), fill=0, width=3)
        out.append((f"strokes {i}", np.asarray(im)))
    return out


def mouse_drawings(count: int) -> list[tuple[str, np.ndarray]]:
    paths = sorted((PEOPLE / "mouse224" / "tree").glob("*.png"), key=lambda p: int(p.stem))
    return [
        (f"mouse {paths[i].stem}", read_sketch(paths[i]))
        for i in np.linspace(0, len(paths) - 1, count).astype(int)
    ]


def hand_drawings() -> list[tuple[str, np.ndarray]]:
    return [
        (f"hand {p.stem}", read_sketch(p)) for p in sorted((ROOT / "examples/hand").glob("*.png"))
    ]


def tile(name: str, img: np.ndarray, ink: np.ndarray, kept: np.ndarray) -> Image.Image:
    """The drawing with the ink left out in red, and its normalised picture."""
    rgb = np.where(ink[..., None], np.array([255, 0, 0], np.uint8), np.uint8(255))
    rgb[kept] = 0
    pair = Image.new("RGB", (2 * TILE, TILE + 12), "white")
    for k, pic in enumerate((Image.fromarray(rgb), Image.fromarray(normalise_drawing(img)))):
        pic.thumbnail((TILE, TILE))
        pair.paste(pic, (k * TILE, 0))
    ImageDraw.Draw(pair).text((2, TILE), name, fill=(0, 0, 0))
    return pair


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--count", type=int, default=60, help="drawings of each people's set")
    ap.add_argument("--sheet", type=Path, help="PNG of the drawings that lose ink")
    args = ap.parse_args()
    sets = {"hand": hand_drawings()}
    if PEOPLE.is_dir():
        sets["strokes"] = stroke_drawings(args.count)
        sets["mouse"] = mouse_drawings(args.count)
    tiles = []
    for what, drawings in sets.items():
        lost = []
        for name, img in drawings:
            # the people's drawings and examples/hand are on white paper: the ink rule
            # of a clean page is the reader's
            ink = ink_mask(img)
            kept = tree_ink(ink)
            if (ink & ~kept).any():
                lost.append(f"{name.split()[-1]} ({(ink & ~kept).sum() / ink.sum():.0%})")
                tiles.append(tile(name, img, ink, kept))
        print(f"{what}: {len(lost)} of {len(drawings)} lose ink: {', '.join(lost) or '-'}")
    if args.sheet and tiles:
        cols = 3
        sheet = Image.new("RGB", (cols * 2 * TILE, -(-len(tiles) // cols) * (TILE + 12)), "grey")
        for k, t in enumerate(tiles):
            sheet.paste(t, ((k % cols) * 2 * TILE, (k // cols) * (TILE + 12)))
        sheet.save(args.sheet)
        print(f"sheet: {args.sheet}")


if __name__ == "__main__":
    main()
