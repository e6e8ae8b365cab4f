"""How near can a tree standing round its trunk come to people's drawn outlines (issue 48)?

Reads a ``bench_drawings.py --part follow --json RUN`` run (its ``.npz`` beside it) and, for
each drawing of a set, takes the drawing's envelope (``eval.envelope``) against the best
outline symmetric about the frame's centre line (the trunk's axis in the drawing's frame),
row by row: each row's half-width chosen to maximise intersection minus ``--lam`` times
union (at an overlap near ``lam`` that is the row's share of the best overlap).  Any tree
whose crown stands round its trunk has such an outline, so its median bounds what the
generator can reach.  ``--best-axis`` also lets each drawing's axis move (every 4 px within
a quarter of the frame).  Also printed: where the returned trees miss, the tree's width
minus the drawn width over the drawing's height in ten bins from the top (medians); the
tree's envelope outside the drawn one and the drawn one outside the tree's, each as a
share of the union (means), on the left and right of the frame's centre line; and the
median overlap were each tree's envelope shifted sideways by the best of -16..16 px.

    .venv/bin/python benchmarks/probes/outline_bound.py RUN.json [RUN2.json ...] [--set people]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from eval.envelope import SIDE, envelope
from refine.envelope import mask_iou

BINS = 10


def row_extents(env: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(rows with ink, each row's left edge, each row's right edge + 1)."""
    has = env.any(axis=1)
    left = np.argmax(env, axis=1)
    right = env.shape[1] - np.argmax(env[:, ::-1], axis=1)
    return has, left.astype(float), right.astype(float)


def symmetric_bound(env: np.ndarray, axis: float, lam: float) -> float:
    """The overlap of ``env`` with its best outline symmetric about column ``axis``."""
    has, left, right = row_extents(env)
    lo, hi = left[has][:, None], right[has][:, None]
    w = np.arange(0.0, SIDE / 2 + 1, 0.5)[None, :]
    inter = np.clip(np.minimum(axis + w, hi) - np.maximum(axis - w, lo), 0.0, None)
    union = (hi - lo) + 2 * w - inter
    pick = np.argmax(inter - lam * union, axis=1)
    rows = np.arange(len(pick))
    return float(inter[rows, pick].sum() / union[rows, pick].sum())


def width_misses(drawn: np.ndarray, tree: np.ndarray) -> np.ndarray:
    """Tree width minus drawn width over the drawn height, in ``BINS`` bins from the top."""
    ha, la, ra = row_extents(drawn)
    ht, lt, rt = row_extents(tree)
    ys = np.flatnonzero(ha)
    top, bottom = ys[0], ys[-1]
    wa = np.where(ha, ra - la, 0.0)
    wt = np.where(ht, rt - lt, 0.0)
    edges = top + (bottom - top) * np.arange(BINS + 1) // BINS
    return np.array(
        [
            (wt[a:b].mean() - wa[a:b].mean()) / (bottom - top)
            for a, b in zip(edges, edges[1:], strict=False)
        ]
    )


def best_shift(drawn: np.ndarray, tree: np.ndarray, reach: int = 16) -> float:
    """The overlap of ``drawn`` with ``tree`` shifted sideways by the best whole pixel."""
    return max(mask_iou(drawn, np.roll(tree, dx, axis=1)) for dx in range(-reach, reach + 1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "run", type=Path, nargs="+", help="bench_drawings.py --part follow --json (one or more)"
    )
    ap.add_argument("--set", default="people", help="people, paper or pairs")
    ap.add_argument("--lam", type=float, default=0.8)
    ap.add_argument("--best-axis", action="store_true")
    args = ap.parse_args()
    runs = [(json.loads(p.read_text()), np.load(p.with_suffix(".npz"))) for p in args.run]
    bound, free, got, misses, shifted, shares = [], [], [], [], [], []
    for r, sketches in ((r, z) for doc, z in runs for r in doc["records"]):
        if not r["name"].startswith(args.set + "/"):
            continue
        drawn = envelope(sketches[r["name"] + "/input_sketch"])
        tree = envelope(sketches[r["name"] + "/sketch_after"])
        bound.append(symmetric_bound(drawn, SIDE / 2, args.lam))
        if args.best_axis:
            axes = np.arange(SIDE * 3 / 8, SIDE * 5 / 8 + 1, 4.0)
            free.append(max(symmetric_bound(drawn, a, args.lam) for a in axes))
        got.append(r["overlap_after"])
        misses.append(width_misses(drawn, tree))
        shifted.append(best_shift(drawn, tree))
        union = float((drawn | tree).sum())
        half = SIDE // 2
        shares.append(
            [
                float(m[:, side].sum()) / union
                for m in (tree & ~drawn, drawn & ~tree)
                for side in (slice(None, half), slice(half, None))
            ]
        )
    print(f"{args.set}: {len(got)} drawings")
    print(f"returned trees' overlap, median {np.median(got):.3f}")
    print(f"best outline symmetric about the trunk's axis, median {np.median(bound):.3f}")
    if free:
        print(f"... about the best axis per drawing, median {np.median(free):.3f}")
    print(f"share of the bound reached, median {np.median(np.array(got) / np.array(bound)):.3f}")
    m = np.median(np.array(misses), axis=0)
    print(
        "tree minus drawn width over the height, top to bottom:", " ".join(f"{v:+.2f}" for v in m)
    )
    sh = np.mean(np.array(shares), axis=0)
    print(
        f"tree outside the drawing {sh[0] + sh[1]:.3f} of the union (left {sh[0]:.3f}, right "
        f"{sh[1]:.3f}); drawing outside the tree {sh[2] + sh[3]:.3f} (left {sh[2]:.3f}, right "
        f"{sh[3]:.3f}) (means)"
    )
    print(f"each tree shifted sideways by its best whole pixel, median {np.median(shifted):.3f}")


if __name__ == "__main__":
    main()
