"""`treesketch eval tsn`: the paper-style 1-RMSE table of a TSN checkpoint on a split.

Scores every sketch of the split (held-out trees, every view):

* **raw**: 1-RMSE per head and overall on the normalised network output for the sketch
  alone, the paper's definition (``eval.metrics.one_minus_rmse``);
* **flip**: the same on the output ``tsn.predict`` uses by default, the mean over the
  sketch and its mirror image (test-time averaging, ``TSNModel.flip``);
* **decoded+projected**: the same on the dictionary ``tsn.predict`` returns (decoded,
  then projected onto the identified species), re-encoded and normalised;
* species identification accuracy (Algorithm 1 on the output ``tsn.predict`` uses).
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import numpy as np
import typer

from .cli_common import checkpoint_option, dataset_option, fail, styles_kept, styles_option


def evaluate(
    data: Path,
    checkpoint: Path | None = None,
    split: str = "test",
    batch: int = 32,
    max_sketches: int | None = None,
    bar: bool = True,
    styles: tuple[str, ...] | None = None,
    normalise: bool | None = None,
) -> dict[str, Any]:
    """Scores of a checkpoint on ``split`` of the dataset at ``data`` (only its sketches
    drawn in ``styles`` when given); with ``normalise``, each sketch first goes through the
    drawing normaliser, as ``predict`` and the service feed the network (``None``: as the
    checkpoint was trained)."""
    from eval.metrics import one_minus_rmse
    from eval.scoring import dataset_sketch, progress_bar, tsn_scorer
    from render.dataset import read_manifest
    from tsn import encoding
    from weberpenn import TreeParams

    rows = read_manifest(data, split=split, styles=styles)
    if max_sketches is not None:
        rows = rows[:max_sketches]
    if not rows:
        what = f" in the styles {', '.join(styles)}" if styles else ""
        raise ValueError(f"{data}: the {split!r} split is empty{what}")
    from .estimators import TSNEstimator
    from .pipeline import prepare_input

    model = TSNEstimator.load(checkpoint).model
    if normalise is None:
        normalise = bool(model.info.get("config", {}).get("normalise", False))
    b = tsn_scorer(model)
    raw, flip, proj, tgt, sp_pred, sp_true = [], [], [], [], [], []
    params: dict[str, TreeParams] = {}
    t0 = time.perf_counter()
    starts = range(0, len(rows), batch)
    for s in progress_bar(starts, "eval tsn", len(starts), bar):
        chunk = rows[s : s + batch]
        imgs = [dataset_sketch(data / r["sketch"]) for r in chunk]
        if normalise:
            imgs = [prepare_input(i) for i in imgs]
        (alone, mirror), features = model.views_and_features(imgs)
        out = 0.5 * (alone + mirror)  # what predict uses (flip=True)
        for r, a, o, f in zip(chunk, alone, out, features, strict=True):
            pred = model.from_raw(o, f)
            if r["params"] not in params:
                text = (data / r["params"]).read_text(encoding="utf-8")
                params[r["params"]] = TreeParams(json.loads(text))
            raw.append(a)
            flip.append(o)
            proj.append(model.normaliser.normalise(encoding.encode(pred.params)))
            tgt.append(model.normaliser.normalise(encoding.encode(params[r["params"]])))
            sp_pred.append(pred.species)
            sp_true.append(r["species"])
    seconds = time.perf_counter() - t0
    t = np.stack(tgt)
    per_species = {
        s: float(np.mean([p == s for p, q in zip(sp_pred, sp_true, strict=True) if q == s]))
        for s in dict.fromkeys(sp_true)
    }
    return {
        "raw": one_minus_rmse(np.stack(raw), t),
        "flip": one_minus_rmse(np.stack(flip), t),
        "projected": one_minus_rmse(np.stack(proj), t),
        "species_acc": float(np.mean([p == q for p, q in zip(sp_pred, sp_true, strict=True)])),
        "species_acc_per_species": per_species,
        "n": len(rows),
        "n_trees": len(params),
        "seconds": seconds,
        "checkpoint": b.info["checkpoint"],
        "name": b.name,
        "input": "normalised drawing" if normalise else "dataset sketch",
    }


def format_result(res: dict[str, Any], split: str) -> str:
    from eval.metrics import PAPER_ONE_MINUS_RMSE, format_hardest, format_table

    table = format_table(
        {
            "paper EfficientNet-B7 (SG test)": PAPER_ONE_MINUS_RMSE,
            f"{res['name']}: raw network output": res["raw"],
            f"{res['name']}: + mirror averaging (predict's output)": res["flip"],
            f"{res['name']}: decoded + projected": res["projected"],
        }
    )
    sp = ", ".join(f"{k} {v:.1%}" for k, v in res["species_acc_per_species"].items())
    return (
        f"1-RMSE on the {split!r} split: {res['n']} sketches of {res['n_trees']} held-out trees "
        f"(checkpoint {res['checkpoint']}, input: {res['input']}, {res['seconds']:.0f} s)"
        f"\n\n{table}\n\n"
        f"species identification (Algorithm 1): {res['species_acc']:.2%} ({sp}); paper target 98%"
        f"\n\nhardest keys (predict's output):\n\n{format_hardest(res['flip'], 8)}"
    )


def eval_tsn(
    data: Path = dataset_option(),
    checkpoint: Path | None = checkpoint_option(),
    split: str = typer.Option("test", "--split", help="train, val or test."),
    max_sketches: int | None = typer.Option(
        None, "--max-sketches", help="Score only the first N sketches."
    ),
    json_out: Path | None = typer.Option(None, "--json", help="Also write the numbers as JSON."),
    styles: str | None = styles_option("score"),
    normalise: bool | None = typer.Option(
        None,
        "--normalise/--raw",
        help="Feed each sketch through the drawing normaliser first, as predict and the "
        "service do (paper flattened, ink thresholded, re-framed), or the dataset's pixels "
        "as they are; default: as the checkpoint was trained.",
        show_default=False,
    ),
) -> None:
    """Paper-style table: 1-RMSE per head and overall, species-identification accuracy."""
    from weberpenn.fileio import atomic_write

    keep = styles_kept(styles)
    try:
        res = evaluate(
            data, checkpoint, split, max_sketches=max_sketches, styles=keep, normalise=normalise
        )
    except (RuntimeError, ValueError, OSError) as e:  # DatasetError/CheckpointError too
        fail(str(e))
    typer.echo(format_result(res, split))
    if json_out is not None:
        plain = {
            k: (
                {**v.heads, "overall": v.overall, "key_rmse": v.key_rmse}
                if hasattr(v, "heads")
                else v
            )
            for k, v in res.items()
        }
        atomic_write(json_out, json.dumps(plain, indent=1) + "\n")


def register(eval_app: typer.Typer) -> None:
    """Add `eval tsn` to the eval group."""
    eval_app.command("tsn")(eval_tsn)
