"""Several drawings of one tree: treesketch.views and Pipeline.run with views."""

from __future__ import annotations

import numpy as np
import pytest
from pipeline_helpers import Fixed, gt_sketch

from treesketch import Estimate, Pipeline, RefineSettings, SketchError
from treesketch.views import (
    MAX_VIEWS,
    SketchView,
    as_views,
    fuse_estimates,
    parse_view,
    parse_yaw,
)
from weberpenn import TreeParams, species


@pytest.mark.parametrize(
    ("text", "source", "yaw"),
    [
        ("side.png@90", "side.png", 90.0),
        ("a@b.png@-90", "a@b.png", 270.0),
        ("s.png@?", "s.png", None),
        ("s.png", "s.png", 90.0),
    ],
)
def test_parse_view(text: str, source: str, yaw: float | None) -> None:
    assert parse_view(text) == SketchView(source, yaw)


@pytest.mark.parametrize("text", ["side.png@east", "side.png@nan", "side.png@1e9", "@90"])
def test_parse_view_refuses_bad_angles(text: str) -> None:
    with pytest.raises(ValueError, match="--view"):
        parse_view(text)


def test_parse_yaw() -> None:
    assert parse_yaw("?") is None and parse_yaw(None) is None
    assert parse_yaw(450) == 90.0 and parse_yaw("-45") == 315.0
    with pytest.raises(ValueError, match="yaw"):
        parse_yaw(True)


def test_as_views() -> None:
    img = np.full((64, 64), 255, np.uint8)
    assert as_views(img) == [SketchView(img, 0.0)]
    views = as_views([img, (img, 90), SketchView(img, None)])
    assert [v.yaw for v in views] == [0.0, 90.0, None]
    with pytest.raises(ValueError, match="first view"):
        as_views([(img, 90), img])
    with pytest.raises(ValueError, match=f"at most {MAX_VIEWS}"):
        as_views([img] * (MAX_VIEWS + 1))
    with pytest.raises(ValueError, match="no drawing"):
        as_views([])


def test_fuse_averages_scores_and_continuous_values() -> None:
    a = species.sample("maple", 1)
    b = species.sample("maple", 2)
    ea = Estimate(a, "maple", {"maple": 0.6, "palm": 0.4})
    eb = Estimate(b, "palm", {"maple": 0.2, "palm": 0.8})
    fused = fuse_estimates([ea, eb])
    assert fused.species == "palm"
    assert fused.species_scores == pytest.approx({"maple": 0.4, "palm": 0.6})
    m = fuse_estimates([ea, Estimate(b, "maple", {"maple": 1.0})])
    assert m.species == "maple"
    # a continuous value is the mean, a discrete one the first view's, fixed ones the species'
    assert m.params["ratio"] == pytest.approx(species.project("maple", m.params)["ratio"])
    lo, hi = sorted([a["ratio"], b["ratio"]])
    assert lo - 1e-9 <= m.params["ratio"] <= hi + 1e-9
    assert m.params["levels"] == a["levels"]
    assert fuse_estimates([ea]) is ea
    assert set(m.alternatives) == set(species.SPECIES) - {"maple"}


def test_fuse_keeps_the_trunk_bend_of_the_view_that_shows_it_most() -> None:
    # a palm's trunk bent 60 degrees, read from a view across its plane (60) and from one
    # along it (-5, nearly straight, the sign the other side's): the mean would be a
    # nearly straight trunk, 27.5
    def palm(bend: float, split_draw: float) -> Estimate:
        values = species.sample("palm", 3).to_dict()
        values["curve"] = [bend, *values["curve"][1:]]
        values["rSplits2"] = split_draw
        return Estimate(species.project("palm", TreeParams(values)), "palm", {"palm": 1.0})

    for order in ((60.0, -5.0), (-5.0, 60.0)):
        fused = fuse_estimates([palm(order[0], 0.2), palm(order[1], 0.4)]).params
        assert fused["curve"][0] == pytest.approx(60.0)
        assert fused["curveBack"][0] == pytest.approx(-60.0)  # the species' mirror rule
        assert fused["rSplits2"] == pytest.approx(0.3)  # the other values: the mean
    bent_other_way = fuse_estimates([palm(-70.0, 0.3), palm(40.0, 0.3)]).params
    assert bent_other_way["curve"][0] == pytest.approx(-70.0)


def test_two_views_are_read_refined_and_kept() -> None:
    front, side = gt_sketch("palm", 3, 0.0), gt_sketch("palm", 3, 90.0)
    est = Fixed("palm", 9)
    seen = []
    r = Pipeline(est, RefineSettings(budget=10, embedding="none")).run(
        [front, (side, 90)], progress=seen.append
    )
    assert est.calls == 2  # the estimator read both drawings
    assert len(r.views) == 2 and r.views[1].yaw == 90.0 and not r.views[1].searched
    assert r.refinement is not None and r.refinement.view_yaws == (90.0,)
    assert len(r.refinement.view_losses_after) == 2
    assert r.losses["after"] == pytest.approx(np.mean(r.refinement.view_losses_after))
    assert r.losses["after"] <= r.losses["before"]
    for v in r.views:
        assert v.sketch_before.shape == v.sketch_after.shape == (256, 256)
        assert v.loss_after <= v.loss_before + 1e-9 or r.losses["after"] <= r.losses["before"]
    assert np.array_equal(r.views[0].sketch_after, r.sketch_after)
    summary = r.summary()
    assert [v["yaw"] for v in summary["views"]] == [0.0, 90.0]
    assert seen[-1].evaluations <= seen[-1].budget


def test_one_view_is_the_list_of_one() -> None:
    front = gt_sketch("palm", 3, 0.0)
    cfg = RefineSettings(budget=6, embedding="none")
    a = Pipeline(Fixed("palm", 9), cfg).run(front)
    b = Pipeline(Fixed("palm", 9), cfg).run([front])
    assert a.params == b.params and a.losses == b.losses and len(a.views) == 1
    assert "views" not in a.summary()


def test_an_unknown_side_is_found() -> None:
    # the truth's own tree drawn from 90 degrees: the start tree is the truth, so the
    # search of the second view's angle must land on 90 (or an equally good mirror)
    tree = species.sample("maple", 4)
    front, side = gt_sketch("maple", 4, 0.0), gt_sketch("maple", 4, 90.0)

    class Truth(Fixed):
        def estimate(self, sketch: np.ndarray) -> Estimate:
            return Estimate(tree, "maple", {"maple": 1.0})

    cfg = RefineSettings(budget=3, search_yaw=False, embedding="none")
    r = Pipeline(Truth("maple", 4), cfg).run([front, (side, None)])
    assert r.views[1].searched and r.views[1].yaw == 90.0
    r0 = Pipeline(Truth("maple", 4), cfg.replace(refine=False)).run([front, (side, "?")])
    assert r0.views[1].yaw == 90.0 and r0.refinement is None


def test_a_blank_second_view_is_refused_before_any_work() -> None:
    est = Fixed("palm", 9)
    blank = np.full((256, 256), 255, np.uint8)
    with pytest.raises(SketchError, match="view 2 of 2"):
        Pipeline(est, RefineSettings(budget=4)).run([gt_sketch("palm", 3, 0.0), (blank, 90)])
    assert est.calls == 0
