"""Which drawings would the network see framed otherwise if a reader constant changed?

Frames each drawing as the pipeline prepares it for the network
(``treesketch.steps.prepare_input``: ``render.reader.normalise_drawing``, the trunk's axis
on the centre line) with the code as it is and again with module constants changed by
``--set`` (``render.reader.SINGLE_STROKES=0``: the trunk's foot read before thick pens
were), and prints per set how many drawings come out another picture (or are refused by
one only), with their indices.  Sets: people's held-out trees of each folder and, with
``--others N``, up to N held-out drawings of each other kind; the paper's ten; hand-style
tree doodles (``--doodles`` a species); ``examples/hand``; the held-out-style drawings of
the mesh-error figure; the code-made doodle pairs.

    .venv/bin/python benchmarks/probes/reframed.py --set render.reader.SINGLE_STROKES=0 \\
        [--others 60] [--doodles 40]
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]


def drawing_sets(others: int, doodles: int) -> dict[str, list[Any]]:
    import bench_drawings as bd

    from eval import doodles as dd
    from eval.people import SOURCES, people_drawings

    sets: dict[str, list[Any]] = {}
    for source in SOURCES:
        sets[f"people {source}, trees"] = [
            d.image() for d in people_drawings("held", (source,), ("tree",))
        ]
        if others:
            held = people_drawings("held", (source,), None, per_kind=others)
            sets[f"people {source}, other things"] = [d.image() for d in held if not d.is_tree]
    sets["the paper's ten"] = [img for _, img in bd.paper_drawings()]
    sets["hand-style tree doodles"] = [
        dd.tree_doodle(s, k) for s in dd.TREE_SPECIES for k in range(doodles)
    ]
    sets["examples/hand"] = sorted((ROOT / "examples" / "hand").glob("*.png"))
    held = bd.tree_drawings(950, 1) + bd.tree_drawings(952, 3)
    sets["held-out style (44)"] = [d["image"] for d in held]
    both = bd.tree_drawings(950, 3, side=True, style="doodle")
    sets["doodle pairs, both views"] = [d["image"] for d in both] + [d["side"] for d in both]
    return sets


def changed(assignments: list[str]) -> Callable[[], None]:
    """Sets ``module.NAME=value`` for each assignment; returns what puts them back."""
    was = []
    for a in assignments:
        name, value = a.split("=", 1)
        module, attr = name.rsplit(".", 1)
        mod = importlib.import_module(module)
        old = getattr(mod, attr)
        was.append((mod, attr, old))
        setattr(mod, attr, type(old)(value))

    def restore() -> None:
        for mod, attr, old in was:
            setattr(mod, attr, old)

    return restore


def main() -> None:
    from render.reader import SketchError
    from treesketch.steps import load_sketch, prepare_input

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", nargs="+", required=True, metavar="MODULE.NAME=VALUE")
    ap.add_argument("--others", type=int, default=0, help="other kinds' drawings per kind")
    ap.add_argument("--doodles", type=int, default=40, help="hand-style doodles per species")
    args = ap.parse_args()

    def framed(page: np.ndarray) -> np.ndarray | None:
        try:
            return prepare_input(page)
        except SketchError:
            return None

    for name, imgs in drawing_sets(args.others, args.doodles).items():
        moved = []
        for i, img in enumerate(imgs):
            page = load_sketch(img)
            now = framed(page)
            restore = changed(args.set)
            try:
                then = framed(page)
            finally:
                restore()
            if (now is None) != (then is None) or (
                now is not None and not np.array_equal(now, then)
            ):
                moved.append(i)
        print(f"{name}: {len(imgs)} drawings, {len(moved)} framed otherwise {moved}", flush=True)


if __name__ == "__main__":
    main()
