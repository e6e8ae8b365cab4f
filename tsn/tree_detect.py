"""Is the drawing a tree at all?  A calibrated probability from the network's features.

The refinement's distances say how well the best tree's sketch fits a drawing; they
cannot tell a quick doodle of a tree (a lollipop, a cloud on a stick: far from any
Weber-Penn tree's sketch) from a house.  The network has seen thousands of trees in every
style, and the pooled features its six heads read describe a drawing much more richly.
:class:`TreeDetector` is a logistic regression on those features (standardised, L2),
fitted on drawings of trees (the renderer's styles, hand-style tree doodles) and of other
things (``eval.doodles`` non-tree doodles), its temperature on held-out ones so its
probability means what it says.  It lives inside the checkpoint (``tree_detector``),
since it reads that network's features; ``scripts/fit_tree_detector.py`` fits it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["TreeDetector"]


@dataclass(frozen=True)
class TreeDetector:
    """P(tree) from ``(N, m)`` pooled network features."""

    mean: np.ndarray  # (m,)
    std: np.ndarray  # (m,)
    weight: np.ndarray  # (m,)
    bias: float
    temperature: float = 1.0

    @classmethod
    def fit(
        cls,
        features: np.ndarray,
        is_tree: Sequence[bool],
        held_out: tuple[np.ndarray, Sequence[bool]] | None = None,
        l2: float = 1e-2,
        weights: Sequence[float] | None = None,
    ) -> TreeDetector:
        """Fit on features and labels (classes weighted equally, so the ratio of trees
        to other drawings in the fitting set does not move the threshold; within a class,
        each drawing by its ``weights``, default equal); the temperature on ``held_out``
        when given."""
        import torch
        from scipy.optimize import minimize_scalar

        x = np.asarray(features, np.float64)
        y = np.asarray(is_tree, bool)
        if x.ndim != 2 or len(x) != len(y) or y.all() or not y.any():
            raise ValueError("fit needs (N, m) features and both trees and other drawings")
        mean, std = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-6)
        xt = torch.from_numpy((x - mean) / std)
        yt = torch.from_numpy(y.astype(np.float64))
        given = np.ones(len(y)) if weights is None else np.asarray(weights, np.float64)
        if given.shape != y.shape or (given < 0).any():
            raise ValueError("weights must be one non-negative number per drawing")
        pos, neg = float(given[y].sum()), float(given[~y].sum())
        wt = torch.from_numpy(given * np.where(y, 0.5 / pos, 0.5 / neg) * len(y))
        w = torch.zeros(x.shape[1], dtype=torch.float64, requires_grad=True)
        b = torch.zeros(1, dtype=torch.float64, requires_grad=True)
        opt = torch.optim.LBFGS([w, b], max_iter=500, line_search_fn="strong_wolfe")

        def closure() -> torch.Tensor:
            opt.zero_grad()
            z = xt @ w + b
            bce = torch.nn.functional.binary_cross_entropy_with_logits(z, yt, weight=wt)
            loss = bce + l2 * (w**2).sum()
            loss.backward()
            return loss

        opt.step(closure)
        out = cls(mean, std, w.detach().numpy(), float(b.detach().numpy()[0]))
        if held_out is None or len(held_out[1]) == 0:
            return out
        z = out.logits(held_out[0])
        yh = np.asarray(held_out[1], bool)

        def nll(t: float) -> float:
            logp = -np.logaddexp(0.0, -np.where(yh, z, -z) / t)
            return float(-logp.mean())

        t = float(minimize_scalar(nll, bounds=(0.05, 20.0), method="bounded").x)
        return cls(out.mean, out.std, out.weight, out.bias, t)

    def logits(self, features: np.ndarray) -> np.ndarray:
        x = (np.asarray(features, np.float64) - self.mean) / self.std
        return x @ self.weight + self.bias

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        """``(N,)`` calibrated probabilities that each drawing is a tree."""
        z = self.logits(features) / self.temperature
        return 1.0 / (1.0 + np.exp(-z))

    def to_dict(self) -> dict[str, Any]:
        return {
            "mean": self.mean.tolist(),
            "std": self.std.tolist(),
            "weight": self.weight.tolist(),
            "bias": float(self.bias),
            "temperature": float(self.temperature),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TreeDetector:
        arrays = [np.asarray(d[k], np.float64) for k in ("mean", "std", "weight")]
        if not (arrays[0].shape == arrays[1].shape == arrays[2].shape and arrays[0].ndim == 1):
            raise ValueError("tree detector: mean, std and weight must be vectors of one length")
        return cls(*arrays, float(d["bias"]), float(d.get("temperature", 1.0)))
