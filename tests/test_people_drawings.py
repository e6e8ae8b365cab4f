"""Drawings as people make them: the shipped checkpoint's "is this a tree?" and species.

Drawings by people of held-out authors (``eval.people``, part ``held``: never trained,
fitted or calibrated on; read from ``../shared/people_doodles``) and code-made palms in the
forms people draw them (``eval.doodles.palm_doodle``, benchmark seeds below 1000).
"""

from __future__ import annotations

import numpy as np
import pytest

from eval.doodles import PALM_FORMS, nontree_doodle, palm_doodle
from eval.people import people_drawings
from treesketch import load_estimator
from treesketch.pipeline import TREE_PROBABILITY_LIMIT, load_sketch, prepare_input


@pytest.fixture(scope="module")
def estimator():
    return load_estimator("tsn")


def _read(estimator, image):
    return estimator.estimate(prepare_input(load_sketch(image)))


@pytest.mark.parametrize("form", PALM_FORMS)
def test_palms_as_people_draw_them_stay_palms(estimator, form: str) -> None:
    species = [_read(estimator, palm_doodle(form, seed)).species for seed in range(6)]
    assert species.count("palm") >= 5, species


def test_a_palm_of_closed_leaf_fronds_is_a_palm_and_a_tree(estimator) -> None:
    est = _read(estimator, palm_doodle("leaf", 11))
    assert est.species == "palm"
    assert est.tree_probability is not None and est.tree_probability >= TREE_PROBABILITY_LIMIT


def test_a_bicycle_doodle_is_asked_whether_it_is_a_tree(estimator) -> None:
    for seed in (1000, 1001, 1002):  # benchmark seeds, never fitted on
        est = _read(estimator, nontree_doodle("bicycle", seed))
        assert est.tree_probability is not None and est.tree_probability < TREE_PROBABILITY_LIMIT


def test_held_out_peoples_trees_pass_and_their_other_things_are_warned(estimator) -> None:
    trees = people_drawings(part="held", sources=("strokes",), kinds=("tree",), per_kind=30)
    others = people_drawings(
        part="held", sources=("strokes",), kinds=("bicycle", "car", "fish", "guitar"), per_kind=8
    )
    p_trees = np.array([_read(estimator, d.image()).tree_probability for d in trees])
    p_others = np.array([_read(estimator, d.image()).tree_probability for d in others])
    assert len(trees) == 30 and len(others) == 32
    assert np.mean(p_trees >= TREE_PROBABILITY_LIMIT) >= 0.9
    assert np.mean(p_others < TREE_PROBABILITY_LIMIT) >= 0.9
    # a person's "tree" is a broadleaf or a conifer, not a palm or a bonsai
    odd = [_read(estimator, d.image()).species in ("palm", "bonsai", "pine") for d in trees]
    assert np.mean(odd) <= 0.1
