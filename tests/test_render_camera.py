"""render.camera and render.backend: framing, views, rays, libLLVM search (no mitsuba)."""

from __future__ import annotations

import numpy as np
import pytest

from render.backend import MIN_LLVM, find_libllvm, llvm_version
from render.camera import VIEWS, Camera, Framing, resolve_yaw


def test_views_are_the_four_yaws():
    assert VIEWS == {"front": 0.0, "back": 180.0, "left": 90.0, "right": 270.0}
    assert resolve_yaw("Front") == 0.0
    assert resolve_yaw("37.5") == 37.5
    assert resolve_yaw(400) == 400.0


@pytest.mark.parametrize("bad", ["top", "", "nan-ish"])
def test_unknown_view_is_a_clear_error(bad):
    with pytest.raises(ValueError, match="unknown view"):
        resolve_yaw(bad)


def test_nonfinite_yaw_and_big_pitch_rejected():
    f = Framing(0.0, 1.0, 0.5)
    with pytest.raises(ValueError, match="finite"):
        resolve_yaw(float("nan"))
    with pytest.raises(ValueError, match="pitch"):
        Camera(f, 0.0, 80.0)
    with pytest.raises(ValueError, match="image size"):
        Camera(f).rays(3)


def test_framing_fills_the_same_height_fraction_for_any_tree_size():
    # a tall thin palm-like and a tiny bonsai-like point set (both taller than wide)
    rng = np.random.default_rng(0)
    for height, radius in ((12.0, 2.0), (0.8, 0.25)):
        v = rng.uniform(-1, 1, (500, 3)) * [radius, radius, 0]
        v[:, 2] = rng.uniform(0, height, 500)
        v[0] = [0, 0, 0]
        v[1] = [0, 0, height]
        f = Framing.from_vertices(v)
        cam = Camera(f, 0.0)
        rows = cam.project(np.array([[0, 0, 0], [0, 0, height]]), 256)[:, 1]
        assert rows[0] == pytest.approx(256 * (1 - f.margin_bottom))
        assert rows[1] == pytest.approx(256 * f.margin_top)


def test_wide_tree_is_fitted_by_its_widest_radius():
    v = np.array([[0, 0, 0], [0, 0, 1.0], [3.0, 0, 0.5]])
    f = Framing.from_vertices(v)
    assert f.span == pytest.approx(6.0 / (1 - 2 * f.margin_side))
    for yaw in (0, 90, 180, 270, 33):
        cols = Camera(f, yaw).project(v, 200)[:, 0]
        assert cols.min() >= 200 * f.margin_side - 1e-6
        assert cols.max() <= 200 * (1 - f.margin_side) + 1e-6


def test_framing_does_not_depend_on_yaw_and_base_stays_put():
    v = np.array([[0, 0, 0], [1, 2, 5], [-2, 0.5, 3]])
    f = Framing.from_vertices(v)
    for yaw in (0, 90, 180, 270, 10):
        base = Camera(f, yaw).project(np.zeros((1, 3)), 128)[0]
        assert base == pytest.approx([64.0, 128 * (1 - f.margin_bottom)])


def test_camera_basis_and_rays():
    f = Framing(0.0, 2.0, 0.5)
    right, up, fwd = Camera(f, 0.0).basis()
    assert np.allclose([right, up, fwd], [[1, 0, 0], [0, 0, 1], [0, 1, 0]])
    _, _, fwd90 = Camera(f, 90.0).basis()
    assert np.allclose(fwd90, [-1, 0, 0])
    o, d = Camera(f, 0.0, 10.0).rays(16, supersample=2)
    assert o.shape == (3, 32 * 32) and o.dtype == np.float32
    assert np.linalg.norm(d) == pytest.approx(1.0)
    assert d[2] < 0  # raised camera looks down


def test_margins_validated():
    with pytest.raises(ValueError, match="margin_side"):
        Framing(0, 1, 1, margin_side=0.6)


def test_llvm_search_never_picks_llvm_15(tmp_path):
    for name in ("libLLVM-14.so", "libLLVM-15.so", "libLLVM.so.15.0", "libLLVM-19.so"):
        (tmp_path / name).write_bytes(b"")
    assert llvm_version("/usr/lib/x86_64-linux-gnu/libLLVM-19.so") == 19
    assert llvm_version("/usr/lib/llvm-14/lib/libLLVM.so") == 14
    assert llvm_version("libLLVM.so.19.1") == 19
    found = find_libllvm((str(tmp_path),))
    assert found is not None and llvm_version(found) == 19
    (tmp_path / "libLLVM-19.so").unlink()
    assert find_libllvm((str(tmp_path),)) is None  # 14 and 15 are too old / abort
    assert MIN_LLVM == 16
