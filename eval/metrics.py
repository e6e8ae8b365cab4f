"""1-RMSE tables as the paper reports them, and per-key errors.

The paper (and its code, ``OneMinusRMSE``) computes, for each of the six output heads, the
RMSE between the *normalised* target sub-matrix and the prediction (max-abs normalisation
per key, fitted on the training split), over every sample, row and column of that head;
the score is ``1 - RMSE``.  "Overall" is the plain mean of the six head scores
(0.9253 = mean(0.8093, 0.9595, 0.8129, 0.9798, 0.9936, 0.9964) for EfficientNet-B7).

Inputs here are normalised target matrices, shape ``(N, 4, 62)`` with columns in
``weberpenn.params.PREDICTED_KEYS`` order (scalars repeated in the four rows) -- exactly
what ``tsn.encoding`` produces.  :class:`Scores` and :func:`one_minus_rmse` live in
``tsn.metrics`` (training validates with the same function) and are re-exported here.
"""

from __future__ import annotations

from collections.abc import Mapping

from tsn.metrics import Scores, one_minus_rmse

__all__ = [
    "HEAD_LABELS",
    "PAPER_ONE_MINUS_RMSE",
    "Scores",
    "format_hardest",
    "format_table",
    "one_minus_rmse",
]

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
