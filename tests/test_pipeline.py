"""treesketch.pipeline: predict_then_refine on synthetic sketches and non-trees."""

from __future__ import annotations

import numpy as np
import pytest

from treesketch.pipeline import (
    SketchError,
    load_sketch,
    predict_then_refine,
    rescale_height,
    tree_height,
)
from weberpenn import build_mesh, grow, species


def _gt_sketch(name: str = "palm", seed: int = 3, yaw: float = 0.0) -> np.ndarray:
    from render.sketch import SketchRenderer

    return SketchRenderer(build_mesh(grow(species.sample(name, seed)), species=name)).sketch(
        yaw, 256
    )


def _estimator(name: str, seed: int):
    def estimate(img: np.ndarray):
        return species.sample(name, seed), name

    return estimate


def test_refine_improves_and_fields() -> None:
    img = _gt_sketch()
    r = predict_then_refine(img, budget=25, model=_estimator("palm", 9))
    assert r.species == "palm" and r.estimator == "tsn"
    assert r.losses["after"] <= r.losses["before"]
    assert r.sketch_before.shape == r.sketch_after.shape == (256, 256)
    assert r.input_sketch is not None and r.input_sketch.dtype == np.uint8
    assert r.refinement is not None and r.refinement.evaluations <= 25
    assert len(r.tree_mesh.branches.faces) > 0
    assert {"prepare", "estimate", "refine", "total"} <= set(r.timings)
    assert 0.0 < r.confidence <= 1.0


def test_no_refine_and_height() -> None:
    img = _gt_sketch()
    r = predict_then_refine(img, refine=False, height=7.5, model=_estimator("palm", 9))
    assert r.refinement is None
    assert r.losses["after"] == r.losses["before"]
    lo, hi = r.tree_mesh.bounds()
    assert hi[2] - lo[2] == pytest.approx(7.5, rel=0.02)
    assert tree_height(r.params) == pytest.approx(7.5, rel=0.02)
    with pytest.raises(ValueError, match="height"):
        rescale_height(species.sample("palm", 1), -2.0)


def test_template_estimate_without_model(monkeypatch: pytest.MonkeyPatch) -> None:
    import treesketch.pipeline as pl

    monkeypatch.setattr(pl, "_load_model", lambda model: None)
    r = predict_then_refine(_gt_sketch("pine", 2), budget=8)
    assert r.estimator == "template" and r.species in species.SPECIES
    assert r.losses["after"] <= r.losses["before"]


def test_blank_page_is_a_clear_error() -> None:
    with pytest.raises(SketchError, match="blank"):
        predict_then_refine(np.full((200, 300), 255, np.uint8), model=_estimator("palm", 1))


@pytest.mark.parametrize("kind", ["circle", "noise"])
def test_non_trees_are_flagged(kind: str) -> None:
    n = 256
    if kind == "circle":
        yy, xx = np.mgrid[:n, :n]
        img = np.where(np.abs(np.hypot(yy - n / 2, xx - n / 2) - 80) < 2, 0, 255)
    else:
        img = (np.random.default_rng(0).random((n, n)) > 0.5) * 255
    r = predict_then_refine(img.astype(np.uint8), budget=6, model=_estimator("maple", 1))
    assert r.warning is not None and "low confidence" in r.warning
    assert r.low_confidence and r.confidence < 0.5


def test_load_sketch_inputs(tmp_path) -> None:
    from PIL import Image

    img = _gt_sketch()
    p = tmp_path / "s.png"
    Image.fromarray(img).convert("RGBA").save(p)
    assert np.array_equal(load_sketch(p), img)
    assert np.array_equal(load_sketch(p.read_bytes()), img)
    with pytest.raises(SketchError, match="not found"):
        load_sketch(tmp_path / "missing.png")
    with pytest.raises(SketchError, match="cannot read"):
        load_sketch(b"not an image")
    with pytest.raises(SketchError, match="2-D"):
        load_sketch(np.zeros(10))
