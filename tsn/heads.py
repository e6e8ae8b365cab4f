"""Refit the network's six heads on its frozen pooled features (weighted ridge regression).

Each head is ``Dropout -> Linear`` on the backbone's pooled features (``tsn.model.TSN``),
so with the backbone frozen the least-squares heads have a closed form. Gradient training
leaves them short of it: the shipped network's heads, after five epochs over eleven
species, score under the paper on three of the six heads on the paper's own test split,
while the least-squares heads on the very same features score above it (RESULTS.md, "The
heads refitted on frozen features"). The species classifier and the tree detector read
these same features, so a refit leaves them valid as they are.

* :class:`HeadData`: features, normalised targets and a weight (each dataset's share of
  the fit, whatever its size);
* :class:`RidgeFit`: the weighted, centred Gram matrix decomposed once, so the heads for
  any ridge strength cost one matrix product (:meth:`RidgeFit.heads`);
* :func:`choose_ridge`: per head, the strength of a grid with the least weighted
  validation error;
* :func:`head_outputs` and :func:`set_heads`: use heads on features, write them into a
  :class:`~tsn.model.TSN`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import torch

from weberpenn.params import HEADS

from . import encoding
from .model import TSN

__all__ = [
    "RIDGE_GRID",
    "HeadData",
    "Heads",
    "RidgeFit",
    "choose_ridge",
    "head_errors",
    "head_outputs",
    "heads_of",
    "set_heads",
]

# ridge strengths tried (times the mean feature variance): weak enough to fit the fixed
# values of a species nearly exactly, strong enough to keep noisy heads smooth
RIDGE_GRID = tuple(10.0 ** (k / 2) for k in range(-20, 3))  # 1e-10 .. 10

Heads = dict[str, tuple[np.ndarray, np.ndarray]]  # head -> (weight (4n, m), bias (4n,))


@dataclass(frozen=True)
class HeadData:
    """Pooled features ``(n, m)``, normalised targets ``(n, 4, 62)`` and the dataset's
    weight (its share of the fit or of the validation error, however many rows it has)."""

    features: np.ndarray
    targets: np.ndarray
    weight: float = 1.0

    def __post_init__(self) -> None:
        f, t = np.asarray(self.features), np.asarray(self.targets)
        if f.ndim != 2 or t.ndim != 3 or len(f) != len(t) or not len(f):
            raise ValueError(
                f"features (n, m) and targets (n, 4, 62) of the same n > 0 expected, got "
                f"{f.shape} and {t.shape}"
            )
        if not (np.isfinite(self.weight) and self.weight > 0):
            raise ValueError(f"a dataset's weight must be a positive number, got {self.weight}")
        if not (np.isfinite(f).all() and np.isfinite(t).all()):
            raise ValueError("features or targets contain NaN or infinity")


def _columns() -> dict[str, np.ndarray]:
    """Each head's columns in a flattened ``(4, 62)`` matrix, in its Linear's output order."""
    idx = np.arange(4 * 62, dtype=np.float64).reshape(4, 62)
    return {h: v.reshape(-1).astype(int) for h, v in encoding.split_heads(idx).items()}


class RidgeFit:
    """Weighted ridge regression of the targets on the features, decomposed once."""

    def __init__(self, data: Sequence[HeadData]) -> None:
        if not data:
            raise ValueError("no data to fit the heads on")
        m = {d.features.shape[1] for d in data}
        if len(m) != 1:
            raise ValueError(f"the datasets' features differ in width: {sorted(m)}")
        x = np.concatenate([d.features for d in data]).astype(np.float64)
        y = np.concatenate([d.targets.reshape(len(d.targets), -1) for d in data])
        w = np.concatenate([np.full(len(d.features), d.weight / len(d.features)) for d in data])
        w = w / w.sum()
        self.mean_x = w @ x
        self.mean_y = w @ y
        xc = x - self.mean_x
        gram = xc.T @ (w[:, None] * xc)
        self.scale = float(np.trace(gram)) / len(gram)  # mean feature variance
        self.evals, self.evecs = np.linalg.eigh(gram)
        self.proj = self.evecs.T @ (xc.T @ (w[:, None] * (y - self.mean_y)))

    def heads(self, strength: float | Mapping[str, float]) -> Heads:
        """The heads at one ridge strength, or one per head."""
        cols = _columns()
        out: Heads = {}
        cache: dict[float, np.ndarray] = {}
        for h in HEADS:
            lam = float(strength[h] if isinstance(strength, Mapping) else strength)
            if lam not in cache:
                inv = 1.0 / np.maximum(self.evals + lam * self.scale, 1e-30)
                cache[lam] = self.evecs @ (inv[:, None] * self.proj)
            coef = cache[lam][:, cols[h]]
            bias = self.mean_y[cols[h]] - self.mean_x @ coef
            out[h] = (coef.T.astype(np.float32), bias.astype(np.float32))
        return out


def head_outputs(heads: Heads, features: np.ndarray) -> np.ndarray:
    """Normalised ``(n, 4, 62)`` outputs of the heads for pooled features ``(n, m)``."""
    f = np.asarray(features, dtype=np.float32)
    return encoding.join_heads(
        {h: (f @ w.T + b).reshape(len(f), 4, -1) for h, (w, b) in heads.items()}
    )


def head_errors(heads: Heads, data: Sequence[HeadData]) -> dict[str, float]:
    """Per head, the weighted mean over the datasets of each one's mean squared error."""
    total = sum(d.weight for d in data)
    out = dict.fromkeys(HEADS, 0.0)
    for d in data:
        err = encoding.split_heads(head_outputs(heads, d.features) - d.targets)
        for h in HEADS:
            out[h] += d.weight / total * float(np.mean(err[h] ** 2))
    return out


def choose_ridge(
    fit: RidgeFit, val: Sequence[HeadData], grid: Sequence[float] = RIDGE_GRID
) -> tuple[dict[str, float], dict[float, dict[str, float]]]:
    """Per head, the strength of ``grid`` with the least weighted validation error, and
    every strength's errors (``{strength: {head: mse}}``)."""
    if not grid:
        raise ValueError("an empty grid of ridge strengths")
    table = {float(lam): head_errors(fit.heads(float(lam)), val) for lam in grid}
    best = {h: min(table, key=lambda lam, h=h: table[lam][h]) for h in HEADS}
    return best, table


def heads_of(model: TSN) -> Heads:
    """The model's own heads as arrays."""
    return {
        h: (
            m[1].weight.detach().float().cpu().numpy(),
            m[1].bias.detach().float().cpu().numpy(),
        )
        for h, m in model.heads.items()
    }


@torch.no_grad()
def set_heads(model: TSN, heads: Heads) -> None:
    """Write ``heads`` into ``model``'s Linear layers (shapes checked first)."""
    for h in HEADS:
        lin = model.heads[h][1]
        w, b = heads[h]
        if tuple(w.shape) != tuple(lin.weight.shape) or tuple(b.shape) != tuple(lin.bias.shape):
            raise ValueError(
                f"head {h}: weights {w.shape} and bias {b.shape} do not fit the network's "
                f"{tuple(lin.weight.shape)} and {tuple(lin.bias.shape)}"
            )
    for h in HEADS:
        lin = model.heads[h][1]
        lin.weight.copy_(torch.from_numpy(np.ascontiguousarray(heads[h][0])))
        lin.bias.copy_(torch.from_numpy(np.ascontiguousarray(heads[h][1])))
