"""What the 1-RMSE table needs from a model, and small helpers shared by the evaluations.

A :class:`Scorer` maps sketches to the model's normalised ``(N, 4, 62)`` output and
parameter dictionaries to normalised targets on the same scale (the paper's 1-RMSE is
computed on these).  :func:`tsn_scorer` makes one from a loaded TSN model; the
nearest-neighbour baseline makes its own (``eval.baseline.NNSIndex.scorer``).  First
estimates and refinements are not made here: the evaluations run a pipeline
(``treesketch.Pipeline``) handed to them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from render.reader import read_sketch

__all__ = ["Scorer", "dataset_sketch", "progress_bar", "tsn_scorer"]


@dataclass
class Scorer:
    name: str
    # (sketches (N,H,W) uint8) -> normalised network output (N, 4, 62)
    predict_normalised: Callable[[np.ndarray], np.ndarray]
    # parameter dictionaries -> normalised targets (N, 4, 62)
    normalise_targets: Callable[[Sequence[Mapping]], np.ndarray]
    info: dict = field(default_factory=dict)


def tsn_scorer(model: Any, name: str | None = None) -> Scorer:
    """A :class:`Scorer` over a loaded ``tsn.predict.TSNModel``."""
    from tsn import encoding

    def normalise_targets(ps: Sequence[Mapping]) -> np.ndarray:
        return np.stack([model.normaliser.normalise(encoding.encode(p)) for p in ps])

    label = name or f"TSN {model.net.backbone_name} ({Path(str(model.loaded.path)).name})"
    return Scorer(
        name=label,
        predict_normalised=lambda imgs: model.raw_batch(list(imgs)),
        normalise_targets=normalise_targets,
        info={
            "checkpoint": str(model.loaded.path),
            "backbone": model.net.backbone_name,
            "input size": model.size,
            "epoch": model.info.get("epoch"),
        },
    )


def dataset_sketch(path: str | Path) -> np.ndarray:
    """A dataset's sketch PNG as uint8 grey (the one reader)."""
    return read_sketch(path)


def progress_bar(
    iterable: Iterable[Any], desc: str, total: int | None = None, enabled: bool = True
) -> Iterable[Any]:
    if not enabled:
        return iterable
    from tqdm.auto import tqdm

    return tqdm(iterable, desc=desc, total=total, leave=False, dynamic_ncols=True)
