"""Which species a drawing is: the network's scores and the synthesis distances together.

The estimator gives a score per species (the TSN checkpoint's calibrated classifier: a
probability); refining a species gives the distance of its best tree's sketch to the
drawing.  Neither alone is enough: a confident network can be overruled by a filled crown
that happens to cover a palm's fronds, and a network that has never seen a drawing's style
can be wrong where the synthesis is right.  The posterior of species ``s`` is

    p(s) ∝ score(s) ** NET_WEIGHT * exp(-distance(s) / DISTANCE_SCALE)

over the candidates that were refined (a species not refined has no distance and keeps
its share of the estimator's score: ``UNREFINED_PENALTY`` times the worst refined
distance stands in for it).  ``NET_WEIGHT`` and ``DISTANCE_SCALE`` were fitted on 66
held-out drawings of trees in SG, doodles and hand-style doodles (``benchmarks/
bench_species.py calibrate``; RESULTS.md, "The species people draw"): the likelihood is
best with the network's weight 1 and the distance's scale going to infinity, i.e. at the
shipped network's calibration the refined distances add no information on their own; a
scale of 2 (a distance lower by 0.3 moves the odds by 16 %) keeps them as a tie-breaker
between species the network hesitates over, as accurate (90.9 %) with an ECE of 0.078.

:func:`describe` puts the outcome in words: "a palm; could also be a cherry".
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from weberpenn import TreeParams, species

__all__ = [
    "DISTANCE_SCALE",
    "NET_WEIGHT",
    "Candidate",
    "describe",
    "posterior",
]

NET_WEIGHT = 1.0
DISTANCE_SCALE = 2.0
UNREFINED_PENALTY = 1.25
SCORE_FLOOR = 1e-4  # a species the network rules out can still win on a clear distance
ALSO_SHARE = 0.15  # "could also be" names a species of at least this probability


@dataclass(frozen=True)
class Candidate:
    """One species the drawing could be: its tree, its distance and its probability."""

    species: str
    params: TreeParams
    score: float  # the estimator's score
    distance: float | None  # sketch distance of its best tree (None: not refined)
    probability: float = 0.0
    sketch: np.ndarray | None = field(default=None, compare=False, repr=False)

    @property
    def name(self) -> str:
        return species.common_name(self.species)

    def summary(self) -> dict[str, Any]:
        return {
            "species": self.species,
            "name": self.name,
            "display": species.display_name(self.species),
            "probability": float(self.probability),
            "score": float(self.score),
            "distance": None if self.distance is None else float(self.distance),
            "params": self.params.to_dict(),
        }


def posterior(
    scores: Mapping[str, float],
    distances: Mapping[str, float],
    net_weight: float = NET_WEIGHT,
    distance_scale: float = DISTANCE_SCALE,
) -> dict[str, float]:
    """Probability per species of ``scores`` (see the module text); sums to 1."""
    names = list(dict.fromkeys([*scores, *distances]))
    if not names:
        return {}
    worst = max(distances.values()) if distances else 0.0
    total = sum(max(float(scores.get(s, 0.0)), 0.0) for s in names) or 1.0
    logit = {}
    for s in names:
        p = max(float(scores.get(s, 0.0)) / total, SCORE_FLOOR)
        d = distances.get(s, UNREFINED_PENALTY * worst)
        logit[s] = net_weight * math.log(p) - float(d) / distance_scale
    top = max(logit.values())
    e = {s: math.exp(v - top) for s, v in logit.items()}
    z = sum(e.values())
    return {s: v / z for s, v in e.items()}


def describe(candidates: list[Candidate]) -> str:
    """The result in words: "a palm (87 %); could also be a cherry"."""
    if not candidates:
        return ""
    best, *rest = sorted(candidates, key=lambda c: -c.probability)
    text = f"{_article(best.name)} {best.name} ({best.probability:.0%})"
    also = [c.name for c in rest if c.probability >= ALSO_SHARE]
    if also:
        text += "; could also be " + " or ".join(f"{_article(n)} {n}" for n in also)
    return text


def _article(name: str) -> str:
    return "an" if name[:1].lower() in "aeiou" else "a"
