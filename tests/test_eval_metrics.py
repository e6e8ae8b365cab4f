"""eval.metrics: 1-RMSE per head / overall on normalised matrices, per-key errors, tables."""

from __future__ import annotations

import numpy as np
import pytest

from eval.metrics import (
    PAPER_ONE_MINUS_RMSE,
    format_hardest,
    format_table,
    one_minus_rmse,
)
from weberpenn.params import HEAD_KEYS, HEADS, PREDICTED_KEYS

COL = {k: i for i, k in enumerate(PREDICTED_KEYS)}


def test_perfect_prediction_scores_one():
    t = np.random.default_rng(0).uniform(-1, 1, (5, 4, 62))
    s = one_minus_rmse(t, t.copy())
    assert s.overall == pytest.approx(1.0)
    assert all(v == pytest.approx(1.0) for v in s.heads.values())
    assert all(v == 0 for v in s.key_rmse.values())
    assert s.n == 5


def test_hand_computed_case():
    t = np.zeros((2, 4, 62))
    p = t.copy()
    k = HEAD_KEYS["-1_1"][0]  # the only key of its head
    p[0, :, COL[k]] = 0.5  # sample 0 off by 0.5 in all rows, sample 1 exact
    # head RMSE = sqrt((4*0.25 + 4*0) / 8) = sqrt(0.125)
    a = HEAD_KEYS["0_1"][0]
    p[:, 0, COL[a]] = 0.2  # one row of one of 17 keys off by 0.2 in both samples
    s = one_minus_rmse(p, t)
    assert s.heads["-1_1"] == pytest.approx(1 - np.sqrt(0.125))
    assert s.heads["0_1"] == pytest.approx(1 - np.sqrt(2 * 0.04 / (2 * 4 * 17)))
    assert s.heads["angle"] == pytest.approx(1.0)
    assert s.overall == pytest.approx(np.mean([s.heads[h] for h in HEADS]))
    assert s.key_rmse[k] == pytest.approx(np.sqrt(0.125))
    assert s.key_rmse[a] == pytest.approx(np.sqrt(2 * 0.04 / 8))
    assert s.hardest(2)[0][:2] == (k, "-1_1")


def test_paper_overall_is_mean_of_heads():
    heads = [v for h, v in PAPER_ONE_MINUS_RMSE.items() if h != "overall"]
    assert np.mean(heads) == pytest.approx(PAPER_ONE_MINUS_RMSE["overall"], abs=1e-4)


def test_bad_shapes_rejected():
    with pytest.raises(ValueError, match=r"\(N, 4, 62\)"):
        one_minus_rmse(np.zeros((2, 4, 61)), np.zeros((2, 4, 61)))
    with pytest.raises(ValueError, match="shape"):
        one_minus_rmse(np.zeros((2, 4, 62)), np.zeros((3, 4, 62)))
    bad = np.zeros((1, 4, 62))
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        one_minus_rmse(bad, np.zeros((1, 4, 62)))


def test_tables_render():
    t = np.zeros((3, 4, 62))
    s = one_minus_rmse(t + 0.1, t)
    md = format_table({"ours": s, "paper (EfficientNet-B7)": PAPER_ONE_MINUS_RMSE})
    assert "0.9000" in md and "0.9253" in md and md.count("\n") == 3
    assert format_hardest(s, 3).count("\n") == 4
