"""The heads refitted on frozen features (``tsn.heads``)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from tsn import encoding
from tsn.heads import (
    HeadData,
    RidgeFit,
    choose_ridge,
    head_errors,
    head_outputs,
    heads_of,
    set_heads,
)
from tsn.model import TSN
from weberpenn.params import HEADS


def _linear_data(rng: np.random.Generator, n: int, m: int, noise: float = 0.0):
    w = rng.normal(size=(m, 4 * 62))
    b = rng.normal(size=4 * 62)
    x = rng.normal(size=(n, m))
    y = x @ w + b + noise * rng.normal(size=(n, 4 * 62))
    return x, y.reshape(n, 4, 62), w, b


def test_a_noiseless_linear_map_is_recovered():
    rng = np.random.default_rng(0)
    x, y, w, b = _linear_data(rng, 400, 12)
    heads = RidgeFit([HeadData(x, y)]).heads(1e-10)
    np.testing.assert_allclose(head_outputs(heads, x), y, atol=1e-3)


def test_weights_decide_which_dataset_the_fit_follows():
    rng = np.random.default_rng(1)
    x = rng.normal(size=(300, 8))
    y_a = np.tile((x @ rng.normal(size=8))[:, None, None], (1, 4, 62))
    y_b = np.tile((x @ rng.normal(size=8))[:, None, None], (1, 4, 62))
    a, b = HeadData(x, y_a, 1.0), HeadData(x, y_b, 1.0)
    leaning_a = RidgeFit([HeadData(x, y_a, 20.0), b]).heads(1e-8)
    leaning_b = RidgeFit([a, HeadData(x, y_b, 20.0)]).heads(1e-8)
    err_a = head_errors(leaning_a, [a])
    assert all(err_a[h] < head_errors(leaning_b, [a])[h] for h in HEADS)


def test_the_ridge_strength_is_chosen_per_head_on_validation():
    rng = np.random.default_rng(2)
    x, y, w, b = _linear_data(rng, 60, 40, noise=3.0)  # few rows, noisy: strength helps
    xv = rng.normal(size=(60, 40))
    yv = (xv @ w + b + 3.0 * rng.normal(size=(60, 4 * 62))).reshape(60, 4, 62)
    best, table = choose_ridge(RidgeFit([HeadData(x, y)]), [HeadData(xv, yv)], (1e-8, 1.0))
    assert set(best) == set(HEADS)
    assert set(table) == {1e-8, 1.0}
    for h in HEADS:
        assert table[best[h]][h] == min(t[h] for t in table.values())


def test_set_heads_writes_the_network_and_refuses_a_wrong_shape():
    net = TSN("resnet_small", pretrained=False).eval()
    heads = {h: (w * 0 + 0.5, b * 0 - 1.0) for h, (w, b) in heads_of(net).items()}
    set_heads(net, heads)
    with torch.no_grad():
        out = net(torch.ones(1, 1, 64, 64))
    full = encoding.join_heads({h: v.numpy() for h, v in out.items()})
    features = np.full((1, net.backbone.out_features), 0.0, np.float32)
    assert np.isfinite(full).all()
    np.testing.assert_allclose(head_outputs(heads_of(net), features), -1.0)
    bad = dict(heads)
    bad[HEADS[0]] = (np.zeros((3, 3), np.float32), np.zeros(3, np.float32))
    before = heads_of(net)[HEADS[1]][0].copy()
    with pytest.raises(ValueError, match=HEADS[0]):
        set_heads(net, bad)
    assert np.array_equal(heads_of(net)[HEADS[1]][0], before)  # nothing half-written


@pytest.mark.parametrize(
    ("features", "targets", "weight", "match"),
    [
        (np.zeros((3, 4)), np.zeros((2, 4, 62)), 1.0, "same n"),
        (np.zeros((0, 4)), np.zeros((0, 4, 62)), 1.0, "same n"),
        (np.zeros((3, 4)), np.zeros((3, 4, 62)), 0.0, "weight"),
        (np.full((3, 4), np.nan), np.zeros((3, 4, 62)), 1.0, "NaN"),
    ],
)
def test_bad_data_is_refused_plainly(features, targets, weight, match):
    with pytest.raises(ValueError, match=match):
        HeadData(features, targets, weight)


def test_datasets_of_other_feature_widths_are_refused():
    a = HeadData(np.zeros((3, 4)), np.zeros((3, 4, 62)))
    b = HeadData(np.zeros((3, 5)), np.zeros((3, 4, 62)))
    with pytest.raises(ValueError, match="width"):
        RidgeFit([a, b])
