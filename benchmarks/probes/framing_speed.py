"""Does the drawing reader frame every drawing as the code at another commit does, and how
fast does it frame the refinement's candidate sketches?  Is a candidate framed without the
page's cleaning (``refine.objective.framed_sketch``) the same picture, and its envelope?

Frames (``render.reader.normalise_drawing``, both axes) people's held-out tree drawings
and the paper's ten (``bench_drawings.py --part follow``'s cases) and the refinement's
fast sketches (``refine.start.cheap_sketch``) of ``--seeds`` trees of each species at
four views, and times the candidates' framing as the search does it
(``refine.objective.framed``, median of ``--repeats`` rounds).  The candidates, and the
same trees grown from a custom shape (as the outline step's polish grows them), are
framed by ``framed_sketch`` too: how many pictures are ``framed``'s and how many envelopes
(``refine.start.seen_envelope``'s) are, and each's time.  ``--save`` writes every
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
from refine.objective import framed, framed_sketch
from refine.prepare import prepare_sketch
from refine.shape import prepared_envelope
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
    custom = [
        cheap_sketch(
            species.sample(name, 100 + seed).replace(
                shape=8, customShape=[0.3, 1.0, 0.6, 0.4], baseSize=0.35
            ),
            name,
            128,
            yaw,
        )
        for seed in range(args.seeds)
        for name in species.SPECIES
        for yaw in YAWS
    ]
    compare_candidates(sketches + custom, args.repeats)
    stack = np.stack(pictures)
    if args.save:
        np.savez_compressed(args.save, pictures=stack)
    if args.compare:
        saved = np.load(args.compare)["pictures"]
        if saved.shape != stack.shape:
            raise SystemExit(f"{len(saved)} saved pictures, {len(stack)} now")
        different = [i for i in range(len(stack)) if not np.array_equal(saved[i], stack[i])]
        print(f"{len(different)} of {len(stack)} different from {args.compare}: {different[:10]}")


def compare_candidates(sketches: list[np.ndarray], repeats: int) -> None:
    """``framed_sketch`` against ``framed``: the same pictures, the same envelopes, and
    the median time of ``repeats`` rounds."""

    def envelope(picture: np.ndarray) -> np.ndarray:
        return prepared_envelope(prepare_sketch(picture, 128))

    ways = {
        "framed": lambda s: framed(s, 128),
        "framed_sketch": lambda s: framed_sketch(s, 128),
    }
    same = {name: [0, 0] for name in ways}
    for s in sketches:
        full = framed(s, 128)
        for name, way in ways.items():
            out = way(s)
            same[name][0] += np.array_equal(out, full)
            same[name][1] += np.array_equal(envelope(out), envelope(full))
    for name, way in ways.items():
        rounds = []
        for _ in range(repeats):
            t = time.perf_counter()
            for s in sketches:
                way(s)
            rounds.append((time.perf_counter() - t) / len(sketches))
        print(
            f"{name:>12}: {same[name][0]} of {len(sketches)} pictures and {same[name][1]} "
            f"envelopes framed's; {1000 * float(np.median(rounds)):.2f} ms a candidate"
        )


if __name__ == "__main__":
    main()
