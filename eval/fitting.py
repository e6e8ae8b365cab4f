"""Drawings and network readings for fitting a checkpoint's small classifiers.

The species classifier (``scripts/fit_species_classifier.py``) and the tree detector
(``scripts/fit_tree_detector.py``) are fitted on drawings made by code: trees of every
species drawn in the renderer's styles (:func:`styled_trees`), and the doodles of
``eval.doodles``.  :func:`read_drawings` puts each through the pipeline's own reader and
preparation (given by the caller: this package sits below the pipeline), as at inference,
and returns what the classifiers read.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from render.reader import SketchError
from render.sketch import SketchRenderer
from render.styles import STYLES, Silhouettes, draw
from weberpenn import build_mesh, grow, species

__all__ = ["accepted", "read_drawings", "styled_trees"]


def styled_trees(seed0: int, n: int) -> tuple[list[np.ndarray], list[str]]:
    """``n`` trees (tree seeds from ``seed0``) and their species, the species and the
    renderer's styles in turn, each seen from a random view."""
    rng = np.random.default_rng(seed0)
    names, out, labels = list(STYLES), [], []
    for k in range(n):
        name = species.SPECIES[k % len(species.SPECIES)]
        renderer = SketchRenderer(
            build_mesh(grow(species.sample(name, seed0 + k)), species=name), species=name
        )
        parts = renderer.parts(float(rng.uniform(0.0, 360.0)), 256)
        out.append(draw(names[k % len(names)], Silhouettes.from_parts(parts), rng, 256))
        labels.append(name)
    return out, labels


def accepted(
    images: Sequence[Any], prepare: Callable[[Any], np.ndarray]
) -> tuple[list[np.ndarray], np.ndarray]:
    """The images the pipeline accepts, prepared (``prepare``: its reader and preparation;
    a blank page is refused before the network sees it), and which they were (bool)."""
    prepared, kept = [], []
    for im in images:
        try:
            prepared.append(prepare(im))
            kept.append(True)
        except SketchError:
            kept.append(False)
    return prepared, np.asarray(kept, bool)


def read_drawings(
    model: Any,
    images: Sequence[Any],
    prepare: Callable[[Any], np.ndarray],
    batch: int = 32,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(outputs (N, 4, 62) un-normalised, features (N, m) as ``tsn.predict`` makes them,
    kept (len(images),) bool)`` of the drawings the pipeline accepts (``prepare``: its reader and preparation;
    a blank page is refused before the network sees it, so it is left out here too);
    ``model`` is a ``tsn.predict.TSNModel``."""
    prepared, kept = accepted(images, prepare)
    mats, pooled = [], []
    for i in range(0, len(prepared), batch):
        raw, feats = model.raw_and_features(prepared[i : i + batch])
        mats.append(model.normaliser.denormalise(raw))
        pooled.append(feats)
    if not prepared:
        return np.zeros((0, 4, 62)), np.zeros((0, 0)), kept
    return np.concatenate(mats), np.concatenate(pooled), kept
