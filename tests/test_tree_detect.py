"""tsn.tree_detect: the calibrated "is it a tree?" probability, on generated features."""

from __future__ import annotations

import numpy as np
import pytest

from tsn.tree_detect import TreeDetector


def _data(seed: int, n: int = 200) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    y = rng.random(n) < 0.3  # fewer trees than other things: the classes are weighted
    x = rng.normal(size=(n, 5))
    x[:, 0] += np.where(y, 1.5, -1.5)
    return x, y


def test_fit_separates_and_calibrates() -> None:
    det = TreeDetector.fit(*_data(0), held_out=_data(1))
    x, y = _data(2)
    p = det.probabilities(x)
    assert p.shape == (len(y),) and ((p >= 0) & (p <= 1)).all()
    assert np.mean((p >= 0.5) == y) > 0.9
    # balanced: neither class is sacrificed for the larger one
    assert np.mean(p[y] >= 0.5) > 0.85 and np.mean(p[~y] < 0.5) > 0.85
    assert 0.05 <= det.temperature <= 20


def test_round_trip() -> None:
    det = TreeDetector.fit(*_data(0))
    again = TreeDetector.from_dict(det.to_dict())
    x, _ = _data(3)
    assert np.allclose(det.probabilities(x), again.probabilities(x))


def test_bad_inputs() -> None:
    x, y = _data(0)
    with pytest.raises(ValueError, match="both"):
        TreeDetector.fit(x, np.ones(len(x), bool))
    with pytest.raises(ValueError, match="one length"):
        TreeDetector.from_dict({"mean": [0, 1], "std": [1], "weight": [1, 1], "bias": 0})


def test_the_shipped_checkpoint_tells_a_tree_from_a_house() -> None:
    from eval.doodles import nontree_doodle, tree_doodle
    from treesketch import load_estimator

    est = load_estimator("tsn")
    if est.model.loaded.tree_detector is None:
        pytest.fail("the shipped checkpoint has no tree detector (scripts/fit_tree_detector.py)")
    # benchmark seeds (never fitted on)
    tree = est.estimate(_prepared(tree_doodle("oak", 3)))
    house = est.estimate(_prepared(nontree_doodle("house", 1003)))
    assert tree.tree_probability is not None and house.tree_probability is not None
    assert tree.tree_probability > 0.5 > house.tree_probability


def _prepared(img: np.ndarray) -> np.ndarray:
    from treesketch.pipeline import prepare_input

    return prepare_input(img)


def test_a_new_detector_is_saved_into_a_checkpoint_with_the_rest_kept(tmp_path) -> None:
    from tsn.checkpoint import load_checkpoint, save_loaded
    from tsn.predict import DEFAULT_CHECKPOINT

    loaded = load_checkpoint(DEFAULT_CHECKPOINT)
    fake = TreeDetector.fit(
        np.random.default_rng(0).normal(size=(40, 1280)), np.arange(40) % 2 == 0
    )
    again = load_checkpoint(save_loaded(loaded, tmp_path / "t.pt", {"x": 1}, tree_detector=fake))
    assert again.info == {"x": 1}
    assert again.tree_detector is not None
    assert np.allclose(again.tree_detector.weight, fake.weight)
    assert again.species_id.to_dict() == loaded.species_id.to_dict()
    assert again.normaliser.to_dict() == loaded.normaliser.to_dict()
    a, b = loaded.model.state_dict(), again.model.state_dict()
    assert a.keys() == b.keys() and all(bool((a[k] == b[k]).all()) for k in a)
    assert loaded.species_branch is not None and again.species_branch is not None
    a, b = loaded.species_branch.stage_state(), again.species_branch.stage_state()
    assert a.keys() == b.keys() and all(bool((a[k] == b[k]).all()) for k in a)


def test_weights_move_the_fit_toward_the_drawings_that_weigh_more() -> None:
    x, y = _data(0)
    # a second kind of "other thing" that overlaps the trees; weighted up, it is learned
    rng = np.random.default_rng(5)
    odd = rng.normal(size=(40, 5))
    odd[:, 0] += 1.5
    odd[:, 1] += 3.0
    xs, ys = np.concatenate([x, odd]), np.concatenate([y, np.zeros(40, bool)])
    light = TreeDetector.fit(xs, ys, weights=np.r_[np.ones(len(x)), np.full(40, 0.05)])
    heavy = TreeDetector.fit(xs, ys, weights=np.r_[np.ones(len(x)), np.full(40, 5.0)])
    test = rng.normal(size=(200, 5))
    test[:, 0] += 1.5
    test[:, 1] += 3.0
    assert np.mean(heavy.probabilities(test) < 0.5) > np.mean(light.probabilities(test) < 0.5)
    assert np.mean(heavy.probabilities(test) < 0.5) > 0.8
    with pytest.raises(ValueError, match="weights"):
        TreeDetector.fit(x, y, weights=np.ones(3))


def _ring(seed: int, n: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """Trees inside a ring of other things: no hyperplane parts them."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 4))
    y = np.hypot(x[:, 0], x[:, 1]) < 1.1
    return x, y


def test_networks_part_what_one_hyperplane_cannot() -> None:
    linear = TreeDetector.fit(*_ring(0))
    nets = TreeDetector.fit(*_ring(0), held_out=_ring(1), hidden=16, members=2, l2=1e-3)
    x, y = _ring(2)
    assert np.mean((linear.probabilities(x) >= 0.5) == y) < 0.75
    p = nets.probabilities(x)
    assert ((p >= 0) & (p <= 1)).all()
    assert np.mean(p[y] >= 0.5) > 0.85 and np.mean(p[~y] < 0.5) > 0.85
    assert nets.hidden_weight is not None and nets.hidden_weight.shape == (2, 4, 16)


def test_networks_round_trip_through_a_checkpoint(tmp_path) -> None:
    from tsn.checkpoint import load_checkpoint, save_loaded
    from tsn.predict import DEFAULT_CHECKPOINT

    x, y = _data(0, 120)
    x = np.hstack([x, np.random.default_rng(1).normal(size=(120, 1275))])
    nets = TreeDetector.fit(x, y, hidden=8, members=2, l2=1e-3)
    # the same seeds, the same detector
    refit = TreeDetector.fit(x, y, hidden=8, members=2, l2=1e-3)
    assert np.allclose(refit.probabilities(x), nets.probabilities(x))
    again = TreeDetector.from_dict(nets.to_dict())
    assert np.allclose(again.probabilities(x), nets.probabilities(x), atol=1e-5)
    loaded = load_checkpoint(DEFAULT_CHECKPOINT)
    back = load_checkpoint(save_loaded(loaded, tmp_path / "t.pt", {}, tree_detector=nets))
    assert back.tree_detector is not None
    assert np.allclose(back.tree_detector.probabilities(x), nets.probabilities(x), atol=1e-5)


def test_networks_of_mismatched_shapes_are_refused() -> None:
    nets = TreeDetector.fit(*_ring(0, 100), hidden=4, members=2).to_dict()
    with pytest.raises(ValueError, match="hidden_weight"):
        TreeDetector.from_dict({**nets, "hidden_bias": [[0.0] * 3] * 2})
    with pytest.raises(ValueError, match="hidden_weight"):
        TreeDetector.from_dict({**nets, "bias": 0.0})


def test_probabilities_of_far_out_features_stay_finite() -> None:
    det = TreeDetector.fit(*_data(0))
    p = det.probabilities(np.full((2, 5), 1e6) * np.array([[1], [-1]]))
    assert np.isfinite(p).all() and p[0] > 0.99 and p[1] < 0.01


def test_fitting_networks_leaves_the_callers_random_state_alone() -> None:
    import torch

    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    TreeDetector.fit(*_ring(0, 200), hidden=4, members=2)
    assert torch.equal(torch.rand(3), expected)


def test_a_balanced_limit_judges_both_kinds_wrongly_alike() -> None:
    # trees that read less surely than the fit's (people's): at the plain 0.5 they are
    # warned far more often than other things pass; the offset moves the limit between
    x, y = _data(0, 400)
    det = TreeDetector.fit(x, y)
    xs, ys = _data(1, 400)
    shifted = xs.copy()
    shifted[ys] -= 0.8 * (xs[ys].mean(axis=0) - xs[~ys].mean(axis=0))  # trees drawn oddly

    def rates(d: TreeDetector) -> tuple[float, float]:
        p = d.probabilities(shifted)
        return float(np.mean(p[ys] >= 0.5)), float(np.mean(p[~ys] < 0.5))

    spared, warned = rates(det)
    assert spared < warned - 0.1  # the plain limit is lopsided
    balanced = det.with_balanced_limit(shifted, ys)
    assert balanced.offset > 0
    b_spared, b_warned = rates(balanced)
    assert min(b_spared, b_warned) > min(spared, warned)
    assert abs(b_spared - b_warned) < abs(spared - warned)
    again = TreeDetector.from_dict(balanced.to_dict())
    assert again.offset == balanced.offset
    np.testing.assert_allclose(again.probabilities(xs), balanced.probabilities(xs))
    with pytest.raises(ValueError, match="both"):
        det.with_balanced_limit(xs[ys], ys[ys])
