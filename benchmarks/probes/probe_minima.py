"""Local minima of the sketch distance around a tree's true parameters, per searched value.

For one sampled tree per species (``species.sample(name, --seed)``): the front sketch of the
true tree at the search's size is the target; each live value of the search
(``SearchSpace.create(...).live()``, the yaw held at the front) is moved alone through
``--steps`` evenly spaced offsets in ``[-span, +span]`` of the unit cube around the truth,
and the sketch distance is measured at every point with both metrics from the same
rendered sketch: ``"ink"`` (line pixels, the metric before) and ``"shape"`` (the
style-blind distance, now the default).

A local minimum is a point (or a run of equal values) lower than both neighbours; the
ends of the profile are not counted.  The truth (offset 0) is one by construction (the
distance there is 0); "spurious" counts the others: each is a place where a local search
moving this value can stop short of the truth.

    nice -n 10 .venv/bin/python benchmarks/probes/probe_minima.py --species maple \
        --json /tmp/probe_minima.json
    .venv/bin/python benchmarks/probes/probe_minima.py --markdown /tmp/probe_minima.json
"""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from refine.objective import SearchSpace, SketchObjective, framed, make_target
from refine.search import RefineSettings
from render.sketch import SketchRenderer
from weberpenn import build_mesh, grow, species
from weberpenn.fileio import atomic_write

METRICS = ("ink", "shape")


def local_minima(values: np.ndarray) -> list[int]:
    """Indices of the interior local minima of a profile; a run of equal values counts
    once (its first index) and only when both sides of the run are higher."""
    v = np.asarray(values, dtype=np.float64)
    # collapse runs of equal values so a flat stretch is judged by what lies beyond it
    starts = np.flatnonzero(np.r_[True, np.diff(v) != 0])
    runs = v[starts]
    inner = np.arange(1, len(runs) - 1)
    low = (runs[inner] < runs[inner - 1]) & (runs[inner] < runs[inner + 1])
    return [int(starts[i]) for i in inner[low]]


def probe_species(
    name: str, seed: int, span: float, steps: int, size: int, done: Callable[[dict], None]
) -> list[dict]:
    """Profiles of every live value of one species' sampled tree; ``done(record)`` after
    each value (so a cut run keeps what it measured)."""
    gt = species.sample(name, seed)
    space = SearchSpace.create(name, gt, search_yaw=False).live()
    x0 = space.from_params(space.base)
    truth = framed(
        SketchRenderer(build_mesh(grow(space.to_params(x0)), species=name)).sketch(0.0, size),
        size,
    )
    objs = {m: SketchObjective(make_target(truth, size, m), space, metric=m) for m in METRICS}
    offsets = np.linspace(-span, span, steps)
    out = []
    for i, u in enumerate(space.dims):
        t0 = time.perf_counter()
        prof: dict[str, list[float]] = {m: [] for m in METRICS}
        used = []
        for d in offsets:
            t = x0[i] + d
            if not 0.0 <= t <= 1.0:
                continue  # past the value's range: the search cannot go there either
            x = x0.copy()
            x[i] = t
            img = objs["shape"].sketch_at(x)
            used.append(float(d))
            for m in METRICS:
                prof[m].append(objs[m].loss_of_sketch(img))
        centre = int(np.argmin(np.abs(np.asarray(used))))
        rec = {
            "species": name,
            "seed": seed,
            "key": u.label,
            "x0": float(x0[i]),
            "offsets": used,
            "seconds": time.perf_counter() - t0,
        }
        for m in METRICS:
            mins = local_minima(np.asarray(prof[m]))
            rec[m] = prof[m]
            rec[f"{m}_minima"] = len(mins)
            rec[f"{m}_spurious"] = sum(j != centre for j in mins)
        out.append(rec)
        done(rec)
        print(
            f"{name:>7} {u.label:<18} ink {rec['ink_minima']} shape {rec['shape_minima']} "
            f"({len(used)} points, {rec['seconds']:.1f}s)",
            flush=True,
        )
    return out


def markdown(recs: list[dict]) -> str:
    out = [
        "| species | key | points | ink minima (spurious) | shape minima (spurious) "
        "| ink max | shape max |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in recs:
        out.append(
            f"| {r['species']} | {r['key']} | {len(r['offsets'])} "
            f"| {r['ink_minima']} ({r['ink_spurious']}) "
            f"| {r['shape_minima']} ({r['shape_spurious']}) "
            f"| {max(r['ink']):.4f} | {max(r['shape']):.4f} |"
        )
    out += [
        "",
        "| species | keys | ink spurious minima | shape spurious minima |",
        "|---|---|---|---|",
    ]
    names = [s for s in species.SPECIES if any(r["species"] == s for r in recs)]
    for name in [*names, None]:
        rows = [r for r in recs if name is None or r["species"] == name]
        out.append(
            f"| {name or '**all**'} | {len(rows)} | {sum(r['ink_spurious'] for r in rows)} "
            f"| {sum(r['shape_spurious'] for r in rows)} |"
        )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--species", default="maple", help="comma list (default: maple)")
    ap.add_argument("--seed", type=int, default=0, help="species.sample seed")
    ap.add_argument("--span", type=float, default=0.1, help="unit-cube offset each way")
    ap.add_argument("--steps", type=int, default=21)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--markdown", type=Path, default=None, help="only print a --json's tables")
    args = ap.parse_args(argv)
    if args.markdown is not None:
        print(markdown(json.loads(args.markdown.read_text())))
        return 0
    if not 0 < args.span <= 0.5:
        ap.error(f"--span must be in (0, 0.5], got {args.span}")
    if args.steps < 3 or args.steps % 2 == 0:
        ap.error(f"--steps must be an odd number >= 3 (so 0 is a point), got {args.steps}")
    try:
        names = [species.canonical(s) for s in args.species.split(",")]
    except ValueError as e:
        ap.error(str(e))
    size = RefineSettings().size
    recs: list[dict] = []

    def done(rec: dict) -> None:
        recs.append(rec)
        if args.json is not None:
            atomic_write(args.json, json.dumps(recs, indent=1))

    for name in names:
        probe_species(name, args.seed, args.span, args.steps, size, done)
    print(markdown(recs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
