"""Property tests of weberpenn.grow over random valid dictionaries (hypothesis)."""

from __future__ import annotations

import time

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from weberpenn import ParamError, species
from weberpenn.grow import grow
from weberpenn.params import SHAPE_CHOICES, SHAPES_CHOICES

angle = st.floats(-180.0, 180.0, allow_nan=False)
unit = st.floats(0.0, 1.0, allow_nan=False)


def vec(elem):
    return st.tuples(elem, elem, elem, elem)


@st.composite
def tree_params(draw):
    """A species sample with many keys perturbed inside their valid ranges (sizes kept small)."""
    name = draw(st.sampled_from(species.SPECIES))
    p = species.sample(name, seed=draw(st.integers(0, 10_000)))
    branches = tuple(
        int(b * f) for b, f in zip(p["branches"], draw(vec(st.floats(0.0, 1.1))), strict=True)
    )
    changes = dict(
        levels=draw(st.integers(1, p["levels"])),
        branches=branches,
        curve=draw(vec(angle)),
        curveBack=draw(vec(angle)),
        curveV1=draw(vec(st.floats(-30.0, 30.0))),
        curveV2=draw(vec(st.floats(-30.0, 30.0))),
        curveRes=draw(vec(st.integers(1, 8))),
        downAngle=draw(vec(angle)),
        downAngleV=draw(vec(st.floats(-60.0, 60.0))),
        rotate=draw(vec(angle)),
        rotateV=draw(vec(st.floats(-30.0, 30.0))),
        segSplits=draw(vec(st.floats(0.0, 0.6))),
        splitAngle=draw(vec(st.floats(-60.0, 60.0))),
        splitAngleV1=draw(vec(st.floats(-10.0, 10.0))),
        splitAngleV2=draw(vec(st.floats(-10.0, 10.0))),
        baseSplits=draw(st.integers(0, 4)),
        splitHeight=draw(unit),
        splitBias=draw(st.floats(-2.0, 2.0)),
        attractUp=draw(vec(st.floats(-5.0, 5.0))),
        attractOut=draw(vec(unit)),
        lengthV=draw(vec(st.floats(0.0, 0.5))),
        taper=draw(vec(unit)),
        radiusTweak=draw(vec(unit)),
        ratioPower=draw(st.floats(0.3, 3.0)),
        shape=draw(st.sampled_from(SHAPE_CHOICES)),
        shapeS=draw(st.sampled_from(SHAPES_CHOICES)),
        leafDist=draw(st.sampled_from(SHAPES_CHOICES)),
        customShape=draw(vec(st.floats(0.01, 1.0))),
        baseSize=draw(unit),
        baseSize_s=draw(unit),
        nrings=draw(st.integers(0, 10)),
        branchDist=draw(st.floats(0.1, 10.0)),
        taperCrown=draw(unit),
        minRadius=draw(st.floats(0.0, 0.05)),
        rootFlare=draw(st.floats(1.0, 3.0)),
        leaves=draw(st.integers(-8, 60)),
        leafShape=draw(st.sampled_from(("hex", "rect"))),
        leafRotate=draw(angle),
        leafRotateV=draw(st.floats(-20.0, 20.0)),
        leafDownAngle=draw(angle),
        leafDownAngleV=draw(st.floats(-40.0, 40.0)),
        leafScaleT=draw(st.floats(-1.0, 1.0)),
        leafangle=draw(angle),
        horzLeaves=draw(st.booleans()),
        useOldDownAngle=draw(st.booleans()),
        useParentAngle=draw(st.booleans()),
        choiceNegPos1=draw(st.sampled_from((-1, 1))),
        choiceNegPos2=draw(st.sampled_from((-1, 1))),
        rSplits2=draw(unit),
        rLastAng=draw(vec(st.floats(0.0, 360.0))),
        prune=draw(st.booleans()),
        pruneWidth=draw(st.floats(0.05, 1.0)),
        pruneBase=draw(unit),
        pruneRatio=draw(unit),
    )
    try:
        return p.replace(**changes)
    except ParamError:
        assume(False)


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
@given(tree_params(), st.integers(0, 2**32))
def test_random_dictionaries_grow(p, seed):
    t0 = time.perf_counter()
    try:
        sk = grow(p, seed=seed)
    except ParamError as exc:  # an exploding tree is refused, quickly, naming the keys
        assert time.perf_counter() - t0 < 20.0
        assert "limit" in str(exc) and exc.key is not None
        return
    elapsed = time.perf_counter() - t0
    assert elapsed < 20.0
    assert 1 <= sk.n_stems <= 60_000
    assert sk.n_leaves <= 400_000
    assert len(sk.points) <= 60_000 * 65
    for a in (sk.points, sk.radii, sk.leaf_positions, sk.leaf_matrices):
        assert np.all(np.isfinite(a))
    assert np.all(sk.radii >= 0.0)
    assert np.all(np.diff(sk.offsets) >= 2)
    assert sk.levels.max() < p["levels"]
    assert np.all(sk.parents[1:] < np.arange(1, sk.n_stems))
    if p["leaves"] == 0:
        assert sk.n_leaves == 0
    for i in range(0, sk.n_stems, max(1, sk.n_stems // 50)):
        _, r = sk.stem(i)
        assert np.all(np.diff(r) <= 1e-12 * max(1.0, r[0]))


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tree_params(), st.integers(0, 1000))
def test_random_dictionaries_are_deterministic(p, seed):
    a, b = grow(p, seed=seed), grow(p, seed=seed)
    assert a.points.tobytes() == b.points.tobytes()
    assert a.radii.tobytes() == b.radii.tobytes()
    assert a.leaf_matrices.tobytes() == b.leaf_matrices.tobytes()
