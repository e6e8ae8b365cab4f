"""Refit a TSN checkpoint's species classifier on its outputs for more kinds of drawing.

    .venv/bin/python scripts/fit_species_classifier.py --checkpoint checkpoints/tsn_lite0.pt \
        --data DS [--doodles 60] [--out checkpoints/tsn_lite0.pt]

The classifier (``tsn.species_id.SpeciesClassifier``) reads the network's output, so it
can learn from drawings that have a species but no exact parameters: besides the
training split of ``--data`` (every style the network was trained on) it is fitted on
``--doodles`` hand-style tree doodles per species (``eval.doodles.tree_doodle``, seeds
from 1000; the benchmarks score seeds below 1000), its temperature on the validation split
and on as many doodles again (seeds from 5000).  Every drawing goes through the pipeline's
own reader and preparation, as at inference.  The network's weights are not touched.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from eval.doodles import TREE_SPECIES, tree_doodle  # noqa: E402
from render.dataset import read_manifest  # noqa: E402
from treesketch.pipeline import load_sketch, prepare_input  # noqa: E402
from tsn.checkpoint import load_checkpoint, save_checkpoint  # noqa: E402
from tsn.predict import TSNModel  # noqa: E402
from tsn.species_id import SpeciesClassifier  # noqa: E402

TRAIN_SEED0 = 1000
HELD_SEED0 = 5000


def outputs(model: TSNModel, images: list, batch: int = 32) -> np.ndarray:
    """Un-normalised ``(N, 4, 62)`` outputs for drawings prepared as the pipeline does."""
    out = []
    for i in range(0, len(images), batch):
        prepared = [prepare_input(load_sketch(im)) for im in images[i : i + batch]]
        out.append(model.normaliser.denormalise(model.raw_batch(prepared)))
    return np.concatenate(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", default=str(ROOT / "checkpoints" / "tsn_lite0.pt"))
    ap.add_argument("--data", required=True, help="the dataset the network was trained on")
    ap.add_argument("--doodles", type=int, default=60, help="hand-style doodles per species")
    ap.add_argument("--out", default=None, help="checkpoint to write (default: --checkpoint)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    loaded = load_checkpoint(args.checkpoint)
    model = TSNModel(loaded)
    data = Path(args.data)
    x, y = [], []
    for split, sink in (("train", (x, y)), ("val", None)):
        rows = read_manifest(data, split=split)
        imgs = [str(data / r["sketch"]) for r in rows]
        labels = [r["species"] for r in rows]
        if sink is None:
            held_x, held_y = outputs(model, imgs), labels
        else:
            sink[0].append(outputs(model, imgs))
            sink[1].extend(labels)
    names = [s for s in TREE_SPECIES if s in loaded.species_id.species]
    for seed0, into in ((TRAIN_SEED0, "train"), (HELD_SEED0, "held")):
        imgs = [tree_doodle(s, seed0 + k) for s in names for k in range(args.doodles)]
        labels = [s for s in names for _ in range(args.doodles)]
        out = outputs(model, imgs)
        if into == "train":
            x.append(out)
            y.extend(labels)
        else:
            held_x = np.concatenate([held_x, out])
            held_y = [*held_y, *labels]
    clf = SpeciesClassifier.fit(
        np.concatenate(x), y, loaded.normaliser.scale, held_out=(held_x, held_y)
    )
    pred = clf.probabilities_many(held_x).argmax(axis=1)
    acc = float(np.mean([clf.species[i] == s for i, s in zip(pred, held_y, strict=True)]))
    n_d = len(names) * args.doodles
    doodle_acc = float(
        np.mean([clf.species[i] == s for i, s in zip(pred[-n_d:], held_y[-n_d:], strict=True)])
    )
    info = {
        **loaded.info,
        "classifier": {
            "data": data.name,
            "doodles_per_species": args.doodles,
            "held_out_accuracy": acc,
            "held_out_doodle_accuracy": doodle_acc,
            "temperature": clf.temperature,
        },
    }
    out = args.out or args.checkpoint
    save_checkpoint(
        out,
        loaded.model,
        loaded.size,
        int(info.get("cut", 12)),
        loaded.normaliser,
        loaded.species_id.with_classifier(clf),
        info,
        loaded.tree_detector,
    )
    print(
        f"classifier: held-out accuracy {acc:.3f} (doodles {doodle_acc:.3f}), temperature "
        f"{clf.temperature:.2f}; wrote {out} ({time.perf_counter() - t0:.0f} s)"
    )


if __name__ == "__main__":
    main()
