"""Compare our trees with Blender Sapling's.

Default: the 15 TreeSketchNet reference files.  Reads
``../shared/reference/sapling_reference_stats.json`` (Sapling 0.3.4 in Blender 3.4, seeds
0, 1, 2) and grows each reference dictionary with seeds 0, 1, 2.  Prints, per file, the
mean bounding-box size of branches and of branches+leaves (ours / Sapling's ratio), stems
per level (ours vs Sapling's) and leaf count, then per-species summaries.

``--species``: every species' base dictionary (``species.base(name)``, seed 0), our
``build_mesh(grow(...))`` against Sapling's tree from the same dictionary as recorded in
``benchmarks/lib/sapling_species_stats.json`` (``benchmarks/lib/sapling_run.py``): whole-tree
bounding-box width, depth and height (must agree within 10 %), branch and leaf triangles
(Sapling's quads count as two), and, for the species people draw, the untouched Sapling
preset they start from (seeds 0, 1, 2) with the values the species sets (its source).
``--blender BIN`` first re-records that file with Blender's Sapling (about 1.5 minutes on
a 2-core machine); ``--markdown`` prints the table as Markdown.

Run: ``.venv/bin/python benchmarks/compare_sapling.py [--ref DIR]``
     ``.venv/bin/python benchmarks/compare_sapling.py --species [--blender blender] [--markdown]``
"""

from __future__ import annotations

import argparse
import json
import random
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.lib.sapling_run import (
    SPECIES_STATS,
    SaplingError,
    record,
    recorded,
    sizes,
)
from weberpenn import build_mesh, load_params, species
from weberpenn.grow import grow

ROOT = Path(__file__).resolve().parents[1]

DEFAULT_REF = ROOT.parent / "shared" / "reference"
LEAF_FACES = {"hex": 2, "rect": 1}
#: Largest relative difference of a whole-tree size (width, depth, height) from Sapling's.
TOLERANCE = 0.10


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


def _box_size(vertices: np.ndarray) -> list[float]:
    v = np.asarray(vertices)
    return (v.max(axis=0) - v.min(axis=0)).tolist() if len(v) else [0.0, 0.0, 0.0]


def ours(name: str) -> dict:
    """Sizes and triangles of our tree from the species' base dictionary."""
    tm = build_mesh(grow(species.base(name)), species=name)
    lo, hi = tm.bounds()
    return {
        "tree": (hi - lo).tolist(),
        "branch": _box_size(tm.branches.vertices),
        "branch_tris": len(tm.branches.faces),
        "leaf_tris": len(tm.leaves.faces),
    }


def compare_species(
    data: dict, ours_of=ours, names: tuple[str, ...] = species.SPECIES
) -> list[dict]:
    """One row per species: our sizes and triangles against Sapling's record (``data`` as
    :func:`benchmarks.lib.sapling_run.recorded` returns it), the worst size ratio's distance
    from 1, and the untouched preset's mean size where the species starts from one."""
    rows = []
    for name in names:
        entry = data["trees"][name]
        sap = entry["base"]
        o = ours_of(name)
        s_tree = sizes(sap)["tree"]
        ratio = [a / b if b > 0 else float("inf") for a, b in zip(o["tree"], s_tree, strict=True)]
        preset = entry.get("preset_rows") or []
        rows.append(
            {
                "species": name,
                "display": entry.get("display", name),
                "ours": o["tree"],
                "sapling": s_tree,
                "ratio": ratio,
                "worst": max(abs(r - 1.0) for r in ratio),
                "ours_tris": (o["branch_tris"], o["leaf_tris"]),
                "sapling_tris": (2 * sap["branch_faces"], 2 * sap["leaf_faces"]),
                "preset": entry.get("preset"),
                "preset_size": np.mean([sizes(r)["tree"] for r in preset], axis=0).tolist()
                if preset
                else None,
                "preset_tris": (
                    float(np.mean([2 * r["branch_faces"] for r in preset])),
                    float(np.mean([2 * r["leaf_faces"] for r in preset])),
                )
                if preset
                else None,
                "source": species.source(name),
            }
        )
    return rows


def dims(v: list[float] | None, unit: str = "") -> str:
    """``w x d x h`` with one decimal, two for a tree under 3 m (a bonsai is a metre tall:
    one decimal would hide a 16 % difference)."""
    if v is None:
        return "-"
    fmt = ".2f" if max(v) < 3.0 else ".1f"
    return " x ".join(f"{x:{fmt}}" for x in v) + unit


def species_markdown(rows: list[dict]) -> str:
    lines = [
        "| species | ours w x d x h | Sapling w x d x h (same dictionary) | ours / Sapling "
        "| branch tris ours / Sapling | leaf tris ours / Sapling "
        "| untouched Sapling preset, seeds 0-2: w x d x h, branch / leaf tris "
        "| source (values the species sets) |",
        "|---|---|---|---|---:|---:|---|---|",
    ]
    for r in rows:
        ok = "" if r["worst"] <= TOLERANCE else " **(over 10 %)**"
        pre = (
            "-"
            if r["preset"] is None
            else f"`{r['preset']}`: {dims(r['preset_size'])}, "
            f"{r['preset_tris'][0] / 1000:.0f}k / {r['preset_tris'][1] / 1000:.0f}k"
        )
        lines.append(
            f"| {r['display']} | {dims(r['ours'])} | {dims(r['sapling'])} "
            f"| {' '.join(f'{x:.2f}' for x in r['ratio'])}{ok} "
            f"| {r['ours_tris'][0] / 1000:.0f}k / {r['sapling_tris'][0] / 1000:.0f}k "
            f"| {r['ours_tris'][1] / 1000:.1f}k / {r['sapling_tris'][1] / 1000:.1f}k | {pre} "
            f"| {r['source']} |"
        )
    worst = max(rows, key=lambda r: r["worst"])
    lines += [
        "",
        f"Largest size difference: {worst['display']} {100 * worst['worst']:.1f} % "
        f"(tolerance {100 * TOLERANCE:.0f} %); species over it: "
        + (", ".join(r["display"] for r in rows if r["worst"] > TOLERANCE) or "none")
        + ".",
    ]
    return "\n".join(lines)


def species_main(args: argparse.Namespace) -> int:
    try:
        if args.blender:
            commit = subprocess.run(
                ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                capture_output=True,
                text=True,
            ).stdout.strip()
            record(
                args.blender,
                SPECIES_STATS,
                command=f"benchmarks/compare_sapling.py --species --blender {args.blender}",
                commit=commit,
            )
            print(f"recorded {SPECIES_STATS}", file=sys.stderr)
        data = recorded(SPECIES_STATS)
    except SaplingError as exc:
        print(f"compare_sapling: {exc}", file=sys.stderr)
        return 1
    rows = compare_species(data)
    if args.markdown:
        print(species_markdown(rows))
        return 0
    print(
        f"{'species':<8} {'ours w d h':>20} {'Sapling w d h':>20} {'ratio':>17}  tris ours/Sapling"
    )
    for r in rows:
        flag = "" if r["worst"] <= TOLERANCE else "  OVER 10 %"
        print(
            f"{r['species']:<8} {dims(r['ours']):>20} {dims(r['sapling']):>20} "
            f"{' '.join(f'{x:.2f}' for x in r['ratio']):>17}  "
            f"{r['ours_tris'][0]}+{r['ours_tris'][1]} / "
            f"{r['sapling_tris'][0]}+{r['sapling_tris'][1]}{flag}"
        )
        if r["preset"]:
            print(f"{'':<8} untouched {r['preset']}: {dims(r['preset_size'])}; {r['source']}")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ref", type=Path, default=DEFAULT_REF, help="the shared reference folder")
    ap.add_argument(
        "--species", action="store_true", help="every species' base dictionary vs Sapling"
    )
    ap.add_argument("--blender", help="with --species: re-record Sapling with this Blender")
    ap.add_argument("--markdown", action="store_true", help="with --species: Markdown table")
    args = ap.parse_args(argv)
    if (args.blender or args.markdown) and not args.species:
        ap.error("--blender and --markdown go with --species")
    if args.species:
        return species_main(args)
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
