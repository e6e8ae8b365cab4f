"""Writing the documentation's pictures (docs/*.png) from the make_*_png scripts."""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from weberpenn.fileio import atomic_write


def write_palette_png(image: Image.Image, out: str | Path, colors: int = 128) -> Path:
    """``image`` quantised to ``colors`` (median cut: small files for flat drawings) and
    written as an optimised PNG at ``out``, atomically; says what it wrote."""
    small = image.quantize(colors=colors, method=Image.Quantize.MEDIANCUT)
    out = atomic_write(out, lambda tmp: small.save(tmp, format="PNG", optimize=True))
    print(f"wrote {out} ({out.stat().st_size // 1024} KB)")
    return out
