"""render.edges: the paper's chain on hand-made silhouettes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from render.edges import EdgeConfig, branch_sketch, combine, foliage_sketch, sobel, thin_mask


def _disk_silhouette(n: int = 128, r: float = 30.0) -> np.ndarray:
    yy, xx = np.mgrid[:n, :n]
    inside = (xx - n / 2) ** 2 + (yy - n / 2) ** 2 <= r * r
    return np.where(inside, 0.0, 1.0).astype(np.float32)  # black on white


def test_defaults_are_the_papers_values():
    c = EdgeConfig()
    assert (c.branch_threshold, c.branch_ramp) == (0.5, 0.9)
    assert (c.foliage_threshold, c.foliage_ramp) == (0.9, 0.01)


def test_blank_inputs_give_white():
    white = np.ones((64, 64), np.float32)
    assert (branch_sketch(white) == 1).all()
    assert (foliage_sketch(white) == 1).all()
    assert (combine(branch_sketch(white), foliage_sketch(white)) == 255).all()


def test_foliage_outline_is_a_closed_ring_outside_the_leaves():
    sil = _disk_silhouette()
    out = foliage_sketch(sil)
    dark = out < 0.5
    # closed: the white inside is not connected to the white border
    labels, n = ndimage.label(~dark)
    assert n == 2
    assert labels[64, 64] != labels[0, 0]
    # the strong blur puts the outline outside the leaf silhouette
    rows = np.flatnonzero(dark[:, 64])
    assert rows.min() < 64 - 30 and rows.max() > 64 + 30


def test_branch_chain_draws_a_bar_as_two_lines_and_drops_specks():
    sil = np.ones((256, 256), np.float32)
    sil[20:240, 110:140] = 0.0  # a trunk, 30 px wide
    sil[5, 5] = 0.0  # a speck of background noise (1 px at 256 px)
    out = branch_sketch(sil)
    row = out[128] < 0.5
    assert np.count_nonzero(np.diff(row.astype(int)) == 1) == 2  # two lines
    assert row[120:130].sum() == 0  # hollow in the middle
    assert (out[:12, :12] == 1).all()  # the speck was removed


def test_thinning_removes_the_thinnest_branches():
    hr = np.zeros((128, 128), bool)
    hr[:, 10:11] = True  # half a pixel wide at supersample 2
    hr[:, 60:70] = True  # five pixels wide
    cov = thin_mask(hr, 2, EdgeConfig().branch_thin_px)
    assert cov.shape == (64, 64)
    assert cov[:, 5].max() == 0.0  # gone
    assert (cov[1:-1, 31:34] == 1).all()  # the wide one is only thinner
    assert cov[:, 29:36].sum() < hr[:, 60:70].sum() / 4
    assert np.array_equal(thin_mask(hr, 2, 0.0), hr.reshape(64, 2, 64, 2).mean(axis=(1, 3)))


def test_sobel_is_on_blenders_scale():
    step = np.zeros((9, 9), np.float32)
    step[:, 5:] = 1.0
    assert sobel(step, 4.0).max() == pytest.approx(4.0)


def test_bad_config_values():
    with pytest.raises(ValueError, match="branch_threshold"):
        EdgeConfig(branch_threshold=0.0)
    with pytest.raises(ValueError, match="reference_size"):
        EdgeConfig(reference_size=2)
    with pytest.raises(ValueError, match="leaf_supersample"):
        EdgeConfig(leaf_supersample=1.5)


def test_thinning_is_a_square_erosion():
    rng = np.random.default_rng(0)
    m = rng.random((64, 64)) > 0.3
    for k in (1, 2, 3):
        fp = np.ones((k + 1, k + 1), bool)
        ref = ndimage.binary_erosion(m, structure=fp, border_value=0, origin=-((k + 1) // 2))
        assert np.array_equal(thin_mask(m, 2, k / 4), ref.reshape(32, 2, 32, 2).mean(axis=(1, 3)))


def test_block_counts_are_the_blocks_sums_and_keep_coverage_exact() -> None:
    from render.edges import block_counts
    from render.silhouette import downsample

    rng = np.random.default_rng(11)
    for ss in (1, 2, 3, 4, 16):  # 16: a block of 256 samples outgrows a byte
        mask = rng.random((12 * ss, 12 * ss)) < 0.4
        if ss == 16:
            mask[:16, :16] = True
        counts = block_counts(mask, ss)
        assert counts.dtype == (np.uint8 if ss < 16 else np.uint32)
        assert np.array_equal(counts, mask.reshape(12, ss, 12, ss).sum(axis=(1, 3)))
        # the coverage drawn from them is the float downsample of the mask, bit for bit
        cover = counts.astype(np.float32) * np.float32(1.0 / (ss * ss))
        assert np.array_equal(cover, downsample(mask.astype(np.float32), ss))


def test_binary_edges_are_the_ramped_sobel_of_a_mask() -> None:
    from render.edges import EdgeConfig, binary_edges, branch_sketch, sobel

    rng = np.random.default_rng(5)
    for _ in range(60):  # odd shapes, sparse to full masks, the border included
        h, w = (int(v) for v in rng.integers(3, 48, size=2))
        m = rng.random((h, w)) < rng.random()
        assert np.array_equal(binary_edges(m), sobel(m.astype(np.float32), 4.0) >= 0.9)
    # a ramp above a quarter of the scale takes the float filters, and drops the faint edges
    sil = np.where(rng.random((64, 64)) < 0.2, 0.0, 1.0).astype(np.float32)
    cfg = EdgeConfig(branch_erosion_px=0.0, branch_denoise_px=0.0)
    strict = EdgeConfig(branch_erosion_px=0.0, branch_denoise_px=0.0, branch_ramp=1.5)
    mask = sil <= cfg.branch_threshold
    assert np.array_equal(branch_sketch(sil, cfg) == 0.0, binary_edges(mask))
    want = sobel(mask.astype(np.float32), strict.sobel_scale) >= 1.5
    assert np.array_equal(branch_sketch(sil, strict) == 0.0, want)
    assert want.sum() < binary_edges(mask).sum()
