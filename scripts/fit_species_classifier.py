"""Refit a TSN checkpoint's species classifier for more kinds of drawing.

    .venv/bin/python scripts/fit_species_classifier.py [--checkpoint checkpoints/tsn_lite0.pt] \
        [--data DS] [--doodles 300] [--styled 330] [--reads features] [--out PT]

The classifier (``tsn.species_id.SpeciesClassifier``) reads the network's pooled features
(``--reads features``, the default: they describe a drawing much more richly than the 62
predicted values, and tell a lollipop doodle from a birch; with a species branch in the
checkpoint, the branch's features too: ``tsn.predict``) or its outputs
(``--reads outputs``), so it can learn from drawings that have a species but no exact
parameters.  It is fitted on ``--doodles`` hand-style tree doodles per species
(``eval.doodles.tree_doodle``, seeds from 1000; the benchmarks score seeds below 1000),
``--styled`` trees drawn in the renderer's styles (``eval.fitting.styled_trees``, tree
seeds from 4000) and, with ``--data``, the training split of the dataset the network was
trained on; its temperature on held-out drawings of the same kinds (doodle seeds from
5000, styled tree seeds from 7000, the dataset's validation split).  Every drawing goes
through the pipeline's own reader and preparation, as at inference.  The network's
weights, normaliser and tree detector are not touched.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from eval.doodles import TREE_SPECIES, tree_doodle
from eval.fitting import read_drawings, styled_trees
from render.dataset import read_manifest
from treesketch.pipeline import load_sketch, prepare_input
from tsn.checkpoint import load_checkpoint, save_loaded
from tsn.predict import TSNModel
from tsn.species_id import READS, SpeciesClassifier

ROOT = Path(__file__).resolve().parents[1]

FIT_SEEDS = {"doodle": 1000, "styled": 4000, "split": "train"}
HELD_SEEDS = {"doodle": 5000, "styled": 7000, "split": "val"}
HELD_PART = 0.4  # held-out drawings per fitted one, for the temperature and the accuracies


def prepared(image: Any) -> np.ndarray:
    """A drawing read and prepared as the pipeline does at inference."""
    return prepare_input(load_sketch(image))


def drawings(seeds: dict, args: argparse.Namespace, part: float) -> dict[str, tuple[list, list]]:
    """``{kind: (images, species)}`` for one side (fit or held out)."""
    names = list(TREE_SPECIES)
    n = max(1, round(args.doodles * part))
    out = {
        "hand-style doodles": (
            [tree_doodle(s, seeds["doodle"] + k) for s in names for k in range(n)],
            [s for s in names for _ in range(n)],
        ),
        "renderer styles": styled_trees(seeds["styled"], max(1, round(args.styled * part))),
    }
    if args.data is not None:
        rows = read_manifest(args.data, split=seeds["split"])
        if not rows:
            raise SystemExit(f"error: {args.data} has no {seeds['split']!r} split: build it")
        out[f"{args.data.name} {seeds['split']}"] = (
            [str(args.data / r["sketch"]) for r in rows],
            [r["species"] for r in rows],
        )
    return out


def read(model: TSNModel, sets: dict, reads: str) -> dict[str, tuple[np.ndarray, list[str]]]:
    out = {}
    for kind, (images, labels) in sets.items():
        mats, pooled, kept = read_drawings(model, images, prepared)
        x = pooled if reads == "features" else mats
        out[kind] = (x, [s for s, k in zip(labels, kept, strict=True) if k])
    return out


def stack(sets: dict[str, tuple[np.ndarray, list[str]]]) -> tuple[np.ndarray, list[str]]:
    return np.concatenate([x for x, _ in sets.values()]), [s for _, y in sets.values() for s in y]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", default=str(ROOT / "checkpoints" / "tsn_lite0.pt"))
    ap.add_argument("--data", type=Path, default=None, help="the network's training dataset")
    ap.add_argument("--doodles", type=int, default=300, help="hand-style doodles per species")
    ap.add_argument("--styled", type=int, default=330, help="trees in the renderer's styles")
    ap.add_argument("--reads", choices=READS, default="features")
    ap.add_argument("--l2", type=float, default=3e-3)
    ap.add_argument("--out", default=None, help="checkpoint to write (default: --checkpoint)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    loaded = load_checkpoint(args.checkpoint)
    model = TSNModel(loaded)
    fit = read(model, drawings(FIT_SEEDS, args, 1.0), args.reads)
    held = read(model, drawings(HELD_SEEDS, args, HELD_PART), args.reads)
    clf = SpeciesClassifier.fit(
        *stack(fit), loaded.normaliser.scale, held_out=stack(held), l2=args.l2, reads=args.reads
    )
    accuracy = {
        kind: float(np.mean([clf.species[i] == s for i, s in zip(
            clf.probabilities_many(x).argmax(axis=1), y, strict=True)]))
        for kind, (x, y) in held.items()
    }  # fmt: skip
    info = {
        **loaded.info,
        "classifier": {
            "reads": args.reads,
            "fitted_on": {k: len(y) for k, (_, y) in fit.items()},
            "held_out_accuracy": accuracy,
            "temperature": clf.temperature,
            "l2": args.l2,
            "command": " ".join(sys.argv),
        },
    }
    out = args.out or args.checkpoint
    save_loaded(loaded, out, info, species_id=loaded.species_id.with_classifier(clf))
    for kind, acc in accuracy.items():
        print(f"held out, {kind}: species right {acc:.1%} ({len(held[kind][1])} drawings)")
    print(f"temperature {clf.temperature:.2f}; wrote {out} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
