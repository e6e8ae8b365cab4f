"""The one sketch reader: every image that enters TreeSketch comes through :func:`read_sketch`.

``read_sketch(source)`` takes a path, bytes, a PIL image or an array (grey, RGB, RGBA, with
values 0..255 or 0..1) and gives an ``(H, W)`` ``uint8`` grey image, 255 = white:

1. **Limits before decoding.**  An encoded image's header is read first: its pixel count
   (at most :data:`MAX_PIXELS`), its sides (at least :data:`MIN_SIDE`) and its aspect ratio
   (at most :data:`MAX_ASPECT`) are checked before a single pixel is decoded, so a 109-byte
   PNG that declares 30000 x 30000 pixels or a 1 x 20000 strip is refused at once, with
   bounded memory (Pillow's decompression-bomb error is turned into the same message).
2. **Alpha flattened on white**, then **one grey formula** (ITU-R 601 luma, Pillow's "L").
3. **One ink rule** (:func:`ink_mask`): a pixel is ink when it is darker than
   :data:`INK_LEVEL`.  A page with (almost) no ink is refused as blank, a page that is
   mostly ink as all dark (:func:`check_ink`).

Every failure is a :class:`SketchError` (a ``ValueError``) whose message names what was
wrong in plain words: no object addresses, no class names of other libraries.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "INK_LEVEL",
    "MAX_ASPECT",
    "MAX_BYTES",
    "MAX_PIXELS",
    "MIN_SIDE",
    "SketchError",
    "check_ink",
    "ink_mask",
    "read_sketch",
]

MAX_BYTES = 10 * 1024 * 1024  # an encoded sketch larger than this is refused unread
MAX_PIXELS = 25_000_000  # 5000 x 5000: a phone photo fits, a bomb does not
MAX_ASPECT = 8.0  # a drawing of a tree is not a strip
MIN_SIDE = 8
INK_LEVEL = 200  # a pixel darker than this (0..255) is part of the drawing
MIN_INK = 2e-4  # fraction of ink pixels below which the page counts as blank
MAX_INK = 0.9  # fraction above which the page counts as all dark


class SketchError(ValueError):
    """The input is not a usable sketch (unreadable, too large, blank, all dark)."""


def _check_size(width: int, height: int) -> None:
    if width < MIN_SIDE or height < MIN_SIDE:
        raise SketchError(
            f"the image is {width} x {height} pixels; a sketch needs at least "
            f"{MIN_SIDE} x {MIN_SIDE}"
        )
    if width * height > MAX_PIXELS:
        raise SketchError(
            f"the image is {width} x {height} pixels, over the limit of {MAX_PIXELS:,} "
            "pixels; scale it down (1000 px across is plenty)"
        )
    aspect = max(width, height) / min(width, height)
    if aspect > MAX_ASPECT:
        raise SketchError(
            f"the image is {width} x {height} pixels (aspect ratio {aspect:.0f}:1); a sketch "
            f"must be at most {MAX_ASPECT:.0f} times longer than wide"
        )


def _open(data: bytes, what: str) -> Any:
    """Decode an encoded image after checking its declared size (header only first)."""
    from PIL import Image, UnidentifiedImageError

    if len(data) > MAX_BYTES:
        raise SketchError(f"{what} is {len(data):,} bytes, over the limit of {MAX_BYTES:,}")
    if not data:
        raise SketchError(f"{what} is empty")
    try:
        with Image.open(io.BytesIO(data)) as im:  # lazy: reads the header only
            _check_size(*im.size)
            im.load()
            return _flatten(im)
    except SketchError:
        raise
    except Image.DecompressionBombError:
        raise SketchError(f"{what} declares too many pixels to be a sketch") from None
    except UnidentifiedImageError:
        raise SketchError(f"{what} is not an image Pillow can read (PNG, JPEG, ...)") from None
    except (OSError, ValueError, SyntaxError, EOFError) as exc:
        raise SketchError(f"{what} is a damaged or truncated image ({_plain(exc)})") from None


def _plain(exc: BaseException) -> str:
    """An exception's message without object reprs like ``<_io.BytesIO object at 0x..>``."""
    import re

    text = re.sub(r"<[^<>]* at 0x[0-9a-fA-F]+>", "the data", str(exc))
    return text or type(exc).__name__


def _flatten(im: Any) -> np.ndarray:
    """A PIL image -> uint8 grey: alpha composited on white, then ITU-R 601 luma."""
    from PIL import Image

    if im.mode in ("RGBA", "LA", "PA", "La", "RGBa") or "transparency" in im.info:
        rgba = im.convert("RGBA")
        bg = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        bg.alpha_composite(rgba)
        im = bg
    elif im.mode in ("I", "I;16", "I;16B", "I;16L", "F"):
        a = np.asarray(im, dtype=np.float64)
        top = 65535.0 if a.max(initial=0) > 255 else 255.0
        return np.clip(np.round(a / top * 255.0), 0, 255).astype(np.uint8)
    return np.asarray(im.convert("L"), dtype=np.uint8)


def _from_array(source: Any) -> np.ndarray:
    try:
        a = np.asarray(source)
    except Exception:  # noqa: BLE001 - anything that is not array-like
        raise SketchError(f"cannot read a {type(source).__name__} as an image") from None
    if a.dtype == object or a.dtype.kind not in "biuf":
        raise SketchError(f"an image array must hold numbers, got {a.dtype}")
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (1, 3, 4))):
        raise SketchError(f"an image array must be (H, W), (H, W, 3) or (H, W, 4); got {a.shape}")
    _check_size(a.shape[1], a.shape[0])
    if a.dtype == np.uint8 and a.ndim == 2:
        return a.copy()
    f = a.astype(np.float32)
    if not np.isfinite(f).all():
        raise SketchError("the image holds NaN or infinite values")
    if a.dtype.kind == "f" and f.max(initial=0.0) <= 1.0:
        f = f * 255.0
    f = np.clip(f, 0.0, 255.0)
    if f.ndim == 3:
        if f.shape[2] == 4:
            alpha = f[..., 3:] / 255.0
            f = f[..., :3] * alpha + 255.0 * (1.0 - alpha)
        f = f[..., 0] if f.shape[2] == 1 else f[..., :3] @ np.array([0.299, 0.587, 0.114])
    return np.round(f).astype(np.uint8)


def read_sketch(source: Any) -> np.ndarray:
    """Any supported image -> ``(H, W)`` uint8 grey (255 = white); see the module text.

    Checks size and decoding only; :func:`check_ink` refuses blank and all-dark pages.
    """
    from PIL import Image

    if isinstance(source, str | os.PathLike):
        path = Path(source)
        if not path.is_file():
            raise SketchError(f"sketch file not found: {path}")
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise SketchError(f"{path} is {size:,} bytes, over the limit of {MAX_BYTES:,}")
        return _open(path.read_bytes(), str(path))
    if isinstance(source, bytes | bytearray | memoryview):
        return _open(bytes(source), "the uploaded sketch")
    if isinstance(source, Image.Image):
        _check_size(*source.size)
        try:
            source.load()
        except Image.DecompressionBombError:
            raise SketchError("the image declares too many pixels to be a sketch") from None
        return _flatten(source)
    return _from_array(source)


def ink_mask(img: np.ndarray) -> np.ndarray:
    """The one ink rule: pixels darker than :data:`INK_LEVEL`."""
    return np.asarray(img) < INK_LEVEL


def check_ink(img: np.ndarray) -> float:
    """Refuse blank and all-dark pages; returns the ink fraction."""
    ink = float(ink_mask(img).mean())
    if ink < MIN_INK:
        raise SketchError("the sketch is blank: draw a tree (dark lines on a light page)")
    if ink > MAX_INK:
        raise SketchError(
            f"the page is almost all dark ({ink:.0%} of it): draw dark lines on a light page"
        )
    return ink
