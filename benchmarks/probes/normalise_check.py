"""Check: does ``normalise_drawing`` leave the renderer's own sketches as they are?

``render.reader.normalise_drawing`` promises that a renderer sketch passes (nearly)
unchanged, and refinement relies on it: the input drawing and every candidate go through
it (``refine.objective.framed``) before they are compared.  For each of the 15 published
ground-truth trees (``tests/data/treesketchnet_test_params``, grown with their own seed),
its sketch at each ``--yaws`` and ``--sizes`` is normalised at its own size twice: as it
is, and with a white border of half its side around it (``PAD``).  Both frame the same
drawn extent, so they should agree to a few pixels; but a line that spans most of the page
(what the reader takes for a ruled line or the margin of lined paper) no longer does so
on the larger page.  Reported: % of the reference's ink pixels (the padded page's; ink:
< 128) not within a pixel of the direct result's ink, and the two ink counts.  A large share means strokes
of the tree were taken for paper ruling (e.g. a long straight trunk).

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/normalise_check.py
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from scipy import ndimage

from render.reader import normalise_drawing
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, load_params, species

ROOT = Path(__file__).resolve().parents[2]

GT_DIR = ROOT / "tests" / "data" / "treesketchnet_test_params"
PAD = 0.5  # white border, as a share of the side: no stroke spans 80 % of such a page
TOLERANCE = 2.0  # % of the ink missing that rounding at a line's ends can explain


def check(img: np.ndarray, size: int) -> tuple[int, int, float]:
    """(reference ink, direct ink, % of the reference's ink not near the direct's)."""
    pad = int(round(PAD * max(img.shape)))
    ref = normalise_drawing(np.pad(img, pad, constant_values=255), size) < 128
    direct = normalise_drawing(img, size) < 128
    # a pixel of shift (the two pages round the re-framing differently) is not a loss
    near = ndimage.binary_dilation(direct, np.ones((3, 3), bool))
    missing = float((ref & ~near).sum()) / max(int(ref.sum()), 1)
    return int(ref.sum()), int(direct.sum()), 100.0 * missing


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--yaws", default="0,90,180,270", help="comma list of view yaws")
    ap.add_argument("--sizes", default="128,256", help="comma list of sketch sides")
    args = ap.parse_args(argv)
    try:
        yaws = [float(v) for v in args.yaws.split(",")]
        sizes = [int(v) for v in args.sizes.split(",")]
    except ValueError:
        ap.error("--yaws and --sizes take comma lists of numbers")
    files = sorted(GT_DIR.glob("*.json"), key=lambda p: int(p.stem.split("_", 1)[0]))
    cols = [f"{y:g} deg @ {s} px" for y in yaws for s in sizes]
    changed, total = 0, 0
    print("| tree | " + " | ".join(cols) + " |")
    print("|---|" + "---:|" * len(cols))
    for path in files:
        name = species.canonical(path.stem.split("_", 1)[1])
        r = SketchRenderer(build_mesh(grow(load_params(path)), species=name), species=name)
        cells = []
        for y in yaws:
            for s in sizes:
                ref, direct, missing = check(r.sketch(y, s), s)
                bad = missing > TOLERANCE
                changed, total = changed + bad, total + 1
                b = "**" if bad else ""
                cells.append(f"{b}{missing:.0f} %{b} ({ref} / {direct})")
        print(f"| {path.name} | " + " | ".join(cells) + " |", flush=True)
    print(f"\nmore than {TOLERANCE:g} % of the ink missing (bold): {changed} of {total}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
