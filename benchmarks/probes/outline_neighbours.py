"""How much nearer could the returned trees' outlines come by one more change?

Reads ``bench_drawings.py --part follow --json RUN`` runs (each ``.npz`` beside it) and
grows each returned tree (the record's ``params`` at its ``yaw``; a pair's side at
``yaw + 90``) again with one change, measuring the envelope overlap at the search's work
size (128 px, as ``refine.start.polish`` does) against the returned tree's own:

- ``--values``: one value at a time, each alone (the trunk's flared foot ``rootFlare``,
  the count of first branches, the leaves' size and count, the second branches' length);
  each change's median and the median of the better of it and the returned tree;
- ``--seeds N``: N other draws (``seed``), each at the returned view and 15 and 30 degrees
  either way, the best by the mean over the drawn views (an oracle's pick after the
  outline step, which tries ``refine.start.RESEED_SEEDS`` before its search).

    .venv/bin/python benchmarks/probes/outline_neighbours.py RUN.json [RUN2.json] --values
    .venv/bin/python benchmarks/probes/outline_neighbours.py PAIRS.json --seeds 12
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from refine.envelope import mask_iou
from refine.start import cheap_sketches, seen_envelope
from weberpenn import ParamError, TreeParams

SIZE = 128
TURNS = (-30.0, -15.0, 0.0, 15.0, 30.0)
SIDE_TURN = 90.0  # bench_drawings.py's pairs: the side drawn 90 degrees further round
SEED_STEP = 7919


def _scaled(key: str, i: int, f: float) -> Callable[[TreeParams], TreeParams]:
    def change(p: TreeParams) -> TreeParams:
        v = list(p[key])
        v[i] = int(round(v[i] * f)) if isinstance(v[i], int) else float(v[i]) * f
        return p.replace(**{key: v})

    return change


CHANGES: dict[str, Callable[[TreeParams], TreeParams]] = {
    "rootFlare 1.5": lambda p: p.replace(rootFlare=1.5),
    "rootFlare 2": lambda p: p.replace(rootFlare=2.0),
    "rootFlare 3": lambda p: p.replace(rootFlare=3.0),
    "branches[1] x1.5": _scaled("branches", 1, 1.5),
    "branches[1] x0.7": _scaled("branches", 1, 0.7),
    "branches[2] x1.5": _scaled("branches", 2, 1.5),
    "leafScale x1.4": lambda p: p.replace(leafScale=float(p["leafScale"]) * 1.4),
    "leafScale x0.7": lambda p: p.replace(leafScale=float(p["leafScale"]) * 0.7),
    "leaves x2": lambda p: p.replace(leaves=int(p["leaves"]) * 2),
    "length[2] x1.3": _scaled("length", 2, 1.3),
    "length[2] x0.7": _scaled("length", 2, 0.7),
}


def _cases(runs: list[Path]) -> list[tuple[str, str, TreeParams, list[tuple[np.ndarray, float]]]]:
    """(name, species, returned tree, [(drawn envelope, yaw) per view]) of every record."""
    out = []
    for run in runs:
        sketches = np.load(run.with_suffix(".npz"))
        for r in json.loads(run.read_text())["records"]:
            yaw = float(r["yaw"])
            wants = [(seen_envelope(sketches[r["name"] + "/input_sketch"], SIZE), yaw)]
            if r["name"] + "/view2/input_sketch" in sketches.files:
                side = sketches[r["name"] + "/view2/input_sketch"]
                wants.append((seen_envelope(side, SIZE), yaw + SIDE_TURN))
            out.append((r["name"], r["species"], TreeParams(r["params"]), wants))
    return out


def _overlaps(p: TreeParams, species: str, wants: list, turn: float = 0.0) -> list[float]:
    sketches = cheap_sketches(p, species, SIZE, [yaw + turn for _, yaw in wants])
    return [mask_iou(w, seen_envelope(s, SIZE)) for (w, _), s in zip(wants, sketches, strict=True)]


def _changed(
    f: Callable[[TreeParams], TreeParams], p: TreeParams, species: str, wants: list
) -> float:
    """The front view's overlap of ``p`` changed by ``f``; NaN where the change passes the
    generator's limits (more first branches than its leaves allow)."""
    try:
        q = f(p)
    except ParamError:
        return float("nan")
    return _overlaps(q, species, wants)[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", type=Path, nargs="+", help="bench_drawings.py --part follow --json")
    ap.add_argument("--values", action="store_true", help="each value change alone")
    ap.add_argument("--seeds", type=int, default=0, help="other draws to try, each at 5 turns")
    args = ap.parse_args()
    rows: list[list[float]] = []
    best_rows: list[list[float]] = []
    for name, species, p, wants in _cases(args.runs):
        own = _overlaps(p, species, wants)
        if args.values:
            rows.append([own[0]] + [_changed(f, p, species, wants) for f in CHANGES.values()])
        if args.seeds:
            best = (float(np.mean(own)), own)
            for k in range(1, args.seeds + 1):
                q = p.replace(seed=(int(p["seed"]) + k * SEED_STEP) % 2**31)
                for turn in TURNS:
                    o = _overlaps(q, species, wants, turn)
                    if np.mean(o) > best[0]:
                        best = (float(np.mean(o)), o)
            best_rows.append(own + best[1])
        print(name, species, np.round(own, 3), flush=True)
    if rows:
        a = np.array(rows)
        print(f"{len(a)} drawings, the returned trees' median {np.median(a[:, 0]):.4f}")
        for i, label in enumerate(CHANGES, start=1):
            better = np.fmax(a[:, 0], a[:, i])
            print(
                f"  {label:18s} alone {np.nanmedian(a[:, i]):.4f}, the better of the two "
                f"{np.median(better):.4f}, nearer on {(a[:, i] > a[:, 0] + 0.005).sum()}, "
                f"past the limits on {np.isnan(a[:, i]).sum()}"
            )
    if best_rows:
        b = np.array(best_rows)
        n = b.shape[1] // 2
        print(
            f"{len(b)} drawings, each view's median: returned "
            f"{' / '.join(f'{np.median(b[:, i]):.4f}' for i in range(n))}; the best of "
            f"{args.seeds} more draws {' / '.join(f'{np.median(b[:, n + i]):.4f}' for i in range(n))}"
        )


if __name__ == "__main__":
    main()
