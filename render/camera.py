"""Orthographic cameras that frame every tree the same way (pure numpy, no mitsuba).

Conventions: Z is up and the trunk starts at the origin.  ``yaw`` turns the camera about
the trunk (Z) axis, in degrees: at yaw 0 ("front") the camera looks along +Y, image right
is +X; ``VIEWS`` maps front/left/back/right to 0/90/180/270.  ``pitch`` (degrees,
positive = camera raised, looking down) tilts the view about the horizontal image axis
through the middle of the frame; keep it small (the framing is computed for pitch 0).

Framing (:class:`Framing`) depends only on the tree, never on the view: the square image
spans ``span`` world units; the lowest point (the trunk base, z = 0, for any grown tree)
sits ``margin_bottom`` of the image above the bottom edge, the trunk axis is the vertical
centre line, and ``span`` is the smallest that fits both the tree's height (with
``margin_top``) and the widest radius around the trunk axis over ALL yaws (with
``margin_side`` on both sides).  So a tall palm and a small bonsai fill the same fraction
of the image height (unless a tree is wider than tall, when the width decides), and
turning the camera never rescales or shifts the tree.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np

VIEWS: dict[str, float] = {"front": 0.0, "back": 180.0, "left": 90.0, "right": 270.0}
MAX_PITCH = 45.0


@dataclass(frozen=True)
class Framing:
    """How a tree is placed in the image (world units; identical for every view)."""

    z_bottom: float  # lowest world z shown at the bottom margin
    z_top: float
    radius: float  # max distance of any vertex from the trunk (Z) axis
    margin_bottom: float = 0.04
    margin_top: float = 0.07  # room for the foliage outline (drawn ~10 px outside the leaves)
    margin_side: float = 0.07

    def __post_init__(self) -> None:
        for name in ("margin_bottom", "margin_top", "margin_side"):
            v = getattr(self, name)
            if not 0.0 <= v < 0.45:
                raise ValueError(f"Framing.{name}={v!r} must be in [0, 0.45)")
        if self.margin_bottom + self.margin_top >= 0.9:
            raise ValueError("Framing: margin_bottom + margin_top must be below 0.9")
        for name in ("z_bottom", "z_top", "radius"):
            if not np.isfinite(getattr(self, name)):
                raise ValueError(f"Framing.{name} must be finite, got {getattr(self, name)!r}")

    @property
    def span(self) -> float:
        """World size of the square image side."""
        height = max(self.z_top - self.z_bottom, 1e-6)
        by_height = height / (1.0 - self.margin_bottom - self.margin_top)
        by_width = 2.0 * max(self.radius, 1e-6) / (1.0 - 2.0 * self.margin_side)
        return float(max(by_height, by_width))

    @property
    def centre(self) -> np.ndarray:
        """World point at the centre of the image."""
        s = self.span
        return np.array([0.0, 0.0, self.z_bottom - self.margin_bottom * s + 0.5 * s])

    @classmethod
    def from_vertices(cls, vertices: np.ndarray, **margins: float) -> Framing:
        """Frame a point set (e.g. all vertices of a tree); empty -> a unit box."""
        return cls.from_parts([vertices], **margins)

    @classmethod
    def from_parts(cls, parts: Sequence[np.ndarray], **margins: float) -> Framing:
        """:meth:`from_vertices` of the point sets stacked, without stacking them."""
        z_lo, z_hi, r2 = [], [], []
        for part in parts:
            v = np.asarray(part)
            if v.dtype not in (np.float32, np.float64):
                v = v.astype(np.float64)
            v = np.ascontiguousarray(v).reshape(-1, 3)
            if not len(v):
                continue
            extent = _extent(v)
            if not np.isfinite(extent).all():
                # a point off to infinity or NaN: only the finite rows (the row-wise
                # filter is slow: only when needed)
                v = v.astype(np.float64)[np.isfinite(v).all(axis=1)]
                if not len(v):
                    continue
                extent = (v[:, 2].min(), v[:, 2].max(), (v[:, 0] ** 2 + v[:, 1] ** 2).max())
            z_lo.append(extent[0])
            z_hi.append(extent[1])
            r2.append(extent[2])
        if not z_lo:
            return cls(0.0, 1.0, 0.5, **margins)
        z_bottom = float(min(min(z_lo), 0.0))
        return cls(z_bottom, float(max(z_hi)), float(np.sqrt(max(r2))), **margins)


@numba.njit(cache=True)
def _extent(v: np.ndarray) -> np.ndarray:
    """(lowest z, highest z, largest x^2 + y^2) of the points ``v`` (n >= 1, 3), in
    float64 as numpy computes them from a float64 copy (one pass, no copy: a tree's
    mesh has 10^5 vertices, framed for every candidate of a refinement); NaN when a
    point is not finite."""
    out = np.array([np.inf, -np.inf, -np.inf])
    for i in range(v.shape[0]):
        x, y, z = np.float64(v[i, 0]), np.float64(v[i, 1]), np.float64(v[i, 2])
        if not (np.isfinite(x) and np.isfinite(y) and np.isfinite(z)):
            out[:] = np.nan
            return out
        out[0] = min(out[0], z)
        out[1] = max(out[1], z)
        out[2] = max(out[2], x * x + y * y)
    return out


def view_direction(yaw: float) -> np.ndarray:
    """The horizontal unit vector a camera at ``yaw`` (pitch 0) looks along (yaw 0: +Y)."""
    a = np.radians(float(yaw))
    return np.array([-np.sin(a), np.cos(a), 0.0])


def resolve_yaw(view: str | float) -> float:
    """A view name (front/back/left/right) or a number of degrees -> degrees."""
    if isinstance(view, str):
        key = view.strip().lower()
        if key in VIEWS:
            return VIEWS[key]
        try:
            return float(key)
        except ValueError:
            raise ValueError(
                f"unknown view {view!r}: use one of {', '.join(VIEWS)} or a yaw in degrees"
            ) from None
    yaw = float(view)
    if not np.isfinite(yaw):
        raise ValueError(f"yaw must be finite, got {view!r}")
    return yaw


@dataclass(frozen=True)
class Camera:
    """An orthographic camera: rays start on a plane and all travel along ``forward``."""

    framing: Framing
    yaw: float = 0.0
    pitch: float = 0.0

    def __post_init__(self) -> None:
        if not np.isfinite(self.yaw):
            raise ValueError(f"Camera.yaw must be finite, got {self.yaw!r}")
        if not (np.isfinite(self.pitch) and abs(self.pitch) <= MAX_PITCH):
            raise ValueError(f"Camera.pitch={self.pitch!r} must be within +-{MAX_PITCH} degrees")

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, forward) unit vectors in world space."""
        p = np.radians(self.pitch)
        cp, sp = np.cos(p), np.sin(p)
        horiz = view_direction(self.yaw)
        right = np.array([horiz[1], -horiz[0], 0.0])
        forward = cp * horiz - sp * np.array([0.0, 0.0, 1.0])
        up = sp * horiz + cp * np.array([0.0, 0.0, 1.0])
        return right, up, forward

    def rays(self, size: int, supersample: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Ray origins ``(3, n)`` float32 (row-major over the ``size*ss`` square grid,
        top row first) and the common direction ``(3,)``.

        Sub-pixel samples are a regular ``ss x ss`` grid, so results are deterministic.
        """
        size, ss = check_size(size), int(supersample)
        if ss < 1:
            raise ValueError(f"supersample must be >= 1, got {supersample!r}")
        n = size * ss
        right, up, forward = self.basis()
        s = self.framing.span
        t = ((np.arange(n, dtype=np.float64) + 0.5) / n - 0.5) * s
        x = t[None, :]  # columns left -> right
        y = -t[:, None]  # rows top -> bottom
        back = 2.0 * s + 1.0  # start well outside the tree's bounding sphere
        o0 = self.framing.centre - back * forward
        origins = (
            o0[:, None, None] + right[:, None, None] * x[None] + up[:, None, None] * y[None]
        ).reshape(3, -1)
        return np.ascontiguousarray(origins, dtype=np.float32), forward

    def project(self, points: np.ndarray, size: int) -> np.ndarray:
        """World points ``(n, 3)`` -> pixel coordinates ``(n, 2)`` as (column, row)."""
        right, up, _ = self.basis()
        d = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.framing.centre
        s = self.framing.span
        col = (d @ right / s + 0.5) * size
        row = (0.5 - d @ up / s) * size
        return np.stack([col, row], axis=1)


def check_size(size: int) -> int:
    if isinstance(size, bool) or int(size) != size or not 8 <= int(size) <= 4096:
        raise ValueError(f"image size must be an integer in [8, 4096], got {size!r}")
    return int(size)
