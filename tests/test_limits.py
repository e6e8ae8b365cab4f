"""Tests of weberpenn.limits: exploding dictionaries are refused before allocating."""

from __future__ import annotations

import time

import numpy as np
import pytest
from paths import GT_PARAM_DIR as PARAM_DIR

from weberpenn import ParamError, build_mesh, default_params, grow, load_params, species
from weberpenn.limits import (
    MAX_MESH_FACES,
    MAX_MESH_VERTICES,
    MAX_STEMS,
    mesh_size,
)
from weberpenn.mesh import tube_counts
from weberpenn.skeleton import Skeleton


def _size(sk: Skeleton) -> tuple[int, int]:
    return mesh_size(np.diff(sk.offsets), sk.res_u, sk.bevel_res, sk.n_leaves, sk.leaf_shape)


def test_issue_11_dictionary_is_refused_quickly_naming_its_keys():
    # valid key by key; before the limits, growing and meshing it asked numpy for 140 GiB
    p = default_params().replace(
        levels=1, segSplits=(3.0, 3.0, 3.0, 3.0), curveRes=(64, 64, 64, 64), resU=32, bevelRes=32
    )
    t0 = time.perf_counter()
    with pytest.raises(ParamError, match=r"segSplits\[0\]=3.0") as err:
        grow(p)
    assert time.perf_counter() - t0 < 5.0
    assert err.value.key == "segSplits"
    assert "curveRes[0]=64" in str(err.value)


def test_mesh_bound_names_the_resolution_keys():
    # 512 stems is fine to grow; with 32 x 68-sided rings per segment the mesh is 36 M
    p = default_params().replace(
        levels=1, segSplits=(1.0, 0, 0, 0), curveRes=(16, 5, 3, 1), resU=32, bevelRes=32
    )
    with pytest.raises(ParamError, match="vertices") as err:
        grow(p)
    msg = str(err.value)
    assert err.value.key == "resU" and "bevelRes=32" in msg and "resU=32" in msg
    sk = grow(p.replace(resU=2, bevelRes=0))  # the same stems at a coarse resolution
    verts, faces = _size(sk)
    assert verts <= MAX_MESH_VERTICES and faces <= MAX_MESH_FACES


def test_exploding_split_of_a_species_is_refused():
    p = species.sample("bonsai", seed=2).replace(segSplits=(1.0, 1.0, 1.0, 1.0))
    with pytest.raises(ParamError, match=f"more than {MAX_STEMS} stems") as err:
        grow(p)
    assert err.value.key == "segSplits"


def test_build_mesh_checks_a_hand_made_skeleton_before_allocating():
    s, n = 2000, 64  # 2000 stems of 64 points at resU 32, bevelRes 32: 274 M vertices
    pts = np.zeros((s * n, 3))
    pts[:, 2] = np.tile(np.arange(n, dtype=float), s)
    sk = Skeleton(
        points=pts,
        radii=np.full(s * n, 0.1),
        offsets=np.arange(s + 1, dtype=np.int64) * n,
        levels=np.zeros(s, np.int64),
        parents=np.full(s, -1, np.int64),
        leaf_positions=np.zeros((0, 3)),
        leaf_matrices=np.zeros((0, 3, 3)),
        leaf_shape="hex",
        res_u=32,
        bevel_res=32,
    )
    assert _size(sk)[0] == s * tube_counts(n, 32, 32)[0]
    t0 = time.perf_counter()
    with pytest.raises(ParamError, match="resU=32, bevelRes=32"):
        build_mesh(sk)
    assert time.perf_counter() - t0 < 1.0


def test_mesh_size_is_exact():
    sk = grow(species.sample("maple", seed=3))
    mesh = build_mesh(sk)
    verts, faces = _size(sk)
    assert verts == len(mesh.branches.vertices) + len(mesh.leaves.vertices)
    assert faces == len(mesh.branches.faces) + len(mesh.leaves.faces)


def test_reference_trees_stay_well_under_the_limits():
    files = sorted(PARAM_DIR.glob("*.json"))
    assert len(files) == 15
    for f in files:
        sk = grow(load_params(f))
        verts, faces = _size(sk)
        # cherry, the biggest, is about 0.5 M vertices and 0.65 M triangles
        assert verts < MAX_MESH_VERTICES / 5 and faces < MAX_MESH_FACES / 5, f.name
        assert sk.n_stems < MAX_STEMS / 5, f.name
