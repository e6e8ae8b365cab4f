"""TSN, the TreeSketchNet regressor: target encoding, model, training, prediction, species.

``from tsn import load_model`` works; torch is imported on first use of these names, not
when a light submodule (``tsn.encoding``) is imported.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["CheckpointError", "Prediction", "TSNModel", "load_model", "preprocess"]

_HOME = {
    "CheckpointError": "tsn.checkpoint",
    "Prediction": "tsn.predict",
    "TSNModel": "tsn.predict",
    "load_model": "tsn.predict",
    "preprocess": "tsn.predict",
}


def __getattr__(name: str) -> Any:
    if name in _HOME:
        return getattr(importlib.import_module(_HOME[name]), name)
    raise AttributeError(f"module 'tsn' has no attribute {name!r}")
