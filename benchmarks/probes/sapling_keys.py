"""Probe: what makes a species people draw differ from its untouched Sapling preset, and
how much one seed says (issue 27, item 1).

    .venv/bin/python benchmarks/probes/sapling_keys.py [--blender blender] [--seeds 5]

1. Every preset of the species people draw has ``splitByLen: True``, a Sapling key our
   generator does not implement (``weberpenn.preset`` exports ``splitByLen: False``).
   Sapling grows each untouched preset (leaves shown) with it on and off, Sapling seeds
   0..2: the change in size and branch faces is what that key alone does.
2. One seed of a dictionary is one draw of its trunk splits: the species' base
   dictionary is grown with seeds 0..N-1 by us and by Sapling (``replace(seed=s)``), and
   the mean sizes, branch triangles and trunk stems (Sapling's: its draws replayed by
   ``compare_sapling.replay_trunk_splines``) are compared.
3. The bonsai's height: its base dictionary with the trunk's realised curve variation
   (``curveV1[0]``, ``curveV2[0]``) kept and set to 0, by us and by Sapling.  Sapling has
   no realised curve: the export maps it to an amplitude ``curveV = (|V1| + |V2|) * curveRes``
   that Sapling draws per segment at random.
4. The weeping willow (no value set by the species): its untouched preset, then with
   each Sapling key that ``species.base`` treats otherwise set as the base has it, one
   after the other (``splitByLen`` off, ``handleType`` auto, the variation amplitudes 0),
   Sapling seed 0.

``--part`` runs one of them (default: all).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from benchmarks.compare_sapling import replay_trunk_splines
from benchmarks.lib.sapling_run import PRESETS, preset_line, run_sapling, sizes
from weberpenn import build_mesh, grow, species
from weberpenn.export import save_sapling_preset


def _dims(v: list[float], digits: int = 1) -> str:
    return " x ".join(f"{x:.{digits}f}" for x in v)


def _mean(rows: list[list[float]]) -> list[float]:
    return [statistics.mean(c) for c in zip(*rows, strict=True)]


def split_by_len(blender: str) -> None:
    print("| species | preset | splitByLen | Sapling w x d x h (seeds 0-2) | branch tris |")
    print("|---|---|---|---|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        jobs = []
        for name in species.PEOPLE_SPECIES:
            raw = preset_line(PRESETS / f"{species.sapling_preset(name)}.py")
            for on in (True, False):
                for seed in (0, 1, 2):
                    path = Path(tmp) / f"{name}_{on}_{seed}.py"
                    d = {**raw, "seed": seed, "showLeaves": True, "splitByLen": on}
                    path.write_text(repr(d) + "\n", encoding="utf-8")
                    jobs.append((name, on, path))
        rows = run_sapling(blender, [j[2] for j in jobs])
    by: dict[tuple[str, bool], list[dict]] = {}
    for (name, on, _), r in zip(jobs, rows, strict=True):
        by.setdefault((name, on), []).append(r)
    for (name, on), rs in by.items():
        size = _mean([sizes(r)["tree"] for r in rs])
        tris = statistics.mean(2 * r["branch_faces"] for r in rs)
        print(
            f"| {name} | `{species.sapling_preset(name)}` | {on} | {_dims(size)} "
            f"| {tris / 1000:.0f}k |"
        )


def seeds(blender: str, n: int, names: list[str]) -> None:
    print(
        "\n| species | seeds | ours mean w x d x h | Sapling mean w x d x h | ours / Sapling "
        "| branch tris ours / Sapling (mean) | trunk stems ours / Sapling (mean) |"
    )
    print("|---|---|---|---|---|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        jobs = []
        for name in names:
            for s in range(n):
                p = species.base(name).replace(seed=s)
                jobs.append((name, p, save_sapling_preset(p, Path(tmp) / f"{name}_{s}.py")))
        rows = run_sapling(blender, [j[2] for j in jobs])
    for name in names:
        ours, sap, ot, st, tr_o, tr_s = [], [], [], [], [], []
        for (nm, p, _), r in zip(jobs, rows, strict=True):
            if nm != name:
                continue
            sk = grow(p)
            tm = build_mesh(sk, species=name)
            tr_o.append(int(sk.stems_per_level()[0]))
            tr_s.append(replay_trunk_splines(p.to_dict(), int(p["seed"])))
            lo, hi = tm.bounds()
            ours.append((hi - lo).tolist())
            ot.append(len(tm.branches.faces))
            sap.append(sizes(r)["tree"])
            st.append(2 * r["branch_faces"])
        o, s_ = _mean(ours), _mean(sap)
        ratio = " ".join(f"{a / b:.2f}" for a, b in zip(o, s_, strict=True))
        print(
            f"| {name} | 0-{n - 1} | {_dims(o)} | {_dims(s_)} | {ratio} "
            f"| {statistics.mean(ot) / 1000:.0f}k / {statistics.mean(st) / 1000:.0f}k "
            f"| {statistics.mean(tr_o):.1f} / {statistics.mean(tr_s):.1f} |"
        )


def trunk_curve(blender: str) -> None:
    print("\n| bonsai base dictionary | ours w x d x h | Sapling w x d x h | ours / Sapling |")
    print("|---|---|---|---|")
    b = species.base("bonsai")
    v1, v2 = list(b["curveV1"]), list(b["curveV2"])
    variants = {
        f"as is (trunk curveV1 {v1[0]:.1f}, curveV2 {v2[0]:.1f})": b,
        "trunk curveV1 = curveV2 = 0": b.replace(curveV1=[0.0, *v1[1:]], curveV2=[0.0, *v2[1:]]),
    }
    with tempfile.TemporaryDirectory() as tmp:
        paths = [
            save_sapling_preset(p, Path(tmp) / f"bonsai_{i}.py")
            for i, p in enumerate(variants.values())
        ]
        rows = run_sapling(blender, paths)
    for (label, p), r in zip(variants.items(), rows, strict=True):
        lo, hi = build_mesh(grow(p), species="bonsai").bounds()
        o, s_ = (hi - lo).tolist(), sizes(r)["tree"]
        ratio = " ".join(f"{a / b_:.2f}" for a, b_ in zip(o, s_, strict=True))
        print(f"| {label} | {_dims(o, 2)} | {_dims(s_, 2)} | {ratio} |")


def willow_steps(blender: str) -> None:
    print(
        "\n| weeping_willow preset, seed 0 | Sapling w x d x h | splines | branch tris "
        "| leaf faces |"
    )
    print("|---|---|---:|---:|---:|")
    zero = [0.0, 0.0, 0.0, 0.0]
    d = {**preset_line(PRESETS / "weeping_willow.py"), "seed": 0, "showLeaves": True}
    steps = [
        ("untouched", {}),
        ("+ splitByLen off", {"splitByLen": False}),
        ("+ handleType auto ('0')", {"handleType": "0"}),
        ("+ curveV 0", {"curveV": zero}),
        ("+ downAngleV 0", {"downAngleV": zero}),
        ("+ rotateV, splitAngleV, scaleV 0", {"rotateV": zero, "splitAngleV": zero, "scaleV": 0.0}),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, (_, change) in enumerate(steps):
            d = {**d, **change}
            path = Path(tmp) / f"willow_{i}.py"
            path.write_text(repr(d) + "\n", encoding="utf-8")
            paths.append(path)
        rows = run_sapling(blender, paths)
    for (label, _), r in zip(steps, rows, strict=True):
        print(
            f"| {label} | {_dims(sizes(r)['tree'])} | {r['splines']} "
            f"| {2 * r['branch_faces'] / 1000:.0f}k | {r['leaf_faces'] / 1000:.0f}k |"
        )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--seeds", type=int, default=5, help="seeds of the base dictionary")
    ap.add_argument("--species", default="willow", help="species for the seed study")
    ap.add_argument(
        "--part", choices=("all", "splitbylen", "seeds", "curve", "willow"), default="all"
    )
    args = ap.parse_args()
    if args.part in ("all", "splitbylen"):
        split_by_len(args.blender)
    if args.part in ("all", "seeds"):
        names = [species.canonical(s) for s in args.species.split(",")]
        seeds(args.blender, args.seeds, names)
    if args.part in ("all", "curve"):
        trunk_curve(args.blender)
    if args.part in ("all", "willow"):
        willow_steps(args.blender)
    return 0


if __name__ == "__main__":
    sys.exit(main())
