"""eval.hausdorff: zero on itself, d for a copy moved by d, symmetry, normalisation, empties."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from eval.hausdorff import Distance, bbox_diagonal, hausdorff, summarise, tree_hausdorff


def _plane(n: int = 8, size: float = 2.0) -> trimesh.Trimesh:
    xs = np.linspace(0, size, n)
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    v = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(n * n)])
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = (
        idx[:-1, :-1].ravel(),
        idx[1:, :-1].ravel(),
        idx[1:, 1:].ravel(),
        idx[:-1, 1:].ravel(),
    )
    f = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return trimesh.Trimesh(v, f, process=False)


def test_self_distance_is_zero():
    m = trimesh.creation.icosphere(subdivisions=2)
    d = hausdorff(m, m, samples=5000)
    assert d.status == "ok"
    assert d.max == pytest.approx(0.0, abs=1e-6)
    assert d.mean == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize("dist", [0.05, 0.3, 1.5])
def test_plane_moved_along_normal_by_d(dist):
    a = _plane()
    b = a.copy()
    b.apply_translation([0, 0, dist])
    d = hausdorff(b, a, samples=5000)
    assert d.max == pytest.approx(dist, rel=1e-4)
    assert d.mean == pytest.approx(dist, rel=1e-4)  # every point is exactly d away


def test_box_moved_by_d_max_is_d():
    a = trimesh.creation.box(extents=(1, 1, 1))
    b = a.copy()
    b.apply_translation([0.2, 0, 0])
    d = hausdorff(b, a, samples=10000)
    assert d.max == pytest.approx(0.2, rel=1e-3)
    assert 0 < d.mean < 0.2


def test_symmetric():
    a = trimesh.creation.icosphere(subdivisions=2)
    b = trimesh.creation.box(extents=(0.5, 0.5, 3.0))
    ab, ba = hausdorff(a, b, samples=20000), hausdorff(b, a, samples=20000)
    assert ab.max == pytest.approx(ba.max, rel=0.02)
    assert ab.mean == pytest.approx(ba.mean, rel=0.02)


def test_one_sided_distance_caught_both_ways():
    # a small sphere inside a big one: the big one's surface is far from the small one
    small = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    big = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    assert hausdorff(small, big, samples=5000).max == pytest.approx(1.5, abs=0.05)
    assert hausdorff(big, small, samples=5000).max == pytest.approx(1.5, abs=0.05)


def test_normalised_by_ground_truth_diagonal():
    a = _plane()
    gt = a.copy()
    gt.apply_translation([0, 0, 0.4])
    d = hausdorff(a, gt, samples=4000)
    diag = bbox_diagonal(gt.vertices)
    assert diag == pytest.approx(math.sqrt(8))
    assert d.diagonal == pytest.approx(diag)
    assert d.max_norm == pytest.approx(d.max / diag)
    assert d.mean_norm == pytest.approx(d.mean / diag)
    # the prediction's size does not matter, only the ground truth's
    big = a.copy()
    big.apply_scale(3.0)
    assert hausdorff(big, gt, samples=2000).diagonal == pytest.approx(diag)
    assert hausdorff(a, gt, samples=2000, diagonal=2.0).max_norm == pytest.approx(
        d.max / 2.0, rel=1e-3
    )


def test_arrays_accepted_and_bad_input_rejected():
    m = trimesh.creation.box()
    d = hausdorff((m.vertices, m.faces), (m.vertices, m.faces), samples=1000)
    assert d.max == pytest.approx(0, abs=1e-6)
    with pytest.raises(ValueError, match="samples"):
        hausdorff(m, m, samples=0)
    with pytest.raises(ValueError, match="face indices"):
        hausdorff((m.vertices, m.faces + 100), m)
    bad = m.vertices.copy()
    bad[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        hausdorff((bad, m.faces), m)
    with pytest.raises(TypeError, match="pred"):
        hausdorff("mesh.obj", m)


def test_empty_meshes():
    m = trimesh.creation.box()
    empty = trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    both = hausdorff(empty, empty)
    assert both.status == "both empty" and both.max == 0.0
    p = hausdorff(empty, m)
    assert p.status == "pred empty" and math.isnan(p.max)
    g = hausdorff(m, empty)
    assert g.status == "gt empty" and math.isnan(g.mean)
    s = summarise([p, hausdorff(m, m, samples=500)])
    assert s["skipped"] == 1 and s["n"] == 2 and s["max"] == pytest.approx(0, abs=1e-6)


def test_tree_parts_use_whole_tree_diagonal():
    from weberpenn.treemesh import TreeMesh

    trunk = trimesh.creation.box(extents=(0.2, 0.2, 4.0))
    crown = trimesh.creation.icosphere(radius=1.0)
    crown.apply_translation([0, 0, 2.5])
    gt = TreeMesh(branches=trunk, leaves=crown)
    moved = crown.copy()
    moved.apply_translation([0, 0, 0.1])
    pred = TreeMesh(branches=trunk.copy(), leaves=moved)
    out = tree_hausdorff(pred, gt, samples=4000)
    assert set(out) == {"branches", "leaves", "combined"}
    diag = bbox_diagonal(gt.bounds())
    assert all(isinstance(d, Distance) and d.diagonal == pytest.approx(diag) for d in out.values())
    assert out["branches"].max == pytest.approx(0, abs=1e-6)
    assert out["leaves"].max == pytest.approx(0.1, abs=0.01)
    assert 0 < out["combined"].max <= out["leaves"].max + 1e-6


def test_rotate_about_trunk_matches_camera_yaw():
    """A tree turned by d, seen from yaw y + d, looks like the tree seen from yaw y."""
    from eval.hausdorff import rotate_about_trunk
    from refine.objective import sketch_distance
    from render.sketch import SketchRenderer
    from weberpenn import build_mesh, grow, species

    m = build_mesh(grow(species.sample("maple", 5)), species="maple")
    t = rotate_about_trunk(m, 60.0)
    assert t.species == "maple" and len(t.leaves.faces) == len(m.leaves.faces)
    assert np.allclose(t.bounds()[:, 2], m.bounds()[:, 2])
    a = SketchRenderer(m).sketch(30.0, 128)
    same = sketch_distance(a, SketchRenderer(t).sketch(90.0, 128))
    other = sketch_distance(a, SketchRenderer(t).sketch(-30.0, 128))
    assert same < 0.02 < other, (same, other)
    assert hausdorff(rotate_about_trunk(t, -60.0).combined(), m.combined(), 2000).max < 1e-6


def test_aligned_distance_undoes_a_turn():
    from eval.hausdorff import aligned_tree_hausdorff, rotate_about_trunk
    from weberpenn import build_mesh, grow, species

    m = build_mesh(grow(species.sample("palm", 2)), species="palm")
    turned = rotate_about_trunk(m, 90.0)
    plain = tree_hausdorff(turned, m, 2000)["combined"].max
    turn, d = aligned_tree_hausdorff(turned, m, samples=2000, step=45.0, coarse_samples=500)
    assert turn == 270.0 and d.max < 1e-6 < plain
    assert d.diagonal == pytest.approx(bbox_diagonal(m.bounds()))
    with pytest.raises(ValueError, match="step"):
        aligned_tree_hausdorff(m, m, step=0)


def test_paper_wording_reported_beside_the_symmetric_max():
    # a small sphere inside a big one: from the small one's vertices the big surface is
    # 1.5 away, and from the big one's vertices the small surface is 1.5 away too
    small = trimesh.creation.icosphere(subdivisions=2, radius=0.5)
    big = trimesh.creation.icosphere(subdivisions=2, radius=2.0)
    d = hausdorff(small, big, samples=2000)
    diag = bbox_diagonal(big.vertices)
    assert d.pred_to_gt_vertex * diag == pytest.approx(1.5, abs=0.05)
    assert d.gt_to_pred_vertex * diag == pytest.approx(1.5, abs=0.05)
    # a plane and a longer plane: only the longer one's extra vertices are far
    a = _plane(n=5, size=1.0)
    b = _plane(n=9, size=2.0)
    d = hausdorff(a, b, samples=2000, diagonal=1.0)
    assert d.pred_to_gt_vertex == pytest.approx(0.0, abs=1e-9)
    assert d.gt_to_pred_vertex == pytest.approx(math.sqrt(2.0), rel=1e-9)
    assert d.max == pytest.approx(math.sqrt(2.0), rel=1e-9)


def test_agrees_with_meshlab_metro_on_a_near_pair():
    """The exact AABB distances against MeshLab's Metro filter sampling every vertex."""
    from eval.metro import metro
    from weberpenn import build_mesh, grow, species

    p = species.sample("maple", 3)
    a = build_mesh(grow(p, seed=0)).branches
    b = build_mesh(grow(p, seed=1)).branches
    reach = float(bbox_diagonal(np.vstack([a.vertices, b.vertices])))
    res = metro(a, b, len(a.vertices) + len(b.vertices), faces=False, reach=reach)
    d = hausdorff(a, b, samples=1)  # the vertices decide: both measure every one of them
    assert d.max == pytest.approx(max(m["max"] for m in res), rel=1e-5)
    diag = d.diagonal
    assert d.pred_to_gt_vertex * diag == pytest.approx(res[0]["max"], rel=1e-5)
    assert d.gt_to_pred_vertex * diag == pytest.approx(res[1]["max"], rel=1e-5)


@pytest.mark.slow
def test_far_apart_pair_finishes_in_seconds():
    # a cherry estimate against a maple ground truth took MeshLab's Metro filter > 15 min
    import time

    from weberpenn import build_mesh, grow, species

    cherry = build_mesh(grow(species.sample("cherry", 1)))
    maple = build_mesh(grow(species.sample("maple", 1)))
    t0 = time.perf_counter()
    d = hausdorff(cherry.combined(), maple.combined())
    assert time.perf_counter() - t0 < 60.0  # about 9 s on a loaded 2-core machine
    assert 0.3 < d.max_norm < 1.0 and d.pred_to_gt_vertex <= d.max_norm + 1e-12
    assert d.max_norm == pytest.approx(max(d.pred_to_gt_vertex, d.gt_to_pred_vertex), rel=0.05)
