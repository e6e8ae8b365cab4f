"""Fit a TSN checkpoint's tree detector: is a drawing a tree at all?

    .venv/bin/python scripts/fit_tree_detector.py [--checkpoint checkpoints/tsn_lite0.pt] \
        [--per-species 25] [--per-kind 16] [--styled 66] [--out checkpoints/tsn_lite0.pt]

The detector (``tsn.tree_detect.TreeDetector``) reads the network's pooled features.  It is
fitted on drawings made by code, none of them a benchmark's: hand-style tree doodles
(``eval.doodles.tree_doodle``, ``--per-species`` per species, seeds from 1000), trees of
every species drawn in every renderer style (``render.styles``, ``--styled``, tree seeds
from 4000, a random view) and doodles of other things (``eval.doodles.nontree_doodle``,
``--per-kind`` per kind, seeds from 20000; and simple pictures, ``eval.pictures``, of the
kinds ``FIT_PICTURES``); its temperature on as many again from other
seeds (tree doodles from 5000, styled trees from 7000, other things from 30000), where
the rates it prints are measured.  The benchmarks score tree doodles below seed 1000 and
other things from 1000 to 1999.  Every drawing goes through the pipeline's own reader and
preparation.  The network's weights, normaliser and species identifier are not touched.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from eval.doodles import NONTREE_KINDS, TREE_SPECIES, nontree_doodle, tree_doodle
from eval.fitting import read_drawings, styled_trees
from eval.pictures import PICTURE_KINDS, picture
from treesketch.pipeline import load_sketch, prepare_input
from tsn.checkpoint import load_checkpoint, save_loaded
from tsn.predict import TSNModel
from tsn.tree_detect import TreeDetector

ROOT = Path(__file__).resolve().parents[1]

FIT_SEEDS = {"doodle": 1000, "styled": 4000, "other": 20_000}
HELD_SEEDS = {"doodle": 5000, "styled": 7000, "other": 30_000}
# simple pictures (``eval.pictures``) fitted on; the other kinds are only ever held out, to
# see how the detector does on kinds of picture it has never been shown
FIT_PICTURES = ("noise", "circle", "square", "house", "face", "text", "strokes", "grid", "car")
UNSEEN_PICTURES = tuple(k for k in PICTURE_KINDS if k not in FIT_PICTURES)


def prepared(image: Any) -> np.ndarray:
    """A drawing read and prepared as the pipeline does at inference."""
    return prepare_input(load_sketch(image))


def drawings(seeds: dict[str, int], args: argparse.Namespace) -> dict[str, list[np.ndarray]]:
    return {
        "tree doodles": [
            tree_doodle(s, seeds["doodle"] + k)
            for s in TREE_SPECIES
            for k in range(args.per_species)
        ],
        "styled trees": styled_trees(seeds["styled"], args.styled)[0],
        "other things": [
            nontree_doodle(kind, seeds["other"] + k)
            for kind in NONTREE_KINDS
            for k in range(args.per_kind)
        ]
        + [
            picture(kind, seeds["other"] + k) for kind in FIT_PICTURES for k in range(args.per_kind)
        ],
    }


def features(model: TSNModel, images: list[np.ndarray]) -> np.ndarray:
    """The pooled features the network's heads read, of the drawings the pipeline would
    accept."""
    return model.head_features(read_drawings(model, images, prepared)[1])


def labelled(model: TSNModel, sets: dict[str, list[np.ndarray]]) -> dict[str, np.ndarray]:
    return {name: features(model, imgs) for name, imgs in sets.items()}


def stack(feats: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    x = np.concatenate(list(feats.values()))
    y = np.concatenate([np.full(len(v), k != "other things") for k, v in feats.items()])
    return x, y


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", default=str(ROOT / "checkpoints" / "tsn_lite0.pt"))
    ap.add_argument("--per-species", type=int, default=25, help="tree doodles per species")
    ap.add_argument("--per-kind", type=int, default=16, help="doodles per kind of other thing")
    ap.add_argument("--styled", type=int, default=66, help="trees drawn in the renderer's styles")
    ap.add_argument("--l2", type=float, default=1e-2)
    ap.add_argument("--out", default=None, help="checkpoint to write (default: --checkpoint)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    loaded = load_checkpoint(args.checkpoint)
    model = TSNModel(loaded)
    fit = labelled(model, drawings(FIT_SEEDS, args))
    held = labelled(model, drawings(HELD_SEEDS, args))
    det = TreeDetector.fit(*stack(fit), held_out=stack(held), l2=args.l2)
    unseen = [
        picture(kind, HELD_SEEDS["other"] + k)
        for kind in UNSEEN_PICTURES
        for k in range(args.per_kind)
    ]
    held_rates = {**held, f"unseen kinds ({', '.join(UNSEEN_PICTURES)})": features(model, unseen)}
    rates = {
        k: float(np.mean((det.probabilities(v) >= 0.5) != (k in ("tree doodles", "styled trees"))))
        for k, v in held_rates.items()
    }
    hand = sorted((ROOT / "examples" / "hand").glob("*.png"))
    hand_p = det.probabilities(features(model, [load_sketch(p) for p in hand]))
    info = {
        **loaded.info,
        "tree_detector": {
            "fitted_on": {k: len(v) for k, v in fit.items()},
            "held_out_wrong": rates,
            "temperature": det.temperature,
            "l2": args.l2,
            "command": " ".join(sys.argv),
        },
    }
    out = args.out or args.checkpoint
    save_loaded(loaded, out, info, tree_detector=det)
    for k, v in rates.items():
        print(f"held out, {k}: {v:.1%} judged wrongly ({len(held_rates[k])} drawings)")
    print(f"examples/hand (all trees): {np.mean(hand_p < 0.5):.1%} judged not trees")
    for p, v in zip(hand, hand_p, strict=True):
        print(f"  {p.stem:<16} P(tree) {v:.2f}")
    print(f"temperature {det.temperature:.2f}; wrote {out} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
