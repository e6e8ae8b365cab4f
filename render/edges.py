"""The paper's sketch chain (section "The dataset creation pipeline"), with scikit-image.

Inputs are the two silhouettes of one view as black-on-white float images (1 = white
background, 0 = fully covered), i.e. ``1 - coverage`` from :mod:`render.silhouette`.

Branches: slight thinning (removes the thinnest branches) -> threshold 0.5 (remove the
background) -> denoise (drop isolated specks; the paper uses Intel Open Image Denoise for
residual background artefacts) -> Sobel -> colour ramp at 0.9 (below -> 0, else 1) ->
invert (white background, dark edges) -> erosion (the white shrinks, so the dark strokes
thicken and merge, and stray single pixels of white inside strokes vanish).

Foliage: threshold 0.9 -> strong Gaussian blur -> colour ramp at 0.01 (everything the blur
reached becomes foliage: a smooth closed blob around the leaves) -> Sobel -> invert (a
closed outline).

Sketch = branches x foliage, as uint8 (255 = white).

The Sobel magnitude is on Blender's scale (un-normalised 3x3 kernels: a 0 -> 1 step gives
4), which is what the paper's 0.9 ramp refers to; scikit-image's ``sobel_h``/``sobel_v``
are normalised by 4, so they are multiplied by ``sobel_scale``.  Pixel-sized constants are
given for a 256-pixel image and scale with the image size, so a 128-pixel sketch looks
like a downsized 256-pixel one.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numba
import numpy as np
from scipy import ndimage
from skimage import filters, morphology


@dataclass(frozen=True)
class EdgeConfig:
    """Every constant of the sketch chain; defaults are the paper's values."""

    reference_size: int = 256  # the pixel constants below are for this image size
    supersample: int = 2  # branch silhouette samples per pixel side (sub-pixel thinning)
    leaf_supersample: int = 1  # leaf silhouette samples per pixel side (it gets blurred anyway)
    # branches
    branch_thin_px: float = 0.25  # thinning: the silhouette loses 2x this width (px)
    branch_threshold: float = 0.5  # paper: remove the background at 0.5
    branch_denoise_px: float = 3.0  # drop isolated specks smaller than this area (px^2)
    branch_ramp: float = 0.9  # paper: ramp below 0.9 -> 0, else 1
    branch_erosion_px: float = 1.0  # erosion footprint radius (px) on the white image
    # foliage
    foliage_threshold: float = 0.9  # paper: remove the background at 0.9
    foliage_sigma_px: float = 3.5  # the "strong" Gaussian (standard deviation, px)
    foliage_ramp: float = 0.01  # paper: ramp below 0.01 -> 0, else 1
    # shared
    sobel_scale: float = 4.0  # Blender's un-normalised Sobel = 4 x scikit-image's

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"EdgeConfig.{f.name}={v!r} must be a finite number >= 0")
        for name in ("branch_threshold", "foliage_threshold"):
            if not 0.0 < getattr(self, name) <= 1.0:
                raise ValueError(f"EdgeConfig.{name}={getattr(self, name)!r} must be in (0, 1]")
        if self.reference_size < 8:
            raise ValueError(f"EdgeConfig.reference_size={self.reference_size!r} must be >= 8")
        for name in ("supersample", "leaf_supersample"):
            v = getattr(self, name)
            if int(v) != v or not 1 <= v <= 8:
                raise ValueError(f"EdgeConfig.{name}={v!r} must be an integer in 1..8")

    def px(self, value: float, size: int) -> float:
        """A pixel constant given at ``reference_size`` scaled to ``size``."""
        return float(value) * size / self.reference_size


def sobel(img: np.ndarray, scale: float) -> np.ndarray:
    """Sobel gradient magnitude (scikit-image kernels times ``scale``)."""
    gh = filters.sobel_h(img)
    gv = filters.sobel_v(img)
    return scale * np.hypot(gh, gv)


def _disk(radius: float) -> np.ndarray | None:
    r = float(radius)
    if r < 0.5:
        return None
    k = int(np.floor(r))
    yy, xx = np.mgrid[-k : k + 1, -k : k + 1]
    fp = (xx**2 + yy**2) <= r * r + 1e-9
    return fp


def thin_mask(mask_hr: np.ndarray, ss: int, thin_px: float) -> np.ndarray:
    """Thin a supersampled binary silhouette and return per-pixel coverage (size x size).

    The silhouette loses ``2 * thin_px`` pixels of width in total (``thin_px`` per side on
    average, rounded to whole sub-pixels: a square erosion footprint of ``k + 1``
    sub-pixels removes ``k`` of them across every branch), so branches thinner than that
    vanish and the rest get slightly thinner.
    """
    k = int(round(2.0 * thin_px * ss))
    m = np.asarray(mask_hr, dtype=bool)
    if k > 0:  # separable erosion by a (k+1) x (k+1) square (outside counts as empty)
        for axis in (0, 1):
            out = m.copy()
            for shift in range(1, k + 1):
                nxt = np.zeros_like(m)
                if axis == 0:
                    nxt[:-shift] = m[shift:]
                else:
                    nxt[:, :-shift] = m[:, shift:]
                out &= nxt
            m = out
    return (block_counts(m, ss) / float(ss * ss)).astype(np.float32)


def block_counts(mask: np.ndarray, ss: int) -> np.ndarray:
    """(n, n) unsigned: how many samples of each ``ss`` x ``ss`` block of the bool ``mask``
    (``(n * ss, n * ss)``) are set (uint8 up to ``ss`` 15, wider past it).  One compiled
    pass: a refinement counts about two hundred 512-sample masks per drawing, and numpy's
    sum over a block's short inner axis cost ten times as long (the counts are the same
    integers)."""
    n = mask.shape[0] // ss
    out = np.zeros((n, n), dtype=np.uint8 if ss * ss <= 255 else np.uint32)
    _count_blocks(np.asarray(mask, dtype=bool), int(ss), out)
    return out


@numba.njit(cache=True, nogil=True)
def _count_blocks(mask: np.ndarray, ss: int, out: np.ndarray) -> None:
    n = out.shape[0]
    for i in range(n * ss):
        row = out[i // ss]
        for j in range(n * ss):
            if mask[i, j]:
                row[j // ss] += 1


def binary_edges(mask: np.ndarray) -> np.ndarray:
    """Where the Sobel gradient of a bool ``mask`` (scikit-image's kernels, reflected at
    the border) is not zero.  Of a mask, each kernel's response is a whole number of
    quarters, so any nonzero magnitude is at least a quarter: with the paper's ramp
    (0.9, on four times scikit-image's scale) the ramped edge is exactly this set.
    Summed in small integers, at a tenth of the float filters' cost (the branch chain
    runs on every candidate the refinement draws)."""
    p = np.pad(np.asarray(mask, dtype=np.int8), 1, mode="symmetric")
    down = p[:-2] - p[2:]  # across rows, then smoothed (1, 2, 1) along them
    across = p[:, :-2] - p[:, 2:]
    gh = down[:, :-2] + 2 * down[:, 1:-1] + down[:, 2:]
    gv = across[:-2] + 2 * across[1:-1] + across[2:]
    return (gh != 0) | (gv != 0)


def branch_sketch(silhouette: np.ndarray, cfg: EdgeConfig | None = None) -> np.ndarray:
    """Branch chain on a black-on-white silhouette (already thinned): float 0..1, 1 = white."""
    cfg = cfg or EdgeConfig()
    img = np.asarray(silhouette, dtype=np.float32)
    size = img.shape[0]
    mask = img <= cfg.branch_threshold  # (a) remove the background (half-covered counts)
    min_area = cfg.branch_denoise_px * (size / cfg.reference_size) ** 2  # an area scales as size^2
    if min_area >= 1.5 and mask.any():  # (b) denoise: drop specks
        mask = morphology.remove_small_objects(mask, max_size=int(round(min_area)) - 1)
    if 0.0 < cfg.branch_ramp <= 0.25 * cfg.sobel_scale:  # (c, d) any change of the mask
        edge = binary_edges(mask)
    else:
        edge = sobel(mask.astype(np.float32), cfg.sobel_scale) >= cfg.branch_ramp
    out = (~edge).astype(np.float32)  # (e) invert: white background, dark edges
    fp = _disk(cfg.px(cfg.branch_erosion_px, size))  # (f) erosion
    if fp is not None:
        out = ndimage.grey_erosion(out, footprint=fp, mode="nearest")
    return out


def foliage_sketch(silhouette: np.ndarray, cfg: EdgeConfig | None = None) -> np.ndarray:
    """Foliage chain on a black-on-white leaf silhouette: float 0..1, 1 = white."""
    cfg = cfg or EdgeConfig()
    img = np.asarray(silhouette, dtype=np.float32)
    size = img.shape[0]
    mask = (img < cfg.foliage_threshold).astype(np.float32)  # (a)
    if not mask.any():
        return np.ones_like(img)
    sigma = cfg.px(cfg.foliage_sigma_px, size)
    blurred = filters.gaussian(mask, sigma=sigma, mode="constant", cval=0.0) if sigma > 0 else mask
    blob = (blurred >= cfg.foliage_ramp).astype(np.float32)  # (c) ramp
    mag = sobel(blob, cfg.sobel_scale)  # (d)
    return np.clip(1.0 - mag, 0.0, 1.0).astype(np.float32)  # (e) invert


def combine(branches: np.ndarray, foliage: np.ndarray) -> np.ndarray:
    """Multiply the two chains and quantise: uint8, 255 = white."""
    return np.round(np.clip(branches * foliage, 0.0, 1.0) * 255.0).astype(np.uint8)
