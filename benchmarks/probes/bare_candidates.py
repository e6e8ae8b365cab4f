"""Check: would leafless candidates fix leafless hand drawings?

The bare (winter) hand drawings of ``examples/hand`` (``winter``, ``ballpoint``) come back
as palms: the network says palm, and so does the refinement's distance, which compares
the drawing with candidates drawn *with* their leaves.  This check draws every species'
start (the estimate's dictionary for that species, ``Estimate.params_for``) two ways, as
the refinement draws its candidates (the SG chain, leaves on) and with no leaves at all
(``leaves=0``: the same branches, the generator's random stream does not depend on the
leaves) in the bare style of ``render.styles.bare`` (strokes down to ``--twig`` px), best
of the views ``--yaws``, and prints the refinement's distance (``refine.shape`` plus the
shipped embedding) and the hand-made shape distance alone for each.  Leafy drawings are
listed as the reference in the same run: there the leafy candidates must stay ahead.

    PYTHONPATH=$PWD .venv/bin/python benchmarks/probes/bare_candidates.py [--drawings winter,ballpoint,cherry,weeping]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from refine.objective import framed, make_target
from refine.search import RefineSettings
from render.sketch import SketchRenderer, sketch_mesh
from render.styles import Silhouettes, bare
from treesketch.pipeline import Pipeline, load_sketch, prepare_input
from weberpenn import grow, species

ROOT = Path(__file__).resolve().parents[2]

SIZE = 128  # the refinement's own size (RefineSettings.size)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--drawings", default="winter,ballpoint,cherry,weeping")
    ap.add_argument("--yaws", default="0,45,90,135,180")
    ap.add_argument("--twig", type=float, default=1.2, help="bare style: thinnest branch drawn")
    args = ap.parse_args(argv)
    yaws = [float(y) for y in args.yaws.split(",")]
    embedder = RefineSettings().load_embedder()
    pipe = Pipeline("tsn", RefineSettings(refine=False))
    print(
        "| drawing | network | species | leaves: distance (shape alone) | bare: distance (shape alone) |"
    )
    print("|---|---|---|---:|---:|")
    for name in args.drawings.split(","):
        prepared = prepare_input(load_sketch(ROOT / "examples" / "hand" / f"{name}.png"))
        est = pipe.estimator.estimate(prepared)  # what the pipeline's network sees
        img = framed(prepared, SIZE)
        with_emb = make_target(img, SIZE, "shape", embedder)
        alone = make_target(img, SIZE, "shape", None)
        for sp in species.SPECIES:
            cells = []
            for leafless in (False, True):
                p = est.params_for(sp)
                p = p.replace(leaves=0) if leafless else p
                r = SketchRenderer(sketch_mesh(grow(p), SIZE, sp), engine="raster")
                best = (np.inf, np.inf)
                for y in yaws:
                    if leafless:
                        sil = Silhouettes.from_parts(r.parts(y, SIZE))
                        cand = bare(sil, np.random.default_rng(0), SIZE, twig_px=(args.twig,) * 2)
                    else:
                        cand = r.sketch(y, SIZE)
                    f = framed(cand, SIZE)
                    d = with_emb.distance(make_target(f, SIZE, "shape", embedder))
                    if d < best[0]:
                        best = (d, alone.distance(make_target(f, SIZE, "shape", None)))
                cells.append(f"{best[0]:.2f} ({best[1]:.2f})")
            print(f"| {name} | {est.species} | {sp} | {cells[0]} | {cells[1]} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
