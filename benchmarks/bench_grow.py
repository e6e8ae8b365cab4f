"""Benchmark grow + mesh per species and compare with Blender Sapling's recorded seconds.

    .venv/bin/python benchmarks/bench_grow.py [--trees 20] [--markdown] [--write]
        [--blender blender] [--repeats 3]

For each species: ``species.sample(name, seed)`` for seeds 0..trees-1, then
``build_mesh(grow(params))`` timed on one thread (BLAS/OpenMP pinned to 1 thread); the
median seconds, median branch/leaf triangle counts and Sapling's mean seconds on the
species' three reference dictionaries (``sapling_reference_stats.json``; for the species
people draw, which have none, on the base dictionary as ``sapling_species_stats.json``
records it; Sapling's branch faces are quads, so its triangles are twice its faces) give
the speed-up.  ``--write``
replaces this benchmark's section of ``benchmarks/RESULTS.md``.

``--blender BIN`` also times Blender's own Sapling in the same run, on this machine: the
species' three reference dictionaries (the species people draw: its base dictionary) are
exported as Sapling presets (``weberpenn.export.save_sapling_preset``),
``benchmarks/lib/sapling_run.py`` runs ``tree_add`` on each ``--repeats`` times inside
Blender, and our grow + mesh is timed on the very same dictionaries; the same-run ratio is
reported beside the recorded one.  ``--species a,b`` limits the run to those species.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import datetime as dt  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from benchmarks.lib.results_md import cpu_name, write_section  # noqa: E402
from benchmarks.lib.sapling_run import (  # noqa: E402
    REFERENCE_STATS,
    SaplingError,
    recorded,
    reference_rows,
    run_sapling,
)
from weberpenn import build_mesh, grow, load_params, species  # noqa: E402
from weberpenn.export import save_sapling_preset  # noqa: E402
from weberpenn.params import TreeParams  # noqa: E402

SECTION = "## Generator: grow + mesh"


def _sapling(name: str) -> dict[str, float] | None:
    """Sapling's recorded seconds and triangles: the reference dictionaries' mean, or for
    a species without any, its base dictionary's record (None when neither is there)."""
    rows = reference_rows(name)
    if not rows and not species.reference_files(name):
        try:
            rows = [recorded()["trees"][name]["base"]]
        except SaplingError:
            return None
    if not rows:
        return None
    return {
        "seconds": statistics.mean(r["seconds_sapling"] for r in rows),
        "branch_tris": statistics.mean(2 * r["branch_faces"] for r in rows),
        "leaf_tris": statistics.mean(2 * r["leaf_faces"] for r in rows),
    }


def run(trees: int, names: tuple[str, ...] = species.SPECIES) -> list[dict]:
    rows = []
    build_mesh(grow(species.sample("maple", 0)))  # warm-up (imports, caches)
    for name in names:
        secs, grow_s, bt, lt = [], [], [], []
        for seed in range(trees):
            p = species.sample(name, seed)
            t0 = time.perf_counter()
            sk = grow(p)
            t1 = time.perf_counter()
            tm = build_mesh(sk, species=name)
            t2 = time.perf_counter()
            secs.append(t2 - t0)
            grow_s.append(t1 - t0)
            bt.append(len(tm.branches.faces))
            lt.append(len(tm.leaves.faces))
        sap = _sapling(name)
        med = statistics.median(secs)
        rows.append(
            {
                "species": name,
                "median_s": med,
                "max_s": max(secs),
                "grow_s": statistics.median(grow_s),
                "branch_tris": int(statistics.median(bt)),
                "leaf_tris": int(statistics.median(lt)),
                "sapling_s": sap["seconds"] if sap else None,
                "sapling_branch_tris": sap["branch_tris"] if sap else None,
                "sapling_leaf_tris": sap["leaf_tris"] if sap else None,
                "speedup": sap["seconds"] / med if sap else None,
            }
        )
    return rows


def _dictionaries(name: str) -> list[tuple[str, TreeParams]]:
    """(label, dictionary) the species is timed on: its three reference dictionaries, or
    its base dictionary when it has none (the species people draw)."""
    ref_dir = REFERENCE_STATS.parent / "treesketchnet_test_params"
    files = species.reference_files(name)
    if not files:
        return [(name, species.base(name))]
    return [(Path(f).stem, load_params(ref_dir / Path(f).name)) for f in files]


def same_run_sapling(
    blender: str, repeats: int, names: tuple[str, ...] = species.SPECIES
) -> list[dict]:
    """Sapling and our generator on each species' dictionaries, this machine."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        presets, owners = [], []
        for name in names:
            for label, params in _dictionaries(name):
                preset = Path(tmp) / f"{label}.py"
                save_sapling_preset(params, preset)
                presets.append(preset)
                owners.append((name, params))
        try:
            sap = run_sapling(blender, presets, repeats)
        except SaplingError as exc:
            raise SystemExit(str(exc)) from None
    for (name, params), s in zip(owners, sap, strict=True):
        ours = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            build_mesh(grow(params), species=name)
            ours.append(time.perf_counter() - t0)
        out.append(
            {
                "species": name,
                "sapling_s": min(s["seconds"]),
                "ours_s": min(ours),
            }
        )
    by: dict[str, dict] = {}
    for r in out:
        b = by.setdefault(r["species"], {"species": r["species"], "sapling": [], "ours": []})
        b["sapling"].append(r["sapling_s"])
        b["ours"].append(r["ours_s"])
    return [
        {
            "species": b["species"],
            "sapling_s": statistics.mean(b["sapling"]),
            "ours_s": statistics.mean(b["ours"]),
            "speedup": statistics.mean(b["sapling"]) / statistics.mean(b["ours"]),
        }
        for b in by.values()
    ]


def markdown_same_run(rows: list[dict], repeats: int) -> str:
    lines = [
        "",
        f"Same run, same machine (`--blender blender --repeats {repeats}`): Blender "
        "Sapling (Debian blender 3.4.1) and our grow + mesh on each species' three "
        "reference dictionaries (the species people draw: its base dictionary; best of "
        "the repeats per dictionary, since both are disturbed by other jobs on this shared "
        "machine, mean over the dictionaries).",
        "",
        "| species | Sapling s | ours s | speed-up (same run) |",
        "|---|---:|---:|---:|",
    ]
    lines += [
        f"| {r['species']} | {r['sapling_s']:.3f} | {r['ours_s']:.3f} | {r['speedup']:.1f}x |"
        for r in rows
    ]
    lines += [
        "",
        f"Smallest same-run speed-up: {min(r['speedup'] for r in rows):.1f}x (target >= 10x).",
        "",
    ]
    return "\n".join(lines)


def markdown(rows: list[dict], trees: int) -> str:
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    now = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        SECTION,
        "",
        f"`.venv/bin/python benchmarks/bench_grow.py --trees {trees} --write`",
        "",
        f"machine: {cpu_name()}, nproc {os.cpu_count()}, one thread, load average {load:.2f} "
        f"(shared with other jobs); {now}. Trees: `species.sample(name, seed)`, seeds "
        f"0..{trees - 1}. Sapling: Blender 3.4 Sapling on the species' three reference "
        "dictionaries (sapling_reference_stats.json, 2-core machine; the species people draw: "
        "their base dictionary, sapling_species_stats.json); its quads counted as 2 "
        "triangles.",
        "",
        "| species | grow+mesh median s | max s | grow s | branch tris | leaf tris "
        "| Sapling s | Sapling branch / leaf tris | speed-up |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        sap = "-" if r["sapling_s"] is None else f"{r['sapling_s']:.3f}"
        sap_t = (
            "-"
            if r["sapling_s"] is None
            else f"{r['sapling_branch_tris']:.0f} / {r['sapling_leaf_tris']:.0f}"
        )
        sp = "-" if r["speedup"] is None else f"{r['speedup']:.1f}x"
        lines.append(
            f"| {r['species']} | {r['median_s']:.3f} | {r['max_s']:.3f} | {r['grow_s']:.3f} "
            f"| {r['branch_tris']} | {r['leaf_tris']} | {sap} | {sap_t} | {sp} |"
        )
    worst = max(r["median_s"] for r in rows)
    speed = [r["speedup"] for r in rows if r["speedup"] is not None]
    short = (
        ", ".join(
            f"{r['species']} (grow alone {r['grow_s'] * 1000:.0f} ms, a tenth of Sapling "
            f"{r['sapling_s'] * 100:.0f} ms)"
            for r in rows
            if r["speedup"] is not None and r["speedup"] < 10
        )
        or "none"
    )
    lines += [
        "",
        f"Slowest species median: {worst:.3f} s (target < 0.2 s); smallest speed-up over "
        f"Sapling: {min(speed):.1f}x (target >= 10x). Below 10x: {short}. "
        "Timings on this shared 2-CPU machine vary by about +-30% from run to run."
        if speed
        else f"Slowest species median: {worst:.3f} s (target < 0.2 s).",
        "",
    ]
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trees", type=int, default=20, help="trees per species (seeds 0..N-1)")
    ap.add_argument("--markdown", action="store_true", help="print the Markdown section")
    ap.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    ap.add_argument("--blender", help="Blender binary: also time Sapling in the same run")
    ap.add_argument("--repeats", type=int, default=3, help="Sapling/ours runs per dictionary")
    ap.add_argument("--species", help="comma-separated species (default: all)")
    args = ap.parse_args()
    if args.trees < 1 or args.repeats < 1:
        ap.error("--trees and --repeats must be at least 1")
    try:
        names = (
            tuple(species.canonical(n) for n in args.species.split(",") if n.strip())
            if args.species
            else species.SPECIES
        )
    except ValueError as exc:
        ap.error(str(exc))
    if not names:
        ap.error("--species names no species")
    if args.write and names != species.SPECIES:
        ap.error("--write replaces the all-species section; drop --species or --write")
    rows = run(args.trees, names)
    text = markdown(rows, args.trees)
    if args.blender:
        text = (
            text.rstrip("\n")
            + "\n"
            + markdown_same_run(same_run_sapling(args.blender, args.repeats, names), args.repeats)
        )
        extra = f" --species {args.species}" if args.species else ""
        text = text.replace(
            f"--trees {args.trees} --write`",
            f"--trees {args.trees} --blender {args.blender} --repeats {args.repeats}{extra}"
            " --write`",
        )
    if args.markdown or not args.write:
        print(text)
    if args.write:
        write_section(text)


if __name__ == "__main__":
    main()
