"""render.reader: the one sketch reader, and the hostile inputs it must refuse quickly."""

from __future__ import annotations

import io
import struct
import time
import tracemalloc
import zlib

import numpy as np
import pytest
from PIL import Image

from render.reader import MAX_PIXELS, SketchError, check_ink, read_sketch


def _png_header_only(width: int, height: int) -> bytes:
    """A tiny PNG that declares ``width x height`` pixels (its data is one empty block)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", ihdr)
        + chunk(b"IDAT", zlib.compress(b""))
        + chunk(b"IEND", b"")
    )


def _png(a: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(a).save(buf, format="PNG")
    return buf.getvalue()


@pytest.mark.parametrize(
    ("w", "h", "match"),
    [(1, 20000, "at least"), (8, 10000, "aspect ratio"), (30000, 30000, "pixels")],
)
def test_hostile_sizes_are_refused_before_decoding(w: int, h: int, match: str) -> None:
    data = _png_header_only(w, h)
    assert len(data) < 200
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(SketchError, match=match):
        read_sketch(data)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert seconds < 0.5 and peak < 10_000_000


def test_a_real_strip_is_refused_too() -> None:
    strip = np.full((20000, 8), 255, np.uint8)
    with pytest.raises(SketchError, match="aspect ratio"):
        read_sketch(_png(strip))
    with pytest.raises(SketchError, match="aspect ratio"):
        read_sketch(strip)


def test_messages_have_no_object_addresses() -> None:
    for bad in (b"not an image", _png(np.zeros((40, 40), np.uint8))[:40]):
        with pytest.raises(SketchError) as info:
            read_sketch(bad)
        assert "0x" not in str(info.value) and "BytesIO" not in str(info.value)


def test_alpha_is_flattened_on_white_and_grey_is_luma() -> None:
    rgba = np.zeros((16, 16, 4), np.uint8)
    rgba[..., 3] = 0  # fully transparent black: white paper
    rgba[4:8, 4:8] = (255, 0, 0, 255)  # opaque red
    g = read_sketch(_png(rgba))
    assert g[0, 0] == 255
    assert g[5, 5] == round(0.299 * 255)
    assert np.array_equal(read_sketch(rgba), g)


def test_float_images_and_errors() -> None:
    f = np.ones((20, 20), np.float32)
    f[5:10, 5:10] = 0.0
    g = read_sketch(f)
    assert g.dtype == np.uint8 and g[0, 0] == 255 and g[6, 6] == 0
    with pytest.raises(SketchError, match="NaN"):
        read_sketch(np.full((20, 20), np.nan))
    with pytest.raises(SketchError, match="numbers"):
        read_sketch(np.array([["a"] * 20] * 20))


def test_check_ink() -> None:
    with pytest.raises(SketchError, match="blank"):
        check_ink(np.full((64, 64), 255, np.uint8))
    with pytest.raises(SketchError, match="dark"):
        check_ink(np.zeros((64, 64), np.uint8))
    page = np.full((64, 64), 255, np.uint8)
    page[10:50, 30:33] = 0
    assert 0 < check_ink(page) < 0.1
    assert MAX_PIXELS >= 4000 * 4000
