"""Tests of weberpenn.lod: triangle budgets, coarser tubes first, decimation last."""

from __future__ import annotations

import pytest

from eval.hausdorff import hausdorff
from weberpenn import build_mesh, grow, species
from weberpenn.lod import MIN_FACES, branch_faces, lod, lod_chain
from weberpenn.treemesh import TreeMesh


@pytest.fixture(scope="module")
def maple():
    return build_mesh(grow(species.sample("maple", 0)), species="maple")


def test_branch_face_formula(maple):
    sk = maple.skeleton
    assert branch_faces(sk, sk.res_u, sk.bevel_res) == len(maple.branches.faces)


def test_fits_budget_by_resolution_first(maple):
    assert lod(maple, maple.n_faces) is maple
    budget = len(maple.branches.faces) // 2 + len(maple.leaves.faces)
    m = lod(maple, budget)
    assert m.n_faces <= budget
    assert m.meta["lod"]["decimated"] is False
    assert len(m.leaves.faces) == len(maple.leaves.faces)  # leaves untouched
    h = hausdorff(m.combined(), maple.combined(), 3000)
    assert h.max < 0.05 * float(abs(maple.bounds()[1] - maple.bounds()[0]).max())


def test_small_budgets_thin_leaves_and_decimate(maple):
    for budget in (5000, 1000):
        m = lod(maple, budget)
        assert m.n_faces <= budget
        assert len(m.leaves.faces) > 0 and len(m.branches.faces) > 0
        assert m.meta["lod"]["leaf_shape"] == "rect"
    m = lod(maple, 1000)
    assert m.meta["lod"]["stems_dropped"] > 0 and m.meta["lod"]["decimated"] is False
    trunk = maple.skeleton.stem(0)[0]
    assert m.branches.vertices[:, 2].max() >= trunk[:, 2].max() * 0.99  # trunk kept whole
    tiny = lod(maple, MIN_FACES)  # below the trunk's own coarsest tube: decimation
    assert tiny.n_faces <= MIN_FACES and tiny.meta["lod"]["decimated"] is True
    chain = lod_chain(maple, (None, 20000, 5000))
    assert chain[0] is maple and chain[1].n_faces > chain[2].n_faces


def test_without_skeleton(maple):
    bare = TreeMesh(maple.branches, maple.leaves, species="maple", meta=dict(maple.meta))
    m = lod(bare, 4000)
    assert m.n_faces <= 4000 and len(m.leaves.faces) % 4 == 0


def test_bad_budgets(maple):
    with pytest.raises(ValueError, match=str(MIN_FACES)):
        lod(maple, 10)
    with pytest.raises(ValueError):
        lod(maple, 1000.5)
