"""eval.hausdorff's family of 3D errors (issue 29): each member and its normaliser on
meshes with known answers, the branch-only variant, and the floors on a small tree."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh

from eval.hausdorff import (
    FAMILY,
    FAMILY_PARTS,
    Distance,
    Floors,
    bbox_diagonal,
    floors,
    hausdorff,
    seed_floor,
    summarise,
    tree_hausdorff,
)


def _square(size: float, z: float = 0.0) -> trimesh.Trimesh:
    """A ``size`` x ``size`` square in the plane at height ``z``, corner at the origin."""
    v = np.array([[0, 0, z], [size, 0, z], [size, size, z], [0, size, z]], dtype=float)
    return trimesh.Trimesh(v, [[0, 1, 2], [0, 2, 3]], process=False)


def _cube(side: float) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=(side, side, side))


def test_family_names_every_member():
    d = hausdorff(_square(1.0), _square(1.0, 0.5), samples=200)
    assert list(d.family()) == list(FAMILY)
    assert set(FAMILY) <= set(d.to_dict())


@pytest.mark.parametrize("dist", [0.1, 0.7])
def test_squares_offset_by_d_every_member_known(dist):
    # every point of either square is exactly ``dist`` from the other
    pred, gt = _square(1.0, dist), _square(1.0)
    d = hausdorff(pred, gt, samples=3000)
    own = math.sqrt(2.0)  # each square's diagonal
    both = math.sqrt(2.0 + dist * dist)  # the box around both
    assert d.max_norm == pytest.approx(dist / own, rel=1e-9)
    assert d.meshlab_pred_to_gt == pytest.approx(dist / own, rel=1e-9)
    assert d.meshlab_gt_to_pred == pytest.approx(dist / own, rel=1e-9)
    assert d.metro_max == pytest.approx(dist / both, rel=1e-9)
    for k in ("surface_mean", "surface_rms", "surface_p95"):
        assert getattr(d, k) == pytest.approx(dist / own, rel=1e-9), k


def _big_to_small_distances(n: int = 801) -> np.ndarray:
    """Distances from the faces of a side-2 cube to a concentric side-1 cube, on a fine
    grid over one face (all six alike): the point (1, y, z) is outside the small cube,
    so its distance to the small cube's surface is its distance to the solid."""
    t = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    y, z = np.meshgrid(t, t, indexing="ij")
    dy, dz = np.maximum(np.abs(y) - 0.5, 0.0), np.maximum(np.abs(z) - 0.5, 0.0)
    return np.sqrt(0.25 + dy * dy + dz * dz).ravel()


def test_cube_against_a_cube_twice_its_size():
    """Each normaliser apart: big cube (side 2) as the prediction, the unit cube as the
    ground truth, both centred at the origin."""
    big, small = _cube(2.0), _cube(1.0)
    d = hausdorff(big, small, samples=40_000)
    corner = math.sqrt(3.0) * 0.5  # big corner (1,1,1) to small corner (.5,.5,.5)
    diag_small, diag_big = math.sqrt(3.0), 2.0 * math.sqrt(3.0)
    # the farthest point is the big cube's corner; small's vertices are 0.5 off big's faces
    assert d.max == pytest.approx(corner, rel=1e-9)
    assert d.max_norm == pytest.approx(corner / diag_small, rel=1e-9)  # ground truth's box
    assert d.meshlab_pred_to_gt == pytest.approx(corner / diag_big, rel=1e-9)  # big's own
    assert d.meshlab_gt_to_pred == pytest.approx(0.5 / diag_small, rel=1e-9)  # small's own
    assert d.metro_max == pytest.approx(corner / diag_big, rel=1e-9)  # both: big's box
    # pooled, half the samples are the small cube's (each exactly 0.5 from the big one)
    ref = np.concatenate([np.full(len(_big_to_small_distances()), 0.5), _big_to_small_distances()])
    assert d.surface_mean == pytest.approx(ref.mean() / diag_small, rel=0.01)
    assert d.surface_rms == pytest.approx(math.sqrt(np.mean(ref**2)) / diag_small, rel=0.01)
    assert d.surface_p95 == pytest.approx(np.percentile(ref, 95) / diag_small, rel=0.01)
    # swapped: the one-sided members swap, and each keeps its own mesh's diagonal
    s = hausdorff(small, big, samples=2000)
    assert s.meshlab_pred_to_gt == pytest.approx(0.5 / diag_small, rel=1e-9)
    assert s.meshlab_gt_to_pred == pytest.approx(corner / diag_big, rel=1e-9)
    assert s.max_norm == pytest.approx(corner / diag_big, rel=1e-9)
    assert s.metro_max == pytest.approx(d.metro_max, rel=1e-9)


def test_one_sided_members_use_vertices_only():
    # a unit square above the corner of a 2 x 2 square: from the unit square every point
    # is 0.7 away; the big square's far vertex (2, 2) is sqrt(1 + 1 + 0.49) away
    pred, gt = _square(1.0, 0.7), _square(2.0)
    d = hausdorff(pred, gt, samples=4000)
    far = math.sqrt(2.0 + 0.49)
    assert d.meshlab_pred_to_gt == pytest.approx(0.7 / math.sqrt(2.0), rel=1e-9)
    assert d.meshlab_gt_to_pred == pytest.approx(far / math.sqrt(8.0), rel=1e-9)
    assert d.max_norm == pytest.approx(far / math.sqrt(8.0), rel=1e-9)
    assert d.metro_max == pytest.approx(far / math.sqrt(8.0 + 0.49), rel=1e-9)
    # the surface statistics sit between the near part and the far corner
    assert 0.7 / math.sqrt(8.0) < d.surface_mean < d.surface_rms < d.surface_p95 < d.max_norm


def test_diagonal_given_moves_ours_and_the_surface_statistics_only():
    pred, gt = _square(1.0, 0.3), _square(1.0)
    a = hausdorff(pred, gt, samples=500)
    b = hausdorff(pred, gt, samples=500, diagonal=10.0)
    assert b.max_norm == pytest.approx(0.03) and b.surface_mean == pytest.approx(0.03)
    for k in ("meshlab_pred_to_gt", "meshlab_gt_to_pred", "metro_max"):
        assert getattr(a, k) == getattr(b, k), k


def test_empties_and_summarise():
    m = _cube(1.0)
    empty = trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    both = hausdorff(empty, empty)
    assert all(v == 0.0 for v in both.family().values())
    one = hausdorff(empty, m)
    assert all(math.isnan(v) for v in one.family().values())
    s = summarise([one, hausdorff(_square(1.0, 0.2), _square(1.0), samples=300)])
    assert s["skipped"] == 1
    assert s["metro_max"] == pytest.approx(0.2 / math.sqrt(2.04))
    assert s["surface_p95"] == pytest.approx(0.2 / math.sqrt(2.0))


def _tree(trunk_shift: float = 0.0, crown_shift: float = 0.0):
    from weberpenn.treemesh import TreeMesh

    trunk = trimesh.creation.box(extents=(0.2, 0.2, 4.0))
    trunk.apply_translation([trunk_shift, 0, 0])
    crown = trimesh.creation.icosphere(radius=1.0)
    crown.apply_translation([0, 0, 2.5 + crown_shift])
    return TreeMesh(branches=trunk, leaves=crown)


def test_branches_only_and_leaves_included():
    gt = _tree()
    out = tree_hausdorff(_tree(trunk_shift=0.05), gt, samples=3000, parts=FAMILY_PARTS)
    assert list(out) == ["combined", "branches"]
    tree_diag = bbox_diagonal(gt.bounds())
    trunk_diag = math.sqrt(0.08 + 16.0)
    br = out["branches"]
    assert br.max * 1.0 == pytest.approx(0.05, rel=1e-6)
    assert br.max_norm == pytest.approx(0.05 / tree_diag, rel=1e-6)  # the whole tree's
    # MeshLab and Metro see the branch meshes alone: their own boxes
    assert br.meshlab_pred_to_gt == pytest.approx(0.05 / trunk_diag, rel=1e-6)
    both = math.sqrt(0.25**2 + 0.2**2 + 16.0)
    assert br.metro_max == pytest.approx(0.05 / both, rel=1e-6)
    # the crown hides most of the trunk's move once the leaves are included
    assert out["combined"].max <= br.max + 1e-9
    moved = tree_hausdorff(_tree(crown_shift=0.1), gt, samples=3000, parts=("branches",))
    assert list(moved) == ["branches"] and moved["branches"].max == pytest.approx(0, abs=1e-9)
    with pytest.raises(ValueError, match="parts"):
        tree_hausdorff(gt, gt, parts=("trunk",))


def _small_truth():
    from weberpenn import species

    return species.sample("palm", 2).replace(leaves=20)


def test_floors_of_the_truth_itself_seen_turned():
    truth = _small_truth()
    # the truth itself, found to show the front drawing when seen from yaw 90
    f = floors(truth, truth, 90.0, samples=1000, step=45.0)
    assert isinstance(f, Floors) and set(f.seed) == set(FAMILY_PARTS)
    assert f.aligned_turn == 90.0  # turning it back finds the truth exactly
    assert all(d.max_norm < 1e-9 for d in f.aligned.values())
    # the perfect values are the truth's, at the estimate's (wrong) view
    assert f.perfect_values["combined"].max_norm > 0.01
    # the seed floor is the truth against itself grown with another seed
    ref = seed_floor(truth, (1, 0), 1000, FAMILY_PARTS)
    assert f.seed["combined"].to_dict() == ref["combined"].to_dict()
    assert f.seed["combined"].max_norm > 0
    json.dumps(f.to_dict())  # plain data


def test_floors_perfect_values_take_the_estimates_seed_and_view():
    from weberpenn import build_mesh, grow

    truth = _small_truth()
    other = truth.replace(seed=int(truth["seed"]) + 7, leaves=10)
    known = seed_floor(truth, (1, 0), 800, FAMILY_PARTS)
    f = floors(truth, other, 0.0, samples=800, step=90.0, known_seed_floor=known)
    assert f.seed is not known and f.seed == known
    want = tree_hausdorff(
        build_mesh(grow(truth.replace(seed=other["seed"]))),
        build_mesh(grow(truth)),
        800,
        FAMILY_PARTS,
    )
    assert f.perfect_values["combined"] == want["combined"]
    # the same values and seed at the truth's view: no error at all
    same = floors(truth, truth, 0.0, samples=800, step=90.0, known_seed_floor=known)
    assert all(d.max == pytest.approx(0, abs=1e-9) for d in same.perfect_values.values())
    assert isinstance(same.aligned["branches"], Distance)
    with pytest.raises(ValueError, match="known_seed_floor"):
        floors(truth, truth, 0.0, samples=800, known_seed_floor={"combined": known["combined"]})
    with pytest.raises(ValueError, match="yaw"):
        floors(truth, truth, math.nan)
