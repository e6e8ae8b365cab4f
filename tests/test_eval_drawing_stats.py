"""What a drawing looks like in numbers (eval/drawing_stats.py): known values on strokes and
images made by hand here."""

from __future__ import annotations

import json

import numpy as np
import pytest

from eval.drawing_stats import (
    PEOPLE_CANVAS,
    image_stats,
    rasterise,
    read_strokes,
    stroke_stats,
    summarise,
)


def _square(x: float, y: float, side: float) -> np.ndarray:
    return np.array([(x, y), (x + side, y), (x + side, y + side), (x, y + side), (x, y)], float)


def test_stroke_counts_closed_strokes_and_a_steady_hand() -> None:
    strokes = [_square(100, 100, 100), np.array([(100, 250), (200, 250)], float)]
    st = stroke_stats(strokes)
    assert st["strokes"] == 2
    assert st["closed"] == 0.5  # the square comes back to its start, the line does not
    # straight lines: no shake (a square's corners are not shake, but they do count a little)
    lines = [np.array([(0, 0), (200, 50)], float), np.array([(0, 100), (200, 100)], float)]
    assert stroke_stats(lines)["jitter"] == pytest.approx(0.0, abs=1e-9)
    assert st["jitter"] < 0.1
    # a shaky line strays from its own smoothed path
    rng = np.random.default_rng(0)
    shaky = np.stack([np.linspace(0, 200, 100), 100 + rng.normal(0, 2, 100)], 1)
    assert stroke_stats([shaky])["jitter"] > 0.3
    # a dot and a short tick count as strokes but are neither open nor closed
    assert stroke_stats([np.array([[5.0, 5.0]]), *strokes])["closed"] == 0.5


def _t_tree(ground: bool) -> np.ndarray:
    """A box of a crown 120 wide and 60 tall over a box of a trunk 24 wide and 60 tall,
    drawn on a 256 page."""
    img = np.full((256, 256), 255, np.uint8)
    img[60:120, 68:188] = 0  # the crown, rows 60-119, columns 68-187
    img[120:180, 116:140] = 0  # the trunk, rows 120-179
    if ground:
        img[180:182, 40:216] = 0
    return img


def test_image_stats_read_the_crown_the_trunk_and_the_ground() -> None:
    st = image_stats(_t_tree(False))
    assert st["crown_aspect"] == pytest.approx(60 / 120)
    assert st["trunk_height"] == pytest.approx(0.5)
    assert st["trunk_width"] == pytest.approx(24 / 120)
    assert st["ground"] == 0.0
    assert st["size"] == pytest.approx(120 / 256)
    assert st["cx"] == pytest.approx((68 + 187) / 2 / 256)
    assert st["ink"] == pytest.approx((60 * 120 + 60 * 24) / 256**2)
    with_ground = image_stats(_t_tree(True))
    assert with_ground["ground"] == 1.0
    # the crown and trunk are read above the ground line
    assert with_ground["trunk_height"] == pytest.approx(0.5, abs=0.03)
    assert with_ground["trunk_width"] == pytest.approx(24 / 120)
    with pytest.raises(ValueError, match="no ink"):
        image_stats(np.full((8, 8), 255, np.uint8))


def test_rasterise_keeps_the_drawings_place_on_the_page(tmp_path) -> None:
    path = tmp_path / "tree.ndjson"
    row = {"author": "a", "session": "s", "strokes": [[[0, 0], [200, 200]], [], [[300, 100]]]}
    path.write_text(json.dumps(row) + "\n\n")
    (drawing,) = read_strokes(path)
    assert drawing["author"] == "a" and len(drawing["strokes"]) == 2  # the empty one dropped
    img = rasterise(drawing["strokes"], PEOPLE_CANVAS, 256, 3)
    assert img.shape == (256, 256) and img.dtype == np.uint8
    assert img[64, 64] == 0 and img[200, 200] == 255  # the line ends at the canvas' middle
    assert img[64, 192] == 0  # the dot, scaled from (300, 100) on the 400 canvas


def test_summarise_gives_quartiles() -> None:
    rows = [{"a": float(v)} for v in range(5)]
    assert summarise(rows) == {"a": (1.0, 2.0, 3.0)}
