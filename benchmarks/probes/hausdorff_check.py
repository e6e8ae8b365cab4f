"""eval.hausdorff (libigl AABB, exact) against MeshLab's Metro filter, and a far-apart pair.

    .venv/bin/python benchmarks/probes/hausdorff_check.py [--samples 20000] [--no-metro]

Near pairs: each species' ``species.sample(name, 1)`` grown with seeds 0 and 1 (the
seed floor), measured by ``eval.hausdorff.tree_hausdorff`` and by the Metro filter as
``eval.hausdorff`` called it before (``get_hausdorff_distance``, vertices and faces
sampled, ``samplenum`` = ``--samples``, ``maxdist`` = the diagonal of both meshes: no
sample dropped).  Metro samples at most ``samplenum`` of a mesh's vertices; ours takes
every vertex, so on trees with more vertices our max can only be larger or equal.
Far pair: a cherry against a maple (``species.sample(.., 1)``), combined meshes, ours
only (Metro took more than 15 minutes on such a pair).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from eval.hausdorff import bbox_diagonal, hausdorff, tree_hausdorff
from eval.metro import metro
from weberpenn import build_mesh, grow, species


def metro_norm(a, b, samples: int, diag: float) -> tuple[float, float]:
    """(max, mean) normalised, both directions, as MeshLab's Metro filter measures."""
    reach = bbox_diagonal(np.vstack([a.vertices, b.vertices])) * 1.01 + 1e-9
    r = metro(a, b, samples, faces=True, reach=reach)
    return max(x["max"] for x in r) / diag, 0.5 * (r[0]["mean"] + r[1]["mean"]) / diag


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=20_000)
    ap.add_argument("--no-metro", action="store_true")
    args = ap.parse_args()
    print(
        "| species | part | vertices | max (ours) | max (Metro) | mean (ours) | mean (Metro) "
        "| paper pred->gt | paper gt->pred | s ours (3 parts) | s Metro (this part) |"
    )
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in species.SPECIES:
        p = species.sample(name, 1)
        a, b = build_mesh(grow(p, seed=0)), build_mesh(grow(p, seed=1))
        t0 = time.perf_counter()
        ours = tree_hausdorff(a, b, args.samples)
        t_ours = time.perf_counter() - t0
        diag = bbox_diagonal(b.bounds())
        for part in ("branches", "leaves", "combined"):
            ma, mb = (getattr(m, part) if part != "combined" else m.combined() for m in (a, b))
            d = ours[part]
            if args.no_metro:
                mx, mn, t_m = float("nan"), float("nan"), float("nan")
            else:
                t1 = time.perf_counter()
                mx, mn = metro_norm(ma, mb, args.samples, diag)
                t_m = time.perf_counter() - t1
            nv = len(ma.vertices) + len(mb.vertices)
            print(
                f"| {name} | {part} | {nv} | {d.max_norm:.4f} | {mx:.4f} | {d.mean_norm:.5f} | "
                f"{mn:.5f} | {d.pred_to_gt_vertex:.4f} | {d.gt_to_pred_vertex:.4f} | "
                f"{t_ours if part == 'branches' else 0:.1f} | {t_m:.1f} |",
                flush=True,
            )
    cherry = build_mesh(grow(species.sample("cherry", 1))).combined()
    maple = build_mesh(grow(species.sample("maple", 1))).combined()
    t0 = time.perf_counter()
    d = hausdorff(cherry, maple, args.samples)
    print(
        f"\nfar pair (cherry estimate vs maple ground truth, combined): max {d.max_norm:.4f}, "
        f"paper wording {d.pred_to_gt_vertex:.4f} / {d.gt_to_pred_vertex:.4f}, "
        f"{time.perf_counter() - t0:.1f} s"
    )


if __name__ == "__main__":
    main()
