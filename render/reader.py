"""The one sketch reader: every image that enters TreeSketch comes through :func:`read_sketch`.

``read_sketch(source)`` takes a path, bytes, a PIL image or an array (grey, RGB, RGBA, with
values 0..255 or 0..1) and gives an ``(H, W)`` ``uint8`` grey image, 255 = white:

1. **Limits before decoding.**  An encoded image's format is recognised from its first
   bytes (:func:`image_format`): only the raster formats in :data:`FORMATS` are handed to
   Pillow, and only to that format's reader, so an EPS or PDF (which Pillow would give to
   Ghostscript) is refused unread.  Its header is read next: its pixel count
   (at most :data:`MAX_PIXELS`), its sides (at least :data:`MIN_SIDE`) and its aspect ratio
   (at most :data:`MAX_ASPECT`) are checked before a single pixel is decoded, so a 109-byte
   PNG that declares 30000 x 30000 pixels or a 1 x 20000 strip is refused at once, with
   bounded memory (Pillow's decompression-bomb error is turned into the same message).
2. **Upright**: a photo's EXIF orientation (a phone stores a portrait photo sideways and
   says so) is applied.
3. **Alpha flattened on white**, then **one grey formula** (ITU-R 601 luma, Pillow's "L");
   **one level rule** for every kind of pixel value (:func:`_levels`): booleans are black
   and white (False black, as in a 1-bit PNG), floats in 0..1 are fractions of white,
   wider values are 0..255, or 0..65535 when any is over 255 (a 16-bit PNG, scan or
   array), and NaN or infinite values are refused.
4. **One ink rule** (:func:`ink_mask`): a pixel is ink when it is darker than
   :data:`INK_LEVEL`.  A page with (almost) no ink is refused as blank, a page that is
   mostly ink as all dark (:func:`check_ink`).

Every failure is a :class:`SketchError` (a ``ValueError``) whose message names what was
wrong in plain words: no object addresses, no class names of other libraries.
"""

from __future__ import annotations

import io
import os
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from .distance import distance_to_background

__all__ = [
    "FORMATS",
    "INK_LEVEL",
    "MAX_ASPECT",
    "MAX_BYTES",
    "MAX_PIXELS",
    "MIN_SIDE",
    "FormatError",
    "SketchError",
    "check_ink",
    "drop_specks",
    "frame_ink",
    "image_format",
    "ink_mask",
    "light_on_dark",
    "line_spread",
    "read_sketch",
    "tree_ink",
    "crown_axis",
    "trunk_axis",
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


class FormatError(SketchError):
    """The input is a picture, but in a format that is not read (EPS, PDF, SVG, HEIC...)."""


# The raster formats a sketch may come in (Pillow's names), each recognised by its first
# bytes (https://www.garykessler.net/library/file_sigs.html) before Pillow sees the data:
# left to itself Pillow tries every plugin it has, EPS among them, which runs Ghostscript.
FORMATS = ("PNG", "JPEG", "WEBP", "GIF", "BMP", "TIFF")
_NAMES = "PNG, JPEG, WebP, GIF, BMP or TIFF"


def _raster(head: bytes) -> str | None:
    if head.startswith(b"\x89PNG\r\n\x1a\n"):
        return "PNG"
    if head.startswith(b"\xff\xd8\xff"):
        return "JPEG"
    if head[:4] == b"RIFF" and head[8:12] == b"WEBP":
        return "WEBP"
    if head[:6] in (b"GIF87a", b"GIF89a"):
        return "GIF"
    if head[:2] == b"BM":
        return "BMP"
    if head[:4] in (b"II*\x00", b"MM\x00*"):
        return "TIFF"
    return None


def _other(head: bytes) -> str | None:
    """The name of a known picture or document format that is not read, for the message."""
    text = head.lstrip(b"\xef\xbb\xbf \t\r\n").lower()
    if head.startswith((b"%!PS", b"\xc5\xd0\xd3\xc6")):
        return "PostScript (EPS)"
    if head.startswith(b"%PDF"):
        return "PDF"
    if text.startswith((b"<svg", b"<?xml")) and b"<svg" in text:
        return "SVG"
    if head[4:8] == b"ftyp" and head[8:12] in (b"heic", b"heix", b"mif1", b"msf1", b"hevc"):
        return "HEIC (a phone's 'high efficiency' photo)"
    if head[4:8] == b"ftyp" and head[8:12] in (b"avif", b"avis"):
        return "AVIF"
    if head.startswith(b"8BPS"):
        return "Photoshop (PSD)"
    return None


def image_format(data: bytes, what: str = "the image") -> str:
    """The format (a name in :data:`FORMATS`) of encoded image ``data``, from its first
    bytes alone; :class:`FormatError` for a known format that is not read, SketchError for
    anything else."""
    head = bytes(data[:64])
    fmt = _raster(head)
    if fmt is not None:
        return fmt
    other = _other(head)
    if other is not None:
        raise FormatError(
            f"{what} is {other}, not a raster picture; send a {_NAMES} image "
            "(export or save it as PNG or JPEG)"
        )
    raise SketchError(f"{what} is not an image in a format read here ({_NAMES})")


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
    fmt = image_format(data, what)
    try:
        # only the one reader the first bytes name (lazy: reads the header only); Pillow's
        # warnings about the file (a damaged EXIF block) would only be noise on stderr
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with Image.open(io.BytesIO(data), formats=[fmt]) as im:
                _check_size(*im.size)
                im.load()
                return _upright(_flatten(im), _orientation(im))
    except SketchError:
        raise
    except Image.DecompressionBombError:
        raise SketchError(f"{what} declares too many pixels to be a sketch") from None
    except UnidentifiedImageError:
        raise SketchError(f"{what} is a damaged {fmt} image (its header is not valid)") from None
    except (OSError, ValueError, SyntaxError, EOFError) as exc:
        raise SketchError(f"{what} is a damaged or truncated image ({_plain(exc)})") from None


def _plain(exc: BaseException) -> str:
    """An exception's message without object reprs like ``<_io.BytesIO object at 0x..>``."""
    import re

    text = re.sub(r"<[^<>]* at 0x[0-9a-fA-F]+>", "the data", str(exc))
    return text or type(exc).__name__


EXIF_ORIENTATION = 0x0112


def _orientation(im: Any) -> int:
    """The EXIF orientation (1..8) a picture says it is stored in; 1 (as stored) when it
    says nothing or its EXIF block is damaged: the picture is still worth reading."""
    try:
        with warnings.catch_warnings():  # Pillow warns of a damaged block on stderr
            warnings.simplefilter("ignore")
            value = int(im.getexif().get(EXIF_ORIENTATION, 1))
    except Exception:  # noqa: BLE001 - any damage inside the EXIF block
        return 1
    return value if 1 <= value <= 8 else 1


def _upright(g: np.ndarray, orientation: int) -> np.ndarray:
    """A grey image stored with EXIF ``orientation``, turned the way it was taken (the
    same turns as Pillow's ``ImageOps.exif_transpose``)."""
    if orientation in (5, 6, 7, 8):  # stored on its side: a quarter turn (and a mirror)
        g = {5: g.T, 6: np.rot90(g, -1), 7: g.T[::-1, ::-1], 8: np.rot90(g, 1)}[orientation]
    elif orientation in (2, 3, 4):
        g = {2: g[:, ::-1], 3: g[::-1, ::-1], 4: g[::-1]}[orientation]
    return np.ascontiguousarray(g)


def _levels(a: np.ndarray) -> np.ndarray:
    """Pixel values of any numeric type -> float32 0..255 (255 = white), one rule for
    arrays and decoded images alike: booleans black (False) and white (True), as in a
    1-bit PNG; floats all within 0..1 are fractions of white; other values are 0..255, or
    0..65535 when any is over 255 (16 bits: a 16-bit PNG, a scan, a uint16 array).
    NaN and infinite values are refused."""
    if a.dtype == np.bool_:
        return a.astype(np.float32) * 255.0
    if a.dtype == np.uint8:
        return a.astype(np.float32)
    if a.dtype.kind == "f" and not np.isfinite(a).all():
        raise SketchError(
            "the image holds NaN or infinite values; a sketch's pixels are numbers from "
            "black to white"
        )
    top = float(a.max(initial=0))
    if a.dtype.kind == "f" and top <= 1.0:
        scale = 255.0
    elif top > 255.0:
        scale = 255.0 / 65535.0
    else:
        scale = 1.0
    return np.clip(a.astype(np.float32) * np.float32(scale), 0.0, 255.0)


def _flatten(im: Any) -> np.ndarray:
    """A PIL image -> uint8 grey: alpha composited on white, then ITU-R 601 luma."""
    from PIL import Image

    if im.mode in ("RGBA", "LA", "PA", "La", "RGBa") or "transparency" in im.info:
        rgba = im.convert("RGBA")
        bg = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        bg.alpha_composite(rgba)
        im = bg
    elif im.mode in ("I", "I;16", "I;16B", "I;16L", "F"):
        return np.round(_levels(np.asarray(im))).astype(np.uint8)
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
    f = _levels(a)
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
        # an image opened by the caller: Pillow chose its reader, so refuse the formats
        # not read here before loading (an EPS would run Ghostscript)
        if source.format is not None and source.format not in (*FORMATS, "MPO"):
            raise FormatError(
                f"the image is {source.format}, not one of the formats read: {_NAMES}"
            )
        _check_size(*source.size)
        try:
            source.load()
        except Image.DecompressionBombError:
            raise SketchError("the image declares too many pixels to be a sketch") from None
        return _upright(_flatten(source), _orientation(source))
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


# --------------------------------------------------------------------------- normalising
# Where the renderer puts a tree's sketch in its square frame (measured on SG sketches of
# every species, `tests/test_reader.py` checks it): the trunk base's ink ends at FRAME_BOTTOM
# of the side, the trunk axis is the vertical centre line, and the drawing reaches up to
# FRAME_EDGE from the top or sideways to FRAME_EDGE from an edge, whichever comes first.
FRAME_BOTTOM = 0.969
FRAME_EDGE = 0.043
WORK_SIDE = 512  # drawings are normalised at most this large (bounded time and memory)
DRAWING_SIDE = 256  # the side of a normalised drawing (the dataset's sketch size)
MIN_PAPER = 0.25  # paper darker than this (fraction of white) is refused as a dark page
INK_CONTRAST = 0.85  # ink is at most this bright relative to the paper around it


def flatten_paper(img: np.ndarray) -> np.ndarray:
    """Grey ``uint8`` -> float 0..1 relative to the paper around each pixel (1 = paper).

    The paper's brightness is estimated with a maximum filter wider than any stroke (so
    strokes vanish from it) and smoothed; dividing by it removes uneven light, grey or
    off-white paper and the vignetting of phone photos.  A page whose paper is darker than
    :data:`MIN_PAPER` is refused.
    """
    from PIL import Image
    from scipy import ndimage

    g = np.asarray(img, dtype=np.uint8)
    h, w = g.shape
    k = max(5, int(round(max(h, w) / 24)) | 1)
    # the paper is smooth on the scale of k: estimate it on blocks' maxima (a block is at
    # most k/4 wide, so a stroke still vanishes) and resize back, ~b^2 times less work
    b = max(1, k // 4)
    hb, wb = -(-h // b), -(-w // b)
    padded = np.pad(g, ((0, hb * b - h), (0, wb * b - w)), mode="edge")
    blocks = padded.reshape(hb, b, wb, b).max(axis=3).max(axis=1).astype(np.float32) / 255.0
    kb = max(3, int(round(k / b)) | 1)
    small = ndimage.maximum_filter(blocks, size=kb, mode="nearest")
    small = ndimage.uniform_filter(small, size=kb, mode="nearest")
    level = float(np.median(small))
    if level < MIN_PAPER and float(np.percentile(blocks, 95)) > 2 * MIN_PAPER:
        # light paper shows at the edges, but most of the page is one dark area
        raise SketchError(
            "the drawing is a dark filled area over most of the page: draw the tree with "
            "lines (its crown's outline, trunk and branches), not a fill"
        )
    if level < MIN_PAPER:
        raise SketchError(
            f"the page is too dark (paper at {level:.0%} of white): draw or photograph dark "
            "lines on light paper, in good light"
        )
    if b > 1:
        up = Image.fromarray(small, mode="F").resize((wb * b, hb * b), Image.Resampling.BILINEAR)
        paper = np.asarray(up, dtype=np.float32)[:h, :w]
    else:
        paper = small
    f = g.astype(np.float32) / 255.0
    return np.clip(f / np.maximum(paper, MIN_PAPER / 2), 0.0, 1.0)


GRAIN_SIGMAS = 4.0  # ink is darker than the paper by this many of its grain's deviations
GRAIN_EDGE_SIGMAS = 2.0  # ... in places, and everywhere by this many (a stroke's edges)
# a second, lighter pen (see _second_pen): PEN_SHARE of the marks lighter than Otsu's split
# within PEN_LEVELS grey levels of one level, at least PEN_PIXELS of them, its lines no
# wider than PEN_WIDTH of the page's longer side
PEN_SHARE = 0.5
PEN_LEVELS = 2
PEN_PIXELS = 50
PEN_WIDTH = 0.02
PEN_APART = 3


def _paper_grain(counts: np.ndarray, split: float) -> tuple[float, float]:
    """The paper's level and its grain's robust standard deviation (0..255 units) from a
    page's 256-bin histogram, measured on the paper side of ``split`` (0..1) only, since
    the ink may be most of a page; (255, 0) when nothing is on that side."""
    side = counts.copy()
    side[: int(np.ceil(split * 255.0))] = 0
    cum = np.cumsum(side)
    if cum[-1] == 0:
        return 255.0, 0.0
    paper = int(np.searchsorted(cum, cum[-1] / 2))
    spread = np.bincount(np.abs(np.arange(256) - paper), weights=side, minlength=256)
    mad = int(np.searchsorted(np.cumsum(spread), cum[-1] / 2))
    return float(paper), 1.4826 * mad


def _ink_of(flat: np.ndarray) -> np.ndarray:
    """Ink pixels of a flattened page: darker than Otsu's split, than INK_CONTRAST and
    than the paper's grain reaches (``GRAIN_SIGMAS``), without isolated specks (paper
    grain, sensor noise)."""
    from scipy import ndimage
    from skimage.filters import threshold_otsu

    dark = flat < INK_CONTRAST
    if not dark.any():
        return dark
    # Otsu on a 256-bin histogram counted with bincount (np.histogram on floats is slow)
    levels = np.round(flat * 255.0).astype(np.uint8)
    counts = np.bincount(levels.ravel(), minlength=256)
    if np.count_nonzero(counts) > 1:
        t = min(INK_CONTRAST, float(threshold_otsu(hist=(counts, np.arange(256) / 255.0))))
    else:
        t = INK_CONTRAST
    ink = flat < max(t, 0.5)
    if not ink.any():
        # a page of two levels (a grey pen in a paint program, no smoothing): Otsu's
        # split is the pen's own level, the dark class's brightest (skimage's convention).
        # Only then: on a smoothed page the split's level is the strokes' soft edge,
        # which the strict rule leaves out (counting it moved examples/hand/corner.png)
        ink = flat <= t
    # on grainy paper with few, light strokes Otsu splits the grain itself: a mark is ink
    # only where some of it is darker than the paper's grain reaches, and each of its
    # pixels clears the grain's usual spread (hysteresis: grain on its own goes, strokes
    # keep their lighter edges); a clean page has no grain, so nothing changes there
    paper, sigma = _paper_grain(counts, max(t, 0.5))
    sure = flat < (paper - GRAIN_SIGMAS * sigma) / 255.0
    if not (ink <= sure).all():
        ink &= flat < (paper - GRAIN_EDGE_SIGMAS * sigma) / 255.0
        lab, n = ndimage.label(ink, structure=np.ones((3, 3), bool))
        seeded = np.zeros(n + 1, bool)
        seeded[np.unique(lab[sure & ink])] = True
        seeded[0] = False
        ink = seeded[lab]
    return _without_dust(ink | _second_pen(levels, dark & sure & ~ink, ink))


def _second_pen(levels: np.ndarray, light: np.ndarray, ink: np.ndarray) -> np.ndarray:
    """The lines of a second, lighter pen among the marks Otsu's split left out
    (``light``, ``levels`` the page's grey levels) beside the ``ink``: a yellow-green
    crown over a brown trunk, two greys in a paint program.  A pen lays one level: at
    least ``PEN_SHARE`` of those marks' pixels within ``PEN_LEVELS`` of one level (a
    blurred upscale's or a photo's shading spreads over many).  Only its lines, no wider
    than ``PEN_WIDTH`` of the page's longer side (a crown coloured in is the drawing's
    fill, not its outline), and most of each line more than ``PEN_APART`` pixels from the
    ink (a stroke's smoothed edge, however even its level, hugs its stroke); not a lined
    page's rules (``RULED_ROW``)."""
    from scipy import ndimage

    n = int(light.sum())
    if n < PEN_PIXELS:
        return np.zeros_like(light)
    counts = np.bincount(levels[light], minlength=256)
    window = np.convolve(counts, np.ones(2 * PEN_LEVELS + 1), mode="same")
    peak = int(np.argmax(window))
    if window[peak] < PEN_SHARE * n:
        return np.zeros_like(light)
    pen = light & (np.abs(levels.astype(np.int16) - peak) <= PEN_LEVELS)
    lab, k = ndimage.label(pen, structure=np.ones((3, 3), bool))
    if k == 0:
        return pen
    ids = np.arange(1, k + 1)
    widest = np.asarray(ndimage.maximum(distance_to_background(pen), lab, ids))
    apart = distance_to_background(~ink) > PEN_APART if ink.any() else np.ones_like(ink)
    share = np.asarray(ndimage.mean(apart, lab, ids))
    keep = (widest <= PEN_WIDTH * max(pen.shape) / 2) & (share >= 0.5)
    # a lined page's rules and margin are printed in one level too (cut into pieces where
    # the drawing crosses them): what lies in the rows or columns the level fills across
    # the page (as :func:`_drop_ruled_lines` finds them) stays paper
    ruled = _rows_across(pen, RULED_ROW)[:, None] | _rows_across(pen.T, RULED_COLUMN)[None, :]
    keep &= np.asarray(ndimage.mean(ruled, lab, ids)) < 0.5
    return np.concatenate([[False], keep])[lab]


def _without_dust(ink: np.ndarray) -> np.ndarray:
    """``ink`` without marks too small to be drawn (a pixel or two at any page size;
    marks joined side to side, as ``remove_small_objects`` joins them)."""
    from skimage.morphology import remove_small_objects

    min_px = max(2, int(round(ink.size * 2e-5)))
    if min_px > 2:
        return remove_small_objects(ink, max_size=min_px - 1)
    # a page under 75,000 pixels (the refinement's 256 px sketches): only lone pixels
    # go, found from their four neighbours at a twentieth of labelling's cost
    alone = ink.copy()
    alone[1:] &= ~ink[:-1]
    alone[:-1] &= ~ink[1:]
    alone[:, 1:] &= ~ink[:, :-1]
    alone[:, :-1] &= ~ink[:, 1:]
    return ink & ~alone


TWO_LEVEL_INK = 0.35  # see _page_ink
# light lines on a dark page (chalk on a board, a drawing app in dark mode) are read as the
# same lines dark on light: the page's border at least DARK_BORDER dark (under
# DARK_LEVEL), its light pixels (over LIGHT_LEVEL) between a trace and LIGHT_LINES of it
DARK_LEVEL = 96
LIGHT_LEVEL = 160
DARK_BORDER = 0.9
LIGHT_LINES = 0.3
LIGHT_FILL = 0.5  # the light marks cover at most this share of the box they span ...
LIGHT_REACH = 0.1  # ... and the longest reaches this share of the page's longer side


def light_on_dark(page: np.ndarray) -> bool:
    """Whether a grey ``uint8`` page is light lines drawn on a dark ground: its border
    dark, the rest mostly dark, a small share of it light, in marks that leave most of
    their box dark and of which one runs on.  Read inverted, the lines are ink on paper.
    A dark page without light lines (an unlit photo, a night photo's lights and lit
    windows) and a dark fill on light paper (whose border is light) are not, and stay
    refused by :func:`flatten_paper`."""
    a = np.asarray(page)
    edge = max(1, min(a.shape) // 50)
    border = np.concatenate(
        [a[:edge].ravel(), a[-edge:].ravel(), a[:, :edge].ravel(), a[:, -edge:].ravel()]
    )
    if float((border < DARK_LEVEL).mean()) < DARK_BORDER:
        return False
    light = a > LIGHT_LEVEL
    share = float(light.mean())
    if not (MIN_INK <= share <= LIGHT_LINES and float((a < DARK_LEVEL).mean()) >= 1 - LIGHT_LINES):
        return False
    # drawn lines: leaving most of the box they span dark (a lit window in a night photo
    # fills its box) and running on (street lights and stars are dots); such a photo
    # stays refused as too dark
    from scipy import ndimage

    ys, xs = np.flatnonzero(light.any(axis=1)), np.flatnonzero(light.any(axis=0))
    if light.sum() > LIGHT_FILL * (ys[-1] + 1 - ys[0]) * (xs[-1] + 1 - xs[0]):
        return False
    side = max(a.shape)
    lab, _ = ndimage.label(light, structure=np.ones((3, 3), bool))
    reach = max(max(s.stop - s.start for s in box) for box in ndimage.find_objects(lab))
    return reach >= LIGHT_REACH * side


def _dark_on_light(page: np.ndarray) -> np.ndarray:
    """The page with a picture of light lines on a dark ground (:func:`light_on_dark`)
    turned dark on light; the picture judged within the page's white margins (the web
    page's pad puts a picture of another shape on white, centred)."""
    marked = page < 250
    rows = np.flatnonzero(marked.any(axis=1))
    if rows.size == 0:
        return page
    cols = np.flatnonzero(marked.any(axis=0))
    box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    if not light_on_dark(page[box]):
        return page
    out = np.full_like(page, 255)
    out[box] = 255 - page[box]
    return out


def _page_ink(page: np.ndarray) -> np.ndarray:
    """The ink of a page (grey ``uint8``): :func:`_ink_of` its :func:`flatten_paper`.

    A page of pure black and white (a sketch the renderer made, a drawing a program
    saved without smoothing) has no paper to flatten and no grain: its ink is its black,
    less dust, unless :func:`flatten_paper` would refuse it as dark paper.  That takes
    half the page's blocks black all through (a block with a white pixel sets the paper
    white over every window it is in, its own included), so a page under ``TWO_LEVEL_INK``
    black is read straight (the margin: a page's last blocks, padded, hold fewer of its
    pixels, under a tenth of the blocks at any allowed aspect).  The
    refinement frames every candidate tree's sketch, such a page, through here.
    """
    black = page == 0
    if np.all(black | (page == 255)) and float(black.mean()) < TWO_LEVEL_INK:
        return _without_dust(black)
    return _ink_of(flatten_paper(page))


SPECK_WIDTHS = 1.5  # a mark smaller than a square this many stroke widths wide ...
SPECK_GAP = 3.0  # ... and further than this many stroke widths from the strokes is grain


def stroke_width(ink: np.ndarray) -> float:
    """The drawing's typical stroke width in pixels: twice the median distance from the
    centre line of its strokes to their edge (at least 1)."""
    from skimage.morphology import skeletonize

    if not ink.any():
        return 1.0
    inside = distance_to_background(ink)
    return max(1.0, 2.0 * float(np.median(inside[skeletonize(ink)])))


def line_spread(ink: np.ndarray) -> float:
    """How far the ink spreads across its longest axis, over its reach along it: about
    0.005 for a straight line drawn by hand (a stick with a dot on it as well), at least
    0.08 for people's drawings of trees (``treesketch.pipeline.LINE_SPREAD``); 1 for
    fewer than two ink pixels."""
    ys, xs = np.nonzero(ink)
    if ys.size < 2:
        return 1.0
    pts = np.stack([ys, xs], axis=1).astype(np.float64)
    pts -= pts.mean(axis=0)
    values, vectors = np.linalg.eigh(pts.T @ pts / len(pts))
    along = pts @ vectors[:, 1]
    return float(np.sqrt(max(values[0], 0.0)) / (along.max() - along.min() + 1.0))


def straight_share(ink: np.ndarray, lines: int = 2) -> float:
    """The share of the ink's centre line (its skeleton) within reach of its ``lines``
    strongest straight lines (Hough peaks; within 2 % of the ink's reach and a pixel):
    1 for a cross, a plus, an X, a T or a V drawn with two strokes; at most 0.78 for
    people's held-out drawings of trees but for one single stroke, 0.13-0.44 for
    ``examples/hand`` (``treesketch.pipeline.STRAIGHT_SHARE``); 1 for fewer than two ink
    pixels."""
    from skimage.morphology import skeletonize
    from skimage.transform import hough_line, hough_line_peaks

    centre = skeletonize(ink)
    ys, xs = np.nonzero(centre)
    if ys.size < 2:
        return 1.0
    accumulator, angles, offsets = hough_line(centre, theta=_HOUGH_ANGLES)
    _, angles, offsets = hough_line_peaks(
        accumulator, angles, offsets, num_peaks=lines, threshold=0
    )
    reach = max(ys.max() - ys.min(), xs.max() - xs.min()) + 1
    near = np.zeros(ys.size, bool)
    for a, r in zip(angles, offsets, strict=True):
        near |= np.abs(xs * np.cos(a) + ys * np.sin(a) - r) <= 0.02 * reach + 1.0
    return float(near.mean())


_HOUGH_ANGLES = np.linspace(-np.pi / 2, np.pi / 2, 360, endpoint=False)  # every half degree


def drop_specks(ink: np.ndarray) -> np.ndarray:
    """Ink without paper grain and pencil dust among the drawing's lines (which
    :func:`_drop_extras` keeps, being near them): marks smaller than a square
    ``SPECK_WIDTHS`` stroke widths wide that lie more than ``SPECK_GAP`` stroke widths
    from every larger mark.  Both limits follow the drawing's own stroke width, so they
    hold at any resolution; a dash of a broken line is longer than that, and the small
    marks a drawing's own strokes leave (a leaf, a twig's end) touch or nearly touch
    them."""
    if not ink.any():
        return ink
    # the work on the ink's bounding box (a margin of one pixel): every distance measured
    # here runs between two of its pixels, and a drawing is often a small part of its page
    ys, xs = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    box = (slice(max(ys[0] - 1, 0), ys[-1] + 2), slice(max(xs[0] - 1, 0), xs[-1] + 2))
    out = np.zeros_like(ink)
    out[box] = _kept_marks(ink[box])
    return out


def _kept_marks(ink: np.ndarray) -> np.ndarray:
    from scipy import ndimage

    lab, n = ndimage.label(ink, structure=np.ones((3, 3), bool))
    if n <= 1:
        return ink
    idx = np.arange(1, n + 1)
    area = ndimage.sum_labels(ink, lab, index=idx)
    width = stroke_width(ink)
    small = area < (SPECK_WIDTHS * width) ** 2
    small[int(np.argmax(area))] = False  # the drawing itself, however thin
    if not small.any():
        return ink
    big = ink & ~np.concatenate([[False], small])[lab]
    gap = distance_to_background(~big)
    # each mark's nearest pixel's gap (ndimage.minimum sorts every pixel by label first)
    nearest = np.full(n + 1, np.inf)
    on = lab > 0
    np.minimum.at(nearest, lab[on], gap[on])
    keep = np.concatenate([[False], ~small | (nearest[1:] <= SPECK_GAP * width)])
    return keep[lab]


STRAY_GAP = 0.08  # of the page's longer side: ink this far from the drawing is apart
STRAY_SHARE = 0.02  # a part apart from the drawing with less of its ink than this is dust
# The tree among the parts: of the large ones (a box or ink at least EXTRA_SHARE of the
# largest's: a small tree drawn with a fine pen may hold less ink than a cloud, a sun with
# rays may have as large a box) and not thin lines (a ground line, a cloud's base), the one
# reaching lowest: a tree stands on the ground, a sun or a cloud is in the sky.  A part
# apart from the tree, mostly beside it (EXTRA_BESIDE of its width outside the tree's
# columns at least) and smaller than EXTRA_SHARE of the tree in box or in ink, or wholly
# above the tree's top, is not the tree: a sun, a cloud, grass or a scribble.  A part
# above or below the tree (a crown drawn apart from its trunk, a pot, a cloud over the
# crown) is kept, and so is one as large as the tree beside it: when in doubt the ink
# stays
EXTRA_BESIDE = 0.5
EXTRA_SHARE = 0.5
LINE_ASPECT = 0.25  # a part or a run no taller than this share of its width is a line


def _parts(ink: np.ndarray) -> tuple[np.ndarray, int]:
    """The drawing's parts: ink joined over gaps up to ``STRAY_GAP`` of the page, so a
    tree drawn in separate strokes stays one part.  Returns a label per pixel (0 off the
    ink) and the count.  The joining runs on a coarse grid (blocks of half the gap), so
    it costs little at any page size."""
    from scipy import ndimage

    r = max(1, int(round(STRAY_GAP * max(ink.shape) / 2)))
    h, w = ink.shape
    hb, wb = -(-h // r), -(-w // r)
    padded = np.pad(ink, ((0, hb * r - h), (0, wb * r - w)))
    counts = padded.reshape(hb, r, wb, r).sum(axis=(1, 3))
    near = ndimage.binary_dilation(counts > 0, structure=np.ones((3, 3), bool))
    lab, n = ndimage.label(near)
    pixels = np.repeat(np.repeat(lab, r, axis=0), r, axis=1)[:h, :w]
    return np.where(ink, pixels, 0), n


def _beside(box: tuple[slice, slice], tree: tuple[slice, slice]) -> bool:
    """Whether a part's bounding box lies mostly beside the tree's (in columns the tree
    does not reach), rather than above or below it."""
    left, right = box[1].start, box[1].stop
    inside = max(0, min(right, tree[1].stop) - max(left, tree[1].start))
    return inside < (1.0 - EXTRA_BESIDE) * (right - left)


def _the_tree(ink: np.ndarray, boxes: list[tuple[slice, slice]]) -> int:
    """Which of the parts (their ink counts and bounding boxes) is the tree: see
    ``EXTRA_SHARE``."""
    height = np.array([b[0].stop - b[0].start for b in boxes])
    width = np.array([b[1].stop - b[1].start for b in boxes])
    area = height * width
    large = (area >= EXTRA_SHARE * area.max()) | (ink >= EXTRA_SHARE * ink.max())
    if (large & (height > LINE_ASPECT * width)).any():
        large &= height > LINE_ASPECT * width
    bottom = np.array([b[0].stop for b in boxes])
    return int(np.lexsort((area, bottom, large))[-1])


def _drop_extras(ink: np.ndarray) -> np.ndarray:
    """Ink without what is not the tree (see ``EXTRA_SHARE``): a part apart from the tree
    (further than ``STRAY_GAP`` of the page) goes when it holds less than ``STRAY_SHARE``
    of the ink (pencil dust, a smudge, a speck of dirt in a photo), or when it is a small
    part beside the tree or one beside it in the sky (a sun, a cloud, grass, a scribble
    in a corner).  Either would stretch the frame and shrink the tree into a corner of
    it."""
    from scipy import ndimage

    total = int(ink.sum())
    if total == 0:
        return ink
    lab, n = _parts(ink)
    if n <= 1:
        return ink
    count = ndimage.sum_labels(ink, lab, index=np.arange(1, n + 1))
    boxes = ndimage.find_objects(lab)
    area = np.array([(b[0].stop - b[0].start) * (b[1].stop - b[1].start) for b in boxes])
    tree = _the_tree(count, boxes)
    small = (area < EXTRA_SHARE * area[tree]) | (count < EXTRA_SHARE * count[tree])
    # wholly above the tree's top: in the sky, however large (a sun with its rays)
    sky = np.array([b[0].stop <= boxes[tree][0].start for b in boxes])
    keep = count >= STRAY_SHARE * total
    for k, box in enumerate(boxes):
        if k != tree and (small[k] | sky[k]):
            keep[k] &= not _beside(box, boxes[tree])
    keep[tree] = True
    return ink & np.concatenate([[False], keep])[lab]


# A ground line: a long, thin, nearly level stroke in the lower half of the drawing that
# sticks out sideways beyond the tree above it (by GROUND_OUT of the tree's width) or
# beyond its foot (by GROUND_FOOT_OUT of the foot's width: the tree's ink within
# GROUND_FOOT of the drawing's height above the line).  A crown's or a fir tier's flat
# base, a pot's or a closed trunk's bottom never sticks out of the sides drawn just above
# it; a ground line sticks out of the trunk's foot, however wide the crown above it
# (people draw the ground no wider than the crown: against the tree alone, 13 of 143
# held-out people's drawings kept theirs; RESULTS.md, "The tree follows the drawing")
GROUND_RUN = 0.25  # of the drawing's width: the shortest level run a ground line has
GROUND_TILT = 0.012  # of the page's longer side: the rise and wobble a level line may have
GROUND_OUT = 0.15  # of the tree's width it sticks out on one side (0.1 took a fir tier's base)
GROUND_FOOT = 0.15  # of the drawing's height: the rows above the line its foot is read in
GROUND_FOOT_OUT = 0.3  # of the foot's width (a flared foot's curls stick out a quarter)
GROUND_GRASS = 0.04  # of the drawing's height: grass and a trunk's foot just above the line
GROUND_TUFT = 0.12  # of the drawing's height: a tuft of grass on the line is no taller
# ... and the tree ends on it: below it no more ink than this share of the drawing's height
# (the trunk below a pine's lowest whorl or a crown's flat base, the body of a bonsai's pot
# below its rim; roots drawn below the ground keep the line too)
GROUND_BELOW = 0.05
# ... unless that ink is short (GROUND_ROOTS), spreads wider than the trunk on the line
# (GROUND_ROOTS_SPREAD) and the line runs on past it, on one side at least, by this share
# of its width: roots drawn under the ground, a trunk's foot drawn in front of a horizon,
# are narrower than the ground they stand on; a pot's rim overhangs its body by a lip only
GROUND_PAST_BELOW = 0.3
GROUND_ROOTS = 0.3  # of the drawing's height: roots below the line reach no further
GROUND_ROOTS_SPREAD = 1.5  # of the trunk's width on the line: roots spread at least so wide


def _level_runs(ink: np.ndarray, tilt: int, length: float) -> np.ndarray:
    """Nearly level strokes: the ink widened up and down by ``tilt`` rows (a hand's
    wobble and a slight slope), kept where it runs on unbroken for ``length`` pixels."""
    from scipy import ndimage

    band = ndimage.maximum_filter1d(ink.view(np.uint8), 2 * tilt + 1, axis=0) > 0
    out = np.zeros_like(band)
    rows = np.flatnonzero(band.sum(axis=1) >= length)  # the only rows that may hold one
    if rows.size == 0:
        return out
    # each pixel's run: from the last gap before it to the first gap after it, per row
    b = band[rows]
    at = np.arange(b.shape[1], dtype=np.int32)
    before = np.maximum.accumulate(np.where(b, -1, at), axis=1)
    after = np.minimum.accumulate(np.where(b, b.shape[1], at)[:, ::-1], axis=1)[:, ::-1]
    out[rows] = b & (after - before - 1 >= length)
    return out


def _ground_span(
    ink: np.ndarray, box: tuple[slice, slice], tilt: int, tall: float | None = None
) -> slice | None:
    """Where a level run with bounding box ``box`` is a ground line under the tree (thin,
    in the lower half of the drawing, at its foot and sticking out beyond what stands on
    it or beyond its foot, see ``GROUND_FOOT``), the columns outside which it goes; None
    when it is none.  Next to nothing below it: every column; the tree's roots or foot
    going on below it (``GROUND_PAST_BELOW``): the columns outside theirs.  ``tall``:
    the tallest it may be, a share of the drawing's height (by default a line's
    ``LINE_ASPECT`` of its width)."""
    ys = np.flatnonzero(ink.any(axis=1))
    top, height = int(ys[0]), int(ys[-1] - ys[0] + 1)
    (t, b), (left, right) = (box[0].start, box[0].stop), (box[1].start, box[1].stop)
    thin = b - t <= (LINE_ASPECT * (right - left) if tall is None else tall * height)
    if (t + b) / 2 < top + height / 2 or not thin:
        return None
    standing = _standing(ink[: max(0, t - int(round(GROUND_GRASS * height)))], height)
    if standing is None:  # nothing stands on it
        return None
    foot_rows = max(1, int(round(GROUND_FOOT * height)))
    foot = np.flatnonzero(standing[-foot_rows:].any(axis=0))
    cols = np.flatnonzero(standing.any(axis=0))
    if not (
        _sticks_out(left, right, cols, GROUND_OUT, tilt)
        or (foot.size and _sticks_out(left, right, foot, GROUND_FOOT_OUT, tilt))
    ):
        return None
    # under the tree, not under the line's own ends (a mound's sides go down there)
    under = ink[b + tilt :, cols[0] : cols[-1] + 1]
    below = np.flatnonzero(under.any(axis=1))
    if not below.size or below[-1] + 1 <= GROUND_BELOW * height:
        return slice(0, 0)
    # a trunk, a pot goes on.  Roots or a foot drawn past a ground line are short, a
    # trunk under a crown's or a tier's base is often longer; a pot's rim overhangs its
    # body by a lip (its sides go down from the rim's ends, under no crown when the tree
    # leans out of it)
    if below[-1] + 1 > GROUND_ROOTS * height:
        return None
    # ... and spread wider than the trunk stands on the line (a fir's trunk below its
    # lowest tier goes on as it came)
    stem = np.flatnonzero(standing[-max(2 * tilt, 1) :].any(axis=0))
    spread = np.flatnonzero(under.any(axis=0))
    if stem.size and spread[-1] + 1 - spread[0] < GROUND_ROOTS_SPREAD * (stem[-1] + 1 - stem[0]):
        return None
    lo, hi = min(left, int(cols[0])), max(right, int(cols[-1]) + 1)
    wide = lo + np.flatnonzero(ink[b + tilt :, lo:hi].any(axis=0))
    if not _sticks_out(left, right, wide, GROUND_PAST_BELOW, tilt):
        return None
    return slice(int(wide[0]), int(wide[-1]) + 1)


def _sticks_out(left: int, right: int, span: np.ndarray, share: float, tilt: int) -> bool:
    """Whether a line from column ``left`` to ``right`` (exclusive) runs past the columns
    ``span`` on one side by ``share`` of their width (``4 * tilt`` at least)."""
    out = max(share * (span[-1] + 1 - span[0]), 4 * tilt)
    return bool(left < span[0] - out or right > span[-1] + 1 + out)


def _standing(above: np.ndarray, height: int) -> np.ndarray | None:
    """The ink of what stands on a ground line, from the ink ``above`` it: its strokes
    less the short ones at its bottom (grass on the line, up to ``GROUND_TUFT`` of the
    drawing's ``height``); None when nothing does."""
    from scipy import ndimage

    if not above.any():
        return None
    lab, _ = ndimage.label(above, structure=np.ones((3, 3), bool))
    tuft = GROUND_TUFT * height
    low = above.shape[0] - tuft
    keep = np.zeros(int(lab.max()) + 1, bool)
    for k, b in enumerate(ndimage.find_objects(lab), start=1):
        keep[k] = b is not None and (b[0].stop - b[0].start >= tuft or b[0].stop < low)
    return keep[lab] if keep.any() else None


def _drop_ground(ink: np.ndarray) -> np.ndarray:
    """Ink without a ground line under the tree (see ``GROUND_RUN``), the whole line: the
    renderer's sketches have none, so a line kept under the tree would be a stroke the
    network never saw, and the trunk's foot on it would no longer mark the base."""
    ys, xs = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if xs.size == 0:
        return ink
    tilt = max(1, int(round(GROUND_TILT * max(ink.shape))))
    # the work on the ink's bounding box (a drawing is often a small part of its page),
    # with room above it for the rows a ground line's run is widened by
    box = (slice(max(0, ys[0] - 2 * tilt - 1), ys[-1] + 1), slice(xs[0], xs[-1] + 1))
    out = ink.copy()
    out[box] = _without_ground(ink[box], tilt)
    return out


def _without_ground(ink: np.ndarray, tilt: int) -> np.ndarray:
    """:func:`_drop_ground` on the drawing's box: each level run that is a ground line
    goes, with its crests, its ends and its grass."""
    from scipy import ndimage

    level = _level_runs(ink, tilt, max(8.0, GROUND_RUN * ink.shape[1]))
    lab, _ = ndimage.label(level, structure=np.ones((3, 3), bool))
    ys = np.flatnonzero(ink.any(axis=1))
    height = int(ys[-1] + 1 - ys[0])
    out = ink.copy()
    boxes = list(enumerate(ndimage.find_objects(lab), start=1))
    # from the top down, each judged against what is left above it: the lower edge of a
    # patch of ground sticks out of the tree once the patch's upper edge is gone
    for k, box in sorted(boxes, key=lambda kb: kb[1][0].start):
        kept = _ground_span(out, box, tilt)
        if kept is None:
            continue
        gone = _ground_pixels(ink, lab == k, box, tilt)
        gone[:, kept] = False
        out &= ~gone
        ends = _ground_ends(out, ink & ~out, box[0].start, GROUND_TUFT * height, tilt)
        ends[:, kept] = False
        out &= ~ends
    return _without_grass(out, height, tilt)


# Grass drawn as one zigzag line along the ground ("VVVV" under the tree): no level run at
# a hand's wobble, but one when its ink is widened by its teeth's height; judged as a
# ground line is (under the tree, sticking out of it, next to nothing below), and told
# from a crown's or a tier's wavy edge by the strokes crossing its middle: a tooth crosses
# it twice, a level line runs along it
GRASS_BAND = 0.2  # of the drawing's height: the teeth are no taller
GRASS_CROSSINGS = 6  # strokes across the band's middle, at least
GRASS_TALLEST = 1.5  # of GRASS_BAND: the tallest teeth among them (the band's middle bridged)
GRASS_WIDE = 0.85  # of the width of what stands on it: the grass is no narrower


def _without_grass(ink: np.ndarray, height: int, tilt: int) -> np.ndarray:
    """``ink`` without grass drawn as a zigzag line under the tree (see ``GRASS_BAND``;
    ``height`` the drawing's, ``tilt`` a hand's wobble as for a ground line); a trunk
    standing in it keeps its foot down to the teeth's tops."""
    from scipy import ndimage

    reach = max(2, int(round(GRASS_BAND * height / 2)))
    level = _level_runs(ink, reach, max(8.0, GROUND_RUN * ink.shape[1]))
    if not level.any():
        return ink
    lab, _ = ndimage.label(level, structure=np.ones((3, 3), bool))
    out = ink
    for k, box in enumerate(ndimage.find_objects(lab), start=1):
        if box is None:
            continue
        rows = np.flatnonzero(ink[box].any(axis=1)) + box[0].start
        if rows.size == 0:
            continue
        # the strokes each row crosses, over the run's box and ``reach`` more each way
        near = slice(max(0, box[0].start - reach), box[0].stop + reach)
        crossed = np.array([len(_runs(row)) for row in ink[near, box[1]]])
        mid = (int(rows[0]) + int(rows[-1])) // 2 - near.start
        if crossed[max(0, mid - 1) : mid + 2].max() < GRASS_CROSSINGS:
            continue
        # judged on the teeth's own rows (the run's box is widened by ``reach``): those
        # that cross three strokes or more (a trunk standing in the grass, two)
        teeth = near.start + np.flatnonzero(crossed >= 3)
        # grass runs along the ground as wide as the crown at least; a trunk's foot
        # flaring into roots or curls is narrower
        standing = _standing(out[: max(0, teeth[0] - reach)], height)
        if standing is None:
            continue
        cols = np.flatnonzero(standing.any(axis=0))
        if box[1].stop - box[1].start < GRASS_WIDE * (cols[-1] + 1 - cols[0]):
            continue
        band = (slice(teeth[0], teeth[-1] + 1), box[1])
        kept = _ground_span(out, band, tilt, GRASS_TALLEST * GRASS_BAND)
        if kept is None:
            continue
        gone = _ground_pixels(ink, lab == k, box, reach)
        gone[:, kept] = False
        out = out & ~gone
    return out


def _ground_ends(
    ink: np.ndarray, ground: np.ndarray, top: int, tuft: float, reach: int
) -> np.ndarray:
    """What is left of a ground line beyond its level run: the strokes that touch the
    removed ``ground`` and lie wholly below row ``top`` (a mound's or a hill's sloping
    sides, a curl at a line's end) or are less than ``tuft`` rows tall (grass on it); a
    trunk that stood on the line goes up from it and stays."""
    from scipy import ndimage

    lab, n = ndimage.label(ink, structure=np.ones((3, 3), bool))
    # touching, or nearly: a tuft drawn as its own stroke stands a pixel or two off it
    near = ndimage.maximum_filter(ground.view(np.uint8), size=2 * reach + 1) > 0
    hit = np.zeros(n + 1, bool)
    hit[np.unique(lab[near & ink])] = True
    hit[0] = False
    for k, sl in enumerate(ndimage.find_objects(lab), start=1):
        hit[k] &= sl is not None and (sl[0].start >= top or sl[0].stop - sl[0].start < tuft)
    return hit[lab]


def _ground_pixels(
    ink: np.ndarray, seed: np.ndarray, box: tuple[slice, slice], tilt: int
) -> np.ndarray:
    """The ink of a ground line whose level run is ``seed`` (bounding box ``box``, the
    line widened by ``tilt`` rows each way): the strokes touching the run within the
    box's rows and ``tilt`` more (a wobbly line's crests, grass on it), less what
    reaches them from above the line's own rows (a trunk standing on the line keeps its
    foot down to the line)."""
    top = max(0, box[0].start - tilt)
    rows = slice(top, box[0].stop + tilt)
    out = np.zeros_like(ink)
    out[rows] = _touching(ink[rows], seed[rows])
    line_top = box[0].start + tilt - max(1, tilt // 3)  # a little above the line itself
    if top > 0 and line_top > top:
        out[top:line_top] &= ~_coming_down(ink[top - 1 : line_top])[1:]
    return out


def _coming_down(rows: np.ndarray) -> np.ndarray:
    """The ink of ``rows`` reached from the first row going down, a pixel aside at most
    per row: a trunk coming down onto a ground line, at a slant too, but not the line's
    crest beside its foot, which runs sideways."""
    from scipy import ndimage

    out = np.zeros_like(rows)
    out[0] = rows[0]
    for r in range(1, len(rows)):
        out[r] = ndimage.binary_dilation(out[r - 1], np.ones(3, bool)) & rows[r]
    return out


def _touching(ink: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """The strokes of ``ink`` that touch ``seed``: a ground line's wobbly ends and curls
    that left its level run, grass on it, within the rows of the line only."""
    from scipy import ndimage

    lab, n = ndimage.label(ink, structure=np.ones((3, 3), bool))
    hit = np.zeros(n + 1, bool)
    hit[np.unique(lab[seed & ink])] = True
    hit[0] = False
    return hit[lab]


# A frame drawn round the drawing (a border, a card's edge): marks that lie wholly within
# FRAME_BAND of the ink's bounding box and run along FRAME_COVER of each of its four
# sides, round ink apart from them.  Kept, the frame is read as the tree's outline and the
# tree is framed small inside it
FRAME_BAND = 0.03  # of the box's longer side (at least 3 px): how far from its edge
FRAME_COVER = 0.8  # of each side's length the frame's marks run along, at least


def _drop_frame(ink: np.ndarray) -> np.ndarray:
    """``ink`` without a frame drawn round the drawing (see ``FRAME_BAND``).  A tree's
    sketch runs along at most two sides of its box: four slices of the ink say so."""
    from scipy import ndimage

    ys, xs = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    if ys.size < 3 or xs.size < 3:
        return ink
    top, bottom, left, right = int(ys[0]), int(ys[-1]) + 1, int(xs[0]), int(xs[-1]) + 1
    t = max(3, int(round(FRAME_BAND * max(bottom - top, right - left))))
    if bottom - top <= 4 * t or right - left <= 4 * t:
        return ink
    box = ink[top:bottom, left:right]

    def runs_along(marks: np.ndarray) -> bool:
        sides = (
            marks[:t].any(axis=0),
            marks[-t:].any(axis=0),
            marks[:, :t].any(axis=1),
            marks[:, -t:].any(axis=1),
        )
        return all(side.mean() >= FRAME_COVER for side in sides)

    if not runs_along(box):
        return ink
    lab, n = ndimage.label(box, structure=np.ones((3, 3), bool))
    # the marks with no pixel inside the band round the box's edges
    piece = np.ones(n + 1, bool)
    piece[lab[t:-t, t:-t]] = False  # label 0 too: the paper is no mark
    frame = piece[lab]
    if not (box & ~frame).any() or not runs_along(frame):
        return ink
    out = ink.copy()
    out[top:bottom, left:right] &= ~frame
    return out


# A caption: a word or a name written under or over the drawing ("my tree", "Anna, 7"),
# across blank rows from it.  It is a short row of separate marks as tall as each other
# (letters), none of which a tree's own parts make: a pot in pieces has two sides tall, a
# broken ground line's dashes are flat, a crown drawn apart from its trunk is one mark or
# taller than a caption.  Kept, it is read as the tree's roots or crown and the tree is
# framed small over it
CAPTION_HEIGHT = 0.2  # of the ink's height, at most
CAPTION_GAP = 0.02  # of the ink's height: the blank rows between it and the drawing, at least
CAPTION_MARKS = 3  # separate marks (8-connected) at least ...
CAPTION_MARK = 0.4  # ... each at least this share of the caption's height tall
CAPTION_STROKES = 4.0  # its height in stroke widths, at least (a dashed line's is about one)
CAPTION_ROW = 2.0  # its width over its height, at least


def _drop_captions(ink: np.ndarray) -> np.ndarray:
    """``ink`` without a caption under or over the drawing (see ``CAPTION_HEIGHT``).  Most
    pages (and every candidate's sketch) have no blank rows between their marks: one
    look at the rows then."""
    rows = np.flatnonzero(ink.any(axis=1))
    if rows.size < 2:
        return ink
    height = int(rows[-1] + 1 - rows[0])
    breaks = np.flatnonzero(np.diff(rows) > max(2.0, CAPTION_GAP * height))
    if breaks.size == 0:
        return ink
    out = ink
    under = (int(rows[breaks[-1] + 1]), int(rows[-1] + 1))
    over = (int(rows[0]), int(rows[breaks[0]] + 1))
    for lo, hi in (under, over):
        if hi - lo <= CAPTION_HEIGHT * height and _is_caption(ink[lo:hi]):
            out = out.copy() if out is ink else out
            out[lo:hi] = False
    return out


def _is_caption(block: np.ndarray) -> bool:
    """Whether the rows ``block`` (ink in its first and last) hold a caption."""
    from scipy import ndimage

    h = block.shape[0]
    cols = np.flatnonzero(block.any(axis=0))
    if cols[-1] + 1 - cols[0] < CAPTION_ROW * h or h < CAPTION_STROKES * stroke_width(block):
        return False
    lab, n = ndimage.label(block, structure=np.ones((3, 3), bool))
    if n < CAPTION_MARKS:
        return False
    tall = [sl[0].stop - sl[0].start >= CAPTION_MARK * h for sl in ndimage.find_objects(lab)]
    return sum(tall) >= CAPTION_MARKS


def tree_ink(ink: np.ndarray) -> np.ndarray:
    """The tree's ink alone, so a drawing is framed on the tree and not on everything on
    the page: without stray marks, a sun, a cloud or grass beside the tree, and a ground
    line under it.  The extras go first (a sun over a ground line's end would hide that
    the line sticks out), then the ground, then what the ground joined to the tree."""
    return _tree_ink(ink)


def _tree_ink(ink: np.ndarray, ground_free: np.ndarray | None = None) -> np.ndarray:
    """:func:`tree_ink`; ``ground_free``: ink known to hold no ground line (what
    :func:`_drop_ground` gave back unchanged), not looked through again when the extras
    leave exactly it (a tree's sketch in the refinement, every time)."""
    apart = _drop_extras(ink)
    if ground_free is None or not np.array_equal(apart, ground_free):
        apart = _drop_ground(apart)
    return _drop_extras(apart)


RULED_ROW = 0.6  # a thin horizontal line over this much of the page width is ruling
RULED_COLUMN = 0.8  # a thin vertical line over this much of the page height (a margin)
RULED_THICK = 5  # rows (columns) a ruled line, tilt included, may cover at most
# a ruling belongs to the page: it runs to (nearly) both page edges; a drawn stroke that
# spans most of the page (a palm's or a pine's trunk in a framed sketch) stops short of
# them (the renderer's frame keeps 3-4 % of the side blank all round)
RULED_EDGE = 0.02


def _rows_across(a: np.ndarray, frac: float) -> np.ndarray:
    """The rows of ``a`` (bool) whose ink, with the rows next to them, covers more than
    ``frac`` of the width: a line tilted by a pixel or two over the page still covers
    the row it is on."""
    near = a.copy()
    near[1:] |= a[:-1]
    near[:-1] |= a[1:]
    return near.mean(axis=1) > frac


def _drop_ruled_lines(ink: np.ndarray) -> np.ndarray:
    """Ink without the ruled lines and margin of lined paper (long, thin, straight lines
    across the page, from edge to edge), keeping the drawing's strokes where they cross
    them."""
    from scipy import ndimage

    out = ink.copy()
    for axis, frac in ((0, RULED_ROW), (1, RULED_COLUMN)):
        a = out if axis == 0 else out.T  # a view: rows of ``a`` are the lines looked for
        flagged = _rows_across(a, frac)
        if not flagged.any():
            continue
        runs, _ = ndimage.label(flagged)
        for sl in ndimage.find_objects(runs):
            lo, hi = sl[0].start, sl[0].stop
            if hi - lo > RULED_THICK:  # a dense scribble, not a ruled line
                continue
            band = a[lo:hi].any(axis=0)
            edge = max(1, round(RULED_EDGE * band.size))
            if not (band[:edge].any() and band[-edge:].any()):  # a stroke, not the page's
                continue
            lo, hi = max(lo - 1, 0), min(hi + 1, a.shape[0])
            above = a[lo - 1] if lo > 0 else np.zeros(a.shape[1], bool)
            below = a[hi] if hi < a.shape[0] else np.zeros(a.shape[1], bool)
            # a stroke that crosses the line goes on through it, also at a slant: ink
            # within a few pixels on both sides of the band
            reach = np.ones(2 * (hi - lo) + 1, bool)
            across = ndimage.binary_dilation(above, reach) & ndimage.binary_dilation(below, reach)
            a[lo:hi] = (across & (above | below))[None, :]
    return out


# a trunk drawn as two lines, one ending lower than the other: its partner is looked for
# up to this much of the drawing's height above the lowest ink, at most PARTNER_REACH of
# the height beside it; a base narrower than SINGLE_LINE of the height is one line, and so
# is one no wider than SINGLE_STROKES of the drawing's strokes (a thick pen's slanted
# line: a 28 px Quick, Draw! doodle's line is a tenth of its height wide, and its trunk's
# splayed feet sat the tree on one foot, 74 of 389 held-out trees over a quarter of their
# width off their crown's axis, 6 since, 17 with two strokes; RESULTS.md, "The tree
# follows the drawing")
PARTNER_RISE = 0.15
PARTNER_REACH = 0.7
SINGLE_LINE = 0.05
SINGLE_STROKES = 3.0


def _runs(row: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) columns of each run of ink in a row (gaps of one pixel bridged)."""
    xs = np.flatnonzero(row)
    if xs.size == 0:
        return []
    cut = np.flatnonzero(np.diff(xs) > 2)
    return list(zip(xs[np.r_[0, cut + 1]], xs[np.r_[cut, xs.size - 1]], strict=True))


def _gap(a: tuple[int, int], b: tuple[int, int]) -> int:
    """Columns between two runs (0 when they touch or overlap)."""
    return max(0, a[0] - b[1], b[0] - a[1])


def trunk_axis(ink: np.ndarray) -> float:
    """The column of the trunk's axis at its base (``ink`` bool, not blank): the middle
    of the lowest rows' ink.  People draw a trunk as two lines that seldom end on one
    row: when the lowest rows hold one line (thin, or no wider than ``SINGLE_STROKES``
    of the drawing's strokes), the axis is the middle of it and the nearest line beside
    it a little higher up (the trunk's other side), not the line alone (which would
    frame the tree half off the centre line)."""
    ys = np.flatnonzero(ink.any(axis=1))
    top, bottom = int(ys[0]), int(ys[-1])
    h = bottom - top + 1
    bx = np.flatnonzero(ink[max(top, bottom - max(2, (bottom - top) // 40)) : bottom + 1].any(0))
    lo, hi = int(bx[0]), int(bx[-1])
    base = hi - lo + 1
    if len(_runs(ink[bottom])) <= 1 and (
        base <= SINGLE_LINE * h or base <= SINGLE_STROKES * stroke_width(ink)
    ):
        reach, at = PARTNER_REACH * h, (lo, hi)  # the line followed up as it slants
        for r in range(bottom - 1, max(top, bottom - int(PARTNER_RISE * h)) - 1, -1):
            runs = _runs(ink[r])
            mine = [u for u in runs if u[0] - 2 <= at[1] and u[1] + 2 >= at[0]]
            if not mine:
                break
            at = (min(u[0] for u in mine), max(u[1] for u in mine))
            other = [u for u in runs if u not in mine and _gap(u, at) < reach]
            if other:
                partner = min(other, key=lambda u: _gap(u, at))
                axis = (min(at[0], partner[0]) + max(at[1], partner[1]) + 1) / 2.0
                # the other side only when it puts the tree over its trunk: beside a
                # trunk drawn as one line, the low leaves of a crown are not its side
                above = np.flatnonzero(ink[top : r - int(PARTNER_RISE * h) + 1].any(axis=0))
                middle = (above[0] + above[-1] + 1) / 2.0 if above.size else axis
                if abs(middle - axis) < abs(middle - (lo + hi + 1) / 2.0):
                    return axis
                break
    return (lo + hi + 1) / 2.0


# the trunk's foot, for :func:`crown_axis`: the ink of this much of the drawing's height
# above its lowest ink
FOOT_RISE = 0.15


def crown_axis(ink: np.ndarray) -> float:
    """The column of the tree's axis as a grown tree would stand in the drawing (``ink``
    bool, not blank): of the columns over the trunk's foot (the ink of the lowest
    ``FOOT_RISE`` of the height, where a trunk's two lines, its roots or a flared base
    end), the one the drawing is most nearly mirror-symmetric about (each row filled
    between its leftmost and rightmost ink).

    People draw a trunk as two lines that seldom end on one row, flare one of them or
    draw the crown a little to one side: :func:`trunk_axis` then sits the tree on one of
    its lines, half off the centre line, and shrinks it to fit.  A grown tree's crown
    stands over its trunk, so the frame a tree's outline is compared with the drawn one
    in is the one where the drawn crown does too, as far as the drawn foot allows."""
    ys = np.flatnonzero(ink.any(axis=1))
    top, bottom = int(ys[0]), int(ys[-1])
    h = bottom - top + 1
    foot = np.flatnonzero(ink[max(top, bottom - int(FOOT_RISE * h)) : bottom + 1].any(0))
    # the whole drawing, foot and all (without the foot's rows, people's outlines fell:
    # RESULTS.md, "The tree follows the drawing")
    rows = ink[top : bottom + 1]
    has = rows.any(axis=1)
    left = np.argmax(rows, axis=1)[has].astype(float)
    right = (rows.shape[1] - 1 - np.argmax(rows[:, ::-1], axis=1))[has].astype(float)
    # candidate axes every half column over the foot; each row's span [left, right]
    # mirrored about c is [2c - right, 2c - left]
    c = np.arange(2 * int(foot[0]), 2 * int(foot[-1]) + 1) / 2.0
    lo = np.maximum(left[None, :], 2 * c[:, None] - right[None, :])
    hi = np.minimum(right[None, :], 2 * c[:, None] - left[None, :])
    inter = np.clip(hi - lo + 1, 0, None).sum(axis=1)
    span = (right - left + 1).sum()
    score = inter / np.maximum(2 * span - inter, 1)
    # ties (a symmetric foot) go to the foot's middle
    middle = (foot[0] + foot[-1] + 1) / 2.0
    best = np.flatnonzero(score >= score.max() - 1e-9)
    return float(c[best[np.argmin(np.abs(c[best] + 0.5 - middle))]] + 0.5)


def _axis_and_box(ink: np.ndarray, over_crown: bool) -> tuple[int, int, int, int, float]:
    ys = np.flatnonzero(ink.any(axis=1))
    xs = np.flatnonzero(ink.any(axis=0))
    top, bottom, left, right = int(ys[0]), int(ys[-1]), int(xs[0]), int(xs[-1])
    return top, bottom, left, right, (crown_axis if over_crown else trunk_axis)(ink)


def normalise_drawing(
    img: np.ndarray, size: int = DRAWING_SIDE, over_crown: bool = False
) -> np.ndarray:
    """A drawing (grey ``uint8``, any size) -> ``(size, size)`` uint8 as the renderer
    frames a tree: paper white, strokes dark, trunk base on the bottom margin, trunk axis
    on the centre line, the drawing as large as the frame allows.

    Pencil on grey or off-white paper and phone photos read as ink (:func:`flatten_paper`,
    Otsu), light lines on a dark page as the same lines dark (:func:`light_on_dark`), and
    come out as black strokes on white, like the training sketches, without the
    paper's grain (:func:`drop_specks`) or stray marks apart from the drawing.  It is
    framed on the tree (:func:`tree_ink`), not on all the ink: a ground line under the
    tree, a sun, a cloud or grass beside it are left out of the frame and the picture; a
    drawing in a corner is moved and scaled to the middle.  The refinement frames every
    candidate's sketch the same way, so drawing and candidates always compare at one framing (the
    renderer's own frame fits a tree's width over all sides, not the drawn one).  Refuses
    blank and dark pages.

    The axis is the trunk's (:func:`trunk_axis`), as the network learned its sketches;
    ``over_crown``: where a grown tree would stand (:func:`crown_axis`), the frame
    outlines are compared in.
    """
    from PIL import Image

    a = np.asarray(img, dtype=np.uint8)
    if max(a.shape) > WORK_SIDE:  # bounded work for photos; strokes stay > 1 px
        s = WORK_SIDE / max(a.shape)
        shape = (max(MIN_SIDE, round(a.shape[1] * s)), max(MIN_SIDE, round(a.shape[0] * s)))
        a = np.asarray(Image.fromarray(a).resize(shape, Image.Resampling.BOX))
    a = _dark_on_light(a)
    # a frame round the drawing, then a caption under it, would hide a ground line (ink
    # below it)
    page = _drop_captions(_drop_frame(_page_ink(a)))
    # a ground line drawn from edge to edge looks like ruling, whose removal keeps what
    # crosses it and leaves the line's crests: it goes as a ground line first
    grounded = _drop_ground(page)
    ground_free = grounded if np.array_equal(grounded, page) else None
    ink = _tree_ink(drop_specks(_drop_ruled_lines(grounded)), ground_free)
    return frame_ink(ink, size, over_crown)


def frame_ink(ink: np.ndarray, size: int = DRAWING_SIDE, over_crown: bool = False) -> np.ndarray:
    """A page's tree ink (bool, as :func:`normalise_drawing` leaves it once the page is
    cleaned) -> ``(size, size)`` uint8 framed as the renderer frames a tree: the framing
    half of :func:`normalise_drawing`.  A sketch the renderer drew has no page to clean
    (no paper, frame, caption, ground line, ruling or marks beside the tree):
    ``refine.objective.framed_sketch`` frames its ink here directly.  Refuses blank and
    all-ink pages."""
    from PIL import Image

    frac = float(ink.mean())
    if frac < MIN_INK:
        raise SketchError("the sketch is blank: draw a tree (dark lines on a light page)")
    if frac > MAX_INK:
        raise SketchError(f"the page is almost all ink ({frac:.0%}): draw lines, not a fill")
    top, bottom, left, right, axis = _axis_and_box(ink, over_crown)
    h = bottom - top + 1
    half = max(axis - left, right + 1 - axis, 0.5)
    scale = min((FRAME_BOTTOM - FRAME_EDGE) * size / h, (0.5 - FRAME_EDGE) * size / half)
    if abs(scale - 1.0) < 0.02:  # already framed: move it, do not resample it
        scale = 1.0
    # the page, scaled, with the trunk base at (size/2, FRAME_BOTTOM * size)
    out_w = max(1, int(round(ink.shape[1] * scale)))
    out_h = max(1, int(round(ink.shape[0] * scale)))
    x0 = int(round(size / 2 - axis * scale))
    y0 = int(round(FRAME_BOTTOM * size - (bottom + 1) * scale))
    pic = Image.fromarray(np.where(ink, 0, 255).astype(np.uint8))
    if scale != 1.0:
        resample = Image.Resampling.BOX if scale < 1 else Image.Resampling.BILINEAR
        pic = pic.resize((out_w, out_h), resample)
    canvas = Image.new("L", (size, size), 255)
    canvas.paste(pic, (x0, y0))
    # binary, like the renderer's sketches (and so normalising twice changes nothing); a
    # shrunk drawing keeps a pixel a quarter covered by ink, so a thin pen line stays
    # one unbroken line instead of falling apart into dashes
    level = 128 if scale >= 1.0 else 192
    out = np.where(np.asarray(canvas) < level, 0, 255).astype(np.uint8)
    if float(ink_mask(out).mean()) < MIN_INK:
        raise SketchError("the sketch is blank: draw a tree (dark lines on a light page)")
    return out
