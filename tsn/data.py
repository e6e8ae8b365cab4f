"""Sketch images for TSN: loading, the network's input preparation, and augmentation.

``to_grey(image)`` accepts a path, a PIL image or an array of any size (grey, RGB, or RGBA
composited on white) and gives a ``uint8`` grey array (255 = white).  ``preprocess``
prepares it exactly as in training: crop to the drawing (pixels darker than
:data:`INK_LEVEL`), pad to a square with a white margin of :data:`MARGIN` of the side,
area-resize to ``size`` and scale to ``[0, 1]`` (1 = white).  A page with no drawing or
one that is all black is refused with :class:`SketchInputError`.

``augment(img, rng)`` imitates hand drawing on a ``uint8`` sketch: a small affine jitter
(rotation, anisotropic scale, shear), thicker or thinner strokes (grey erosion or
dilation), line breaks (small white gaps along the strokes) and, sometimes, a missing part
of the crown (a larger white patch in the upper part of the drawing).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

INK_LEVEL = 200  # a pixel darker than this is part of the drawing
MARGIN = 0.04  # white margin around the cropped drawing, fraction of the square side
MAX_BLACK_FRACTION = 0.9  # darker pages than this are refused as "all black"
DEFAULT_SIZE = 128


class SketchInputError(ValueError):
    """The input is not a usable sketch (not an image, empty page, all black)."""


def to_grey(image: Any) -> np.ndarray:
    """Path / PIL image / array (grey, RGB, RGBA) -> ``uint8`` grey (255 = white)."""
    from PIL import Image, UnidentifiedImageError

    if isinstance(image, str | os.PathLike):
        path = Path(image)
        if not path.is_file():
            raise SketchInputError(f"{path}: no such image file")
        try:
            with Image.open(path) as im:
                im.load()
                return to_grey(im)
        except (UnidentifiedImageError, OSError) as e:
            raise SketchInputError(f"{path}: not an image ({e})") from None
    if isinstance(image, Image.Image):
        im = image
        if im.mode in ("RGBA", "LA", "P", "PA") or "transparency" in im.info:
            rgba = im.convert("RGBA")
            bg = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
            bg.alpha_composite(rgba)
            im = bg
        return np.asarray(im.convert("L"), dtype=np.uint8)
    if isinstance(image, bytes | bytearray):
        import io

        try:
            with Image.open(io.BytesIO(image)) as im:
                im.load()
                return to_grey(im)
        except (UnidentifiedImageError, OSError) as e:
            raise SketchInputError(f"not an image ({e})") from None
    try:
        a = np.asarray(image)
    except Exception as e:  # noqa: BLE001 - anything that is not array-like
        raise SketchInputError(f"not an image: {type(image).__name__} ({e})") from None
    if a.dtype == object or a.dtype.kind not in "biuf":
        raise SketchInputError(f"not an image: array of {a.dtype} from {type(image).__name__}")
    if a.ndim == 3 and a.shape[2] in (1, 3, 4):
        pass
    elif a.ndim != 2:
        raise SketchInputError(
            f"not an image: expected (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}"
        )
    if a.size == 0 or min(a.shape[:2]) < 8:
        raise SketchInputError(f"image too small: shape {a.shape} (at least 8x8 pixels)")
    is_float = a.dtype.kind == "f"
    a = a.astype(np.float64)
    if not np.isfinite(a).all():
        raise SketchInputError("image contains NaN or infinity")
    if is_float and a.max() <= 1.0:  # float images in [0, 1]
        a = a * 255.0
    a = np.clip(a, 0, 255)
    if a.ndim == 3:
        if a.shape[2] == 4:
            alpha = a[..., 3:] / 255.0
            a = a[..., :3] * alpha + 255.0 * (1 - alpha)
        a = a[..., 0] if a.shape[2] == 1 else a[..., :3] @ np.array([0.299, 0.587, 0.114])
    return np.round(a).astype(np.uint8)


def check_sketch(img: np.ndarray) -> None:
    """Refuse empty (all white) and all-black pages."""
    dark = img < INK_LEVEL
    if not dark.any():
        raise SketchInputError("empty image: no drawing found (every pixel is white or near white)")
    if (img < 128).mean() > MAX_BLACK_FRACTION:
        raise SketchInputError(
            f"image is (almost) all black ({(img < 128).mean():.0%} dark pixels): not a line sketch"
        )


def crop_square(img: np.ndarray, margin: float = MARGIN) -> np.ndarray:
    """Crop to the drawing's bounding box and pad (white) to a centred square with a margin."""
    check_sketch(img)
    ys = np.flatnonzero((img < INK_LEVEL).any(axis=1))
    xs = np.flatnonzero((img < INK_LEVEL).any(axis=0))
    crop = img[ys[0] : ys[-1] + 1, xs[0] : xs[-1] + 1]
    h, w = crop.shape
    n = int(round(max(h, w) / (1 - 2 * margin)))
    out = np.full((n, n), 255, np.uint8)
    y0, x0 = (n - h) // 2, (n - w) // 2
    out[y0 : y0 + h, x0 : x0 + w] = crop
    return out


def preprocess(image: Any, size: int = DEFAULT_SIZE) -> np.ndarray:
    """Any image -> ``(size, size)`` float32 in [0, 1] (1 = white), as the network sees it."""
    from PIL import Image

    if isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.ndim == 2:
        grey = image
    else:
        grey = to_grey(image)
    sq = crop_square(grey)
    im = Image.fromarray(sq, mode="L").resize((size, size), Image.Resampling.BOX)
    return np.asarray(im, dtype=np.float32) / 255.0


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
