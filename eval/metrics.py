"""1-RMSE tables as the paper reports them, and per-key errors.

The paper (and its code, ``OneMinusRMSE``) computes, for each of the six output heads, the
RMSE between the *normalised* target sub-matrix and the prediction (max-abs normalisation
per key, fitted on the training split), over every sample, row and column of that head;
the score is ``1 - RMSE``.  "Overall" is the plain mean of the six head scores
(0.9253 = mean(0.8093, 0.9595, 0.8129, 0.9798, 0.9936, 0.9964) for EfficientNet-B7).

Inputs here are normalised target matrices, shape ``(N, 4, 62)`` with columns in
``weberpenn.params.PREDICTED_KEYS`` order (scalars repeated in the four rows) -- exactly
what ``tsn.encoding`` produces.  Use :func:`params_matrices` to get them from parameter
dictionaries.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from weberpenn.params import HEAD_KEYS, HEADS, PREDICTED_KEYS

# the paper's SG test-set numbers for EfficientNet-B7 (Table "Core net comparisons of SG sketches")
PAPER_ONE_MINUS_RMSE: dict[str, float] = {
    "-inf_inf": 0.8093,
    "angle": 0.9595,
    "0_1": 0.8129,
    "0_inf": 0.9798,
    "min_max": 0.9936,
    "-1_1": 0.9964,
    "overall": 0.9253,
}
HEAD_LABELS: dict[str, str] = {
    "0_1": "[0,1]",
    "-inf_inf": "(-inf,inf)",
    "0_inf": "[0,inf)",
    "min_max": "[min,max]",
    "angle": "angles [-360,360]",
    "-1_1": "[-1,1]",
}
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


def params_matrices(params: Sequence[Mapping], normaliser) -> np.ndarray:
    """Encode and normalise parameter dictionaries with ``tsn.encoding`` -> ``(N, 4, 62)``.

    ``normaliser`` is the checkpoint's per-key max-abs scale: anything ``tsn.encoding``
    accepts, or a plain ``(62,)`` / ``(4, 62)`` array of divisors.
    """
    from tsn import encoding

    mats = np.stack([np.asarray(encoding.encode(p), dtype=np.float64) for p in params])
    if hasattr(encoding, "normalise") and not isinstance(normaliser, np.ndarray):
        return np.stack([np.asarray(encoding.normalise(m, normaliser)) for m in mats])
    scale = np.asarray(normaliser, dtype=np.float64)
    scale = np.where(scale == 0, 1.0, scale)
    return mats / scale


def format_table(rows: Mapping[str, Scores | Mapping[str, float]], digits: int = 4) -> str:
    """Markdown table, one row per model (``Scores`` or a dict like PAPER_ONE_MINUS_RMSE)."""
    cols = ["-inf_inf", "angle", "0_1", "0_inf", "min_max", "-1_1"]
    head = "| model | " + " | ".join(HEAD_LABELS[c] for c in cols) + " | overall |"
    sep = "|---" * (len(cols) + 2) + "|"
    lines = [head, sep]
    for name, s in rows.items():
        vals = {**s.heads, "overall": s.overall} if isinstance(s, Scores) else dict(s)
        cells = [f"{vals[c]:.{digits}f}" if c in vals else "-" for c in [*cols, "overall"]]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_hardest(scores: Scores, k: int = 10) -> str:
    """Markdown table of the ``k`` keys with the largest normalised RMSE."""
    lines = ["| key | head | RMSE (normalised) |", "|---|---|---|"]
    lines += [f"| {key} | {HEAD_LABELS[h]} | {v:.4f} |" for key, h, v in scores.hardest(k)]
    return "\n".join(lines)
