"""Would Weber-Penn's pruning envelope bring a returned tree's outline nearer the drawn one?

Reads a ``bench_drawings.py --part follow --json RUN`` run (its ``.npz`` beside it).  For
each people's drawing of outlines (``inside_ink`` under ``refine.start.LINES_INSIDE``) it
takes the returned tree (the record's ``params`` at its ``yaw``) and grows it again with
the pruning envelope on (``prune``; Sapling keeps the same keys), the envelope fitted to
the drawn crown: ``pruneBase`` at the drawn crown base, ``pruneWidth`` the widest drawn
half-width over the height, ``pruneWidthPeak`` and the two powers by least squares on the
drawn width profile (``refine.start.profile_of``).  The first-level branches are grown 1,
1.5 and 2 times longer (the envelope only cuts) and the envelope 1 and 1.15 times wider;
the best of the six trees' envelope overlaps (at the search's work size, 128 px, as
``refine.start.polish`` measures it) is set against the returned tree's.

    .venv/bin/python benchmarks/probes/prune_envelope.py RUN.json [--count 20] [--first 0]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from refine.envelope import mask_iou
from refine.objective import framed
from refine.start import BINS, LINES_INSIDE, Profile, cheap_sketches, profile_of, seen_envelope
from weberpenn import TreeParams

SIZE = 128
PEAKS = np.linspace(0.05, 0.95, 19)
HIGH = (0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0)
LOW = (0.001, 0.1, 0.3, 0.6, 1.0, 2.0)


def envelope_width(ratio: np.ndarray, peak: float, high: float, low: float) -> np.ndarray:
    """Weber and Penn's pruning envelope's width at ``ratio`` (1 at its base, 0 at its top;
    the paper's shape 9), as a share of ``pruneWidth``."""
    up = np.clip(ratio / (1.0 - peak), 0.0, None) ** high
    down = np.clip((1.0 - ratio) / peak, 0.0, None) ** low
    return np.where(ratio < 1.0 - peak, up, down)


def fitted_envelope(want: Profile) -> dict[str, float]:
    """The pruning envelope nearest the drawn crown's half-widths (least squares)."""
    frac = (np.arange(BINS) + 0.5) / BINS
    base = float(np.clip(want.crown_base, 0.0, 0.9))
    crown = frac > base
    half = want.widths[crown] / 2
    ratio = (1 - frac[crown]) / (1 - base)
    width = float(half.max())
    best = (np.inf, 0.5, 0.5, 0.001)
    for peak in PEAKS:
        for high in HIGH:
            for low in LOW:
                s = envelope_width(ratio, peak, high, low)
                err = float(((width * s - half) ** 2).sum())
                if err < best[0]:
                    best = (err, float(peak), high, low)
    return {
        "pruneBase": base,
        "pruneWidth": width,
        "pruneWidthPeak": best[1],
        "prunePowerHigh": best[2],
        "prunePowerLow": best[3],
    }


def overlap(want: np.ndarray, q: TreeParams, species: str, yaw: float) -> float:
    """The envelope overlap of ``q``'s fast sketch at ``yaw`` with the drawn ``want``."""
    return mask_iou(want, seen_envelope(cheap_sketches(q, species, SIZE, [yaw])[0], SIZE))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", type=Path, help="bench_drawings.py --part follow --json")
    ap.add_argument("--count", type=int, default=20, help="drawings of outlines to try")
    ap.add_argument("--first", type=int, default=0, help="skip this many of them first")
    args = ap.parse_args()
    doc = json.loads(args.run.read_text())
    sketches = np.load(args.run.with_suffix(".npz"))
    records = [
        r
        for r in doc["records"]
        if r["name"].startswith("people/") and r["inside_ink"] < LINES_INSIDE
    ][args.first : args.first + args.count]
    rows = []
    for r in records:
        drawn = sketches[r["name"] + "/input_sketch"]
        p, yaw, name = TreeParams(r["params"]), float(r["yaw"]), r["species"]
        want = seen_envelope(drawn, SIZE)
        profile = profile_of(framed(drawn, SIZE))
        if profile is None:
            continue
        returned = overlap(want, p, name, yaw)
        env = fitted_envelope(profile)
        t0 = time.perf_counter()
        tries = []
        for longer in (1.0, 1.5, 2.0):
            for wider in (1.0, 1.15):
                length = list(p["length"])
                length[1] = min(length[1] * longer, 3.0)
                q = p.replace(
                    prune=True,
                    pruneRatio=1.0,
                    length=length,
                    **{**env, "pruneWidth": env["pruneWidth"] * wider},
                )
                tries.append(overlap(want, q, name, yaw))
        per_tree = (time.perf_counter() - t0) / len(tries)
        rows.append((returned, max(tries), per_tree))
        print(
            f"{r['name']:24s} {name:7s} returned {returned:.3f}  pruned, best of "
            f"{len(tries)} {max(tries):.3f}  ({per_tree:.2f} s a tree)",
            flush=True,
        )
    a = np.array(rows)
    print(
        f"{len(a)} drawings: returned median {np.median(a[:, 0]):.3f}, pruned best "
        f"{np.median(a[:, 1]):.3f}; pruned nearer on {(a[:, 1] > a[:, 0] + 0.005).sum()}; "
        f"{np.median(a[:, 2]):.2f} s a pruned tree (median)"
    )


if __name__ == "__main__":
    main()
