"""render.distance: the compiled distance transform is scipy's, to the last bit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from render.distance import distance_to_background


@pytest.mark.parametrize("seed", range(6))
def test_distances_are_scipys_on_random_masks(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(40):
        h, w = (int(v) for v in rng.integers(1, 90, 2))
        mask = rng.random((h, w)) < rng.uniform(0.2, 0.999)
        if rng.random() < 0.3:  # one background pixel in a sea of foreground
            mask[:] = True
            mask[rng.integers(h), rng.integers(w)] = False
        want = ndimage.distance_transform_edt(mask)
        got = distance_to_background(mask)
        assert got.dtype == np.float64 and got.shape == mask.shape
        assert np.array_equal(got, want)


def test_strokes_blanks_and_masks_without_background() -> None:
    ring = np.zeros((40, 60), bool)
    ring[5:35, 10:50] = True
    ring[12:28, 20:40] = False  # a frame 7 rows and 10 columns thick
    assert np.array_equal(distance_to_background(ring), ndimage.distance_transform_edt(ring))
    d = distance_to_background(ring)
    assert d[20, 14] == 5.0  # the middle of a side 10 wide
    assert d.max() == np.sqrt(29.0)  # in a corner, straight across it (5 and 2 away)
    assert not distance_to_background(np.zeros((5, 7), bool)).any()
    full = np.ones((4, 6), np.uint8)  # no background: scipy's own answer
    assert np.array_equal(distance_to_background(full), ndimage.distance_transform_edt(full))
    row = np.array([[1, 1, 0, 1, 1, 1]], bool)
    assert distance_to_background(row).tolist() == [[2.0, 1.0, 0.0, 1.0, 2.0, 3.0]]
