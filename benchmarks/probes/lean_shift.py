"""Probe: can a trunk lean carry a crown drawn to one side of its trunk?

For each species' base tree with its trunk made single (``segSplits[0]`` 0: a split trunk
spreads a lean over its forks), the ``trunk_lean`` and ``trunk_bend`` controls at a few
angles; prints the crown's centre right of the trunk's axis over the tree's height
(the envelope the start reads, ``refine.envelope``, of the start's cheap sketch; the
crown is the rows above the start's crown base) at the yaws given.
People draw the crown 0.1-0.4 of the height to one side on about half their trees.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/lean_shift.py [--species oak,maple,cherry]
"""

from __future__ import annotations

import argparse

import numpy as np

from refine.envelope import envelope_of_ink
from refine.start import profile_of
from render.sketch import SketchRenderer, sketch_mesh
from weberpenn import grow, species
from weberpenn.controls import apply_controls


def shift(params, name: str, yaw: float, size: int = 128) -> float:
    r = SketchRenderer(sketch_mesh(grow(params), size, name), engine="raster")
    img = r.sketch(yaw % 360.0, size)
    prof = profile_of(img)
    ink = np.asarray(img) < 128
    if prof is None:
        return float("nan")
    env = envelope_of_ink(ink)
    rows = np.flatnonzero(env.any(axis=1))
    h = rows[-1] - rows[0] + 1
    crown = env[rows[0] : rows[-1] + 1 - round(prof.crown_base * h)]
    cols = np.arange(size) + 0.5
    return ((crown * cols).sum() / crown.sum() - size / 2) / h


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--species", default="oak,maple,cherry,birch,willow")
    ap.add_argument("--yaws", default="0,90")
    ap.add_argument("--angles", default="0,30,60,85")
    args = ap.parse_args()
    yaws = [float(v) for v in args.yaws.split(",")]
    angles = [float(v) for v in args.angles.split(",")]
    print("| species | control | yaw | " + " | ".join(f"{a:g} deg" for a in angles) + " |")
    print("|---|---|---:|" + "---:|" * len(angles))
    for name in args.species.split(","):
        p = species.base(name)
        single = p.replace(segSplits=[0.0, *list(p["segSplits"])[1:]])
        for control in ("trunk_lean", "trunk_bend"):
            for yaw in yaws:
                row = [
                    shift(apply_controls(single, {control: a}) if a else p, name, yaw)
                    for a in angles
                ]
                cells = " | ".join(f"{v:+.3f}" for v in row)
                print(f"| {name} | {control} | {yaw:g} | {cells} |", flush=True)


if __name__ == "__main__":
    main()
