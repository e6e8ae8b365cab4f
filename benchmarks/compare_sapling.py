"""Compare our skeletons with Blender Sapling's on the 15 TreeSketchNet reference files.

Reads ``../shared/reference/sapling_reference_stats.json`` (Sapling 0.3.4 in Blender 3.4,
seeds 0, 1, 2) and grows each reference dictionary with seeds 0, 1, 2.  Prints, per file,
the mean bounding-box size of branches and of branches+leaves (ours / Sapling's ratio),
stems per level (ours vs Sapling's) and leaf count, then per-species summaries.

Run: ``.venv/bin/python benchmarks/compare_sapling.py [--ref DIR]``
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from weberpenn import load_params
from weberpenn.grow import grow

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_REF = ROOT.parent / "shared" / "reference"
LEAF_FACES = {"hex": 2, "rect": 1}


def _leaf_corners(sk) -> np.ndarray:
    if sk.n_leaves == 0:
        return np.zeros((0, 3))
    if sk.leaf_shape == "hex":
        t = np.array(
            [
                [0, 0, 0],
                [0.5, 1 / 3, 0],
                [0.5, 2 / 3, 0],
                [0, 1, 0],
                [-0.5, 2 / 3, 0],
                [-0.5, 1 / 3, 0],
            ]
        )
    else:
        t = np.array([[-0.5, 0, 0], [0.5, 0, 0], [0.5, 1, 0], [-0.5, 1, 0]])
    v = np.einsum("lij,vj->lvi", sk.leaf_matrices, t) + sk.leaf_positions[:, None]
    return v.reshape(-1, 3)


def _sizes(sk) -> tuple[np.ndarray, np.ndarray]:
    """Branch bbox size (control points padded by radius) and leaf bbox size."""
    r = sk.radii[:, None]
    lo = (sk.points - r).min(axis=0)
    hi = (sk.points + r).max(axis=0)
    leaves = _leaf_corners(sk)
    leaf = leaves.max(axis=0) - leaves.min(axis=0) if len(leaves) else np.zeros(3)
    return hi - lo, leaf


def _ints(a: np.ndarray) -> str:
    return "[" + " ".join(f"{x:.0f}" for x in a) + "]"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", type=Path, default=DEFAULT_REF, help="the shared reference folder")
    args = ap.parse_args(argv)
    stats_path = args.ref / "sapling_reference_stats.json"
    if not stats_path.is_file():
        print(f"no Sapling statistics at {stats_path}", file=sys.stderr)
        return 1
    stats = json.loads(stats_path.read_text())["trees"]
    rows = []
    print(
        f"{'file':<22} {'branch bbox ours':>20} {'ratio':>17} {'leaf bbox ratio':>17}  "
        f"{'stems/level ours':<26} {'sapling':<26} {'leaves':>13} {'ms':>5}"
    )
    for name in sorted(stats, key=lambda s: int(s.split("_")[0])):
        p = load_params(args.ref / "treesketchnet_test_params" / f"{name}.json")
        sap = stats[name]
        ours_b, ours_l, spl, nleaf, times = [], [], [], [], []
        for t in sap:
            t0 = time.perf_counter()
            sk = grow(p, seed=int(t["seed"]))
            times.append(time.perf_counter() - t0)
            b, lf = _sizes(sk)
            ours_b.append(b)
            ours_l.append(lf)
            spl.append(sk.stems_per_level())
            nleaf.append(sk.n_leaves)
        ob, ol = np.mean(ours_b, axis=0), np.mean(ours_l, axis=0)
        sb = np.mean([t["branch_bbox_size"] for t in sap], axis=0)
        sl = np.mean([t["leaf_bbox_size"] for t in sap], axis=0)
        ospl = np.mean(spl, axis=0)
        sspl = np.mean([t["splines_per_level"] for t in sap], axis=0)
        sleaf = np.mean([t["leaf_faces"] for t in sap]) / LEAF_FACES[p["leafShape"]]
        rb, rl = ob / sb, ol / sl
        rows.append((name, rb, rl, ospl / sspl, np.mean(nleaf) / sleaf, np.median(times)))
        print(
            f"{name:<22} {np.array2string(ob, precision=2):>20} {np.array2string(rb, precision=2):>17} "
            f"{np.array2string(rl, precision=2):>17}  {_ints(ospl):<26} "
            f"{_ints(sspl):<26} {np.mean(nleaf):6.0f}/{sleaf:<6.0f} "
            f"{1000 * np.median(times):5.0f}"
        )
    print("\nper species (mean ratio ours/Sapling over files and seeds)")
    for sp in ("acer_2", "palm_3", "pine", "cherry_blossom_3", "bonsai"):
        sel = [r for r in rows if r[0].endswith(sp)]
        rb = np.mean([r[1] for r in sel], axis=0)
        rl = np.mean([r[2] for r in sel], axis=0)
        rs = np.mean([r[3] for r in sel], axis=0)
        rv = np.mean([r[4] for r in sel])
        print(
            f"  {sp:<18} branch bbox {np.array2string(rb, precision=2)}  leaf bbox "
            f"{np.array2string(rl, precision=2)}  stems/level {np.array2string(rs, precision=2)}  "
            f"leaves {rv:.2f}"
        )
    worst = max(float(np.max(np.abs(np.log(r[1])))) for r in rows)
    print(f"\nworst branch-bbox axis ratio off by a factor {np.exp(worst):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
