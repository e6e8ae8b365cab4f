"""What an estimator gives: a first guess of the tree before any refinement.

An :class:`Estimator` turns a prepared sketch (square ``uint8``, 255 = white, framed as the
renderer frames a tree) into an :class:`Estimate`: a parameter dictionary, the species it
belongs to, a score per species (higher is more likely; they need not sum to one) and,
when the estimator can tell, the view yaw in degrees and the probability that the drawing
is a tree at all.  TSN, the template match and the
nearest-neighbour baseline implement it (:mod:`treesketch.estimators`); anything with a
``name`` and an ``estimate`` method plugs into :class:`treesketch.Pipeline`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from weberpenn import TreeParams, species

__all__ = ["Estimate", "Estimator"]


@dataclass(frozen=True)
class Estimate:
    """``params`` belong to ``species``; ``alternatives`` may hold the estimator's own
    guess for other species (else :meth:`params_for` projects ``decoded``, the estimate
    before it was fitted to its species, or ``params`` onto the species asked for)."""

    params: TreeParams
    species: str
    species_scores: dict[str, float] = field(default_factory=dict)
    yaw: float | None = None
    decoded: TreeParams | None = None
    alternatives: dict[str, TreeParams] = field(default_factory=dict)
    # the estimator's probability that the drawing is a tree at all (None: it cannot tell)
    tree_probability: float | None = None

    def params_for(self, name: str) -> TreeParams:
        """A starting dictionary for species ``name``."""
        if name == self.species:
            return self.params
        if name in self.alternatives:
            return self.alternatives[name]
        return species.project(name, self.decoded if self.decoded is not None else self.params)

    def ranked(self) -> list[tuple[str, float]]:
        """Species by score, best first (the estimate's own species first on ties)."""
        scores = dict(self.species_scores) or {self.species: 1.0}
        return sorted(scores.items(), key=lambda kv: (-kv[1], kv[0] != self.species))


@runtime_checkable
class Estimator(Protocol):
    name: str

    def estimate(self, sketch: np.ndarray) -> Estimate: ...
