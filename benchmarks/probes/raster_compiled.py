"""Is the rasteriser the one at ``--before``, bit for bit, and how much faster?

Loads ``render/raster.py`` as it was at ``--before`` (``git show``; 954e6a1: the numpy
scanline code, before the loops were compiled with numba; 4eaeece: compiled, on one
thread) beside the current one and draws every
hit mask of the refinement's fast sketch (``refine.start.cheap_sketch``: branches at 512
px facing the camera, leaves at 256 px) of ``--seeds`` trees of each of the eleven
species at four views with both: the masks must be equal, and each one's time is summed
(each code's first call, its compilation or cache load, left out).

    .venv/bin/python benchmarks/probes/raster_compiled.py --before 954e6a1 --seeds 3
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import render.raster as raster
from refine.start import cheap_sketch
from weberpenn import species

NAMES = species.SPECIES
YAWS = (0.0, 37.0, 123.0, 275.5)


def old_module(rev: str):
    text = subprocess.run(
        ["git", "show", f"{rev}:render/raster.py"], capture_output=True, text=True, check=True
    ).stdout
    text = text.replace("from .camera", "from render.camera").replace(
        "from .silhouette", "from render.silhouette"
    )
    path = Path(tempfile.mkdtemp()) / "raster_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("raster_before", path)
    mod = importlib.util.module_from_spec(spec)
    sys.modules["raster_before"] = mod
    spec.loader.exec_module(mod)
    return mod


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", default="954e6a1")
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    before = old_module(args.before)
    now = raster.hit_mask
    t = {"before": 0.0, "now": 0.0}
    counts = {"masks": 0, "different": 0}

    def both(v, f, cam, n, front_only=False):
        s = time.perf_counter()
        a = before.hit_mask(v, f, cam, n, front_only)
        t["before"] += time.perf_counter() - s
        s = time.perf_counter()
        b = now(v, f, cam, n, front_only)
        t["now"] += time.perf_counter() - s
        counts["masks"] += 1
        counts["different"] += int(not np.array_equal(a, b))
        return b

    raster.hit_mask = both
    # both codes' first calls (their compilation or cache load) left out
    cheap_sketch(species.sample("oak", 1), "oak", 128, 0.0)
    t.update(before=0.0, now=0.0)
    counts.update(masks=0, different=0)
    for seed in range(args.seeds):
        for name in NAMES:
            p = species.sample(name, 100 + seed)
            for yaw in YAWS:
                cheap_sketch(p, name, 128, yaw)
    raster.hit_mask = now
    print(
        f"{counts['masks']} hit masks, {counts['different']} different; at "
        f"{args.before}: {t['before']:.2f} s, now: {t['now']:.2f} s "
        f"({t['before'] / t['now']:.1f}x)"
    )


if __name__ == "__main__":
    main()
