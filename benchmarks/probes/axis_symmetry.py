"""On which axis does a person's drawn tree stand (issue 48)?

Each held-out people's tree drawing of ``--source`` (``eval.people``) normalised as the
network reads it (``render.reader.normalise_drawing``: the trunk's axis on the centre
line) and as outlines are compared (``over_crown``: ``render.reader.crown_axis``); for
each, the overlap of the drawing's envelope (``eval.envelope``) with its mirror image
about the frame's centre line: how near a tree whose crown stands round its trunk can
come to it in that frame.  Prints the medians and means, and how many drawings the
network's frame sets off their crown's axis (``crown_axis`` of the framed drawing) by
more than 0.15 and 0.25 of their width: a trunk's axis found on one of its feet.

    .venv/bin/python benchmarks/probes/axis_symmetry.py [--people 80] [--source quickdraw28]
"""

from __future__ import annotations

import argparse

import numpy as np

from eval.envelope import envelope
from eval.people import SOURCES, people_drawings
from refine.envelope import mask_iou
from render.reader import crown_axis, ink_mask, normalise_drawing
from treesketch.steps import load_sketch

SIDE = 256


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=80)
    ap.add_argument("--source", choices=SOURCES, default="strokes")
    args = ap.parse_args()
    held = people_drawings("held", (args.source,), ("tree",))[: args.people]
    pages = [load_sketch(d.image()) for d in held]
    for over_crown, name in ((False, "the trunk's axis"), (True, "over the crown")):
        mirror, off = [], []
        for page in pages:
            framed = normalise_drawing(page, SIDE, over_crown=over_crown)
            e = envelope(framed)
            mirror.append(mask_iou(e, e[:, ::-1]))
            ink = ink_mask(framed)
            cols = np.flatnonzero(ink.any(axis=0))
            off.append(abs(crown_axis(ink) - SIDE / 2) / (cols[-1] + 1 - cols[0]))
        off_ = np.array(off)
        print(
            f"{name:>16}: mirror overlap median {np.median(mirror):.3f}, "
            f"mean {np.mean(mirror):.3f}; off the crown's axis by over 0.15 of the width "
            f"{int(np.sum(off_ > 0.15))}, over 0.25 {int(np.sum(off_ > 0.25))} "
            f"({len(mirror)} drawings)"
        )


if __name__ == "__main__":
    main()
