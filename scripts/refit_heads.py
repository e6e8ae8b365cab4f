"""Refit a TSN checkpoint's six heads on its frozen features (weighted ridge regression).

    .venv/bin/python scripts/refit_heads.py --data DS_PEOPLE:1 --data DS_V1:16 \
        [--checkpoint checkpoints/tsn_lite0.pt] [--cache DIR] [--out PT]

Every sketch of each dataset's ``train`` split, and its mirror image, goes through the
network as at inference (the drawing normaliser first when the checkpoint was trained on
normalised drawings); the heads are then the ridge solution on the pooled features
(``tsn.heads``), each dataset weighted by the number after its colon (its share of the
fit, whatever its size), each head's strength chosen on the ``val`` splits, weighted the
same way. The backbone, normaliser, species classifier and tree detector are not touched
(the last two read the same features). Printed: each dataset's ``test`` split (when it
has one) scored before and after, beside the paper's figures. Reading the features costs
about 50 ms a sketch on two cores; ``--cache`` keeps them for a rerun.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

from eval.metrics import PAPER_ONE_MINUS_RMSE, format_table, one_minus_rmse
from eval.scoring import dataset_sketch
from eval.stamp import file_sha256
from render.dataset import read_manifest
from treesketch.pipeline import prepare_input
from tsn import encoding
from tsn.checkpoint import CheckpointError, load_checkpoint, save_loaded
from tsn.heads import HeadData, RidgeFit, choose_ridge, head_outputs, heads_of, set_heads
from tsn.predict import DEFAULT_CHECKPOINT, TSNModel
from weberpenn import TreeParams


def dataset_arg(text: str) -> tuple[Path, float]:
    path, _, weight = text.partition(":")
    try:
        w = float(weight) if weight else 1.0
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: the weight after ':' is not a number"
        ) from None
    if not (np.isfinite(w) and w > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: the weight must be positive")
    if not (Path(path) / "manifest.csv").is_file():
        raise argparse.ArgumentTypeError(f"{path}: not a dataset (no manifest.csv)")
    return Path(path), w


def read_split(
    model: TSNModel, data: Path, split: str, normalise: bool, cache: Path | None, sha: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(features, mirror features, normalised targets)`` of a split, or None if empty."""
    rows = read_manifest(data, split=split)
    if not rows:
        return None
    key = hashlib.sha256(f"{sha} {data.resolve()} {split} {normalise} {len(rows)}".encode())
    path = None if cache is None else cache / f"heads_{key.hexdigest()[:16]}.npz"
    if path is not None and path.is_file():
        z = np.load(path)
        return z["f"], z["fm"], z["t"]
    f, fm, targets, params = [], [], [], {}
    t0 = time.perf_counter()
    for s in range(0, len(rows), 32):
        chunk = rows[s : s + 32]
        imgs = [dataset_sketch(data / r["sketch"]) for r in chunk]
        a, b = model.pooled_features([prepare_input(i) for i in imgs] if normalise else imgs)
        f.append(a)
        fm.append(b)
        for r in chunk:
            if r["params"] not in params:
                p = TreeParams(json.loads((data / r["params"]).read_text(encoding="utf-8")))
                params[r["params"]] = model.normaliser.normalise(encoding.encode(p))
            targets.append(params[r["params"]])
    out = np.concatenate(f), np.concatenate(fm), np.stack(targets)
    print(f"{data.name} {split}: {len(rows)} sketches read ({time.perf_counter() - t0:.0f} s)")
    if path is not None:
        cache.mkdir(parents=True, exist_ok=True)
        np.savez(path, f=out[0], fm=out[1], t=out[2])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT)
    ap.add_argument(
        "--data", type=dataset_arg, action="append", required=True, metavar="DS[:WEIGHT]"
    )
    ap.add_argument("--cache", type=Path, default=None, help="keep the features here")
    ap.add_argument("--out", type=Path, default=None, help="default: --checkpoint")
    args = ap.parse_args()
    t0 = time.perf_counter()
    for data, _ in args.data:  # every dataset checked before any sketch is read
        if not read_manifest(data, split="train") or not read_manifest(data, split="val"):
            raise SystemExit(f"error: {data} needs a train and a val split")
    try:
        loaded = load_checkpoint(args.checkpoint)
    except CheckpointError as exc:
        raise SystemExit(f"error: {exc}") from None
    model = TSNModel(loaded)
    normalise = bool(loaded.info.get("config", {}).get("normalise", False))
    sha = file_sha256(args.checkpoint)
    train, val, test = [], [], {}
    for data, weight in args.data:
        got = {
            s: read_split(model, data, s, normalise, args.cache, sha)
            for s in ("train", "val", "test")
        }
        assert got["train"] is not None and got["val"] is not None  # checked above
        f, fm, t = got["train"]
        train.append(HeadData(np.concatenate([f, fm]), np.concatenate([t, t]), weight))
        f, fm, t = got["val"]
        val.append(HeadData(0.5 * (f + fm), t, weight))  # what predict reads (flip)
        if got["test"] is not None:
            test[data.name] = got["test"]
    fit = RidgeFit(train)
    strength, table = choose_ridge(fit, val)
    old, new = heads_of(loaded.model), fit.heads(strength)
    for name, (f, fm, t) in test.items():
        x = 0.5 * (f + fm)
        print(f"\n{name} test split ({len(t)} sketches), 1-RMSE of predict's output:\n")
        print(format_table({
            "paper EfficientNet-B7 (SG test)": PAPER_ONE_MINUS_RMSE,
            "heads before": one_minus_rmse(head_outputs(old, x), t),
            "heads refitted": one_minus_rmse(head_outputs(new, x), t),
        }))  # fmt: skip
    set_heads(loaded.model, new)
    info = {
        **loaded.info,
        "heads": {
            "refit": "weighted ridge on frozen pooled features (tsn.heads)",
            "datasets": {str(d): w for d, w in args.data},
            "strength": strength,
            "val_mse": {f"{k:g}": v for k, v in table.items()},
            "from": sha,
            "command": " ".join(sys.argv),
        },
    }
    out = args.out or args.checkpoint
    save_loaded(loaded, out, info)
    print(f"\nstrength per head {strength}; wrote {out} ({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
