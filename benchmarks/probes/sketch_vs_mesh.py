"""Probe: how well does any distance between two drawings rank the two trees' 3D difference?

    .venv/bin/python benchmarks/probes/sketch_vs_mesh.py [--pairs 300] [--first-seed 1000000] [--workers 2]

Pairs of fresh trees as the shape embedding's training pairs are made
(``refine.embed.build_pairs``: pair ``t`` is species ``t`` in turn, seeds ``first_seed +
2t`` and ``+ 2t + 1``, one random view for both), each drawn once in the renderer's own (SG)
style.  For every pair: the benchmarks' mesh error of the two trees (symmetric max
Hausdorff over the first tree's diagonal, the same frame, as drawn) and several distances
between the two drawings as the refinement prepares them (``ShapeTarget`` at 128 px,
framed by height): the refinement's shape distance (hand-made, and with the shipped
embedding), the 2D Hausdorff max and 95th percentile of the ink and of the filled
silhouettes, the ink's mean chamfer, one minus the silhouettes' IoU.  Prints each one's
Pearson and Spearman correlation with the mesh error, over all pairs and within a species
(mean of the species').  A distance that ranks the 3D difference poorly cannot steer a
search towards the 3D tree, however well it is minimised.
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from scipy import ndimage, stats

from eval.hausdorff import hausdorff
from refine.embed import EMBED_SIZE, load_embedder
from refine.shape import EMBED_WEIGHT, ShapeTarget, embedding_distance, target_shape_distance
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, species

_SAMPLES = 5000


def _pair(args: tuple[int, int]) -> tuple[int, float, np.ndarray, np.ndarray]:
    """Pair ``t``: its species index, its trees' mesh error and their two SG sketches."""
    t, first_seed = args
    kind = t % len(species.SPECIES)
    name = species.SPECIES[kind]
    yaw = float(np.random.default_rng([first_seed, t]).uniform(0, 360))
    meshes = [
        build_mesh(grow(species.sample(name, first_seed + 2 * t + k)), species=name) for k in (0, 1)
    ]
    sketches = [SketchRenderer(m).sketch(yaw, 256) for m in meshes]
    err = hausdorff(meshes[1].combined(), meshes[0].combined(), _SAMPLES).max_norm
    return kind, float(err), sketches[0], sketches[1]


def _mask_distances(a: np.ndarray, b: np.ndarray) -> tuple[float, float, float]:
    """2D Hausdorff max, 95th percentile (each the larger direction) and mean chamfer."""
    if not a.any() or not b.any():
        return float("nan"), float("nan"), float("nan")
    ab = ndimage.distance_transform_edt(~b)[a]
    ba = ndimage.distance_transform_edt(~a)[b]
    p95 = max(np.percentile(ab, 95), np.percentile(ba, 95))
    return float(max(ab.max(), ba.max())), float(p95), float(0.5 * (ab.mean() + ba.mean()))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=300)
    ap.add_argument("--first-seed", type=int, default=1_000_000)
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    embedder = load_embedder()
    jobs = [(t, args.first_seed) for t in range(args.pairs)]
    names = (
        "shape + embedding (the refinement's)",
        "shape (hand-made)",
        "embedding",
        "ink: 2D Hausdorff max",
        "ink: 2D Hausdorff p95",
        "ink: mean chamfer",
        "silhouette: 2D Hausdorff max",
        "silhouette: 2D Hausdorff p95",
        "silhouette: 1 - IoU",
    )
    rows: list[list[float]] = []
    kinds: list[int] = []
    errs: list[float] = []
    with ProcessPoolExecutor(max_workers=max(1, args.workers)) as pool:
        for kind, err, sa, sb in pool.map(_pair, jobs, chunksize=4):
            ta, tb = (ShapeTarget.from_image(s, EMBED_SIZE) for s in (sa, sb))
            ea, eb = embedder.embed(ta), embedder.embed(tb)
            hand = target_shape_distance(ta, tb)
            emb = embedding_distance(ea, eb)
            fa, fb = (t.levels[0].sdf <= 0 for t in (ta, tb))
            ink = _mask_distances(ta.ink > 0.5, tb.ink > 0.5)
            fill = _mask_distances(fa, fb)
            iou = 1.0 - (fa & fb).sum() / max(int((fa | fb).sum()), 1)
            rows.append([hand + EMBED_WEIGHT * emb, hand, emb, *ink, fill[0], fill[1], iou])
            kinds.append(kind)
            errs.append(err)
    x, k, m = np.array(rows), np.array(kinds), np.array(errs)
    print(f"{len(m)} pairs, mesh error mean {m.mean():.3f} (sd {m.std():.3f})")
    print("| distance between the drawings | Pearson | Spearman | Spearman within a species |")
    print("|---|---:|---:|---:|")
    for j, name in enumerate(names):
        ok = np.isfinite(x[:, j])
        within = [
            stats.spearmanr(x[ok & (k == s), j], m[ok & (k == s)])[0]
            for s in np.unique(k)
            if (ok & (k == s)).sum() > 3
        ]
        w = f"{np.mean(within):.2f}" if within else "-"
        print(
            f"| {name} | {np.corrcoef(x[ok, j], m[ok])[0, 1]:.2f} | "
            f"{stats.spearmanr(x[ok, j], m[ok])[0]:.2f} | {w} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
