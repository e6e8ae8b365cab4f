"""Tests of weberpenn.textures and the bark UVs (weberpenn.mesh, weberpenn.uv)."""

from __future__ import annotations

import numpy as np
import pytest

from weberpenn import build_mesh, grow, species
from weberpenn.textures import bark_texture, leaf_texture
from weberpenn.uv import close_seams


@pytest.mark.parametrize("name", [*species.SPECIES, None])
def test_textures_tile_and_have_alpha(name):
    bark = np.asarray(bark_texture(name, 64), dtype=float)
    assert bark.shape == (64, 64, 3)
    inner = np.abs(np.diff(bark, axis=1)).mean()
    assert np.abs(bark[:, 0] - bark[:, -1]).mean() < 3 * inner  # wraps left-right
    assert np.abs(bark[0] - bark[-1]).mean() < 3 * np.abs(np.diff(bark, axis=0)).mean() + 1
    leaf = np.asarray(leaf_texture(name, 64))
    assert leaf.shape == (64, 64, 4)
    alpha = leaf[..., 3]
    assert 0.05 < (alpha == 255).mean() < 0.9 and set(np.unique(alpha)) == {0, 255}
    assert np.array_equal(leaf, np.asarray(leaf_texture(name, 64)))  # deterministic
    with pytest.raises(ValueError, match="texture size"):
        bark_texture(name, 4)


def test_bark_uv_runs_along_and_around():
    tm = build_mesh(grow(species.sample("palm", 0)))
    uv = tm.branches.visual.uv
    sides = tm.meta["sides"]
    assert uv.shape == (len(tm.branches.vertices), 2)
    first = uv[: sides * 3].reshape(3, sides, 2)  # the trunk's first three rings
    assert np.allclose(first[:, :, 0], np.arange(sides) / sides)
    assert np.all(np.diff(first[:, 0, 1]) > 0)  # v grows along the stem


def test_close_seams():
    uv = np.array([[0.0, 0.0], [0.75, 0.0], [0.75, 1.0], [0.0, 1.0]])
    faces = np.array([[1, 0, 3], [1, 3, 2], [0, 1, 2]])
    f, src, out = close_seams(faces, uv)
    fu = out[f, 0]
    assert (fu.max(axis=1) - fu.min(axis=1)).max() <= 0.5
    assert list(src) == [0, 1, 2, 3, 0, 3] and np.allclose(out[4:, 0], 1.0)
