"""Bark and leaf textures made by the project: procedural, deterministic, per species.

- :func:`bark_texture` is an RGB image that tiles in both directions (made from
  band-limited periodic noise, so the left edge meets the right and the top the bottom):
  ``u`` goes once around a stem, ``v`` along it (see ``weberpenn.mesh``).
- :func:`leaf_texture` is an RGBA image of one leaf (or needle tuft, frond, blossom) on a
  transparent background, base at the bottom centre and tip at the top, filling the leaf
  template's UV square (``weberpenn.mesh.HEX`` / ``RECT`` shifted by +0.5 in u).

Same species and size, same pixels: the random generator is seeded from the species
name.  Colours come from :data:`COLOURS` (also used for flat-colour exports).
"""

from __future__ import annotations

import zlib

import numpy as np
from PIL import Image

__all__ = ["COLOURS", "bark_texture", "colours", "leaf_texture"]

RGB = tuple[float, float, float]

# (bark RGB, leaf RGB) in 0..1, per species; None = default.
COLOURS: dict[str | None, tuple[RGB, RGB]] = {
    None: ((0.36, 0.27, 0.20), (0.25, 0.50, 0.18)),
    "maple": ((0.38, 0.30, 0.24), (0.72, 0.30, 0.10)),
    "pine": ((0.33, 0.22, 0.15), (0.13, 0.33, 0.16)),
    "bonsai": ((0.42, 0.34, 0.26), (0.22, 0.46, 0.16)),
    "palm": ((0.55, 0.45, 0.32), (0.30, 0.55, 0.20)),
    "cherry": ((0.30, 0.20, 0.18), (0.95, 0.72, 0.80)),
}

# Bark look per species: (frequency scale across, along, crack depth, horizontal bands).
_BARK: dict[str | None, tuple[float, float, float, float]] = {
    None: (10.0, 2.0, 0.55, 0.0),
    "maple": (12.0, 2.5, 0.5, 0.0),
    "pine": (6.0, 3.0, 0.7, 0.0),  # plates
    "bonsai": (14.0, 2.0, 0.45, 0.0),
    "palm": (3.0, 1.0, 0.3, 10.0),  # leaf-scar rings
    "cherry": (3.0, 10.0, 0.35, 0.0),  # horizontal lenticels
}

MIN_SIZE, MAX_SIZE = 16, 2048


def colours(species: str | None) -> tuple[RGB, RGB]:
    """(bark, leaf) RGB for a species name (the default pair for None or an unknown name)."""
    return COLOURS.get(species, COLOURS[None])


def _check_size(size: int) -> int:
    if isinstance(size, bool) or int(size) != size or not MIN_SIZE <= int(size) <= MAX_SIZE:
        raise ValueError(
            f"texture size must be an integer in [{MIN_SIZE}, {MAX_SIZE}], got {size!r}"
        )
    return int(size)


def _rng(kind: str, species: str | None) -> np.random.Generator:
    return np.random.default_rng(zlib.crc32(f"{kind}:{species or 'default'}".encode()))


def _periodic_noise(rng: np.random.Generator, size: int, fu: float, fv: float) -> np.ndarray:
    """Noise in [0, 1] that tiles: white noise low-passed in the Fourier domain with an
    anisotropic cut-off (``fu`` cycles across, ``fv`` along the image)."""
    white = rng.standard_normal((size, size))
    ky = np.fft.fftfreq(size)[:, None] * size  # cycles per image along v (rows)
    kx = np.fft.rfftfreq(size)[None, :] * size  # across u (columns)
    gain = np.exp(-((kx / fu) ** 2 + (ky / fv) ** 2))
    field = np.fft.irfft2(np.fft.rfft2(white) * gain, s=(size, size))
    lo, hi = np.percentile(field, [1, 99])
    return np.clip((field - lo) / max(hi - lo, 1e-12), 0.0, 1.0)


def bark_texture(species: str | None = None, size: int = 256) -> Image.Image:
    """A tiling RGB bark texture for ``species`` (``size`` x ``size`` pixels)."""
    size = _check_size(size)
    rng = _rng("bark", species if species in _BARK else None)
    fu, fv, depth, bands = _BARK.get(species, _BARK[None])
    base = _periodic_noise(rng, size, fu, fv)
    fine = _periodic_noise(rng, size, 4 * fu, 4 * fv)
    ridges = 1.0 - np.abs(2.0 * base - 1.0)  # dark cracks where the noise crosses 0.5
    shade = 1.0 - depth * (1.0 - ridges) ** 2 + 0.25 * (fine - 0.5)
    if bands:
        rows = np.arange(size)[:, None] / size
        shade = shade * (0.8 + 0.2 * np.cos(2 * np.pi * bands * rows) ** 8)
    rgb = np.asarray(colours(species)[0])[None, None, :] * (0.45 + 0.75 * shade[..., None])
    return Image.fromarray((np.clip(rgb, 0, 1) * 255).round().astype(np.uint8), "RGB")


def _leaf_mask(species: str | None, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Inside-the-leaf mask on a grid, u in [-0.5, 0.5] across, v in [0, 1] base -> tip."""
    if species == "maple":  # five lobes around a centre above the base
        du, dv = u, v - 0.45
        r, th = np.hypot(du, dv), np.arctan2(du, dv)  # th = 0 points at the tip
        lobes = 0.30 + 0.15 * np.cos(2.5 * th) ** 2 - 0.05 * (np.abs(th) > 2.4)
        return (r < lobes) | ((np.abs(u) < 0.02) & (v < 0.2))
    if species == "pine":  # a fan of needles from the base
        th = np.arctan2(u, np.maximum(v, 1e-6))
        angles = np.linspace(-0.5, 0.5, 7)
        near = np.min(np.abs(th[..., None] - angles), axis=-1)
        return (near * np.maximum(v, 0.05) < 0.012) & (np.hypot(u, v) < 0.97)
    if species == "palm":  # a frond: midrib and leaflets angled towards the tip
        rib = np.abs(u) < 0.02
        leaflet = np.abs(((v - 0.9 * np.abs(u)) * 14.0) % 1.0 - 0.5) < 0.18
        width = 0.5 * np.sin(np.pi * np.clip(v, 0, 1)) ** 0.6
        return rib | (leaflet & (np.abs(u) < width) & (v > 0.05))
    if species == "cherry":  # a five-petal blossom
        du, dv = u, v - 0.5
        r, th = np.hypot(du, dv), np.arctan2(du, dv)
        return r < 0.22 + 0.24 * np.abs(np.cos(2.5 * th))
    # a plain pointed leaf (bonsai and default)
    width = 0.42 * np.sin(np.pi * np.clip(v, 0, 1)) ** 0.75
    return (np.abs(u) < width) | ((np.abs(u) < 0.02) & (v < 0.12))


def leaf_texture(species: str | None = None, size: int = 256) -> Image.Image:
    """An RGBA leaf for ``species``: alpha 255 on the leaf, 0 around it; veins darker."""
    size = _check_size(size)
    rng = _rng("leaf", species if species in COLOURS else None)
    c = (np.arange(size) + 0.5) / size
    u = c[None, :] - 0.5
    v = 1.0 - c[:, None]  # image row 0 is the tip (v = 1, the OBJ/trimesh UV convention)
    u, v = np.broadcast_to(u, (size, size)), np.broadcast_to(v, (size, size))
    mask = _leaf_mask(species, u, v)
    veins = (np.abs(u) < 0.012) | (np.abs((v - 1.6 * np.abs(u)) * 8.0 % 1.0 - 0.5) < 0.03)
    noise = _periodic_noise(rng, size, 8.0, 8.0)
    shade = 0.85 + 0.3 * (noise - 0.5) + 0.15 * v - 0.25 * veins
    rgb = np.asarray(colours(species)[1])[None, None, :] * shade[..., None]
    rgba = np.empty((size, size, 4), dtype=np.uint8)
    rgba[..., :3] = (np.clip(rgb, 0, 1) * 255).round().astype(np.uint8)
    rgba[..., 3] = np.where(mask, 255, 0)
    return Image.fromarray(rgba, "RGBA")
