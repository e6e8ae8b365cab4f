"""Does the drawing reader frame every drawing as the code at another commit does, and how
fast does it frame the refinement's candidate sketches?

Frames (``render.reader.normalise_drawing``, both axes) people's held-out tree drawings
and the paper's ten (``bench_drawings.py --part follow``'s cases) and the refinement's
fast sketches (``refine.start.cheap_sketch``) of ``--seeds`` trees of each species at
four views, and times the candidates' framing as the search does it
(``refine.objective.framed``, median of ``--repeats`` rounds).  ``--save`` writes every
framed picture; ``--compare`` checks them against a saved file, picture for picture.
Run the other commit's code from its worktree with this file:

    git worktree add /tmp/before 4eaeece
    PYTHONPATH=/tmp/before .venv/bin/python benchmarks/probes/framing_speed.py --save /tmp/a.npz
    .venv/bin/python benchmarks/probes/framing_speed.py --compare /tmp/a.npz
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.bench_drawings import follow_cases
from refine.objective import framed
from refine.start import cheap_sketch
from render.reader import SketchError, normalise_drawing
from weberpenn import species

YAWS = (0.0, 37.0, 123.0, 275.5)


def drawings() -> list[np.ndarray]:
    out = []
    for only in ("people", "paper"):
        ns = argparse.Namespace(only=only, people=143, people_from=0, pairs=0, hand=False)
        out += [np.asarray(img) for _, img in follow_cases(ns)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--save")
    ap.add_argument("--compare")
    args = ap.parse_args()
    sketches = [
        cheap_sketch(species.sample(name, 100 + seed), name, 128, yaw)
        for seed in range(args.seeds)
        for name in species.SPECIES
        for yaw in YAWS
    ]
    pictures = []
    for img in drawings() + sketches:
        for over_crown in (False, True):
            try:
                pictures.append(normalise_drawing(img, 256, over_crown=over_crown))
            except SketchError:  # refused: an empty picture stands for it
                pictures.append(np.zeros((256, 256), np.uint8))
    framed(sketches[0], 128)  # compilation or cache load left out
    rounds = []
    for _ in range(args.repeats):
        t = time.perf_counter()
        for s in sketches:
            framed(s, 128)
        rounds.append((time.perf_counter() - t) / len(sketches))
    print(
        f"{len(pictures)} framed pictures; a candidate framed in "
        f"{1000 * float(np.median(rounds)):.2f} ms (median of {args.repeats} rounds of "
        f"{len(sketches)})"
    )
    stack = np.stack(pictures)
    if args.save:
        np.savez_compressed(args.save, pictures=stack)
    if args.compare:
        saved = np.load(args.compare)["pictures"]
        if saved.shape != stack.shape:
            raise SystemExit(f"{len(saved)} saved pictures, {len(stack)} now")
        different = [i for i in range(len(stack)) if not np.array_equal(saved[i], stack[i])]
        print(f"{len(different)} of {len(stack)} different from {args.compare}: {different[:10]}")


if __name__ == "__main__":
    main()
