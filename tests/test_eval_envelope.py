"""The envelope overlap (eval.envelope, refine.envelope) on hand-made pictures."""

from __future__ import annotations

import numpy as np
import pytest

from eval.envelope import SIDE, envelope, envelope_overlap
from refine.envelope import close_disk, mask_iou, row_fill


def page() -> np.ndarray:
    return np.full((SIDE, SIDE), 255, np.uint8)


def outline_box(img: np.ndarray, top: int, bottom: int, left: int, right: int) -> np.ndarray:
    img[top, left : right + 1] = 0
    img[bottom, left : right + 1] = 0
    img[top : bottom + 1, left] = 0
    img[top : bottom + 1, right] = 0
    return img


def test_row_fill_fills_between_the_outermost_ink():
    m = np.zeros((4, 6), bool)
    m[1, 1] = m[1, 4] = True
    m[2, 3] = True
    out = row_fill(m)
    assert out[1].tolist() == [False, True, True, True, True, False]
    assert out[2].tolist() == [False, False, False, True, False, False]
    assert not out[0].any() and not out[3].any()


def test_closing_joins_two_trunk_lines_within_the_disk():
    m = np.zeros((40, 40), bool)
    m[5:35, 15] = m[5:35, 25] = True  # a trunk drawn as two lines 10 px apart
    closed = close_disk(m, 6)
    assert closed[20, 15:26].all()  # joined: 10 px gap < 2 * 6
    far = np.zeros((40, 40), bool)
    far[5:35, 5] = far[5:35, 35] = True  # 30 px apart: stays two lines
    assert not close_disk(far, 6)[20, 10:30].any()


def test_an_outline_box_is_a_filled_box():
    env = envelope(outline_box(page(), 40, 200, 60, 180))
    assert env[40:201, 60:181].all()
    assert env.sum() == 161 * 121


def test_identical_pictures_overlap_one_and_disjoint_ones_zero():
    a = outline_box(page(), 20, 100, 20, 100)
    b = outline_box(page(), 150, 230, 150, 230)
    assert envelope_overlap(a, a) == 1.0
    assert envelope_overlap(a, b) == 0.0


def test_overlap_is_intersection_over_union_of_the_filled_shapes():
    a = outline_box(page(), 0, 99, 0, 99)  # 100 x 100
    b = outline_box(page(), 0, 99, 50, 149)  # moved half its width
    assert envelope_overlap(a, b) == pytest.approx(50 * 100 / (150 * 100))


def test_any_size_is_measured_at_256():
    small = np.full((128, 128), 255, np.uint8)
    outline_box(small, 10, 100, 20, 90)
    assert envelope(small).shape == (SIDE, SIDE)
    assert envelope_overlap(small, small) == 1.0


def test_blank_pictures():
    assert not envelope(page()).any()
    assert mask_iou(np.zeros((3, 3), bool), np.zeros((3, 3), bool)) == 1.0


def test_the_search_distance_counts_the_envelope_gap(monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 48: the refinement's distance rewards the outline where the tree stands in
    # the frame; two crowns alike but for a flat top differ by the envelope term
    from refine import objective, shape

    flat, round_ = page(), page()
    outline_box(flat, 30, 150, 60, 196)
    flat[150:240, 120] = flat[150:240, 136] = 0
    round_[150:240, 120] = round_[150:240, 136] = 0
    from PIL import Image, ImageDraw

    im = Image.fromarray(round_)
    ImageDraw.Draw(im).ellipse([60, 30, 196, 150], outline=0, width=1)
    round_ = np.asarray(im)
    a = shape.ShapeTarget.from_image(flat, 128)
    b = shape.ShapeTarget.from_image(round_, 128)
    gap = 1.0 - mask_iou(a.envelope, b.envelope)
    assert gap > 0.05 and shape.outline_gap(a, b) == pytest.approx(gap)
    # the search adds the gap; the shape distance itself stays without it (style-blind)
    searched = objective.search_distance(a, b)
    assert searched == pytest.approx(a.distance(b) + objective.ENVELOPE_WEIGHT * gap)
    monkeypatch.setattr(objective, "ENVELOPE_WEIGHT", 0.0)
    assert objective.search_distance(a, b) == pytest.approx(a.distance(b))
    assert objective.search_distance(a, a) == 0.0
