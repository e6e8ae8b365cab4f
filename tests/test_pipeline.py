"""treesketch.pipeline: the seam (Estimator, Pipeline, RefineSettings) on synthetic sketches."""

from __future__ import annotations

import time

import numpy as np
import pytest
from pipeline_helpers import Fixed, gt_sketch

from treesketch import (
    Cancelled,
    Estimate,
    Estimator,
    Pipeline,
    RefineSettings,
    SketchError,
    load_estimator,
    load_sketch,
    predict_then_refine,
)
from treesketch.pipeline import (
    LOW_CONFIDENCE_LOSS,
    LOW_CONFIDENCE_LOSS_SHAPE,
    rescale_height,
    tree_height,
)
from weberpenn import species


def test_fixed_is_an_estimator() -> None:
    assert isinstance(Fixed("palm", 1), Estimator)
    assert load_estimator(Fixed("palm", 1)).name == "fixed"


def test_refine_improves_and_fields() -> None:
    img = gt_sketch()
    seen = []
    r = Pipeline(Fixed("palm", 9), RefineSettings(budget=25)).run(img, progress=seen.append)
    assert r.species == "palm" and r.estimator == "fixed"
    assert r.losses["after"] <= r.losses["before"]
    assert r.sketch_before.shape == r.sketch_after.shape == (256, 256)
    assert r.input_sketch is not None and r.input_sketch.dtype == np.uint8
    assert r.refinement is not None and r.refinement.evaluations <= 25
    assert len(r.tree_mesh.branches.faces) > 0
    assert {"prepare", "estimate", "refine", "total"} <= set(r.timings)
    assert 0.0 < r.confidence <= 1.0
    # "estimate" is told as it starts and again with the first estimate's tree
    assert [p.stage for p in seen][:4] == ["read", "estimate", "estimate", "refine"]
    assert seen[1].params is None and seen[2].params is not None
    refining = [p for p in seen if p.stage == "refine" and p.evaluations]
    assert refining and refining[-1].evaluations == r.refinement.evaluations
    assert all(p.budget == 25 for p in seen)
    summary = r.summary()
    assert summary["species"] == "palm" and summary["evaluations"] == r.refinement.evaluations
    assert summary["species_scores"] == {"palm": 1.0}


def _frame_gaps(sketch: np.ndarray) -> tuple[float, float]:
    """How far a sketch's ink is from the drawing's frame (px): its base from the bottom
    margin, and the nearest of its top and sides from the frame's edge."""
    from render.reader import FRAME_BOTTOM, FRAME_EDGE

    ink = np.asarray(sketch) < 128
    side = ink.shape[0]
    ys, xs = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    edge = FRAME_EDGE * side
    base = abs(ys[-1] + 1 - FRAME_BOTTOM * side)
    return float(base), float(min(ys[0] - edge, xs[0] - edge, side - 1 - edge - xs[-1]))


def test_the_tree_is_framed_as_the_drawing() -> None:
    # an oak wider from another side: the renderer's frame (fit over all sides) leaves it
    # 26 px below the top and 5 px inside the sides; beside the drawing it is shown, and
    # its outline compared, as the drawing is framed (issue 48)
    r = Pipeline(Fixed("oak", 3), RefineSettings(budget=6)).run(gt_sketch("oak", 3))
    for sketch in (r.input_sketch, r.sketch_before, r.sketch_after):
        base, edge = _frame_gaps(sketch)
        assert base <= 2.0 and abs(edge) <= 2.0, (base, edge)


def test_predict_then_refine_is_the_pipeline() -> None:
    img = gt_sketch()
    a = predict_then_refine(img, estimator=Fixed("palm", 9), budget=6)
    b = Pipeline(Fixed("palm", 9), RefineSettings(budget=6)).run(img)
    assert a.params == b.params and a.losses == b.losses and a.yaw == b.yaw


def test_no_refine_and_height() -> None:
    img = gt_sketch()
    r = Pipeline(Fixed("palm", 9), RefineSettings(refine=False)).run(img, height=7.5)
    assert r.refinement is None
    assert r.losses["after"] == r.losses["before"]
    lo, hi = r.tree_mesh.bounds()
    assert hi[2] - lo[2] == pytest.approx(7.5, rel=0.02)
    assert tree_height(r.params) == pytest.approx(7.5, rel=0.02)
    with pytest.raises(ValueError, match="height"):
        rescale_height(species.sample("palm", 1), -2.0)


def test_the_refined_tree_keeps_the_searchs_own_size() -> None:
    # the estimate is a bonsai of another seed: the search changes the trunk's length and
    # bend, which a sketch framed to its tree cannot tell from the tree's size (the
    # hand-made distance alone: with the embedding's term these 25 evaluations find no
    # better point, and the rule under test needs a search that moves)
    img = gt_sketch("bonsai", 3)
    start = tree_height(Fixed("bonsai", 7).tree)
    free = Pipeline(Fixed("bonsai", 7), RefineSettings(budget=25, embedding="none")).run(img)
    assert abs(tree_height(free.params) - start) > 0.01 * start
    # the size values are the estimate's; the height follows the proportions
    assert all(free.params[k] == Fixed("bonsai", 7).tree[k] for k in ("scale", "scaleV"))
    lo, hi = free.tree_mesh.bounds()
    assert hi[2] - lo[2] == pytest.approx(tree_height(free.params), rel=1e-6)


@pytest.mark.parametrize("height", [float("inf"), 1e308, float("nan"), 0.0, -1.0])
def test_bad_height_is_refused_before_any_work(height: float) -> None:
    est = Fixed("palm", 9)
    img = gt_sketch()
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="height"):
        Pipeline(est, RefineSettings(budget=50)).run(img, height=height)
    assert est.calls == 0 and time.perf_counter() - t0 < 1.0


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"budget": 0}, "budget"),
        ({"budget": True}, "budget"),
        ({"time_limit": 0.0}, "time_limit"),
        ({"time_limit": float("inf")}, "time_limit"),
        ({"algorithm": "nope"}, "algorithm"),
        ({"hold": ("notakey",)}, "hold"),
        ({"species_ratio": 1.5}, "species_ratio"),
        ({"fast_sketch": 1}, "fast_sketch"),
    ],
)
def test_settings_are_validated(change: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        RefineSettings(**change).validate()
    with pytest.raises(ValueError, match=match):
        Pipeline(Fixed("palm", 1), RefineSettings(**change))


def test_tiny_time_limit_still_evaluates_the_first_estimate() -> None:
    r = Pipeline(Fixed("palm", 9), RefineSettings(time_limit=1e-6)).run(gt_sketch())
    assert r.refinement is not None and r.refinement.evaluations >= 1
    assert np.isfinite(r.losses["before"]) and np.isfinite(r.losses["after"])
    assert r.losses["after"] <= r.losses["before"]


def test_cancel_stops_within_one_evaluation() -> None:
    seen = []

    def cancel() -> bool:
        return len([p for p in seen if p.evaluations >= 2]) > 0

    with pytest.raises(Cancelled):
        Pipeline(Fixed("palm", 9), RefineSettings(budget=40)).run(
            gt_sketch(), progress=seen.append, cancel=cancel
        )
    assert max(p.evaluations for p in seen) <= 3


def test_template_estimator() -> None:
    from treesketch.estimators import TemplateEstimator

    assert isinstance(load_estimator("template"), TemplateEstimator)
    # one tree a species (the default three build 132 sketches: 19 s of the suite)
    r = Pipeline(TemplateEstimator(seeds=1), RefineSettings(budget=8)).run(gt_sketch("pine", 2))
    assert r.estimator == "template" and r.species in species.SPECIES
    assert r.losses["after"] <= r.losses["before"]
    assert set(r.species_scores) == set(species.SPECIES)
    assert max(r.species_scores, key=r.species_scores.get) == r.estimate.species


def test_load_estimator_errors(tmp_path) -> None:
    with pytest.raises(ValueError, match="unknown estimator"):
        load_estimator("magic")
    with pytest.raises(ValueError, match="dataset"):
        load_estimator("nns")
    with pytest.raises(ValueError):
        load_estimator(tmp_path / "missing.pt")


def test_blank_page_is_a_clear_error() -> None:
    with pytest.raises(SketchError, match="blank"):
        Pipeline(Fixed("palm", 1)).run(np.full((200, 300), 255, np.uint8))


@pytest.mark.parametrize("embedding", ["shipped", "none"])
@pytest.mark.parametrize("kind", ["circle", "noise"])
def test_non_trees_are_flagged(kind: str, embedding: str) -> None:
    n = 256
    if kind == "circle":
        yy, xx = np.mgrid[:n, :n]
        img = np.where(np.abs(np.hypot(yy - n / 2, xx - n / 2) - 80) < 2, 0, 255)
    else:
        img = (np.random.default_rng(0).random((n, n)) > 0.5) * 255
    cfg = RefineSettings(budget=6, embedding=embedding)
    r = Pipeline(Fixed("maple", 1), cfg).run(img.astype(np.uint8))
    assert r.warning is not None and "low confidence" in r.warning
    assert r.low_confidence and r.confidence < 0.5
    # each distance is judged by the limit calibrated for it
    limit = LOW_CONFIDENCE_LOSS if embedding == "shipped" else LOW_CONFIDENCE_LOSS_SHAPE
    assert f"limit {limit};" in r.warning


def test_load_sketch_inputs(tmp_path) -> None:
    from PIL import Image

    img = gt_sketch()
    p = tmp_path / "s.png"
    Image.fromarray(img).convert("RGBA").save(p)
    assert np.array_equal(load_sketch(p), img)
    assert np.array_equal(load_sketch(p.read_bytes()), img)
    assert np.array_equal(load_sketch(Image.open(p)), img)
    with pytest.raises(SketchError, match="not found"):
        load_sketch(tmp_path / "missing.png")
    with pytest.raises(SketchError, match="not an image"):
        load_sketch(b"not an image")
    with pytest.raises(SketchError, match=r"\(H, W\)"):
        load_sketch(np.zeros(10))


class Unsure:
    """Says maple, nearly as sure of palm: species by synthesis must settle it."""

    name = "unsure"

    def estimate(self, sketch: np.ndarray) -> Estimate:
        return Estimate(
            species.sample("maple", 1),
            "maple",
            {"maple": 1.0, "palm": 0.9, "pine": 0.1},
            alternatives={"palm": species.sample("palm", 9)},
        )


def _species_own_shapes(monkeypatch) -> None:
    """Refine every species from the estimate, not from a start fitted to the drawn
    outline (issue 48, ``refine.start``): with it a maple takes this palm's outline
    (distance 2.37 against the palm's 2.56 from its poor start here)."""
    monkeypatch.setattr("refine.search.choose_start", lambda d, params, name, yaw: (params, ()))


def test_species_by_synthesis_keeps_the_better_match(monkeypatch) -> None:
    # on the species' own shapes (the outline-fitted start off)
    _species_own_shapes(monkeypatch)
    seen = []
    r = Pipeline(Unsure(), RefineSettings(budget=12)).run(
        gt_sketch("palm", 3), progress=seen.append
    )
    assert set(r.extras["tried"]) == {"maple", "palm"}  # pine scores too low to try
    assert r.species == "palm" == min(r.extras["tried"], key=r.extras["tried"].get)
    # species are weighed by their searches' distances, not by how far the outline step
    # after each search followed the drawn outline (a maple takes a palm's outline)
    assert r.extras["tried"]["palm"] == r.refinement.evidence
    assert r.losses["after"] == r.refinement.loss_after
    assert r.summary()["tried"] == r.extras["tried"]
    evals = [p.evaluations for p in seen]
    assert evals == sorted(evals)  # progress never runs backwards across candidates
    one = Pipeline(Unsure(), RefineSettings(budget=12, species_tries=1)).run(gt_sketch("palm", 3))
    assert one.species == "maple" and set(one.extras["tried"]) == {"maple"}


def test_candidates_list_three_species_with_trees_distances_and_probabilities(
    monkeypatch,
) -> None:
    # the species' own shapes, as in the test above
    _species_own_shapes(monkeypatch)
    r = Pipeline(Unsure(), RefineSettings(budget=12)).run(gt_sketch("palm", 3))
    names = [c.species for c in r.candidates]
    assert len(names) >= 3 and names[0] == r.species and len(set(names)) == len(names)
    assert abs(sum(c.probability for c in r.candidates) - 1.0) < 0.05
    assert r.candidates[0].probability == max(c.probability for c in r.candidates)
    refined = {c.species for c in r.candidates if c.distance is not None}
    assert refined == {"maple", "palm"}
    for c in r.candidates:
        assert c.sketch is not None and c.sketch.dtype == np.uint8
        assert c.params.seed >= 0 and species.canonical(c.species) == c.species
    summary = r.summary()
    assert [c["species"] for c in summary["candidates"]] == names
    assert summary["candidates"][0]["params"] == r.params.to_dict()
    assert summary["species_text"].startswith("a palm")
    # the species' probability, lowered when the drawing may not be a tree at all
    assert r.confidence <= r.candidates[0].probability + 1e-12
    if r.warning is None:
        assert r.confidence == pytest.approx(r.candidates[0].probability)


def test_the_species_the_user_means_is_the_one_refined() -> None:
    est = Unsure()  # it would say maple or palm; the user says pine
    r = Pipeline(est, RefineSettings(budget=10)).run(gt_sketch("palm", 3), species="Pine")
    assert r.species == "pine" and set(r.extras["tried"]) == {"pine"}
    assert r.params["levels"] == species.base("pine")["levels"]
    assert r.candidates[0].species == "pine" and r.candidates[0].probability == 1.0
    christmas = Pipeline(est, RefineSettings(refine=False)).run(
        gt_sketch("palm", 3), species="christmas tree"
    )
    assert (
        christmas.species == "fir" and christmas.params["leaves"] == species.base("fir")["leaves"]
    )
    with pytest.raises(ValueError, match="unknown species 'baobab'"):
        Pipeline(est, RefineSettings(budget=10)).run(gt_sketch("palm", 3), species="baobab")


def test_posterior_lets_a_confident_network_stand_against_a_small_distance_gap() -> None:
    from treesketch.species_choice import posterior

    # the network is sure of palm; the cherry's filled crown fits a little better
    p = posterior({"palm": 0.95, "cherry": 0.05}, {"palm": 1.00, "cherry": 0.98})
    assert max(p, key=p.get) == "palm"
    # ...but a clearly better fit wins over a mild preference
    p = posterior({"palm": 0.6, "cherry": 0.4}, {"palm": 1.5, "cherry": 0.5})
    assert max(p, key=p.get) == "cherry"
    assert abs(sum(p.values()) - 1) < 1e-9


def test_describe_puts_the_species_in_words() -> None:
    from treesketch.species_choice import Candidate, describe

    t = species.sample("palm", 0)
    text = describe(
        [Candidate("palm", t, 0.7, 1.0, 0.7), Candidate("cherry", t, 0.2, 1.1, 0.25),
         Candidate("oak", t, 0.1, None, 0.05)]
    )  # fmt: skip
    assert text == "a palm (70%); could also be a cherry"
    assert describe([Candidate("oak", t, 1.0, 1.0, 1.0)]).startswith("an oak")


def test_the_drawing_is_framed_and_prepared_once_per_run(monkeypatch) -> None:
    # two species refined, the first estimate's distance and the line distance: every
    # comparison with the drawing uses the one PreparedDrawing the run builds
    from refine import objective, shape

    made, prepared = [], []
    create, from_image = objective.PreparedDrawing.create.__func__, shape.ShapeTarget.from_image

    def counting_create(cls, img, *args, **kwargs):
        made.append(np.asarray(img).copy())
        return create(cls, img, *args, **kwargs)

    def counting_from_image(img, *args, **kwargs):
        prepared.append(np.asarray(img).copy())
        return from_image(img, *args, **kwargs)

    monkeypatch.setattr(objective.PreparedDrawing, "create", classmethod(counting_create))
    monkeypatch.setattr(shape.ShapeTarget, "from_image", counting_from_image)
    r = Pipeline(Unsure(), RefineSettings(budget=12, embedding="none")).run(gt_sketch("palm", 3))
    assert set(r.extras["tried"]) == {"maple", "palm"}
    assert len(made) == 1 and np.array_equal(made[0], r.input_sketch)
    framed_input = objective.framed(r.input_sketch, 128)
    assert sum(np.array_equal(p, framed_input) for p in prepared) == 1


def test_a_drawing_prepared_for_other_settings_is_refused() -> None:
    from refine.objective import PreparedDrawing
    from refine.search import refine

    img = gt_sketch("palm", 3)
    drawing = PreparedDrawing.create(img, 64, "ink")
    with pytest.raises(ValueError, match="prepared for size 64"):
        refine(drawing, species.sample("palm", 9), RefineSettings(budget=2), species="palm")
    with pytest.raises(ValueError, match="shape metric only"):
        PreparedDrawing.create(img, 128, "ink", embedder=object())


def test_progress_shows_the_current_best_tree_within_the_budget() -> None:
    """The first estimate comes with the "estimate" stage; the refinement's best follows;
    the count never passes the plan (both species' budgets) and the distance only falls."""
    seen = []
    r = Pipeline(Unsure(), RefineSettings(budget=12)).run(
        gt_sketch("palm", 3), progress=seen.append
    )
    assert set(r.extras["tried"]) == {"maple", "palm"}
    # the plan is known once the candidates are: palm gets max(8, 12 // 2)
    assert {p.budget for p in seen if p.params is not None} == {12 + 8}
    assert all(p.evaluations <= p.budget for p in seen)
    first = next(p for p in seen if p.params is not None)
    assert first.stage == "estimate" and first.species == "maple" and first.version == 1
    assert first.params.to_dict() == Unsure().estimate(None).params.to_dict()
    losses = [p.best_loss for p in seen if not np.isnan(p.best_loss)]
    assert losses and all(b <= a for a, b in zip(losses, losses[1:], strict=False))
    versions = [p.version for p in seen]
    assert versions == sorted(versions) and versions[-1] > 1
    last = seen[-1]
    assert last.species == r.species and last.params is not None
    assert last.best_loss == pytest.approx(min(losses))
