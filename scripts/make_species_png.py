"""Make docs/species.png: every species, our tree beside Blender Sapling's tree from the
same dictionary, and beside the untouched Sapling preset the species starts from.

    .venv/bin/python scripts/make_species_png.py [--blender blender] [--cols 4] [--tile 480]

Each species' base dictionary (``species.base(name)``, seed 0) is grown by us
(``build_mesh(grow(...))``) and exported as a Sapling preset
(``weberpenn.export.save_sapling_preset``); for the species people draw, the untouched
Sapling preset they start from (seed 0, leaves shown: ``sapling_run.write_untouched``)
comes third.  ``scripts/blender_species.py`` renders them inside Blender from the front at
one scale per tile (flat bark and leaf colours of ``weberpenn.textures.colours``).  Each
tile is labelled with the species' display name and every tree's width x depth x height,
as ``benchmarks/compare_sapling.py
--species`` compares them (Sapling's from ``benchmarks/lib/sapling_species_stats.json``, which
``compare_sapling.py --species --blender blender`` records; a record of other dictionaries
is refused as stale).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from docs_png import write_palette_png
from PIL import Image, ImageDraw, ImageFont

from benchmarks.compare_sapling import TOLERANCE, compare_species, dims
from benchmarks.lib.sapling_run import SaplingError, recorded, sizes, write_untouched
from weberpenn import build_mesh, grow, species
from weberpenn.export import save_sapling_preset
from weberpenn.textures import colours

ROOT = Path(__file__).resolve().parents[1]

LABEL_H = 70
INK, GREY, WARN = (25, 25, 25), (95, 95, 95), (190, 40, 20)


def render_tiles(blender: str, tmp: Path, width: int, height: int) -> dict[str, Path]:
    """Render every species' pair in one Blender run; the tile of each species."""
    jobs, out = [], {}
    for name in species.SPECIES:
        params = species.base(name)
        tm = build_mesh(grow(params), species=name)
        mesh = tmp / f"{name}.npz"
        np.savez(
            mesh,
            branch_v=tm.branches.vertices,
            branch_f=tm.branches.faces,
            leaf_v=tm.leaves.vertices.reshape(-1, 3),
            leaf_f=tm.leaves.faces.reshape(-1, 3),
        )
        presets = [save_sapling_preset(params, tmp / f"{name}.py")]
        if species.sapling_preset(name):
            presets.append(write_untouched(name, 0, tmp / f"{name}_untouched.py"))
        bark, leaf = colours(name)
        tile = tmp / f"{name}.png"
        jobs.append(
            {
                "mesh": str(mesh),
                "presets": [str(p) for p in presets],
                "bark": list(bark),
                "leaf": list(leaf),
                "out": str(tile),
                "width": width,
                "height": height,
            }
        )
        out[name] = tile
    (tmp / "jobs.json").write_text(json.dumps(jobs))
    cmd = [blender, "--background", "--factory-startup", "--python-exit-code", "1"]
    cmd += ["--python", str(ROOT / "scripts" / "blender_species.py"), "--", str(tmp / "jobs.json")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    missing = [n for n, tile in out.items() if not tile.is_file()]
    if proc.returncode != 0 or missing:
        tail = (proc.stdout + proc.stderr)[-2000:]
        raise SystemExit(f"blender failed (exit {proc.returncode}; no tile for {missing}):\n{tail}")
    return out


def make_grid(tiles: dict[str, Path], record: dict, cols: int) -> Image.Image:
    """The labelled grid; sizes and the verdict from ``compare_sapling.compare_species``
    (the numbers of the RESULTS table)."""
    names = list(species.SPECIES)
    rows_by = {r["species"]: r for r in compare_species(record)}
    first = Image.open(tiles[names[0]])
    tw, th = first.size
    rows = -(-len(names) // cols)
    grid = Image.new("RGB", (cols * tw, rows * (th + LABEL_H)), "white")
    draw = ImageDraw.Draw(grid)
    big = ImageFont.load_default(size=17)
    mid = ImageFont.load_default(size=14)
    small = ImageFont.load_default(size=13)
    for i, name in enumerate(names):
        x, y = (i % cols) * tw, (i // cols) * (th + LABEL_H)
        grid.paste(Image.open(tiles[name]).convert("RGB"), (x, y + LABEL_H))
        row = rows_by[name]
        slots = [("ours", row["ours"]), ("Sapling", row["sapling"])]
        if row["preset"]:
            untouched = sizes(record["trees"][name]["preset_rows"][0])["tree"]
            slots.append((f"{row['preset']} preset", untouched))
        draw.text((x + 8, y + 6), species.display_name(name), font=big, fill=INK)
        worst = row["worst"]
        verdict = f"ours vs Sapling: sizes within {100 * worst:.0f} %"
        colour = GREY if worst <= TOLERANCE else WARN
        if worst > TOLERANCE:
            verdict = f"ours vs Sapling: sizes off by {100 * worst:.0f} %"
        draw.text((x + tw - 8, y + 9), verdict, font=small, fill=colour, anchor="ra")
        for k, (label, size) in enumerate(slots):
            sx = x + (2 * k + 1) * tw // (2 * len(slots))  # over the tree: its slot's centre
            draw.text((sx, y + 32), label, font=mid, fill=INK, anchor="ma")
            draw.text((sx, y + 50), dims(size, " m"), font=small, fill=GREY, anchor="ma")
    # the empty slots of the last row: what the picture shows
    spare = rows * cols - len(names)
    if spare:
        x, y = (len(names) % cols) * tw, (rows - 1) * (th + LABEL_H)
        notes = [
            "Each species' base dictionary (seed 0),",
            "grown by TreeSketch (ours, left) and by",
            "Blender 3.4's Sapling from the same",
            "dictionary (exported preset, middle).",
            "The species people draw: right, the",
            "untouched Sapling preset they start from",
            "(seed 0, leaves shown); what the species sets",
            "is in scripts/make_species_data.py.",
            "Front view, one scale per tile, flat colours.",
            "Sizes: width x depth x height (Z up);",
            f"red: a size more than {100 * TOLERANCE:.0f} % off Sapling's.",
            "Table: benchmarks/RESULTS.md.",
        ]
        for k, line in enumerate(notes):
            draw.text((x + 12, y + LABEL_H + 20 + 20 * k), line, font=small, fill=GREY)
    for c in range(1, cols):
        draw.line([(c * tw, 0), (c * tw, grid.height)], fill=(255, 255, 255), width=3)
    for r in range(1, rows):
        yy = r * (th + LABEL_H)
        draw.line([(0, yy), (grid.width, yy)], fill=(255, 255, 255), width=3)
    return grid


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blender", default="blender", help="Blender binary (with Sapling)")
    ap.add_argument("--cols", type=int, default=4, help="tiles per row")
    ap.add_argument("--tile", type=int, default=480, help="tile width in pixels")
    ap.add_argument("--out", default=str(ROOT / "docs" / "species.png"))
    args = ap.parse_args()
    if not 1 <= args.cols <= len(species.SPECIES) or not 160 <= args.tile <= 1600:
        ap.error("--cols must be 1..number of species and --tile 160..1600")
    try:
        record = recorded()
    except SaplingError as exc:
        print(f"make_species_png: {exc}", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        tiles = render_tiles(args.blender, Path(tmp), args.tile, round(args.tile * 0.82))
        grid = make_grid(tiles, record, args.cols)
    write_palette_png(grid, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
