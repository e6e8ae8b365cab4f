"""eval.pictures: the simple non-tree pictures the benchmarks score and the detector fits on."""

from __future__ import annotations

import numpy as np
import pytest

from eval.pictures import PICTURE_KINDS, SIZE, non_trees, picture


def test_non_trees_are_fifty_and_repeatable() -> None:
    a, b = non_trees(0), non_trees(0)
    assert len(a) == 50 and len({name for name, _ in a}) == 50
    assert all(np.array_equal(x, y) for (_, x), (_, y) in zip(a, b, strict=True))
    assert all(im.shape == (SIZE, SIZE) and im.dtype == np.uint8 for _, im in a)


@pytest.mark.parametrize("kind", PICTURE_KINDS)
def test_each_kind_draws_ink_from_its_seed(kind: str) -> None:
    im = picture(kind, 3)
    assert im.shape == (SIZE, SIZE) and (im < 128).any() and (im > 128).any()
    assert np.array_equal(im, picture(kind, 3))


def test_unknown_kind() -> None:
    with pytest.raises(ValueError, match="unknown picture kind"):
        picture("tree", 0)
