"""Which drawings would the network see framed otherwise if a reader constant changed?

Frames each drawing as the pipeline prepares it for the network
(``treesketch.steps.prepare_input``: ``render.reader.normalise_drawing``, the trunk's axis
on the centre line) with the code as it is and again with module constants changed by
``--set`` (``render.reader.SINGLE_STROKES=0``: the trunk's foot read before thick pens
were), and prints per set how many drawings come out another picture (or are refused by
one only), with their indices.  Sets: ``inside_route.py``'s (people's held-out trees of
each folder, the paper's ten, the code-made doodle pairs' fronts and sides, the
held-out-style drawings of the mesh-error figure); with ``--others N`` up to N held-out
drawings of each other kind; hand-style tree doodles (``--doodles`` a species);
``examples/hand``; with ``--all-people`` instead every drawing of people's three folders
(both parts, every kind).

    .venv/bin/python benchmarks/probes/reframed.py --set render.reader.SINGLE_STROKES=0 \\
        [--others 60] [--doodles 40] [--all-people | --fit-trees] [--pictures DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def drawing_sets(others: int, doodles: int) -> dict[str, list[Any]]:
    """``inside_route.py``'s sets (people's held-out trees, the paper's ten, the doodle
    pairs, the held-out-style drawings), people's other things, hand-style tree doodles
    and ``examples/hand``."""
    from inside_route import drawing_sets as route_sets

    from eval import doodles as dd
    from eval.people import SOURCES, people_drawings

    sets = route_sets(10**6, 3, published=False)
    if others:
        for source in SOURCES:
            held = people_drawings("held", (source,), None, per_kind=others)
            sets[f"people {source}, other things"] = [d.image() for d in held if not d.is_tree]
    sets["hand-style tree doodles"] = [
        dd.tree_doodle(s, k) for s in dd.TREE_SPECIES for k in range(doodles)
    ]
    sets["examples/hand"] = sorted((ROOT / "examples" / "hand").glob("*.png"))
    return sets


def _picture(path: Path, page: np.ndarray, then: np.ndarray | None, now: np.ndarray | None) -> None:
    """The page (fitted into the network's size) beside its two framings (grey: refused)."""
    from PIL import Image

    side = 256
    row = Image.new("L", (3 * side + 8, side), 128)
    im = Image.fromarray(page)
    im.thumbnail((side, side))
    row.paste(im, (0, 0))
    for k, pic in enumerate((then, now), start=1):
        if pic is not None:
            row.paste(Image.fromarray(pic).resize((side, side)), (k * (side + 4), 0))
    path.parent.mkdir(parents=True, exist_ok=True)
    row.save(path)


def main() -> None:
    from outline_replay import set_constants

    from render.reader import SketchError
    from treesketch.steps import load_sketch, prepare_input

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", nargs="+", required=True, metavar="MODULE.NAME=VALUE")
    ap.add_argument("--others", type=int, default=0, help="other kinds' drawings per kind")
    ap.add_argument("--doodles", type=int, default=40, help="hand-style doodles per species")
    ap.add_argument(
        "--all-people",
        action="store_true",
        help="instead: every drawing of each of people's folders (both parts, every kind)",
    )
    ap.add_argument(
        "--fit-trees",
        action="store_true",
        help="instead: the tree drawings of people's fit part (by other people than the "
        "held-out figures' own, so a rule built on those is checked on drawings it never saw)",
    )
    ap.add_argument(
        "--pictures",
        type=Path,
        default=None,
        help="write each drawing framed otherwise here: the page, framed with --set and as is",
    )
    args = ap.parse_args()
    if args.fit_trees:
        from eval.people import SOURCES, people_drawings

        sets = {
            f"people {source}, fit part's trees": [
                d.image() for d in people_drawings("fit", (source,), ("tree",))
            ]
            for source in SOURCES
        }
    elif args.all_people:
        from eval.people import SOURCES, people_drawings

        sets = {
            f"people {source}, every drawing": [d.image() for d in people_drawings(None, (source,))]
            for source in SOURCES
        }
    else:
        sets = drawing_sets(args.others, args.doodles)

    def framed(page: np.ndarray) -> np.ndarray | None:
        try:
            return prepare_input(page)
        except SketchError:
            return None

    for name, imgs in sets.items():
        moved = []
        for i, img in enumerate(imgs):
            try:
                page = load_sketch(img)
            except SketchError:  # refused before any reading (a strip): the same either way
                continue
            now = framed(page)
            restore = set_constants(args.set)
            try:
                then = framed(page)
            finally:
                restore()
            if (now is None) != (then is None) or (
                now is not None and not np.array_equal(now, then)
            ):
                moved.append(i)
                if args.pictures is not None:
                    _picture(args.pictures / f"{name}-{i}.png", page, then, now)
        print(f"{name}: {len(imgs)} drawings, {len(moved)} framed otherwise {moved}", flush=True)


if __name__ == "__main__":
    main()
