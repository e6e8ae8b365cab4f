"""The refinement's fast sketch against the full one: pixels and shape distance.

    .venv/bin/python benchmarks/probes/fast_sketch.py [--seeds 3] [--size 128] [--yaws 0 37]

For ``species.sample(name, seed)``, ``seed < --seeds``, and each yaw, three sketches of
``--size`` px: the full path (``build_mesh`` + mitsuba, what datasets and outputs use),
the rasteriser on the same full mesh (``SketchRenderer(..., engine="raster")``: the
renderer's own difference), and the fast path the refinement uses (``sketch_mesh``
without the stems too thin to be drawn, rasterised).  Against the full sketch: % of
pixels that differ at all, % that differ by more than 64 grey levels, the largest
difference, and the search's sketch distance (``refine.objective.metric_distance``,
shape metric).  Per species: the triangles drawn, and the worst value over seeds and
yaws of each column.

``--coarse`` adds the level-of-detail cuts that were tried and left out, each on top of
the fast path: tubes of 4 sides (``bevel_res`` 0) and 2 samples per curve segment
(``res_u`` 2), as ``weberpenn.lod`` makes them for exports.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from refine.objective import metric_distance
from render.sketch import SketchRenderer, sketch_mesh
from weberpenn import build_mesh, grow, species


def compare(a: np.ndarray, b: np.ndarray) -> tuple[float, float, int, float]:
    d = np.abs(a.astype(np.int16) - b.astype(np.int16))
    return (
        100.0 * float((d > 0).mean()),
        100.0 * float((d > 64).mean()),
        int(d.max()),
        metric_distance(a, b, a.shape[0]),
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--yaws", type=float, nargs="+", default=[0.0, 37.0])
    ap.add_argument("--species", nargs="*", default=list(species.SPECIES))
    ap.add_argument("--coarse", action="store_true", help="also coarser tubes (see above)")
    args = ap.parse_args()
    coarse = {"bevel_res 0": {"bevel_res": 0}, "res_u 2": {"res_u": 2}} if args.coarse else {}
    print(
        "| species | full tris | fast tris | raster, full mesh: px differ % / > 64 % / max "
        "/ distance | fast path: px differ % / > 64 % / max / distance |"
        + "".join(f" fast + {c}: tris, px differ % / > 64 % / max / distance |" for c in coarse)
    )
    print("|---|---:|---:|---|---|" + "---|" * len(coarse))
    for name in args.species:
        tris_full, tris_fast, worst_r, worst_f = [], [], [], []
        worst_c: dict[str, list] = {c: [] for c in coarse}
        tris_c: dict[str, list] = {c: [] for c in coarse}
        for seed in range(args.seeds):
            sk = grow(species.sample(name, seed))
            full = build_mesh(sk, species=name)
            fast = sketch_mesh(sk, args.size, name)
            tris_full.append(full.n_faces)
            tris_fast.append(fast.n_faces)
            ref = SketchRenderer(full)
            ras = SketchRenderer(full, engine="raster")
            fas = SketchRenderer(fast, engine="raster")
            cut = fast.skeleton  # the skeleton sketch_mesh meshed: thin stems left out
            rend_c = {}
            for c, change in coarse.items():
                m = build_mesh(dataclasses.replace(cut, **change), species=name)
                tris_c[c].append(m.n_faces)
                rend_c[c] = SketchRenderer(m, engine="raster")
            for yaw in args.yaws:
                a = ref.sketch(yaw, args.size)
                worst_r.append(compare(a, ras.sketch(yaw, args.size)))
                worst_f.append(compare(a, fas.sketch(yaw, args.size)))
                for c, r in rend_c.items():
                    worst_c[c].append(compare(a, r.sketch(yaw, args.size)))

        def cell(rows: list[tuple[float, float, int, float]]) -> str:
            w = np.max(np.asarray(rows, dtype=np.float64), axis=0)
            return f"{w[0]:.2f} / {w[1]:.2f} / {int(w[2])} / {w[3]:.4f}"

        print(
            f"| {name} | {int(np.median(tris_full))} | {int(np.median(tris_fast))} | "
            f"{cell(worst_r)} | {cell(worst_f)} |"
            + "".join(f" {int(np.median(tris_c[c]))}, {cell(worst_c[c])} |" for c in coarse),
            flush=True,
        )


if __name__ == "__main__":
    main()
