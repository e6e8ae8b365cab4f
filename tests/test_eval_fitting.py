"""``eval.fitting``: the drawings a fitting script reads are the ones the pipeline accepts."""

from __future__ import annotations

import numpy as np

from eval.fitting import accepted
from treesketch.pipeline import load_sketch, prepare_input


def drawn() -> np.ndarray:
    img = np.full((256, 256), 255, np.uint8)
    img[40:220, 120:136] = 0  # a trunk
    img[40:100, 60:200] = 0  # under a crown
    return img


def test_a_blank_page_is_left_out_and_the_rest_kept_in_order() -> None:
    blank = np.full((64, 64), 255, np.uint8)
    prepared, kept = accepted(
        [blank, drawn(), blank, drawn()], lambda im: prepare_input(load_sketch(im))
    )
    assert kept.tolist() == [False, True, False, True]
    assert len(prepared) == 2
    assert np.array_equal(prepared[0], prepared[1])
    assert np.array_equal(prepared[0], prepare_input(load_sketch(drawn())))
