"""Tests of weberpenn.mesh: tube and leaf geometry from hand-made skeletons."""

from __future__ import annotations

import time

import numpy as np
import pytest
import trimesh

from weberpenn.mesh import HEX, RECT, build_mesh, tube_counts
from weberpenn.skeleton import Skeleton
from weberpenn.treemesh import TreeMesh


def _skeleton(stems, leaves=(), leaf_shape="hex", res_u=4, bevel_res=1, levels=None):
    pts = [np.asarray(p, float) for p, _ in stems]
    rad = [np.asarray(r, float) for _, r in stems]
    counts = [len(p) for p in pts]
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    n = len(stems)
    lp = np.array([pos for pos, _ in leaves], float).reshape(-1, 3)
    lm = np.array([m for _, m in leaves], float).reshape(-1, 3, 3)
    return Skeleton(
        points=np.vstack(pts) if pts else np.zeros((0, 3)),
        radii=np.concatenate(rad) if rad else np.zeros(0),
        offsets=offsets,
        levels=np.zeros(n, np.int64) if levels is None else np.asarray(levels, np.int64),
        parents=np.full(n, -1, np.int64),
        leaf_positions=lp,
        leaf_matrices=lm,
        leaf_shape=leaf_shape,
        res_u=res_u,
        bevel_res=bevel_res,
    )


STRAIGHT = ([[0, 0, 0], [0, 0, 1], [0, 0, 2], [0, 0, 3]], [0.3, 0.2, 0.1, 0.05])
BENT = ([[0, 0, 0], [0, 0, 1], [0.5, 0, 1.8]], [0.1, 0.08, 0.02])


def test_counts_match_formula():
    sk = _skeleton([STRAIGHT, BENT, STRAIGHT], res_u=5, bevel_res=2)
    tm = build_mesh(sk)
    assert isinstance(tm, TreeMesh)
    sides = 4 + 2 * 2
    rings = [(4 - 1) * 5 + 1, (3 - 1) * 5 + 1, (4 - 1) * 5 + 1]
    assert len(tm.branches.vertices) == sides * sum(rings)
    assert len(tm.branches.faces) == sum(2 * sides * (r - 1) for r in rings)
    v, f = tube_counts(4, 5, 2)
    assert (v, f) == (sides * 16, 2 * sides * 15)
    assert np.isfinite(tm.branches.vertices).all()
    assert tm.branches.faces.max() < len(tm.branches.vertices)


def test_radius_and_axis_of_straight_tube():
    sk = _skeleton([STRAIGHT], res_u=4, bevel_res=3)
    v = build_mesh(sk).branches.vertices
    sides = 10
    rings = v.reshape(-1, sides, 3)
    assert len(rings) == 13
    # straight line through equally spaced points: ring centres on the Z axis
    centres = rings.mean(axis=1)
    assert np.allclose(centres[:, :2], 0.0, atol=1e-9)
    r = np.linalg.norm(rings[:, :, :2], axis=2)
    assert np.allclose(r, r[:, :1], atol=1e-9)  # round cross-sections
    # control points keep their radii; in between the radius is linear per segment
    assert r[0, 0] == pytest.approx(0.3)
    assert r[4, 0] == pytest.approx(0.2)
    assert r[2, 0] == pytest.approx(0.25)
    assert r[-1, 0] == pytest.approx(0.05)
    assert np.all(np.diff(r[:, 0]) <= 1e-12)  # radii never grow towards the tip
    assert centres[0, 2] == pytest.approx(0.0) and centres[-1, 2] == pytest.approx(3.0)


def test_bezier_passes_through_control_points_and_stays_smooth():
    sk = _skeleton([BENT], res_u=8, bevel_res=0)
    v = build_mesh(sk).branches.vertices.reshape(-1, 4, 3)
    centres = v.mean(axis=1)
    pts = np.asarray(BENT[0], float)
    assert np.allclose(centres[0], pts[0], atol=1e-9)
    assert np.allclose(centres[8], pts[1], atol=1e-9)
    assert np.allclose(centres[16], pts[2], atol=1e-9)
    # consecutive samples are close together: no kinks or jumps
    steps = np.linalg.norm(np.diff(centres, axis=0), axis=1)
    assert steps.max() < 0.2


def test_outward_normals():
    sk = _skeleton([STRAIGHT], res_u=2, bevel_res=2)
    mesh = build_mesh(sk).branches
    centres = mesh.triangles_center
    n = mesh.face_normals
    radial = centres.copy()
    radial[:, 2] = 0.0
    assert np.all(np.einsum("ij,ij->i", n, radial) > 0)


def test_frames_do_not_twist():
    # a stem bending in a plane: the ring's first vertex stays on the same side
    sk = _skeleton([([[0, 0, 0], [0, 0, 1], [1, 0, 2], [2, 0, 2.2]], [0.1] * 4)], bevel_res=1)
    v = build_mesh(sk).branches.vertices.reshape(-1, 6, 3)
    first = v[:, 0] - v.mean(axis=1)
    first /= np.linalg.norm(first, axis=1)[:, None]
    cos = np.einsum("ij,ij->i", first[1:], first[:-1])
    assert cos.min() > 0.8


def test_empty_skeleton():
    tm = build_mesh(_skeleton([]))
    assert tm.is_empty
    assert len(tm.branches.vertices) == 0 and len(tm.leaves.vertices) == 0
    assert np.allclose(tm.bounds(), 0.0)


@pytest.mark.parametrize(("shape", "nv", "nf"), [("hex", 6, 4), ("rect", 4, 2)])
def test_leaves_counts_uvs_and_placement(shape, nv, nf):
    rot = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # 90 deg about Z
    leaves = [((1.0, 2.0, 3.0), 0.5 * np.eye(3)), ((0.0, 0.0, 5.0), 2.0 * rot)]
    tm = build_mesh(_skeleton([STRAIGHT], leaves=leaves, leaf_shape=shape), species="maple")
    lv = tm.leaves
    assert len(lv.vertices) == 2 * nv and len(lv.faces) == 2 * nf
    uv = lv.visual.uv
    assert uv.shape == (2 * nv, 2)
    assert uv.min() >= 0.0 and uv.max() <= 1.0
    tmpl = HEX if shape == "hex" else RECT
    first = lv.vertices[:nv]
    assert np.allclose(first[:, :2], 0.5 * tmpl + [1.0, 2.0])
    assert np.allclose(first[:, 2], 3.0)
    second = lv.vertices[nv:]
    expect = (2.0 * rot @ np.column_stack([tmpl, np.zeros(nv)]).T).T + [0, 0, 5]
    assert np.allclose(second, expect)
    # each leaf's area: the template's area times the scale squared
    areas = lv.area_faces.reshape(2, nf).sum(axis=1)
    base = 2.0 / 3.0 if shape == "hex" else 1.0
    assert areas == pytest.approx([0.25 * base, 4.0 * base])
    assert tm.species == "maple"


@pytest.mark.parametrize("name", ["oak", "palm"])
def test_grown_leaves_are_numpys_broadcast_sums_bit_for_bit(name):
    # the leaf corners are placed in one compiled pass: x * col0 + y * col1 + pos added
    # in numpy's order, so every refinement's sketch stays the same to the bit
    from weberpenn import grow, species

    sk = grow(species.sample(name, 4))
    assert sk.n_leaves > 0
    tmpl = RECT if str(sk.leaf_shape) == "rect" else HEX
    mats, pos = np.asarray(sk.leaf_matrices), np.asarray(sk.leaf_positions)
    want = tmpl[None, :, 0, None] * mats[:, None, :, 0]
    want += tmpl[None, :, 1, None] * mats[:, None, :, 1]
    want += pos[:, None, :]
    got = build_mesh(sk, species=name).leaves.vertices
    assert np.array_equal(got, want.reshape(-1, 3))


def test_grouping_keeps_stems_consistent():
    # stems of different point counts mesh exactly like each one alone
    stems = [STRAIGHT, BENT, ([[1, 1, 0], [1, 1, 1]], [0.2, 0.1])]
    together = build_mesh(_skeleton(stems)).branches
    alone = [build_mesh(_skeleton([s])).branches for s in stems]
    a = np.sort(together.vertices, axis=0)
    b = np.sort(np.vstack([m.vertices for m in alone]), axis=0)
    assert np.allclose(a, b)


def test_rejects_non_skeleton():
    with pytest.raises(TypeError, match="Skeleton"):
        build_mesh({"points": []})  # type: ignore[arg-type]


def test_many_stems_fast_and_deterministic():
    rng = np.random.default_rng(0)
    stems = []
    for _ in range(3000):
        n = int(rng.integers(2, 6))
        p = np.cumsum(rng.normal(size=(n, 3)) * 0.3, axis=0)
        stems.append((p, np.linspace(0.05, 0.01, n)))
    sk = _skeleton(stems, bevel_res=1)
    t0 = time.perf_counter()
    a = build_mesh(sk)
    dt = time.perf_counter() - t0
    b = build_mesh(sk)
    assert np.array_equal(a.branches.vertices, b.branches.vertices)
    assert np.array_equal(a.branches.faces, b.branches.faces)
    assert np.isfinite(a.branches.vertices).all()
    assert dt < 2.0  # about 0.02 s on one core; loose for a busy CI machine
    assert isinstance(a.branches, trimesh.Trimesh)


def test_degenerate_stems_stay_finite():
    # repeated control points and zero radii must not make NaNs
    stems = [
        ([[0, 0, 0], [0, 0, 0], [0, 0, 1]], [0.1, 0.1, 0.0]),
        ([[0, 0, 0], [0, 0, 0]], [0.0, 0.0]),
    ]
    tm = build_mesh(_skeleton(stems))
    assert np.isfinite(tm.branches.vertices).all()


@pytest.mark.parametrize("name", ["maple", "palm"])
def test_public_api_grown_tree(name):
    from weberpenn import build_mesh as bm
    from weberpenn import grow, species

    sk = grow(species.sample(name, seed=3))
    tm = bm(sk, species=name)
    assert len(tm.branches.faces) > 1000 and len(tm.leaves.faces) > 100
    assert np.isfinite(tm.branches.vertices).all() and np.isfinite(tm.leaves.vertices).all()
    lo, hi = tm.bounds()
    sk_lo, sk_hi = sk.bounds()
    assert lo[2] <= 0.01 and hi[2] >= 0.5 * sk_hi[2]
    sides = 4 + 2 * sk.bevel_res
    rings = (np.diff(sk.offsets) - 1) * sk.res_u + 1
    assert len(tm.branches.vertices) == sides * rings.sum()
