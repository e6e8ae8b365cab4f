"""treesketch.steps: each step of ``Pipeline.run`` on its own (stand-in estimators, small
budgets), and the run's judging and height steps of ``treesketch.pipeline``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pipeline_helpers import Fixed, gt_sketch

from refine.search import OUTLINE_TREES, Cancelled, RefineSettings, outline_allowance
from treesketch import Estimate, SketchError
from treesketch.pipeline import fit_height, has_height, judge_views, mesh_height
from treesketch.steps import (
    CANDIDATES,
    FirstEstimate,
    Progress,
    Reporter,
    draw_views,
    first_estimate,
    list_candidates,
    planned_evaluations,
    read_drawings,
    refine_species,
    share,
    species_to_try,
    timed,
)
from weberpenn import species

SCORES = {"palm": 0.6, "pine": 0.3, "oak": 0.02}


def scored(chosen: str | None = None) -> FirstEstimate:
    """A palm first estimate that also scores pine (and oak, far below)."""
    return FirstEstimate(Estimate(species.sample("palm", 9), "palm", dict(SCORES)), chosen)


def test_timed_records_the_block_seconds() -> None:
    timings: dict[str, float] = {}
    with timed(timings, "a"):
        pass
    assert list(timings) == ["a"] and 0.0 <= timings["a"] < 1.0


def test_reporter_tells_stages_then_the_first_tree_and_cancels() -> None:
    seen: list[Progress] = []
    report = Reporter(10, seen.append)
    report.tell("read")
    best = report.first_tree(scored(), plan=15)
    report.tell("refine", 99)
    assert [p.stage for p in seen] == ["read", "estimate", "refine"]
    assert seen[0].params is None and seen[0].budget == 10
    assert seen[1].species == "palm" and seen[1].version == 1 and seen[1].budget == 15
    assert seen[2].evaluations == 15  # never past the plan
    best.offer(species.sample("pine", 1), 30.0, 0.5, "pine", 0.5)
    assert best.species == "pine" and best.shown == 0.5 and best.version == 2
    stopping = Reporter(10, cancel=lambda: True)
    with pytest.raises(Cancelled, match="during read"):
        stopping.tell("read")


def test_read_drawings_prepares_every_view_once() -> None:
    img = gt_sketch()
    read = read_drawings([img, (gt_sketch(yaw=90.0), 90.0)], RefineSettings())
    assert len(read.views) == len(read.images) == len(read.drawings) == 2
    assert read.images[0].shape == (256, 256) and read.images[0].dtype == np.uint8
    assert [o.yaw for o in read.others] == [90.0]
    with pytest.raises(SketchError, match="view 2 of 2"):
        read_drawings([img, np.full((64, 64), 255, np.uint8)], RefineSettings())


def test_first_estimate_fuses_views_and_takes_the_users_species() -> None:
    est = Fixed("palm", 9)
    first = first_estimate(est, [gt_sketch(), gt_sketch(yaw=90.0)], chosen="pine")
    assert est.calls == 2
    assert first.species == "pine" and first.estimate.species == "palm"
    assert first.params == first.estimate.params_for("pine")
    assert first.yaw == 0.0 and first.scores == {"palm": 1.0}


def test_species_to_try_follows_the_settings() -> None:
    cfg = RefineSettings(species_tries=3, species_ratio=0.25)
    assert species_to_try(scored(), cfg) == ["palm", "pine"]
    assert species_to_try(scored(), cfg.replace(species_tries=1)) == ["palm"]
    assert species_to_try(scored("oak"), cfg) == ["oak"]
    assert species_to_try(scored(), cfg.replace(refine=False)) == []


def test_share_gives_the_first_species_the_whole_budget_and_most_of_the_time() -> None:
    cfg = RefineSettings(budget=40, time_limit=10.0)
    assert share(cfg, 0, 1) is cfg
    first, other = share(cfg, 0, 3), share(cfg, 1, 3)
    assert (first.budget, first.time_limit) == (40, pytest.approx(6.0))
    assert (other.budget, other.time_limit) == (20, pytest.approx(2.0))
    assert planned_evaluations(cfg, 3) == 80
    assert planned_evaluations(cfg.replace(refine=False), 3) == 0
    # the default run's second species still gets the whole outline step
    assert outline_allowance(other.budget) == outline_allowance(first.budget) == OUTLINE_TREES


def test_refine_species_without_names_keeps_the_first_estimate() -> None:
    first = scored()
    read = read_drawings(gt_sketch(), RefineSettings())
    search = refine_species(read, first, [], RefineSettings(), Reporter(0))
    assert search.species == "palm" and search.params == first.params
    assert search.result is None and search.opening is None and search.tried == {}
    assert search.evaluations == 0 and math.isclose(sum(search.posterior.values()), 1.0)


def test_refine_species_searches_each_and_picks_by_posterior() -> None:
    cfg = RefineSettings(budget=6, time_limit=None)
    read = read_drawings(gt_sketch(), cfg)
    first = scored()
    report = Reporter(cfg.budget)
    report.first_tree(first, planned_evaluations(cfg, 2))
    search = refine_species(read, first, ["palm", "pine"], cfg, report)
    assert list(search.tried) == ["palm", "pine"] and search.opening is search.refined["palm"]
    assert search.evaluations == sum(r.evaluations for r in search.refined.values())
    assert search.species == max(search.tried, key=lambda s: search.posterior[s])
    assert search.result is search.refined[search.species]
    assert search.start_yaw == search.refined["palm"].start_yaw
    chosen = refine_species(read, scored("pine"), ["pine"], cfg, Reporter(cfg.budget))
    assert chosen.species == "pine"


def test_draw_views_draws_every_view_and_takes_the_searchs_distances() -> None:
    cfg = RefineSettings(budget=6, time_limit=None)
    read = read_drawings([gt_sketch(), (gt_sketch(yaw=90.0), 90.0)], cfg)
    first = scored()
    plain = draw_views(read, first, refine_species(read, first, [], cfg, Reporter(0)))
    assert len(plain.views) == 2 and plain.views[1].yaw == 90.0
    assert plain.before is plain.after  # nothing refined: the estimate is the result
    assert (
        plain.loss_before
        == plain.loss_after
        == pytest.approx(np.mean([v.loss_before for v in plain.views]))
    )
    search = refine_species(read, first, ["palm"], cfg, Reporter(cfg.budget))
    drawn = draw_views(read, first, search)
    assert drawn.loss_after == search.result.loss_after
    assert drawn.loss_before == search.opening.loss_before
    assert drawn.after.shape == drawn.before.shape == (256, 256)


def test_list_candidates_puts_the_result_first() -> None:
    first = scored()
    read = read_drawings(gt_sketch(), RefineSettings())
    search = refine_species(read, first, [], RefineSettings(), Reporter(0))
    sketch = np.zeros((256, 256), np.uint8)
    cands = list_candidates(first, search, first.params, sketch)
    assert len(cands) == CANDIDATES and cands[0].species == "palm" and cands[0].sketch is sketch
    assert cands[1].species == "pine" and cands[1].sketch.shape == (128, 128)
    assert all(c.distance is None for c in cands)
    chosen = refine_species(read, scored("oak"), [], RefineSettings(), Reporter(0))
    forced = list_candidates(scored("oak"), chosen, chosen.params, sketch)
    assert forced[0].probability == 1.0 and all(c.probability == 0.0 for c in forced[1:])


def test_judge_views_uses_the_detector_when_there_is_one() -> None:
    cfg = RefineSettings(budget=6, time_limit=None)
    read = read_drawings(gt_sketch(), cfg)
    est = Estimate(species.sample("palm", 9), "palm", {"palm": 1.0}, tree_probability=0.2)
    first = FirstEstimate(est)
    drawn = draw_views(read, first, refine_species(read, first, [], cfg, Reporter(0)))
    judged = judge_views(read, drawn, first, embedded=True)
    assert judged.tree_like == 0.2 and judged.warning is not None
    assert judged.ink_after >= 0.0
    assert judged.confidence([]) == pytest.approx(0.2 * 0.2)


def test_fit_height_rescales_only_when_asked() -> None:
    params = species.sample("palm", 9)
    from weberpenn import build_mesh, grow

    mesh = build_mesh(grow(params), species="palm")
    assert has_height(mesh, None) and has_height(mesh, mesh_height(mesh))
    assert not has_height(mesh, 7.5)
    params2, mesh2 = fit_height(params, mesh, "palm", 7.5)
    assert mesh_height(mesh2) == pytest.approx(7.5, rel=0.02)
    assert params2["scale"] != params["scale"]
