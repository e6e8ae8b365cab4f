"""Sketch images for TSN: loading, the network's input preparation, and augmentation.

Images are read by the one sketch reader (``render.reader.read_sketch``).  ``preprocess``
prepares one exactly as in training: crop to the drawing (the reader's ink rule), pad to
a square with a white margin of :data:`MARGIN` of the side, area-resize to ``size`` and
scale to ``[0, 1]`` (1 = white).  A blank or all-dark page is refused with
``render.reader.SketchError``.

``augment(img, rng)`` imitates hand drawing on a ``uint8`` sketch: a small affine jitter
(rotation, anisotropic scale, shear), thicker or thinner strokes (grey erosion or
dilation), line breaks (small white gaps along the strokes) and, sometimes, a missing part
of the crown (a larger white patch in the upper part of the drawing).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from render.reader import INK_LEVEL, check_ink, ink_mask, read_sketch

MARGIN = 0.04  # white margin around the cropped drawing, fraction of the square side
DEFAULT_SIZE = 128


def crop_square(img: np.ndarray, margin: float = MARGIN) -> np.ndarray:
    """Crop to the drawing's bounding box and pad (white) to a centred square with a margin."""
    check_ink(img)
    ink = ink_mask(img)
    ys = np.flatnonzero(ink.any(axis=1))
    xs = np.flatnonzero(ink.any(axis=0))
    crop = img[ys[0] : ys[-1] + 1, xs[0] : xs[-1] + 1]
    h, w = crop.shape
    n = int(round(max(h, w) / (1 - 2 * margin)))
    n += (n - w) % 2  # equal margins left and right: a mirrored drawing gives the mirror
    out = np.full((n, n), 255, np.uint8)
    y0, x0 = (n - h) // 2, (n - w) // 2
    out[y0 : y0 + h, x0 : x0 + w] = crop
    return out


def preprocess(image: Any, size: int = DEFAULT_SIZE) -> np.ndarray:
    """Any image -> ``(size, size)`` float32 in [0, 1] (1 = white), as the network sees it."""
    from PIL import Image

    grey = read_sketch(image)
    sq = crop_square(grey)

    def box(a: np.ndarray) -> np.ndarray:
        im = Image.fromarray(np.ascontiguousarray(a), mode="L")
        return np.asarray(im.resize((size, size), Image.Resampling.BOX), dtype=np.float32)

    # Pillow's box filter is not mirror-symmetric at non-integer ratios; the mean of the
    # image's and its mirror's (mirrored back) is, so a mirrored drawing gives the mirror
    return (box(sq) + box(sq[:, ::-1])[:, ::-1]) / (2.0 * 255.0)


def augment(img: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A hand-drawn-looking variant of a ``uint8`` sketch (same size)."""
    from scipy import ndimage

    a = img.astype(np.float32)
    h, w = a.shape
    # small affine jitter about the centre
    ang = np.deg2rad(rng.uniform(-5, 5))
    sx, sy = rng.uniform(0.92, 1.08, size=2)
    sh = rng.uniform(-0.06, 0.06)
    rot = np.array([[np.cos(ang), -np.sin(ang)], [np.sin(ang), np.cos(ang)]])
    mat = rot @ np.array([[sy, sh], [0.0, sx]])
    inv = np.linalg.inv(mat)
    c = np.array([h / 2, w / 2])
    shift = rng.uniform(-0.03, 0.03, size=2) * np.array([h, w])
    offset = c - inv @ (c + shift)
    a = ndimage.affine_transform(a, inv, offset=offset, order=1, cval=255.0)
    # stroke thickness
    r = rng.random()
    if r < 0.3:
        a = ndimage.grey_erosion(a, size=(2, 2))  # thicker dark strokes
    elif r < 0.55:
        a = ndimage.grey_dilation(a, size=(2, 2))  # thinner strokes
    ink = np.argwhere(a < INK_LEVEL)
    if len(ink):
        # line breaks: small gaps along the strokes (one radius per image)
        if rng.random() < 0.6:
            n = int(rng.integers(5, 40))
            pts = ink[rng.integers(0, len(ink), n)]
            rr = int(round(rng.uniform(1.0, 3.0) * h / 256))
            gap = np.zeros((h, w), bool)
            gap[pts[:, 0], pts[:, 1]] = True
            dy, dx = np.mgrid[-rr : rr + 1, -rr : rr + 1]
            gap = ndimage.binary_dilation(gap, structure=dy**2 + dx**2 <= rr * rr + 0.5)
            a[gap] = 255.0
        # a missing part of the crown (upper 60% of the drawing)
        if rng.random() < 0.25:
            top, bottom = ink[:, 0].min(), ink[:, 0].max()
            upper = ink[ink[:, 0] <= top + 0.6 * (bottom - top)]
            if len(upper):
                py, px = upper[rng.integers(0, len(upper))]
                rr = rng.uniform(0.05, 0.12) * max(bottom - top, 1)
                yy, xx = np.ogrid[0:h, 0:w]
                a[(yy - py) ** 2 + (xx - px) ** 2 <= rr * rr] = 255.0
    out = np.clip(np.round(a), 0, 255).astype(np.uint8)
    if not (out < INK_LEVEL).any():  # never erase the whole drawing
        return img
    return out
