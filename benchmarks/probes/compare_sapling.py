"""Compare our skeletons with Blender Sapling's on the 15 TreeSketchNet reference files.

Reads ``../shared/reference/sapling_reference_stats.json`` (Sapling 0.3.4 in Blender 3.4,
seeds 0, 1, 2) and grows each reference dictionary with seeds 0, 1, 2.  Prints, per file,
the mean bounding-box size of branches and of branches+leaves (ours / Sapling's ratio),
stems per level (ours vs Sapling's) and leaf count, then per-species summaries.

Run: ``.venv/bin/python benchmarks/probes/compare_sapling.py [--ref DIR]``
"""

from __future__ import annotations

import argparse
import json
import random
import sys
import time
from pathlib import Path

import numpy as np

from weberpenn import load_params
from weberpenn.grow import grow

ROOT = Path(__file__).resolve().parents[2]
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


def replay_trunk_splines(p, seed: int) -> int:
    """Number of trunk splines Sapling makes for ``seed``, replaying its Python ``random``
    call sequence for the trunk (the dictionaries as mapped in the statistics file:
    scaleV, scaleV0, lengthV and rotateV[0] are zero but still consume draws).  This checks
    the split rule :func:`weberpenn.grow.grow` implements, draw for draw."""
    rnd = random.Random(seed)
    res, sh = p["curveRes"][0], p["splitHeight"]
    rnd.uniform(0.0, 0.0)  # scaleVal
    rnd.uniform(1.0, 1.0)  # trunk start radius
    rnd.uniform(1.0, 1.0)  # lengthV of the first stem
    splines = [{"last": 0, "roll": False}]
    for k in range(res):
        kp = k / (res - 1) if res > 1 else 1.0
        sv = max(((2 * p["splitBias"]) * (kp - 0.5) + 1) * p["segSplits"][0], 0.0)
        for st in list(splines):
            sval = sv * 1.33 if st["last"] == 0 else sv * sv
            if k == 0 or (k < (res - 1) * sh and k != 1):
                ns = 0
            elif k == 1:
                ns = p["baseSplits"]
            elif k == int((res - 1) * sh) + 1 and sval > 0:
                ns = 1
            else:
                ns = 1 if rnd.random() < sval else 0
            rnd.uniform(0, 1)  # curve variation about X
            rnd.uniform(0, 1)  # curve variation about Y
            if ns > 0:
                rnd.choice([-1, 1])
                rnd.uniform(-1, 1)  # split angle
                rnd.choice([-1, 1])
                rnd.uniform(-1, 1)  # spread angle
                if not st["roll"]:
                    rnd.uniform(0, 360)
                    st["roll"] = True
                rnd.uniform(0.0, 0.0)  # rotateV[0]
                for _ in range(ns):
                    rnd.uniform(1.0, 1.0)  # clone lengthV
                    splines.append({"last": 1, "roll": True})
            st["last"] = 1 if ns > 0 else 0
    return len(splines)


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
    print("\ntrunk splines: Sapling's statistics vs. a replay of its random draws with our rule")
    agree = 0
    for name in sorted(stats, key=lambda s: int(s.split("_")[0])):
        p = load_params(args.ref / "treesketchnet_test_params" / f"{name}.json")
        sap = [t["splines_per_level"][0] for t in stats[name]]
        rep = [replay_trunk_splines(p, int(t["seed"])) for t in stats[name]]
        agree += sap == rep
        print(f"  {name:<22} sapling {sap}  replay {rep}")
    print(f"  {agree}/{len(stats)} files agree exactly")
    worst = max(float(np.max(np.abs(np.log(r[1])))) for r in rows)
    print(f"\nworst branch-bbox axis ratio off by a factor {np.exp(worst):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
