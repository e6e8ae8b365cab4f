"""render._fallback_mesh: the stand-in mesher follows the Skeleton's documented geometry."""

from __future__ import annotations

import numpy as np

from render._fallback_mesh import build_mesh
from weberpenn import species
from weberpenn.grow import grow


def test_fallback_mesh_matches_the_skeleton():
    sk = grow(species.sample("palm", seed=3))
    tm = build_mesh(sk)
    sides = 4 + 2 * sk.bevel_res
    counts = np.diff(sk.offsets)
    samples = (counts - 1) * sk.res_u + 1
    assert len(tm.branches.faces) == int((2 * sides * (samples - 1)).sum())
    per_leaf = 4 if sk.leaf_shape == "hex" else 2
    assert len(tm.leaves.faces) == per_leaf * sk.n_leaves
    # the curves pass through the control points: bounds agree up to the radii
    lo, hi = tm.bounds()
    slo, shi = sk.bounds()
    assert np.all(lo <= slo + 1e-6) and np.all(hi >= shi - 1e-6)
    assert np.all(hi - lo < (shi - slo) + 2 * sk.radii.max() + 2.0)
    assert np.isfinite(tm.branches.vertices).all()
    assert abs(tm.branches.vertices[:, 2].min()) < 0.05 * (shi[2] - slo[2])
