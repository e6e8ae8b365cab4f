"""refine.objective: the sketch distance and the search space."""

from __future__ import annotations

import numpy as np
import pytest

from refine.objective import (
    SearchSpace,
    SketchObjective,
    SketchTarget,
    framed,
    make_target,
    sketch_distance,
)
from weberpenn import build_mesh, grow, species


def _ring(r: float, width: float = 2.0, n: int = 128, cx: float = 64) -> np.ndarray:
    yy, xx = np.mgrid[:n, :n]
    return np.where(np.abs(np.hypot(yy - 64, xx - cx) - r) < width, 0, 255).astype(np.uint8)


def test_identical_sketches_are_zero() -> None:
    img = _ring(30)
    assert sketch_distance(img, img) == 0.0
    blank = np.full((64, 64), 255, np.uint8)
    assert sketch_distance(blank, blank) == 0.0


def test_grows_with_known_perturbation() -> None:
    base = _ring(30)
    d = [sketch_distance(base, _ring(30, cx=64 + s)) for s in (0, 2, 5, 10, 20)]
    assert d[0] == 0.0
    assert all(b > a for a, b in zip(d, d[1:], strict=False)), d


def test_symmetric_and_blank_penalised() -> None:
    a, b = _ring(30), _ring(20)
    assert sketch_distance(a, b) == pytest.approx(sketch_distance(b, a))
    blank = np.full((128, 128), 255, np.uint8)
    assert sketch_distance(a, blank) > sketch_distance(a, b)


def test_accepts_float_rgb_and_resizes() -> None:
    a = _ring(30)
    rgb = np.repeat(a[..., None], 3, axis=2)
    assert sketch_distance(a, rgb) == 0.0
    assert sketch_distance(a, a.astype(np.float32) / 255.0) == 0.0
    with pytest.raises(ValueError, match=r"\(H, W\)"):
        SketchTarget.from_image(np.zeros(5))


def test_search_space_round_trip_and_projection() -> None:
    gt = species.sample("bonsai", 4)
    sp = SearchSpace.create("bonsai", gt)
    assert sp.labels[-1] == "yaw" and "curveBack[0]" in sp.labels  # a search freedom
    x = sp.from_params(gt, 90.0)
    assert x.min() >= 0.0 and x.max() <= 1.0
    p = sp.to_params(x)
    assert p["curveBack"][0] == pytest.approx(-p["curve"][0])  # mirror kept
    for u in sp.dims:
        a, b = gt[u.key], p[u.key]
        if u.index is not None:
            a, b = a[u.index], b[u.index]
        assert b == pytest.approx(a, abs=1e-9)
    assert sp.yaw(x) == pytest.approx(90.0)
    with pytest.raises(ValueError, match="not searchable"):
        SearchSpace.create("bonsai", gt, keys=["nosuchkey"])


def test_live_drops_exactly_the_values_that_do_not_change_the_tree() -> None:
    gt = species.sample("palm", 1)
    sp = SearchSpace.create("palm", gt)
    live = sp.live()
    assert live.search_yaw and live.labels[-1] == "yaw"
    dropped = set(sp.labels) - set(live.labels)
    # a palm has no trunk splits (rSplits2, rotate[0]) and its stems ignore rLastAng
    assert {"rSplits2", "rotate[0]"} <= dropped and "curve[0]" in live.labels

    def points(params) -> np.ndarray:  # stems, radii and leaves
        sk = grow(params)
        return np.concatenate([np.ravel(a) for a in (sk.points, sk.radii, sk.leaf_matrices)])

    x0 = sp.from_params(gt, 0.0)
    for i, u in enumerate(sp.dims):
        x = x0.copy()
        x[i] = 1.0 - x[i] if abs(0.5 - x[i]) > 0.05 else 0.0
        moved = points(sp.to_params(x))
        same = moved.shape == points(gt).shape and np.allclose(moved, points(gt), atol=1e-9)
        assert same == (u.label in dropped), u.label
    smaller = live.without(["scaleV", "curve[0]"])
    assert "scaleV" not in smaller.labels and "curve[0]" not in smaller.labels
    assert smaller.n == live.n - 2


def test_objective_deterministic_cached_and_zero_at_truth() -> None:
    from render.sketch import SketchRenderer

    gt = species.sample("palm", 2)
    # drawn as the search draws its candidates (``draw_side(128)``): 0 at the truth
    img = SketchRenderer(build_mesh(grow(gt), species="palm")).sketch(90.0, 256)
    sp = SearchSpace.create("palm", gt)
    obj = SketchObjective(make_target(framed(img, 128), 128), sp)
    x = sp.from_params(gt, 90.0)
    assert obj(x) == pytest.approx(0.0, abs=1e-9)
    assert obj.evaluations == 1
    assert obj(x) == obj(x) and obj.evaluations == 1  # cached
    x2 = x.copy()
    x2[sp.labels.index("scaleV")] = 1.0 - x2[sp.labels.index("scaleV")]
    obj2 = SketchObjective(make_target(framed(img, 128), 128), sp)
    assert obj2(x2) == obj(x2) > 0.0  # deterministic across objectives


def test_framed_pools_each_two_by_two_block_to_its_darkest_pixel() -> None:
    from render.reader import normalise_drawing

    img = _ring(30, width=1.0, n=160)  # a one-pixel pen line: pooling must keep it whole
    big = normalise_drawing(img, 256, over_crown=True)
    out = framed(img, 128)
    assert out.dtype == np.uint8 and out.shape == (128, 128)
    assert np.array_equal(out, big.reshape(128, 2, 128, 2).min(axis=(1, 3)))
    assert (out < 128).sum() >= (big < 128).sum() / 4  # no line lost to the pooling


@pytest.mark.parametrize("name", ["palm", "fir", "oak", "willow", "bonsai"])
def test_a_tree_sketch_frames_as_a_drawing_without_the_page_cleaning(name: str) -> None:
    """A candidate's sketch (the refinement's fast one) framed by ``framed_sketch`` is
    ``framed``'s picture, pixel for pixel, and so its envelope (``seen_envelope``): the
    reader's cleaning of a page finds nothing to clean on a tree the renderer drew but
    its specks, which go (a stray leaf clump drawn above the crown, as a willow's polish
    grew one, would frame the tree smaller).  Trees from the species' own shape and from
    a custom one, as the polish grows them."""
    from refine.objective import framed_sketch
    from refine.prepare import prepare_sketch
    from refine.shape import prepared_envelope
    from refine.start import cheap_sketches, seen_envelope

    p = species.sample(name, 4)
    trees = [p, p.replace(shape=8, customShape=[0.3, 1.0, 0.6, 0.4], baseSize=0.35)]
    for tree in trees:
        for sk in cheap_sketches(tree, name, 128, [20.0, 200.0]):
            stray = sk.copy()  # a small ring over the crown's middle, as a clump of leaves
            ys, xs = np.flatnonzero((sk < 128).any(axis=1)), np.flatnonzero((sk < 128).any(axis=0))
            top, middle = max(4, int(ys[0]) - 12), (int(xs[0]) + int(xs[-1])) // 2
            yy, xx = np.mgrid[:256, :256]
            stray[np.abs(np.hypot(yy - top, xx - middle) - 3) < 0.8] = 0
            for img in (sk, stray):
                assert np.array_equal(framed_sketch(img, 128), framed(img, 128))
            full = prepared_envelope(prepare_sketch(framed(sk, 128), 128))
            assert np.array_equal(seen_envelope(sk, 128), full)


def test_a_blank_tree_sketch_is_refused_as_a_blank_drawing_is() -> None:
    from refine.objective import framed_sketch
    from render.reader import SketchError

    blank = np.full((256, 256), 255, np.uint8)
    with pytest.raises(SketchError, match="blank"):
        framed_sketch(blank, 128)
    with pytest.raises(ValueError, match="2-D"):
        framed_sketch(np.zeros((256, 256, 3), np.uint8), 128)
