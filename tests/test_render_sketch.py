"""render.sketch / render.silhouette: style, empty input, views, framing, determinism."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from render_helpers import empty_mesh, simple_tree

from render.sketch import VIEWS, EdgeConfig, SketchRenderer, sketch
from weberpenn.treemesh import TreeMesh

SIZE = 96


@pytest.fixture(scope="module")
def tree():
    return simple_tree()


@pytest.fixture(scope="module")
def renderer(tree):
    return SketchRenderer(tree)


def test_white_background_and_dark_lines(renderer):
    img = renderer.sketch("front", SIZE)
    assert img.shape == (SIZE, SIZE) and img.dtype == np.uint8
    border = np.concatenate([img[0], img[-1], img[:, 0], img[:, -1]])
    assert (border == 255).all()
    assert (img == 255).mean() > 0.7  # mostly white
    assert (img < 64).mean() > 0.02  # and some dark lines
    assert set(np.unique(img)) <= set(range(256))


def test_outline_is_closed_and_trunk_drawn_as_two_lines(renderer):
    from scipy import ndimage

    img = renderer.sketch("front", 128)
    white = img > 128
    labels, n = ndimage.label(white)
    # the crown outline encloses white regions that the background does not reach
    assert n >= 2
    # a row through the bare trunk (just above the base): exactly two dark runs
    base_row = int(round(128 * (1 - renderer.framing.margin_bottom))) - 6
    dark = img[base_row] < 128
    runs = np.count_nonzero(np.diff(dark.astype(int)) == 1)
    assert runs == 2


def test_empty_mesh_gives_all_white():
    tm = TreeMesh(empty_mesh(), empty_mesh())
    img = sketch(tm, 0.0, 64)
    assert img.shape == (64, 64) and (img == 255).all()
    col = SketchRenderer(tm).colour(0.0, 32)
    assert col.shape == (32, 32, 3) and (col == 255).all()


def test_leafless_and_branchless_trees_render(tree):
    bare = sketch(TreeMesh(tree.branches, empty_mesh()), 0, 64)
    only_leaves = sketch(TreeMesh(empty_mesh(), tree.leaves), 0, 64)
    assert (bare < 128).any() and (only_leaves < 128).any()
    assert not np.array_equal(bare, only_leaves)


def test_four_views_differ(renderer):
    imgs = {v: renderer.sketch(v, SIZE) for v in VIEWS}
    names = list(imgs)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            assert not np.array_equal(imgs[a], imgs[b]), (a, b)
    # the side branch points along +X: right of the trunk at front, left at back
    front, back = imgs["front"] < 128, imgs["back"] < 128
    assert front[:, SIZE // 2 + 8 :].sum() > front[:, : SIZE // 2 - 8].sum()
    assert back[:, : SIZE // 2 - 8].sum() > back[:, SIZE // 2 + 8 :].sum()


def test_same_input_identical_pixels(tree, renderer):
    a = renderer.sketch(30.0, SIZE)
    b = SketchRenderer(tree).sketch(30.0, SIZE)
    c = sketch(tree, 30.0, SIZE)
    assert np.array_equal(a, b) and np.array_equal(a, c)
    assert np.array_equal(renderer.colour(0, 48), renderer.colour(0, 48))


def _height_fraction(img: np.ndarray) -> float:
    rows = np.flatnonzero((img < 128).any(axis=1))
    return (rows[-1] - rows[0] + 1) / img.shape[0]


def test_framing_consistent_for_bonsai_and_palm():
    palm = simple_tree(height=12.0, trunk_radius=0.15, crown_radius=1.8, side_branch=False)
    bonsai = simple_tree(height=0.9, trunk_radius=0.03, crown_radius=0.3, side_branch=False)
    fp = _height_fraction(sketch(palm, 0, 128))
    fb = _height_fraction(sketch(bonsai, 0, 128))
    assert fp == pytest.approx(fb, abs=2 / 128)
    assert fp > 0.85
    # trunk base on the same row
    for t in (palm, bonsai):
        img = sketch(t, 90, 128)
        assert np.flatnonzero((img < 128).any(axis=1))[-1] == pytest.approx(128 * (1 - 0.04), abs=2)


def test_colour_render(renderer):
    col = renderer.colour("left", 64)
    assert col.shape == (64, 64, 3) and col.dtype == np.uint8
    assert (col[0] == 255).all()  # white background
    assert (col.astype(int).sum(axis=2) < 600).mean() > 0.05  # coloured tree


def test_sizes_and_config():
    t = simple_tree()
    r = SketchRenderer(t, EdgeConfig(supersample=1, foliage_sigma_px=2.0))
    assert r.sketch(0, 64).shape == (64, 64)
    assert r.sketch(0, 200).shape == (200, 200)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"size": 4}, "image size"),
        ({"size": 64.5}, "image size"),
        ({"yaw": "sideways"}, "unknown view"),
        ({"pitch": 70}, "pitch"),
    ],
)
def test_bad_arguments(renderer, kwargs, match):
    args = {"yaw": 0.0, "size": 64, **kwargs}
    with pytest.raises(ValueError, match=match):
        renderer.sketch(**args)


def test_bad_inputs():
    with pytest.raises(TypeError, match="TreeMesh"):
        SketchRenderer("not a tree")
    with pytest.raises(ValueError, match="supersample"):
        EdgeConfig(supersample=0)
    with pytest.raises(ValueError, match="foliage_sigma_px"):
        EdgeConfig(foliage_sigma_px=-1)
    t = simple_tree()
    t.branches.vertices[0] = [np.nan, 0, 0]
    with pytest.raises(ValueError, match="non-finite"):
        SketchRenderer(t)


def test_scalar_fallback_matches_llvm_roughly(tmp_path):
    """The scalar_rgb path (no LLVM) gives nearly the same sketch (random sub-pixel
    positions there, so not bit-identical)."""
    code = (
        "import numpy as np;"
        "from render_helpers import simple_tree; from render.sketch import SketchRenderer;"
        "r = SketchRenderer(simple_tree()); print(r.variant);"
        f"np.save(r'{tmp_path}/s.npy', r.sketch(0, 64))"
    )
    # the test's own path (tests/ for render_helpers, this checkout's code) for the child
    env = {
        **os.environ,
        "TREESKETCH_MI_VARIANT": "scalar_rgb",
        "PYTHONPATH": os.pathsep.join(sys.path),
    }
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, cwd=root, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "scalar_rgb" in out.stdout
    scalar = np.load(tmp_path / "s.npy")
    llvm = SketchRenderer(simple_tree()).sketch(0, 64)
    assert (scalar != llvm).mean() < 0.1


def test_small_sketch_is_a_downsized_reference_sketch(renderer):
    big = renderer.sketch(0, 256).astype(np.float32)
    small = renderer.sketch(0, 128).astype(np.float32)
    down = big.reshape(128, 2, 128, 2).mean(axis=(1, 3))
    assert np.abs(small - down).max() <= 1.0
    odd = renderer.sketch(0, 100)
    assert odd.shape == (100, 100) and (odd < 128).any()


def test_pitch_changes_the_view_a_little(renderer):
    flat = renderer.sketch(0, SIZE)
    raised = renderer.sketch(0, SIZE, pitch=10.0)
    assert not np.array_equal(flat, raised)
    assert abs(_height_fraction(flat) - _height_fraction(raised)) < 0.1
