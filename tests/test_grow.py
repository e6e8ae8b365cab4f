"""Tests of weberpenn.grow: structure, the parameters' meaning, determinism, references."""

from __future__ import annotations

import numpy as np
import pytest
from paths import GT_PARAM_FILES as REF_FILES

from weberpenn import default_params, load_params, species
from weberpenn.grow import Skeleton, grow


def _plain(**changes):
    """Default dictionary without curvature, splits or random-looking keys, then changes."""
    values = dict(
        curve=(0.0, 0.0, 0.0, 0.0),
        curveV1=(0.0, 0.0, 0.0, 0.0),
        curveV2=(0.0, 0.0, 0.0, 0.0),
        curveBack=(0.0, 0.0, 0.0, 0.0),
        attractUp=(0.0, 0.0, 0.0, 0.0),
        segSplits=(0.0, 0.0, 0.0, 0.0),
        baseSplits=0,
        scale=10.0,
        scaleV=0.0,
    )
    values.update(changes)
    return default_params().replace(**values)


def _check_structure(sk: Skeleton) -> None:
    assert sk.offsets[0] == 0 and sk.offsets[-1] == len(sk.points) == len(sk.radii)
    assert np.all(np.diff(sk.offsets) >= 2)
    assert len(sk.levels) == len(sk.parents) == sk.n_stems
    assert sk.parents[0] == -1 and sk.levels[0] == 0
    assert np.all(sk.parents[1:] >= 0)
    assert np.all(sk.parents < np.arange(sk.n_stems))
    lp = sk.levels[sk.parents[1:]]
    own = sk.levels[1:]
    assert np.all((lp == own) | (lp == own - 1))
    assert np.all(np.isfinite(sk.points)) and np.all(np.isfinite(sk.radii))
    assert np.all(sk.radii >= 0)
    assert sk.leaf_matrices.shape == (sk.n_leaves, 3, 3)
    assert np.all(np.isfinite(sk.leaf_positions)) and np.all(np.isfinite(sk.leaf_matrices))


def _radii_never_grow(sk: Skeleton) -> None:
    for i in range(sk.n_stems):
        _, r = sk.stem(i)
        assert np.all(np.diff(r) <= 1e-12 * max(1.0, r[0])), (i, r)


def test_levels_respected():
    for levels in (1, 2, 3, 4):
        p = _plain(levels=levels, branches=(0, 6, 4, 3), leaves=0)
        sk = grow(p)
        _check_structure(sk)
        assert sk.levels.max() == levels - 1
        assert len(sk.stems_per_level()) == levels


def test_branch_count_matches_branches():
    # one trunk, no splits: children at t = 1/N .. N/N (N = branches[1]), the lowest
    # int(baseSize * (N + 1)) dropped; t = 1 is the stem that continues from the tip
    for nb, bs in ((20, 0.2), (35, 0.4), (7, 0.0)):
        p = _plain(levels=2, branches=(0, nb, 0, 0), baseSize=bs, leaves=0)
        counts = grow(p).stems_per_level()
        assert counts[0] == 1
        assert counts[1] == nb - int(bs * (nb + 1))


def test_more_branches_more_stems():
    a = grow(_plain(levels=3, branches=(0, 10, 5, 0), leaves=0)).stems_per_level()
    b = grow(_plain(levels=3, branches=(0, 20, 10, 0), leaves=0)).stems_per_level()
    assert b[1] > a[1] and b[2] > a[2]


def test_straight_trunk_height():
    for scale, scale_v, length in ((10.0, 0.0, 1.0), (5.0, 1.5, 0.8), (13.0, -2.0, 0.35)):
        p = _plain(levels=1, scale=scale, scaleV=scale_v, length=(length, 0.3, 0.6, 0.45), leaves=0)
        sk = grow(p)
        assert sk.n_stems == 1
        pts, _ = sk.stem(0)
        expected = (scale + scale_v) * length
        assert pts[-1, 2] == pytest.approx(expected, rel=1e-5)
        assert np.allclose(pts[:, :2], 0.0, atol=1e-9)
        assert np.all(np.diff(pts[:, 2]) > 0)


@pytest.mark.parametrize("k", [0, 1, 2, 3, 5])
def test_base_splits_give_trunk_tips(k):
    p = _plain(levels=1, baseSplits=k, splitAngle=(20.0, 0.0, 0.0, 0.0), leaves=0)
    sk = grow(p)
    assert sk.stems_per_level()[0] == k + 1
    tips = np.array([sk.stem(i)[0][-1] for i in range(sk.n_stems)])
    # the clones fan out: all tips distinct
    d = np.linalg.norm(tips[:, None] - tips[None], axis=2)
    assert np.all(d[~np.eye(len(tips), dtype=bool)] > 1e-3)


@pytest.mark.parametrize("k", [2, 3, 5, 8])
def test_nrings_gives_whorls(k):
    # Sapling: child heights are snapped to ring j/k (j = 1..k-1 above a small baseSize)
    # and the trunk tip sprouts too, so the trunk carries k distinct child heights.
    p = _plain(levels=2, nrings=k, branches=(0, 60, 0, 0), baseSize=0.05, branchDist=1.0, leaves=0)
    sk = grow(p)
    starts = np.array([sk.stem(i)[0][0, 2] for i in range(sk.n_stems) if sk.levels[i] == 1])
    trunk_len = sk.stem(0)[0][-1, 2]
    z = np.sort(starts) / trunk_len
    clusters = 1 + int(np.sum(np.diff(z) > 0.03))
    assert clusters == k


def test_leaves_zero_gives_no_leaves():
    p = _plain(levels=3, branches=(0, 10, 5, 0), leaves=0)
    sk = grow(p)
    assert sk.n_leaves == 0
    assert sk.leaf_positions.shape == (0, 3)


def test_leaves_counts_and_shapes():
    p = _plain(levels=2, branches=(0, 10, 0, 0), leaves=8, leafShape="rect")
    sk = grow(p)
    assert sk.n_leaves > 0 and sk.leaf_shape == "rect"
    # negative leaves: |leaves| fanned at each last-level stem tip only
    q = p.replace(leaves=-5, leafShape="hex")
    sk2 = grow(q)
    assert sk2.leaf_shape == "hex"
    n_last = sk2.stems_per_level()[-1]
    assert sk2.n_leaves == 5 * n_last
    tips = np.array([sk2.stem(i)[0][-1] for i in range(sk2.n_stems) if sk2.levels[i] == 1])
    d = np.linalg.norm(sk2.leaf_positions[:, None] - tips[None], axis=2).min(axis=1)
    assert np.all(d < 1e-9)


def test_leaf_size_follows_leaf_scale():
    p = _plain(
        levels=2, branches=(0, 10, 0, 0), leaves=6, leafScale=0.3, leafScaleX=0.5, leafScaleT=0.0
    )
    sk = grow(p)
    cols = np.linalg.norm(sk.leaf_matrices, axis=1)  # column norms: x width, y length
    assert np.allclose(cols[:, 1], 0.3)
    assert np.allclose(cols[:, 0], 0.15)
    big = grow(p.replace(leafScaleV=2.0))
    assert np.allclose(np.linalg.norm(big.leaf_matrices, axis=1)[:, 1], 0.6)


def test_radii_never_grow_towards_tip():
    p = default_params().replace(levels=3, branches=(0, 15, 6, 0), leaves=0, scale=30.0, ratio=0.05)
    sk = grow(p)
    _check_structure(sk)
    _radii_never_grow(sk)


def test_min_radius_and_root_flare():
    p = _plain(levels=2, branches=(0, 10, 0, 0), leaves=0, minRadius=0.01, rootFlare=1.5)
    sk = grow(p)
    assert sk.radii.min() >= 0.01 - 1e-12
    _, r = sk.stem(0)
    assert r[0] > r[1]


def test_determinism_and_sensitivity():
    p = species.sample("maple", seed=3)
    a, b = grow(p, seed=5), grow(p, seed=5)
    for name in (
        "points",
        "radii",
        "offsets",
        "levels",
        "parents",
        "leaf_positions",
        "leaf_matrices",
    ):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
    c = grow(p, seed=6)
    assert c.points.shape != a.points.shape or not np.array_equal(c.points, a.points)
    d = grow(p.replace(curveV1=(5.0, 20.0, 10.0, 0.0)), seed=5)
    assert d.points.shape != a.points.shape or not np.array_equal(d.points, a.points)
    e = grow(p.replace(rSplits2=(p["rSplits2"] + 0.37) % 1.0), seed=5)
    assert e.points.shape != a.points.shape or not np.array_equal(e.points, a.points)


def test_accepts_plain_dict_and_rejects_bad_input():
    d = default_params().to_dict()
    d["levels"] = 2
    sk = grow(d)
    assert sk.stems_per_level()[0] >= 1
    from weberpenn import ParamError

    d["levels"] = 9
    with pytest.raises(ParamError, match="levels"):
        grow(d)


def test_pruning_shrinks_tree():
    p = default_params().replace(levels=3, branches=(0, 20, 8, 0), leaves=0, scale=10.0, scaleV=0.0)
    free = grow(p)
    pruned = grow(p.replace(prune=True, pruneWidth=0.15, pruneRatio=1.0, pruneBase=0.2))
    _check_structure(pruned)
    wf = np.ptp(free.points[:, :2], axis=0).max()
    wp = np.ptp(pruned.points[:, :2], axis=0).max()
    assert wp < wf


@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.stem)
def test_reference_files_grow(path):
    p = load_params(path)
    sk = grow(p)
    _check_structure(sk)
    _radii_never_grow(sk)
    assert sk.n_leaves > 0
    assert len(sk.stems_per_level()) == p["levels"]
    assert sk.res_u == p["resU"] and sk.bevel_res == p["bevelRes"]


def test_down_angle_between_child_and_trunk():
    for down in (30.0, 60.0, 90.0):
        p = _plain(
            levels=2,
            branches=(0, 12, 0, 0),
            leaves=0,
            downAngle=(0.0, down, 45.0, 45.0),
            downAngleV=(0.0, 0.0, 0.0, 0.0),
        )
        sk = grow(p)
        trunk_top = sk.stem(0)[0][-1]
        for i in range(1, sk.n_stems):
            pts, _ = sk.stem(i)
            if np.allclose(pts[0], trunk_top):
                continue  # the stem continuing from the trunk tip
            d = pts[1] - pts[0]
            ang = np.degrees(np.arccos(d[2] / np.linalg.norm(d)))
            assert ang == pytest.approx(down, abs=1e-6)


def test_length_ratio_of_children():
    # shape 3 (cylindrical) gives every first-level child length[1] * trunk length
    p = _plain(levels=2, branches=(0, 10, 0, 0), leaves=0, shape="3", length=(1.0, 0.4, 0.6, 0.45))
    sk = grow(p)
    trunk_len = np.linalg.norm(np.diff(sk.stem(0)[0], axis=0), axis=1).sum()
    for i in range(1, sk.n_stems):
        pts, _ = sk.stem(i)
        ln = np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()
        assert ln == pytest.approx(0.4 * trunk_len, rel=1e-9)


def test_exploding_splits_are_refused():
    from weberpenn import ParamError

    p = species.sample("bonsai", seed=2).replace(segSplits=(1.0, 1.0, 1.0, 1.0))
    with pytest.raises(ParamError, match="stems"):
        grow(p)


def test_random_draws_follow_the_structure():
    # a small rSplits2 step flips a few split draws; with one random stream per stem the
    # stems away from the flips keep their draws (with one stream per level, every draw
    # after the first flip moved: 72 % of this bonsai's stems stayed)
    p = species.sample("bonsai", 0)
    a = grow(p)
    b = grow(p.replace(rSplits2=(p["rSplits2"] + 0.002) % 1.0))

    def stems(sk):
        return {sk.stem(i)[0].tobytes() for i in range(sk.n_stems)}

    sa, sb = stems(a), stems(b)
    assert sa != sb
    assert len(sa & sb) >= 0.95 * len(sa)


def test_leaf_azimuth_accumulates_along_each_stem():
    # a 0.01 degree change of leafRotateV turns a stem's n-th leaf by n * 0.01 degrees;
    # accumulated over the whole tree (Sapling), the 4000th leaf turned by 40 degrees
    p = species.sample("maple", 0)
    a = grow(p)
    b = grow(p.replace(leafRotateV=p["leafRotateV"] + 0.01))
    assert np.array_equal(a.leaf_positions, b.leaf_positions)
    scale = np.linalg.norm(a.leaf_matrices, axis=(1, 2))
    turn = np.linalg.norm(b.leaf_matrices - a.leaf_matrices, axis=(1, 2)) / scale
    assert 0 < turn.max() < 0.05


def test_leaf_matrix_products_are_numpys_bit_for_bit() -> None:
    # the leaves' 3x3 products run compiled; each entry is summed in numpy's order, so
    # every grown tree stays the same to the bit
    from weberpenn._grow_leaves import _mul  # the module's own test may look inside it

    rng = np.random.default_rng(3)
    stack = np.moveaxis(rng.normal(size=(500, 3, 3)), 0, -1)  # (3, 3, L), strided
    one = rng.normal(size=(3, 3))
    none = np.zeros((3, 3, 0))  # a tree without leaves
    pairs = [(stack, one), (one, stack), (stack, stack[:, :, ::-1]), (one, one)]
    pairs += [(none, one), (one, none), (none, none), (stack[:, :, :1], stack)]
    for a, b in pairs:
        want = np.empty((3, 3) + np.broadcast_shapes(a.shape[2:], b.shape[2:]))
        for i in range(3):
            for k in range(3):
                want[i, k] = a[i, 0] * b[0, k] + a[i, 1] * b[1, k] + a[i, 2] * b[2, k]
        got = _mul(a, b)
        assert got.shape == want.shape and np.array_equal(got, want)


def test_growing_yields_each_level_as_grow_returns_it() -> None:
    from weberpenn import species
    from weberpenn.grow import grow_levels

    for name in ("maple", "pine", "palm"):
        params = species.sample(name, 41)
        sk = grow(params)
        got, again = grow_levels(params)
        assert len(got) == int(sk.levels.max()) + 1
        assert np.array_equal(np.concatenate([p for p, _ in got]), sk.points)
        assert np.array_equal(np.concatenate([r for _, r in got]), sk.radii)
        for field in ("points", "radii", "offsets", "leaf_matrices", "leaf_positions"):
            assert np.array_equal(getattr(again, field), getattr(sk, field)), field
