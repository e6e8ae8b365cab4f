"""Does the code grow, mesh and draw every tree as the code at another commit does, bit
for bit?

For ``--seeds`` trees of each species (``species.sample(name, 300 + seed)``) it keeps the
grown skeleton's arrays (points, radii, stem offsets, leaf matrices and positions), the
full mesh (``build_mesh``: both parts' vertices, faces and texture coordinates), the
refinement's fast sketch at three views (``refine.start.cheap_sketch``) with the envelope
the search compares (``seen_envelope``), and one full (mitsuba) sketch per species.
``--save`` writes them; ``--compare`` checks them against a saved file, array for array.
Run the other commit's code from its worktree with this file:

    git worktree add /tmp/before 4eaeece
    PYTHONPATH=/tmp/before .venv/bin/python benchmarks/probes/same_trees.py --save /tmp/t.npz
    .venv/bin/python benchmarks/probes/same_trees.py --compare /tmp/t.npz
"""

from __future__ import annotations

import argparse

import numpy as np

from refine.start import cheap_sketch, seen_envelope
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, species

YAWS = (0.0, 77.0, 200.0)
SKELETON = ("points", "radii", "offsets", "leaf_matrices", "leaf_positions")


def arrays(seeds: int) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for name in species.SPECIES:
        for seed in range(seeds):
            params = species.sample(name, 300 + seed)
            sk = grow(params)
            key = f"{name}/{seed}"
            for field in SKELETON:
                out[f"{key}/{field}"] = np.asarray(getattr(sk, field))
            mesh = build_mesh(sk, species=name)
            for part in ("branches", "leaves"):
                m = getattr(mesh, part)
                out[f"{key}/{part}/vertices"] = np.asarray(m.vertices)
                out[f"{key}/{part}/faces"] = np.asarray(m.faces)
                if len(m.vertices):
                    out[f"{key}/{part}/uv"] = np.asarray(m.visual.uv)
            for yaw in YAWS:
                s = cheap_sketch(params, name, 128, yaw)
                out[f"{key}/sketch/{yaw}"] = s
                out[f"{key}/envelope/{yaw}"] = seen_envelope(s, 128)
        full = SketchRenderer(build_mesh(grow(species.sample(name, 5)), species=name))
        out[f"{name}/full_sketch"] = full.sketch(45.0, 256)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--save")
    ap.add_argument("--compare")
    args = ap.parse_args()
    got = arrays(args.seeds)
    print(f"{len(got)} arrays of {len(species.SPECIES)} species x {args.seeds} trees")
    if args.save:
        np.savez_compressed(args.save, **got)
    if args.compare:
        saved = np.load(args.compare)
        if sorted(saved.files) != sorted(got):
            raise SystemExit(f"{len(saved.files)} saved arrays, {len(got)} now: not the same set")
        different = [k for k in saved.files if not np.array_equal(saved[k], got[k])]
        print(f"{len(different)} of {len(got)} different from {args.compare}: {different[:10]}")


if __name__ == "__main__":
    main()
