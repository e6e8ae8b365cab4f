"""The network reads its own tree back (``TSNEstimator.reread``), and the search and the
pipeline try what it gives."""

from __future__ import annotations

import numpy as np
import pytest

from eval.hausdorff import hausdorff
from eval.paper import PUBLISHED_DIR
from pipeline_helpers import Fixed, gt_sketch
from refine import RefineSettings, refine
from refine.objective import SearchSpace
from render.sketch import SketchRenderer
from treesketch import Pipeline
from treesketch.estimators import REREAD_STEPS, SeededEstimator, TSNEstimator
from treesketch.pipeline import prepare_input
from weberpenn import TreeParams, build_mesh, grow, load_params, species


@pytest.fixture(scope="module")
def tsn() -> TSNEstimator:
    return TSNEstimator.load()


def _reading(est: TSNEstimator, img: np.ndarray) -> np.ndarray:
    return est.model.raw_and_features([img])[0][0]


def test_reread_moves_the_tree_towards_one_read_as_the_drawing(tsn: TSNEstimator) -> None:
    # a published bonsai drawn from the front: the network's estimate is read back from
    # its own sketch; each step's tree reads nearer the drawing and is nearer the truth
    gt = load_params(PUBLISHED_DIR / "14_bonsai.json")
    truth = build_mesh(grow(gt), species="bonsai")
    drawing = prepare_input(SketchRenderer(truth, species="bonsai").sketch(0.0, 256))
    est = SeededEstimator(tsn, int(gt["seed"]))
    first = est.estimate(drawing)
    assert first.species == "bonsai"
    steps = est.reread([(drawing, 0.0)], first.params, "bonsai")
    assert len(steps) == REREAD_STEPS == 2
    for p in steps:
        assert p["seed"] == gt["seed"]  # grown with the same draws
        assert p == species.project("bonsai", p)  # a member of the species
    want = _reading(tsn, drawing)

    def off(p: TreeParams) -> float:
        own = SketchRenderer(build_mesh(grow(p), species="bonsai"), species="bonsai")
        return float(np.abs(_reading(tsn, prepare_input(own.sketch(0.0, 256))) - want).mean())

    def error(p: TreeParams) -> float:
        mesh = build_mesh(grow(p), species="bonsai").combined()
        return hausdorff(mesh, truth.combined(), 4000).max_norm

    assert off(steps[0]) < off(first.params)
    assert error(steps[-1]) < error(first.params) - 0.02  # 0.088 -> 0.053


def test_a_better_start_given_to_the_search_is_kept() -> None:
    # the search tries the given dictionaries at its start view and goes on from the best
    # (it moves the values it searches; the others stay the first estimate's)
    wrong = species.sample("pine", 8)
    space = SearchSpace.create("pine", wrong, search_yaw=False)
    space = space.without(list(RefineSettings().hold)).live()  # as the search builds it
    gt = space.to_params(space.from_params(species.sample("pine", 7)))
    img = SketchRenderer(build_mesh(grow(gt), species="pine")).sketch(0.0, 128)
    cfg = RefineSettings(budget=6)
    alone = refine(img, wrong, cfg, species="pine", yaw=0.0)
    helped = refine(img, wrong, cfg, species="pine", yaw=0.0, starts=[gt])
    truth_only = refine(img, gt, RefineSettings(budget=1), species="pine", yaw=0.0)
    # at about the drawn tree's own distance (the given values are rounded into the cube)
    assert helped.loss_after <= truth_only.loss_before + 0.01 < 0.5 * alone.loss_after


class Rereading(Fixed):
    """A fixed estimator that also rereads, recording what it was asked."""

    def __init__(self, name: str, seed: int) -> None:
        super().__init__(name, seed)
        self.asked: list[tuple[list[float], str]] = []

    def reread(self, drawings, params: TreeParams, name: str) -> list[TreeParams]:
        self.asked.append(([yaw for _, yaw in drawings], name))
        return [species.sample(name, 11)]


def test_the_pipeline_rereads_for_the_first_species_with_the_known_views() -> None:
    est = Rereading("pine", 2)
    pipe = Pipeline(est).with_settings(budget=8, time_limit=None)
    front, side = gt_sketch("pine", 3, 0.0), gt_sketch("pine", 3, 90.0)
    pipe.run([front, (side, 90.0)])
    assert est.asked == [([0.0, 90.0], "pine")]
    est.asked.clear()
    pipe.run([front, (side, None)])  # a side whose yaw is searched is not read back
    assert est.asked == [([0.0], "pine")]
    est.asked.clear()
    Pipeline(est).with_settings(refine=False).run(front)  # no search, nothing to start
    assert est.asked == []
