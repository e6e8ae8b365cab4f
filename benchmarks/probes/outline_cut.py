"""Does the refinement's fast sketch cost the returned tree's outline anything (issue 48)?

The search draws its candidates from ``render.sketch.sketch_mesh(tree, size)``, which
leaves out stems thinner than half a sample at the comparison size (128 px), though it
draws them at ``refine.objective.draw_side`` (256 px), where the full mesh shows some of
them.  Reads a ``bench_drawings.py --part follow --json RUN`` run (its ``.npz`` beside it)
and, for each drawing, redraws the returned tree at its view with the raster engine from
the mesh cut at 128 px, cut at 256 px and whole (``weberpenn.mesh.build_mesh``), each
framed as the page frames it (``treesketch.steps.as_drawn``), and prints its envelope
overlap with the drawing (``eval.envelope``) beside the run's own (the full mitsuba
sketch).

    .venv/bin/python benchmarks/probes/outline_cut.py RUN.json [--first 0 --count 40]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from eval.envelope import envelope_overlap
from render.sketch import SketchRenderer, sketch_mesh
from treesketch.steps import SKETCH_SIZE, as_drawn
from weberpenn import TreeParams, grow
from weberpenn.mesh import build_mesh

COLUMNS = ("run", "cut 128", "cut 256", "whole")


def overlaps(record: dict, drawing: np.ndarray) -> list[float]:
    """The run's overlap, then the tree redrawn from each mesh (``COLUMNS``)."""
    p = TreeParams(record["params"])
    name, yaw = record["species"], float(record["yaw"]) % 360.0
    skeleton = grow(p)
    meshes = [sketch_mesh(skeleton, 128, name), sketch_mesh(skeleton, 256, name)]
    meshes.append(build_mesh(skeleton, species=name))
    out = [float(record["overlap_after"])]
    for mesh in meshes:
        sketch = SketchRenderer(mesh, engine="raster").sketch(yaw, SKETCH_SIZE)
        out.append(envelope_overlap(drawing, as_drawn(sketch)))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("run", type=Path, help="a follow run's JSON (its .npz beside it)")
    ap.add_argument("--first", type=int, default=0, help="the first record")
    ap.add_argument("--count", type=int, default=40, help="records to redraw")
    args = ap.parse_args(argv)
    records = json.loads(args.run.read_text())["records"][args.first : args.first + args.count]
    sketches = np.load(args.run.with_suffix(".npz"))
    rows = []
    for r in records:
        rows.append(overlaps(r, sketches[f"{r['name']}/input_sketch"]))
        print(f"{r['name']:>24} " + " ".join(f"{v:.3f}" for v in rows[-1]), flush=True)
    a = np.asarray(rows)
    for label, f in (("mean", np.mean), ("median", np.median)):
        print(
            f"{label:>24} "
            + " ".join(f"{v:.4f}" for v in f(a, axis=0))
            + f"  ({', '.join(COLUMNS)})"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
