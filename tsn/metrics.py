"""The paper's metric: 1 - RMSE per output head on normalised ``(N, 4, 62)`` matrices.

Each head's RMSE is taken over every sample, row and column of that head's keys; "overall"
is the plain mean of the six head scores.  Training validates with it and the evaluations
report it (``eval.metrics`` re-exports it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from weberpenn.params import HEAD_KEYS, HEADS, PREDICTED_KEYS

__all__ = ["Scores", "one_minus_rmse"]

_COLUMN = {k: i for i, k in enumerate(PREDICTED_KEYS)}


@dataclass(frozen=True)
class Scores:
    """1-RMSE per head and overall, plus the per-key RMSE (normalised units)."""

    heads: dict[str, float]
    overall: float
    key_rmse: dict[str, float]
    n: int

    def hardest(self, k: int = 10) -> list[tuple[str, str, float]]:
        """The ``k`` keys with the largest RMSE: (key, head, rmse)."""
        head_of = {key: h for h in HEADS for key in HEAD_KEYS[h]}
        ranked = sorted(self.key_rmse.items(), key=lambda kv: -kv[1])
        return [(key, head_of[key], v) for key, v in ranked[:k]]


def _check(name: str, a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 2:
        a = a[None]
    if a.ndim != 3 or a.shape[1:] != (4, len(PREDICTED_KEYS)):
        raise ValueError(
            f"{name}: expected normalised target matrices of shape (N, 4, {len(PREDICTED_KEYS)}),"
            f" got {a.shape}"
        )
    if not np.isfinite(a).all():
        raise ValueError(f"{name}: contains NaN or infinity")
    return a


def one_minus_rmse(pred: np.ndarray, target: np.ndarray) -> Scores:
    """Score normalised predictions against normalised targets (both ``(N, 4, 62)``)."""
    p, t = _check("pred", pred), _check("target", target)
    if p.shape != t.shape:
        raise ValueError(f"pred has shape {p.shape} but target has {t.shape}")
    if not len(p):
        raise ValueError("no samples to score")
    sq = (p - t) ** 2
    heads = {}
    for h in HEADS:
        cols = [_COLUMN[k] for k in HEAD_KEYS[h]]
        heads[h] = float(1.0 - np.sqrt(sq[:, :, cols].mean()))
    key_rmse = {k: float(np.sqrt(sq[:, :, _COLUMN[k]].mean())) for k in PREDICTED_KEYS}
    return Scores(heads, float(np.mean([heads[h] for h in HEADS])), key_rmse, len(p))
