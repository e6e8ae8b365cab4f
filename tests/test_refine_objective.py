"""refine.objective: the sketch distance and the search space."""

from __future__ import annotations

import numpy as np
import pytest

from refine.objective import (
    SearchSpace,
    SketchObjective,
    SketchTarget,
    depth_extent,
    framed,
    make_target,
    mass_offset,
    sketch_distance,
    tree_points,
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
    img = SketchRenderer(build_mesh(grow(gt), species="palm")).sketch(90.0, 128)
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


def test_depth_is_where_the_mass_lies_along_the_line_of_sight() -> None:
    from render.camera import Camera, Framing, view_direction

    sk = grow(species.sample("bonsai", 1))  # a bonsai whose crown leans well off its base
    m = mass_offset(sk)
    pts = np.concatenate([sk.points, sk.leaf_positions])
    height = float(np.ptp(pts[:, 2]))
    assert np.linalg.norm(m) > 0.1
    np.testing.assert_allclose(m, pts[:, :2].mean(axis=0) / height)
    gt = species.sample("bonsai", 1)
    sp = SearchSpace.create("bonsai", gt)
    obj = SketchObjective(make_target(np.full((64, 64), 255, np.uint8), 64), sp)
    obj.sketch_at(sp.from_params(gt, 0.0))  # grows the tree
    frame = Framing.from_parts([pts])
    centre = np.array([0.0, 0.0, 0.0])
    mass = np.array([m[0], m[1], 0.0]) * height
    for yaw in (0.0, 35.0, 90.0, 200.0, 300.0):
        cam = Camera(frame, yaw)
        right, _, forward = cam.basis()
        np.testing.assert_allclose(view_direction(yaw), forward, atol=1e-12)
        # what the picture shows across the page, and what it cannot show: the depth
        across = (cam.project(mass[None], 64)[0, 0] - cam.project(centre[None], 64)[0, 0]) / 64
        assert across * frame.span / height == pytest.approx(float(m @ right[:2]), abs=1e-9)
        assert obj.depth(yaw) == pytest.approx(float(m @ forward[:2]), abs=1e-12)
        assert obj.depth(yaw) ** 2 + float(m @ right[:2]) ** 2 == pytest.approx(m @ m)
    # the views where the lean points at the camera, or away from it
    worst = np.degrees(np.arctan2(-m[0], m[1]))
    assert obj.depth(worst) == pytest.approx(np.linalg.norm(m))
    assert obj.depth(worst + 90.0) == pytest.approx(0.0, abs=1e-12)


def test_extent_change_is_the_depth_a_candidate_gains_or_loses_at_its_own_view() -> None:
    from render.camera import view_direction

    ref_params = species.sample("cherry", 4)
    other = species.sample("cherry", 5)
    sk = grow(ref_params)
    ref = tree_points(sk)
    pts = np.concatenate([sk.points, sk.leaf_positions])
    height = float(np.ptp(pts[:, 2]))
    np.testing.assert_allclose(ref, pts / height)
    assert np.ptp(ref[:, 2]) == pytest.approx(1.0)
    for yaw in (0.0, 60.0, 90.0, 250.0):
        d = pts[:, :2] @ view_direction(yaw)[:2] / height
        np.testing.assert_allclose(depth_extent(ref, yaw), [d.min(), d.max()])
        # the far side seen from behind is the near side seen from the front
        np.testing.assert_allclose(depth_extent(ref, yaw + 180.0), [-d.max(), -d.min()])
    sp = SearchSpace.create("cherry", other)
    target = make_target(np.full((64, 64), 255, np.uint8), 64)
    obj = SketchObjective(target, sp, extent_weight=2.0, extent_reference=ref)
    plain = SketchObjective(target, sp)
    x = sp.from_params(other, 0.0)
    loss, base = obj(x), plain(x)
    change = obj.extent_change(0.0)
    mine = depth_extent(tree_points(grow(sp.to_params(x))), 0.0)
    assert change == pytest.approx(float(np.sum((mine - depth_extent(ref, 0.0)) ** 2)))
    assert change > 1e-4  # another seed's tree reaches elsewhere in depth
    assert loss == pytest.approx(base + 2.0 * change)
    assert obj.sketch_loss(x) == pytest.approx(base)
    # the reference itself costs nothing, from any side: turning is the view prior's job
    same = SketchObjective(target, SearchSpace.create("cherry", ref_params), extent_reference=ref)
    same.sketch_at(same.space.from_params(ref_params, 0.0))
    for yaw in (0.0, 135.0, 300.0):
        assert same.extent_change(yaw) == pytest.approx(0.0, abs=1e-12)
