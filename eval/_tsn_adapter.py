"""Adapter from a TSN checkpoint (``tsn.predict`` / ``tsn.encoding``) to ``eval.report.Backend``.

``backend(checkpoint)`` loads the checkpoint once and exposes:

* ``predict``: sketch -> parameters decoded and projected onto the identified species;
* ``predict_normalised``: sketches -> the raw network output, normalised ``(N, 4, 62)``
  (the paper's 1-RMSE is computed on this);
* ``normalise_targets``: dictionaries -> normalised targets with the checkpoint's normaliser;
* ``species_of``: Algorithm 1 (the checkpoint's characteristic parameters) on a dictionary;
* ``tsn_model`` (an extra attribute): the loaded ``tsn.predict.TSNModel``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np


def backend(checkpoint: str | Path | None = None, name: str | None = None):
    try:
        from tsn import encoding
        from tsn import predict as tsn_predict
    except ImportError as e:  # pragma: no cover - tsn is part of the project
        raise RuntimeError(
            f"tsn.predict is not available ({e}); cannot evaluate a checkpoint"
        ) from e
    from .report import Backend

    try:
        model = tsn_predict.load_model(checkpoint)
    except tsn_predict.CheckpointError as e:
        raise FileNotFoundError(str(e)) from None

    def predict(img: np.ndarray):
        return model.predict(img).params

    def predict_normalised(imgs: np.ndarray) -> np.ndarray:
        return model.raw_batch(list(imgs))

    def normalise_targets(ps: Sequence[Mapping]) -> np.ndarray:
        return np.stack([model.normaliser.normalise(encoding.encode(p)) for p in ps])

    def species_of(params: Mapping) -> str:
        return model.species_id.identify(params)

    info = model.info
    label = name or f"TSN {model.net.backbone_name} ({Path(str(model.loaded.path)).name})"
    b = Backend(
        name=label,
        predict=predict,
        predict_normalised=predict_normalised,
        normalise_targets=normalise_targets,
        species_of=species_of,
        info={
            "checkpoint": str(model.loaded.path),
            "backbone": model.net.backbone_name,
            "input size": model.size,
            "epoch": info.get("epoch"),
        },
    )
    b.tsn_model = model  # type: ignore[attr-defined] - for callers that need the Prediction
    return b
