"""Drawing styles (render/styles.py): SG equality, determinism, what each style draws."""

from __future__ import annotations

import numpy as np
import pytest
from render_helpers import simple_tree
from scipy import ndimage

from render.sketch import SketchRenderer
from render.styles import STYLES, Silhouettes, check_styles, draw

OTHER = [s for s in STYLES if s != "sg"]


@pytest.fixture(scope="module")
def renderer() -> SketchRenderer:
    return SketchRenderer(simple_tree(side_branch=False))


@pytest.fixture(scope="module")
def sil(renderer: SketchRenderer) -> Silhouettes:
    return Silhouettes.from_parts(renderer.parts("front", 256))


def test_at_least_five_styles_besides_sg():
    assert "sg" in STYLES and len(OTHER) >= 5


@pytest.mark.parametrize("size", [256, 128])
def test_sg_style_is_the_renderer_sketch(renderer, sil, size):
    assert np.array_equal(draw("sg", sil, 0, size), renderer.sketch("front", size))


@pytest.mark.parametrize("style", OTHER)
def test_style_is_seeded_and_draws_the_tree(sil, style):
    a = draw(style, sil, 3, 256)
    assert a.dtype == np.uint8 and a.shape == (256, 256)
    assert np.array_equal(a, draw(style, sil, np.random.default_rng(3), 256))
    assert not np.array_equal(a, draw(style, sil, 4, 256))
    paper = np.median(a)
    ink = a < paper - 40
    assert 0.005 < ink.mean() < 0.5
    # nothing far from the tree: ink lies within a few pixels of its silhouettes
    tree = (np.asarray(sil.branches) < 0.5) | (np.asarray(sil.leaves) < 0.9)
    near = ndimage.distance_transform_edt(~tree) <= 24  # a cloud's scallops bulge out
    assert ink[~near].mean() < 0.002
    # the trunk (below the crown, centre column) is drawn
    ys, xs = np.nonzero(np.asarray(sil.branches) < 0.5)
    low = ys > np.percentile(ys, 90)
    y0, y1 = int(ys[low].min()), int(ys[low].max())
    x0, x1 = int(xs[low].min()) - 3, int(xs[low].max()) + 4
    assert (a[y0:y1, x0:x1] < paper - 30).any(axis=1).mean() > 0.6


@pytest.mark.parametrize("style", ["pen", "cloud", "felt", "sg"])
def test_crown_outline_is_closed(sil, style):
    a = draw(style, sil, 1, 256)
    white = a > 160
    lab, _ = ndimage.label(white)
    ys, xs = np.nonzero(np.asarray(sil.leaves) < 0.9)
    cy, cx = int(np.median(ys)), int(np.median(xs))
    inside = lab[cy - 20 : cy + 20, cx + 8 : cx + 20]  # beside the trunk, inside the crown
    assert lab[0, 0] not in set(inside[inside > 0].tolist())


def test_pencil_is_light_on_textured_paper(sil):
    a = draw("pencil", sil, 0, 256).astype(float)
    corner = a[:40, :40]
    assert 150 < corner.mean() < 250 and corner.std() > 1.0  # paper is not flat white
    assert a.min() > 20  # light strokes, never pure black


def test_empty_silhouettes_give_blank_paper():
    white = np.ones((256, 256), np.float32)
    sil = Silhouettes(white, white)
    for style in STYLES:
        a = draw(style, sil, 0, 128)
        assert a.shape == (128, 128)
        assert a.std() < 20 and a.min() > 100


def test_bad_arguments(sil):
    with pytest.raises(ValueError, match="unknown drawing style 'crayon'"):
        draw("crayon", sil)
    with pytest.raises(ValueError, match="listed twice"):
        check_styles(["pen", "pen"])
    with pytest.raises(ValueError, match="no drawing style"):
        check_styles([])
    with pytest.raises(ValueError, match="size must be"):
        draw("pen", sil, 0, 512)
    with pytest.raises(ValueError, match="square images"):
        Silhouettes(np.ones((4, 5)), np.ones((4, 5)))


def test_bare_tree_draws_branches_and_no_foliage(sil):
    a = draw("bare", sil, 2, 256)
    ink = a < 128
    branches = np.asarray(sil.branches) < 0.5
    leaves_only = (np.asarray(sil.leaves) < 0.9) & (ndimage.distance_transform_edt(~branches) > 6)
    assert leaves_only.sum() > 500  # the test tree has foliage away from its branches
    assert ink[leaves_only].mean() < 0.01  # ... and a bare tree draws none of it
    near_branches = ndimage.distance_transform_edt(~branches) <= 3
    assert ink[near_branches].mean() > 0.2 and ink[~near_branches].mean() < 0.002
    pen = draw("pen", sil, 2, 256) < 128
    assert pen[leaves_only].mean() > 5 * ink[leaves_only].mean()  # the crown outline


def _count_corners(pts: np.ndarray) -> int:
    return len(pts) - 1


def test_doodle_crowns_are_few_segment_polylines_and_zigzag_cones():
    from render.styles import _crown_lines

    yy, xx = np.mgrid[0:256, 0:256]
    disc = (yy - 100) ** 2 + (xx - 128) ** 2 < 60**2
    rng = np.random.default_rng(0)
    for _ in range(10):
        (poly,) = _crown_lines(disc, rng, 1.0, "polyline", 0.0)
        assert 5 <= _count_corners(poly) <= 20
        assert np.allclose(poly[0], poly[-1])  # closed when not asked to stay open
        r = np.hypot(poly[:, 0] - 100, poly[:, 1] - 128)
        assert np.all(np.abs(r - 60) < 10)  # on the crown's outline, a hand's jitter off
    cone = (xx - 128) ** 2 * 4 < (yy - 40) ** 2 * 1.0  # widening towards the bottom
    cone &= (yy > 40) & (yy < 200)
    (zig,) = _crown_lines(cone, np.random.default_rng(1), 1.0, "zigzag", 0.0)
    half = zig[:, 1] - 128
    # tiers: the outline goes in and out on the left side (zig, zag) while descending
    left = zig[half < 0]
    steps = np.sign(np.diff(left[:, 1]))
    assert (steps[:-1] != steps[1:]).sum() >= 3
    assert zig[:, 0].min() < 45 and zig[:, 0].max() > 190  # apex to base


def _palm_silhouettes(foliage_strokes: bool) -> Silhouettes:
    """A trunk and six fronds radiating from its top, as the renderer's silhouettes."""
    from skimage.draw import line

    branches = np.ones((256, 256), np.float32)
    branches[90:240, 124:132] = 0.0
    fronds = np.zeros((256, 256), bool)
    for angle in np.radians([10, 40, 75, 105, 140, 170]):
        rr, cc = line(90, 128, int(90 - 70 * np.sin(angle)) + 40, int(128 + 90 * np.cos(angle)))
        fronds[np.clip(rr, 0, 255), np.clip(cc, 0, 255)] = True
    fronds = ndimage.binary_dilation(fronds, iterations=3)
    leaves = np.where(fronds, 0.0, 1.0).astype(np.float32)
    return Silhouettes(branches, leaves, foliage_strokes)


def test_doodle_draws_palm_fronds_as_strokes_when_the_species_says_so():
    fronds = np.asarray(_palm_silhouettes(False).leaves) < 0.9
    near = ndimage.binary_dilation(fronds, iterations=2)
    near[80:100, 115:141] = False  # not where the fronds meet the trunk

    def along_fronds(foliage_strokes: bool) -> int:
        """Of 12 doodles, how many put most of their ink along the fronds."""
        sil = _palm_silhouettes(foliage_strokes)
        n = 0
        for seed in range(12):
            a = draw("doodle", sil, seed) < 128
            assert a.mean() < 0.25  # strokes, never a filled mass
            n += a[near].sum() / max(a.sum(), 1) >= 0.45
        return n

    # strokes run along the fronds; an outline runs around the crown
    assert along_fronds(True) >= 4 and along_fronds(False) <= 2


def test_doodle_of_a_bare_tree_is_its_limbs():
    r = SketchRenderer(simple_tree(side_branch=True))
    p = r.parts("front", 256)
    white = np.ones_like(np.asarray(p.leaf_silhouette))
    bare_sil = Silhouettes(p.branch_silhouette, white)
    a = draw("doodle", bare_sil, 0, 256) < 128
    branches = np.asarray(p.branch_silhouette) < 0.5
    near = ndimage.distance_transform_edt(~branches) <= 6
    assert a.any() and a[~near].mean() < 0.003
