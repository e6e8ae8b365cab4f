"""On which axis does a person's drawn tree stand (issue 48)?

Each held-out people's tree drawing (``eval.people``, strokes) normalised as the network
reads it (``render.reader.normalise_drawing``: the trunk's axis on the centre line) and
as outlines are compared (``over_crown``: ``render.reader.crown_axis``); for each, the
overlap of the drawing's envelope (``eval.envelope``) with its mirror image about the
frame's centre line: how near a tree whose crown stands round its trunk can come to it
in that frame.  Prints the medians and means.

    .venv/bin/python benchmarks/probes/axis_symmetry.py [--people 80]
"""

from __future__ import annotations

import argparse

import numpy as np

from eval.envelope import envelope
from eval.people import people_drawings
from refine.envelope import mask_iou
from render.reader import normalise_drawing


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--people", type=int, default=80)
    args = ap.parse_args()
    held = people_drawings("held", ("strokes",), ("tree",))[: args.people]
    for over_crown, name in ((False, "the trunk's axis"), (True, "over the crown")):
        mirror = []
        for d in held:
            e = envelope(normalise_drawing(np.asarray(d.image()), 256, over_crown=over_crown))
            mirror.append(mask_iou(e, e[:, ::-1]))
        print(
            f"{name:>16}: mirror overlap median {np.median(mirror):.3f}, "
            f"mean {np.mean(mirror):.3f} ({len(mirror)} drawings)"
        )


if __name__ == "__main__":
    main()
