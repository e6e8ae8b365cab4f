"""Is the drawing a tree at all?  A calibrated probability from the network's features.

The refinement's distances say how well the best tree's sketch fits a drawing; they
cannot tell a quick doodle of a tree (a lollipop, a cloud on a stick: far from any
Weber-Penn tree's sketch) from a house.  The network has seen thousands of trees in every
style, and the pooled features its six heads read describe a drawing much more richly.
:class:`TreeDetector` is a logistic regression on those features (standardised, L2),
fitted on drawings of trees (the renderer's styles, hand-style tree doodles) and of other
things (``eval.doodles`` non-tree doodles), its temperature on held-out ones so its
probability means what it says.  With ``hidden`` it is instead the mean logit of a few
small one-hidden-layer networks on the same standardised features: on people's drawings
(``scripts/fit_people.py``) they warn more of the other things people draw at the same
rate of trees spared, which one hyperplane in the features cannot.  It lives inside the
checkpoint (``tree_detector``), since it reads that network's features;
``scripts/fit_tree_detector.py`` and ``scripts/fit_people.py`` fit it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

__all__ = ["TreeDetector"]


@dataclass(frozen=True)
class TreeDetector:
    """P(tree) from ``(N, m)`` pooled network features: a logistic regression, or with
    ``hidden_weight`` the mean logit of ``E`` networks of one hidden layer each."""

    mean: np.ndarray  # (m,)
    std: np.ndarray  # (m,)
    weight: np.ndarray  # (m,), or (E, h) each network's output layer
    bias: float | np.ndarray  # or (E,)
    temperature: float = 1.0
    hidden_weight: np.ndarray | None = None  # (E, m, h)
    hidden_bias: np.ndarray | None = None  # (E, h)
    # log-odds added after the temperature: where the warning limit (0.5) falls
    # (:meth:`with_balanced_limit`); 0 for a detector fitted without it
    offset: float = 0.0

    @classmethod
    def fit(
        cls,
        features: np.ndarray,
        is_tree: Sequence[bool],
        held_out: tuple[np.ndarray, Sequence[bool]] | None = None,
        l2: float = 1e-2,
        weights: Sequence[float] | None = None,
        hidden: int = 0,
        members: int = 5,
    ) -> TreeDetector:
        """Fit on features and labels (classes weighted equally, so the ratio of trees
        to other drawings in the fitting set does not move the threshold; within a class,
        each drawing by its ``weights``, default equal); the temperature on ``held_out``
        when given.  ``hidden > 0``: ``members`` networks of ``hidden`` units instead of
        one logistic regression (``l2`` then their weight decay), each from its own seed."""
        import torch

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
        if hidden > 0:
            layers = _fit_networks(xt.float(), yt.float(), wt.float(), hidden, members, l2)
            out = cls(mean, std, layers[2], layers[3], 1.0, layers[0], layers[1])
            return out.with_temperature(held_out)
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
        return out.with_temperature(held_out)

    def with_temperature(self, held_out: tuple[np.ndarray, Sequence[bool]] | None) -> TreeDetector:
        """The same detector, its temperature fitted on ``held_out`` (unchanged without)."""
        from scipy.optimize import minimize_scalar

        if held_out is None or len(held_out[1]) == 0:
            return self
        z = self.logits(held_out[0])
        yh = np.asarray(held_out[1], bool)

        def nll(t: float) -> float:
            logp = -np.logaddexp(0.0, -np.where(yh, z, -z) / t)
            return float(-logp.mean())

        t = float(minimize_scalar(nll, bounds=(0.05, 20.0), method="bounded").x)
        return replace(self, temperature=t)

    def with_balanced_limit(self, features: np.ndarray, is_tree: Sequence[bool]) -> TreeDetector:
        """The same detector, its :attr:`offset` set so that at probability 0.5 the
        drawings given (people's, kept apart from fitting) are judged wrongly as rarely
        on the worse side as can be: the limit that makes the smaller of "trees spared"
        and "other things warned" largest.  The fit weighs both classes equally, yet
        people's trees read less surely than the code-made ones it mostly learned from,
        so at the plain 0.5 they are warned about four times as often as other things
        pass; users mostly draw trees, so neither mistake should be the common one."""
        y = np.asarray(is_tree, bool)
        if len(y) == 0 or y.all() or not y.any():
            raise ValueError("the limit needs both trees and other drawings")
        p = self.probabilities(features)
        limits = np.unique(np.concatenate([p, [0.5]]))
        spared = (p[y][None, :] >= limits[:, None]).mean(axis=1)
        warned = (p[~y][None, :] < limits[:, None]).mean(axis=1)
        worse = np.minimum(spared, warned)
        best = limits[worse == worse.max()]
        # of the limits as good, the one nearest 0.5 (the least moved)
        limit = float(best[np.argmin(np.abs(np.log(best / (1 - best))))])
        limit = min(max(limit, 1e-6), 1 - 1e-6)
        return replace(self, offset=self.offset - float(np.log(limit / (1 - limit))))

    def logits(self, features: np.ndarray) -> np.ndarray:
        x = (np.asarray(features, np.float64) - self.mean) / self.std
        if self.hidden_weight is None or self.hidden_bias is None:
            return x @ self.weight + self.bias
        h = np.maximum(np.einsum("nm,emh->enh", x, self.hidden_weight)
                       + self.hidden_bias[:, None, :], 0.0)  # fmt: skip
        z = np.einsum("enh,eh->en", h, self.weight) + np.asarray(self.bias)[:, None]
        return z.mean(axis=0)

    def probabilities(self, features: np.ndarray) -> np.ndarray:
        """``(N,)`` calibrated probabilities that each drawing is a tree."""
        z = self.logits(features) / self.temperature + self.offset
        return np.exp(-np.logaddexp(0.0, -z))  # 1 / (1 + e^-z) without overflow

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "mean": self.mean.tolist(),
            "std": self.std.tolist(),
            "weight": self.weight.tolist(),
            "bias": np.asarray(self.bias, np.float64).tolist(),
            "temperature": float(self.temperature),
            "offset": float(self.offset),
        }
        if self.hidden_weight is not None and self.hidden_bias is not None:
            out["hidden_weight"] = self.hidden_weight.astype(np.float32).tolist()
            out["hidden_bias"] = self.hidden_bias.tolist()
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> TreeDetector:
        mean, std, weight = (np.asarray(d[k], np.float64) for k in ("mean", "std", "weight"))
        bias = np.asarray(d["bias"], np.float64)
        temperature = float(np.asarray(d.get("temperature", 1.0)))
        offset = float(np.asarray(d.get("offset", 0.0)))
        if not (mean.shape == std.shape and mean.ndim == 1):
            raise ValueError("tree detector: mean and std must be vectors of one length")
        if "hidden_weight" not in d:
            if weight.shape != mean.shape or bias.ndim != 0:
                raise ValueError("tree detector: weight must match mean and bias be a number")
            return cls(mean, std, weight, float(bias), temperature, offset=offset)
        hw = np.asarray(d["hidden_weight"], np.float64)
        hb = np.asarray(d["hidden_bias"], np.float64)
        if not (
            hw.ndim == 3
            and hw.shape[1] == len(mean)
            and hb.shape == (hw.shape[0], hw.shape[2])
            and weight.shape == hb.shape
            and bias.shape == (hw.shape[0],)
        ):
            raise ValueError(
                "tree detector: hidden_weight (E, m, h), hidden_bias and weight (E, h) and "
                "bias (E,) must agree with each other and with mean (m,)"
            )
        return cls(mean, std, weight, bias, temperature, hw, hb, offset)


def _fit_networks(
    x: Any, y: Any, w: Any, hidden: int, members: int, decay: float, epochs: int = 60
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``members`` one-hidden-layer networks on standardised features ``x`` (torch,
    float32), each from seed ``k``: dropout on the inputs and the hidden units keeps them
    from learning the fitting set's few thousand drawings by heart."""
    import torch

    stacked: list[list[np.ndarray]] = [[], [], [], []]
    for k in range(members):
        with torch.random.fork_rng(devices=[]):  # the caller's random state left as it was
            torch.manual_seed(k)  # the layers' initial weights and dropout
            layers = _fit_one(x, y, w, hidden, decay, epochs, torch.Generator().manual_seed(k))
        for out, t in zip(stacked, layers, strict=True):
            out.append(t)
    return (
        np.stack(stacked[0]),
        np.stack(stacked[1]),
        np.stack(stacked[2]),
        np.asarray(stacked[3], np.float64),
    )


def _fit_one(
    x: Any, y: Any, w: Any, hidden: int, decay: float, epochs: int, gen: Any
) -> tuple[np.ndarray, ...]:
    """One network's layers ``(W1 (m, h), b1 (h,), w2 (h,), b2 ())``, batches drawn by
    ``gen``."""
    import torch

    first, last = torch.nn.Linear(x.shape[1], hidden), torch.nn.Linear(hidden, 1)
    net = torch.nn.Sequential(
        torch.nn.Dropout(0.2), first, torch.nn.ReLU(), torch.nn.Dropout(0.3), last
    )
    opt = torch.optim.AdamW(net.parameters(), 1e-3, weight_decay=decay)
    for _ in range(epochs):
        order = torch.randperm(len(y), generator=gen)
        for i in range(0, len(y), 256):
            b = order[i : i + 256]
            z = net(x[b])[:, 0]
            loss = torch.nn.functional.binary_cross_entropy_with_logits(z, y[b], weight=w[b])
            opt.zero_grad()
            loss.backward()
            opt.step()
    with torch.no_grad():
        kept = (first.weight.T, first.bias, last.weight[0], last.bias[0])
        return tuple(t.double().numpy().copy() for t in kept)
