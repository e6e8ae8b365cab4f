"""The estimators behind the seam, and :func:`load_estimator`.

- :class:`TSNEstimator`: the TreeSketchNet regressor (``tsn.predict``), species by the
  paper's Algorithm 1, a score per species (the share of its characteristic parameters
  the output matches).
- :class:`TemplateEstimator`: no network; sampled trees of every species, sketched from
  four yaws, and the closest one (by the sketch distance) starts the search.
- :class:`NNSEstimator`: the nearest-neighbour baseline over a dataset's training sketches
  (``eval.baseline``).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from weberpenn import build_mesh, grow, species

from .estimate import Estimate, Estimator

__all__ = [
    "ESTIMATORS",
    "NNSEstimator",
    "SeededEstimator",
    "TSNEstimator",
    "TemplateEstimator",
    "load_estimator",
]

ESTIMATORS = ("tsn", "template", "nns")
TEMPLATE_SIZE = 128  # the template match compares at the refinement's search size
TEMPLATE_YAWS = (0.0, 90.0, 180.0, 270.0)
SCORE_SCALE = 0.05  # sketch-distance difference that divides a species' score by e


class TSNEstimator:
    """A loaded TSN checkpoint as an :class:`Estimator`."""

    name = "tsn"

    def __init__(self, model: Any) -> None:
        self.model = model  # tsn.predict.TSNModel

    def __reduce__(self) -> tuple[Any, ...]:
        # an executor's worker loads the checkpoint itself instead of receiving the weights
        return (TSNEstimator.load, (str(self.model.loaded.path),))

    @classmethod
    def load(cls, checkpoint: str | os.PathLike[str] | None = None) -> TSNEstimator:
        from tsn.predict import CheckpointError, load_model

        try:
            return cls(load_model(checkpoint))
        except CheckpointError as exc:
            raise ValueError(str(exc)) from None

    def estimate(self, sketch: np.ndarray) -> Estimate:
        with _one_torch_thread():
            raw, features = self.model.raw_and_features([sketch])
        pred = self.model.from_raw(raw[0], features[0])
        scores = self.model.species_id.scores(pred.matrix, features[0])
        tree = self.model.tree_probabilities(features)
        return Estimate(
            pred.params,
            pred.species,
            scores,
            None,
            decoded=pred.decoded,
            tree_probability=None if tree is None else float(tree[0]),
        )


class SeededEstimator:
    """An estimator whose every dictionary carries the given ``seed`` key.

    The seed is not predicted; the paper grows its predictions with the ground truth's
    seed, and so must the refinement that searches the generator's draws it is measured
    with (the report and the published-tree benchmark wrap their estimator in this)."""

    def __init__(self, inner: Estimator, seed: int) -> None:
        self.inner, self.seed, self.name = inner, int(seed), inner.name

    def estimate(self, sketch: np.ndarray) -> Estimate:
        e = self.inner.estimate(sketch)
        s = self.seed
        return dataclasses.replace(
            e,
            params=e.params.replace(seed=s),
            decoded=None if e.decoded is None else e.decoded.replace(seed=s),
            alternatives={k: v.replace(seed=s) for k, v in e.alternatives.items()},
        )


@contextlib.contextmanager
def _one_torch_thread() -> Iterator[None]:
    """Run the network on one thread: a sum split over threads is added in another order,
    which moves the last digits of a prediction, and an executor's workers (one CPU each)
    must give the values this process gives.  A second core is still used: the drawing
    and its mirror run side by side on two threads of one torch thread each
    (``tsn.predict.TSNModel``), which changes no digit."""
    import torch

    n = torch.get_num_threads()
    if n == 1:
        yield
        return
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(n)


def _scores_from_distances(best: dict[str, float]) -> dict[str, float]:
    low = min(best.values())
    return {s: float(math.exp(-(d - low) / SCORE_SCALE)) for s, d in best.items()}


class TemplateEstimator:
    """Closest of ``seeds`` sampled trees per species, each seen from four yaws (the
    species vary a lot within themselves, so one tree each is not enough).  The templates'
    sketches are made once, on first use."""

    name = "template"

    def __init__(self, seeds: int = 3) -> None:
        if seeds < 1:
            raise ValueError(f"seeds must be >= 1, got {seeds}")
        self.seeds = int(seeds)
        self._templates: list[tuple[str, int, float, Any]] | None = None

    def __getstate__(self) -> dict[str, Any]:
        return {"seeds": self.seeds, "_templates": None}  # a worker builds its own

    def _build(self) -> list[tuple[str, int, float, Any]]:
        from refine.objective import draw_side, framed, make_target
        from render.sketch import SketchRenderer

        out = []
        for name in species.SPECIES:
            for seed in range(self.seeds):
                r = SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name))
                for yaw in TEMPLATE_YAWS:
                    img = r.sketch(yaw, draw_side(TEMPLATE_SIZE))
                    target = make_target(framed(img, TEMPLATE_SIZE), TEMPLATE_SIZE)
                    out.append((name, seed, yaw, target))
        return out

    def estimate(self, sketch: np.ndarray) -> Estimate:
        from refine.objective import framed, make_target

        if self._templates is None:
            self._templates = self._build()
        target = make_target(framed(sketch, TEMPLATE_SIZE), TEMPLATE_SIZE)
        best: dict[str, tuple[float, int, float]] = {}
        for name, seed, yaw, cand in self._templates:
            d = target.distance(cand)
            if name not in best or d < best[name][0]:
                best[name] = (d, seed, yaw)
        top = min(best, key=lambda s: best[s][0])
        scores = _scores_from_distances({s: v[0] for s, v in best.items()})
        _, seed, yaw = best[top]
        others = {s: species.sample(s, v[1]) for s, v in best.items() if s != top}
        return Estimate(species.sample(top, seed), top, scores, yaw, alternatives=others)


class NNSEstimator:
    """The nearest-neighbour baseline (``eval.baseline.NNSIndex``) as an estimator."""

    name = "nns"

    def __init__(self, index: Any) -> None:
        self.index = index

    @classmethod
    def load(cls, data: str | os.PathLike[str], max_rows: int | None = 2000) -> NNSEstimator:
        from eval.baseline import NNSIndex

        return cls(NNSIndex.fit(data, max_rows=max_rows, bar=False))

    def estimate(self, sketch: np.ndarray) -> Estimate:
        from refine.search import guess_species

        params = self.index.predict(sketch)
        name = guess_species(params)
        return Estimate(species.project(name, params), name, {name: 1.0}, None)


def load_estimator(
    spec: str | os.PathLike[str] | Estimator = "tsn",
    *,
    checkpoint: str | os.PathLike[str] | None = None,
    data: str | os.PathLike[str] | None = None,
) -> Estimator:
    """``"tsn"`` (the shipped checkpoint, or ``checkpoint``), ``"template"``, ``"nns"``
    (needs ``data``: a dataset folder), a path to a TSN checkpoint, or an estimator (given
    back as it is).  Errors are ValueErrors that say what to give instead."""
    if not isinstance(spec, str | os.PathLike):
        if isinstance(spec, Estimator):
            return spec
        raise ValueError(f"not an estimator: {type(spec).__name__} (needs name and estimate())")
    text = os.fspath(spec)
    if text == "tsn":
        return TSNEstimator.load(checkpoint)
    if text == "template":
        return TemplateEstimator()
    if text == "nns":
        if data is None:
            raise ValueError("the nns estimator needs a dataset folder (data=..., --data DIR)")
        return NNSEstimator.load(data)
    path = Path(text)
    if path.suffix == ".pt" or path.is_file():
        return TSNEstimator.load(path)
    raise ValueError(
        f"unknown estimator {text!r}: give one of {', '.join(ESTIMATORS)} or a .pt checkpoint"
    )
