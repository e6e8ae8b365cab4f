"""Is the sketch distance blind to drawing style?  (issue: a person's drawing)

For N tree pairs (A, B of the same species, fresh seeds) and two styles X != Y drawn by a
seeded choice from ``render.styles``, every drawing normalised as the pipeline does
(``render.reader.normalise_drawing``): the distance wins when the same tree in another
style is closer than another tree of the same species in the same style,
``d(A_X, A_Y) < d(A_X, B_X)``.  Rows: the shape distance (``refine.shape``, what the
refinement uses) and the ink distance (``refine.objective.sketch_distance``, the one before
it), on the same pairs; plus each style pair's share.

    .venv/bin/python benchmarks/bench_distance.py --pairs 100 --size 128
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from refine.objective import sketch_distance  # noqa: E402
from refine.shape import shape_distance  # noqa: E402
from render.reader import normalise_drawing  # noqa: E402
from render.sketch import SketchRenderer  # noqa: E402
from render.styles import STYLES, Silhouettes, draw  # noqa: E402
from weberpenn import build_mesh, grow, species  # noqa: E402

METRICS = {"shape": shape_distance, "ink": sketch_distance}


def drawings(name: str, seed: int, styles: tuple[str, ...], yaw: float) -> dict[str, np.ndarray]:
    r = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name))
    sil = Silhouettes.from_parts(r.parts(yaw, 256))
    return {
        s: normalise_drawing(draw(s, sil, np.random.default_rng([seed, i]), 256), 256)
        for i, s in enumerate(styles)
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    names = list(STYLES)
    wins = {m: [] for m in METRICS}
    by_pair: dict[tuple[str, str], dict[str, list[bool]]] = {}
    t0 = time.perf_counter()
    for i in range(args.pairs):
        name = species.SPECIES[i % len(species.SPECIES)]
        x, y = rng.choice(names, size=2, replace=False)
        yaw = float(rng.uniform(0, 360))
        a = drawings(name, 50_000 + i, (x, y), yaw)
        b = drawings(name, 60_000 + i, (x,), yaw)
        key = tuple(sorted((x, y)))
        for m, fn in METRICS.items():
            same_tree = fn(a[x], a[y], args.size)
            same_style = fn(a[x], b[x], args.size)
            wins[m].append(same_tree < same_style)
            by_pair.setdefault(key, {k: [] for k in METRICS})[m].append(same_tree < same_style)
        print(
            f"{i:3d} {name:7s} {x:>8s}/{y:<8s} "
            + " ".join(f"{m} {'win' if wins[m][-1] else 'LOSS'}" for m in METRICS),
            flush=True,
        )
    print()
    print(f"{args.pairs} pairs, {args.size} px, {time.perf_counter() - t0:.0f} s")
    print("| distance | same tree, other style closer than other tree, same style |")
    print("|---|---|")
    for m in METRICS:
        print(f"| {m} | {np.mean(wins[m]):.0%} ({sum(wins[m])}/{len(wins[m])}) |")
    print()
    print("| styles | pairs | " + " | ".join(METRICS) + " |")
    print("|---|---|" + "---|" * len(METRICS))
    for key in sorted(by_pair, key=lambda k: (names.index(k[0]), names.index(k[1]))):
        v = by_pair[key]
        n = len(next(iter(v.values())))
        print(
            f"| {key[0]}/{key[1]} | {n} | "
            + " | ".join(f"{np.mean(v[m]):.0%}" for m in METRICS)
            + " |"
        )
    _ = itertools
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
