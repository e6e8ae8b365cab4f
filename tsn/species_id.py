"""Species identification, the paper's Algorithm 1.

A *characteristic parameter* (cp) of a species is one value of the target matrix (a key,
and a level for per-level keys) that (i) every training sample of the species has and (ii)
stays within a narrow range there: its spread over the species' training samples is at
most ``span_tol`` in normalised units (the normaliser's divisors).  Its ``value`` is the
middle of that range and its acceptance half-width ``eps`` is half the spread plus
``match_tol`` (normalised units, times the key's divisor).

A dictionary (or a raw network output, as an un-normalised ``(4, 62)`` matrix) counts, for
every species, how many of that species' cps satisfy ``|x - value| <= eps``; the species
with the highest *share* of matching cps wins (ties: the smaller mean normalised distance
over the species' cps).  Everything is plain data (``to_dict``/``from_dict``) so it lives
inside the checkpoint.

A checkpoint may also carry a :class:`SpeciesClassifier`: a multinomial logistic
regression, temperature-scaled on held-out drawings so its probabilities mean what they
say.  It reads either the same output cells (``reads="outputs"``: fitted on the network's
own outputs for its training drawings) or the pooled features the network's heads read
(``reads="features"``: a richer description of the drawing, which tells a lollipop doodle
from a birch's slender crown where the 62 predicted values cannot).  When present it
decides the species and gives the scores (Algorithm 1's shares are counts, not
probabilities, and over eleven species they tie often).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from weberpenn.params import PREDICTED_KEYS, SPECS

from . import encoding

SPAN_TOL = 0.02
MATCH_TOL = 0.05

# cells of the (4, 62) matrix that carry information: all 4 rows of per-level keys, row 0
# of scalars (the other rows repeat it)
_CELLS = np.array(
    [(r, j) for j, k in enumerate(PREDICTED_KEYS) for r in range(4 if SPECS[k].is_vector else 1)]
)


READS = ("outputs", "features")


class SpeciesIdError(ValueError):
    """A species identifier that cannot be built or read."""


@dataclass(frozen=True)
class SpeciesClassifier:
    """Calibrated species probabilities from what it ``reads``: un-normalised ``(N, 4, 62)``
    network outputs, or ``(N, m)`` pooled network features."""

    species: tuple[str, ...]
    mean: np.ndarray  # (m,) of the standardised features
    std: np.ndarray  # (m,)
    weight: np.ndarray  # (k, m)
    bias: np.ndarray  # (k,)
    temperature: float
    scale: np.ndarray  # (62,) normaliser divisors
    reads: str = "outputs"

    @staticmethod
    def features(mats: np.ndarray, scale: np.ndarray) -> np.ndarray:
        """``(N, m)`` informative cells of ``(N, 4, 62)`` outputs, in normalised units."""
        a = np.asarray(mats, dtype=np.float64).reshape(-1, 4, len(PREDICTED_KEYS))
        return a[:, _CELLS[:, 0], _CELLS[:, 1]] / np.asarray(scale, np.float64)[_CELLS[:, 1]]

    @staticmethod
    def design(inputs: np.ndarray, scale: np.ndarray, reads: str) -> np.ndarray:
        """``(N, m)`` regression inputs of what a classifier ``reads``."""
        if reads == "outputs":
            return SpeciesClassifier.features(inputs, scale)
        if reads == "features":
            x = np.asarray(inputs, dtype=np.float64)
            if x.ndim != 2:
                raise SpeciesIdError(f"expected (N, m) pooled features, got shape {x.shape}")
            return x
        raise SpeciesIdError(f"a species classifier reads one of {READS}, not {reads!r}")

    @classmethod
    def fit(
        cls,
        inputs: np.ndarray,
        labels: Sequence[str],
        scale: np.ndarray,
        held_out: tuple[np.ndarray, Sequence[str]] | None = None,
        l2: float = 1e-3,
        reads: str = "outputs",
    ) -> SpeciesClassifier:
        """Fit on what it ``reads`` (``(N, 4, 62)`` outputs or ``(N, m)`` pooled
        features) and their species; the temperature on ``held_out`` (the same kind of
        input, species) when given (else 1)."""
        import torch

        names = tuple(sorted(set(labels), key=list(labels).index))
        x = cls.design(inputs, scale, reads)
        mean, std = x.mean(axis=0), np.maximum(x.std(axis=0), 1e-6)
        y = np.array([names.index(s) for s in labels])
        xt = torch.from_numpy((x - mean) / std)
        yt = torch.from_numpy(y)
        w = torch.zeros((len(names), x.shape[1]), dtype=torch.float64, requires_grad=True)
        b = torch.zeros(len(names), dtype=torch.float64, requires_grad=True)
        opt = torch.optim.LBFGS([w, b], max_iter=500, line_search_fn="strong_wolfe")

        def closure() -> torch.Tensor:
            opt.zero_grad()
            loss = torch.nn.functional.cross_entropy(xt @ w.T + b, yt) + l2 * (w**2).sum()
            loss.backward()
            return loss

        opt.step(closure)
        out = cls(
            names, mean, std, w.detach().numpy(), b.detach().numpy(), 1.0,
            np.asarray(scale, np.float64), reads,
        )  # fmt: skip
        return out if held_out is None else out.calibrated(*held_out)

    def refit(
        self,
        inputs: np.ndarray,
        allowed: Sequence[str | frozenset[str]],
        weights: Sequence[float] | None = None,
        pull: float = 1e-2,
    ) -> SpeciesClassifier:
        """This classifier refitted on more drawings (of the kind it ``reads``), some of
        which are known only as one of a set of species (a tree a person drew is a
        broadleaf or a fir, never a palm): it maximises each drawing's probability of
        its ``allowed`` species (one name, or a set), ``weights`` per drawing, with an L2
        pull of strength ``pull`` toward this classifier's weights, so what it learned
        from drawings not at hand stays.  Its standardisation and the columns it gives no
        weight stay as they are; the temperature is this one's (recalibrate after)."""
        import torch

        x = (self.design(inputs, self.scale, self.reads) - self.mean) / self.std
        mask = np.zeros((len(x), len(self.species)), bool)
        for i, a in enumerate(allowed):
            names = {a} if isinstance(a, str) else set(a)
            unknown = names - set(self.species)
            if unknown or not names:
                raise SpeciesIdError(f"drawing {i}: no known species among {sorted(names)}")
            mask[i, [self.species.index(s) for s in names]] = True
        wt = np.ones(len(x)) if weights is None else np.asarray(weights, np.float64)
        if wt.shape != (len(x),) or (wt < 0).any():
            raise SpeciesIdError("weights must be one non-negative number per drawing")
        used = torch.from_numpy(np.abs(self.weight).sum(axis=0) > 0)
        w0, b0 = torch.from_numpy(self.weight), torch.from_numpy(self.bias)
        xt, wt_t = torch.from_numpy(x), torch.from_numpy(wt / wt.sum())
        log_mask = torch.from_numpy(np.where(mask, 0.0, -np.inf))
        w = w0.clone().requires_grad_(True)
        b = b0.clone().requires_grad_(True)
        opt = torch.optim.LBFGS([w, b], max_iter=500, line_search_fn="strong_wolfe")

        def closure() -> torch.Tensor:
            opt.zero_grad()
            logp = torch.log_softmax(xt @ (w * used).T + b, dim=1)
            nll = -(torch.logsumexp(logp + log_mask, dim=1) * wt_t).sum()
            loss = nll + pull * (((w - w0) * used) ** 2).sum()
            loss.backward()
            return loss

        opt.step(closure)
        weight = (w * used).detach().numpy()
        return dataclasses.replace(self, weight=weight, bias=b.detach().numpy())

    def calibrated(self, inputs: np.ndarray, labels: Sequence[str]) -> SpeciesClassifier:
        """This classifier with the temperature that makes its probabilities most likely
        on held-out ``inputs`` (of the kind it ``reads``) and their species (species it
        does not know are left out; none known: unchanged)."""
        from scipy.optimize import minimize_scalar

        known = [i for i, s in enumerate(labels) if s in self.species]
        if not known:
            return self
        raw = self.logits(np.asarray(inputs)[known])
        yh = np.array([self.species.index(labels[i]) for i in known])

        def nll(t: float) -> float:
            z = raw / t
            z = z - z.max(axis=1, keepdims=True)
            logp = z - np.log(np.exp(z).sum(axis=1, keepdims=True))
            return float(-logp[np.arange(len(yh)), yh].mean())

        t = minimize_scalar(nll, bounds=(0.05, 20.0), method="bounded").x
        return dataclasses.replace(self, temperature=float(t))

    def logits(self, inputs: np.ndarray) -> np.ndarray:
        x = (self.design(inputs, self.scale, self.reads) - self.mean) / self.std
        return x @ self.weight.T + self.bias

    def probabilities_many(self, inputs: np.ndarray) -> np.ndarray:
        """``(N, k)`` calibrated probabilities, columns in ``species`` order, of
        ``(N, ...)`` inputs of the kind it ``reads``."""
        z = self.logits(inputs) / self.temperature
        z = z - z.max(axis=1, keepdims=True)
        e = np.exp(z)
        return e / e.sum(axis=1, keepdims=True)

    def probabilities(self, one: np.ndarray) -> dict[str, float]:
        """Of one input of the kind it ``reads``: a ``(4, 62)`` output or ``(m,)``
        features."""
        p = self.probabilities_many(np.asarray(one)[None])[0]
        return {s: float(v) for s, v in zip(self.species, p, strict=True)}

    def of(self, mat: np.ndarray, features: np.ndarray | None) -> dict[str, float]:
        """Probabilities of one drawing from its un-normalised ``(4, 62)`` output and its
        ``(m,)`` pooled features (None: not at hand, for a classifier that reads outputs)."""
        if self.reads == "outputs":
            return self.probabilities(mat)
        if features is None:
            raise SpeciesIdError(
                "this species classifier reads the network's pooled features; none were given"
            )
        return self.probabilities(features)

    def to_dict(self) -> dict[str, Any]:
        return {
            "species": list(self.species),
            "mean": self.mean.tolist(),
            "std": self.std.tolist(),
            "weight": self.weight.tolist(),
            "bias": self.bias.tolist(),
            "temperature": float(self.temperature),
            "scale": self.scale.tolist(),
            "reads": self.reads,
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SpeciesClassifier:
        reads = str(d.get("reads", "outputs"))  # checkpoints before "reads" read outputs
        if reads not in READS:
            raise SpeciesIdError(f"a species classifier reads one of {READS}, not {reads!r}")
        return cls(
            tuple(d["species"]),
            np.asarray(d["mean"], np.float64),
            np.asarray(d["std"], np.float64),
            np.asarray(d["weight"], np.float64),
            np.asarray(d["bias"], np.float64),
            float(d["temperature"]),
            np.asarray(d["scale"], np.float64),
            reads,
        )


@dataclass(frozen=True)
class SpeciesIdentifier:
    species: tuple[str, ...]
    rows: dict[str, np.ndarray]  # species -> (m,) row index of each cp
    cols: dict[str, np.ndarray]  # species -> (m,) column index
    value: dict[str, np.ndarray]  # species -> (m,) centre (un-normalised)
    eps: dict[str, np.ndarray]  # species -> (m,) acceptance half-width (un-normalised)
    scale: np.ndarray  # (62,) normaliser divisors, for the tie-break distance
    classifier: SpeciesClassifier | None = None  # calibrated probabilities, when fitted

    @classmethod
    def fit(
        cls,
        mats_by_species: Mapping[str, np.ndarray],
        scale: np.ndarray,
        span_tol: float = SPAN_TOL,
        match_tol: float = MATCH_TOL,
    ) -> SpeciesIdentifier:
        """From ``{species: (N, 4, 62) un-normalised training matrices}``."""
        scale = np.asarray(scale, dtype=np.float64)
        rows, cols, value, eps = {}, {}, {}, {}
        for name, mats in mats_by_species.items():
            a = np.asarray(mats, dtype=np.float64)
            if a.ndim != 3 or a.shape[1:] != (4, len(PREDICTED_KEYS)) or not len(a):
                raise SpeciesIdError(f"species {name!r}: no training matrices of shape (N, 4, 62)")
            r, c = _CELLS[:, 0], _CELLS[:, 1]
            v = a[:, r, c]
            lo, hi = v.min(axis=0), v.max(axis=0)
            keep = (hi - lo) / scale[c] <= span_tol
            if not keep.any():
                raise SpeciesIdError(f"species {name!r} has no characteristic parameters")
            rows[name], cols[name] = r[keep], c[keep]
            value[name] = (lo + hi)[keep] / 2
            eps[name] = (hi - lo)[keep] / 2 + match_tol * scale[c[keep]]
        return cls(tuple(mats_by_species), rows, cols, value, eps, scale)

    def shares(self, mat: np.ndarray) -> dict[str, float]:
        """Share of each species' cps that the un-normalised ``(4, 62)`` matrix matches."""
        m = np.asarray(mat, dtype=np.float64)
        if m.shape != (4, len(PREDICTED_KEYS)):
            raise SpeciesIdError(f"expected a (4, 62) matrix, got {m.shape}")
        out = {}
        for s in self.species:
            x = m[self.rows[s], self.cols[s]]
            out[s] = float((np.abs(x - self.value[s]) <= self.eps[s]).mean())
        return out

    def _classifies(self, features: np.ndarray | None) -> bool:
        """Whether the classifier decides: there is one and it has what it reads (a
        dictionary has no network features: Algorithm 1 reads it)."""
        c = self.classifier
        return c is not None and (c.reads == "outputs" or features is not None)

    def identify(
        self,
        params_or_matrix: Mapping[str, Any] | np.ndarray,
        features: np.ndarray | None = None,
    ) -> str:
        """The species of a dictionary or of an un-normalised ``(4, 62)`` matrix (and the
        drawing's ``(m,)`` pooled features, for a classifier that reads them)."""
        m = (
            encoding.encode(params_or_matrix)
            if isinstance(params_or_matrix, Mapping)
            else np.asarray(params_or_matrix, dtype=np.float64)
        )
        if self.classifier is not None and self._classifies(features):
            p = self.classifier.of(m, features)
            return max(p, key=lambda s: p[s])
        sh = self.shares(m)

        def dist(s: str) -> float:
            x = m[self.rows[s], self.cols[s]]
            return float(np.mean(np.abs(x - self.value[s]) / self.scale[self.cols[s]]))

        return max(self.species, key=lambda s: (sh[s], -dist(s)))

    def identify_many(self, mats: Sequence[np.ndarray] | np.ndarray) -> list[str]:
        return [self.identify(np.asarray(m)) for m in mats]

    def scores(self, mat: np.ndarray, features: np.ndarray | None = None) -> dict[str, float]:
        """Species scores of an un-normalised ``(4, 62)`` output (and the drawing's pooled
        features): the classifier's calibrated probabilities when there is one, else
        Algorithm 1's shares."""
        if self.classifier is not None and self._classifies(features):
            return self.classifier.of(mat, features)
        return self.shares(mat)

    def with_classifier(self, classifier: SpeciesClassifier) -> SpeciesIdentifier:
        return SpeciesIdentifier(
            self.species, self.rows, self.cols, self.value, self.eps, self.scale, classifier
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "species": list(self.species),
            "scale": self.scale.tolist(),
            "cps": {
                s: {
                    "rows": self.rows[s].tolist(),
                    "cols": self.cols[s].tolist(),
                    "keys": [PREDICTED_KEYS[c] for c in self.cols[s]],
                    "value": self.value[s].tolist(),
                    "eps": self.eps[s].tolist(),
                }
                for s in self.species
            },
            **({"classifier": self.classifier.to_dict()} if self.classifier is not None else {}),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> SpeciesIdentifier:
        try:
            species = tuple(d["species"])
            cps = d["cps"]
            return cls(
                species,
                {s: np.asarray(cps[s]["rows"], dtype=np.int64) for s in species},
                {s: np.asarray(cps[s]["cols"], dtype=np.int64) for s in species},
                {s: np.asarray(cps[s]["value"], dtype=np.float64) for s in species},
                {s: np.asarray(cps[s]["eps"], dtype=np.float64) for s in species},
                np.asarray(d["scale"], dtype=np.float64),
                SpeciesClassifier.from_dict(d["classifier"]) if d.get("classifier") else None,
            )
        except (KeyError, TypeError, ValueError) as e:
            raise SpeciesIdError(f"not a saved species identifier: {e}") from None
