"""Leaf placement for :mod:`weberpenn.grow` (Sapling's ``genLeafMesh``, as transforms).

Sapling's leaf template lies in its local XZ plane (length along +Z); the Skeleton
contract's template lies in XY (length along +Y), so every matrix ends with a quarter
turn about X that takes the contract's template onto Sapling's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numba
import numpy as np

from ._grow_math import mat_x, mat_z, run_rank

# Per-leaf matrices are built in "structure of arrays" form, (3, 3, L): much faster than
# numpy's batched matmul on tiny 3x3 matrices.


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.array([[c, -s, z], [s, c, z], [z, z, o]])


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.array([[o, z, z], [z, c, -s], [z, s, c]])


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.array([[c, z, s], [z, o, z], [-s, z, c]])


def _zxz(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Rz(a) @ Rx(b) @ Rz(c) in closed form."""
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    return np.array(
        [
            [ca * cc - sa * cb * sc, -ca * sc - sa * cb * cc, sa * sb],
            [sa * cc + ca * cb * sc, -sa * sc + ca * cb * cc, -ca * sb],
            [sb * sc, sb * cc, cb],
        ]
    )


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Product of two stacks of 3x3 matrices in (3, 3, L) layout (either may be (3, 3))."""
    a3 = a if a.ndim == 3 else a[:, :, None]
    b3 = b if b.ndim == 3 else b[:, :, None]
    la, lb = a3.shape[2], b3.shape[2]
    if a.dtype == b.dtype == np.float64 and a.ndim + b.ndim > 4 and (la == lb or 1 in (la, lb)):
        return _mul_stacks(a3, b3)
    out = np.empty((3, 3) + np.broadcast_shapes(a.shape[2:], b.shape[2:]))
    for i in range(3):
        for k in range(3):
            out[i, k] = a[i, 0] * b[0, k] + a[i, 1] * b[1, k] + a[i, 2] * b[2, k]
    return out


@numba.njit(cache=True)
def _mul_stacks(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`_mul` of two stacks of L or of L and one (L may be 0), compiled: each entry
    summed in numpy's order (the first two products, then the third), so the same
    floats, in one pass instead of 27 over arrays of 10^4 leaves."""
    la, lb = a.shape[2], b.shape[2]
    n = la if lb == 1 else lb  # numpy's broadcast: a stack of one goes with any, none too
    out = np.empty((3, 3, n))
    for i in range(3):
        for k in range(3):
            for m in range(n):
                p = m if la > 1 else 0
                q = m if lb > 1 else 0
                t = a[i, 0, p] * b[0, k, q] + a[i, 1, p] * b[1, k, q]
                out[i, k, m] = t + a[i, 2, p] * b[2, k, q]
    return out


def _alternate(first: float, step: float, count: int) -> np.ndarray:
    """Values of Sapling's ``old = -copysign(step, old)`` recurrence before each update."""
    out = np.empty(count)
    old = first
    for i in range(min(count, 2)):
        out[i] = old
        old = -math.copysign(step, old)
    if count > 2:
        # from the second value on the sequence strictly alternates
        i = np.arange(2, count)
        out[2:] = np.where((i - 1) % 2 == 0, out[1], -out[1])
    return out


def leaf_transforms(p: Mapping[str, Any], cp: Any) -> tuple[np.ndarray, np.ndarray]:
    """Positions (L, 3) and matrices (L, 3, 3) of every leaf at the last level's child points."""
    leaves = int(p["leaves"])
    c = len(cp.offset)
    if leaves == 0 or c == 0:
        return np.zeros((0, 3)), np.zeros((0, 3, 3))
    rotate = math.radians(float(p["leafRotate"]))
    rot_v = math.radians(float(p["leafRotateV"]))
    down = math.radians(float(p["leafDownAngle"]))
    down_v = math.radians(float(p["leafDownAngleV"]))
    leafangle = math.radians(float(p["leafangle"]))
    scale = float(p["leafScale"])
    scale_x = float(p["leafScaleX"])
    scale_t = float(p["leafScaleT"])
    scale_v = float(p["leafScaleV"])
    horz = bool(p["horzLeaves"])

    if leaves > 0:
        src = np.arange(c)
        step = rotate + rot_v
        # the azimuth accumulates along each stem (Sapling: along the whole tree, so a
        # small change of leafRotateV turned the thousandth leaf a thousand times as far)
        i = run_rank(cp.src)
        if rotate < 0.0:
            before = _alternate(0.0, step, int(i.max()) + 2)
            old_before, old_after = before[i], before[i + 1]
        else:
            old_before = i * step
            old_after = old_before + step
        offset = cp.offset
        dv = -down_v * offset if down_v > 0.0 else np.full(c, down_v)
        f = offset
    else:
        nl = -leaves
        src = np.repeat(np.arange(c), nl)
        if rotate < 0.0:
            seq = _alternate(-rotate / 2.0, rotate + rot_v, nl + 1)
            ob, oa = seq[:-1], seq[1:]
        elif nl == 1:
            ob = np.array([-rotate / 2.0])
            oa = ob.copy()
        else:
            ob = -rotate / 2.0 + np.arange(nl) * (rotate / (nl - 1))
            oa = ob + rotate / (nl - 1)
        if nl == 1 and rotate >= 0.0:
            ob = np.zeros(1)  # Sapling: a single leaf is not turned
        old_before = np.tile(ob, c)
        old_after = np.tile(oa, c)
        offset = cp.offset[src]
        if nl > 1 and abs(rotate) > 1e-9:  # (Sapling: rotate != 0; tiny values overflow)
            f = 1.0 - np.abs((old_after - rotate / (nl - 1)) / (rotate / 2.0))
        else:
            f = offset

    s = scale * (1.0 - (1.0 - f) * -scale_t) if scale_t < 0.0 else scale * (1.0 - f * scale_t)
    s = s * scale_v
    n = len(src)
    # constant right-hand part: contract template (XY) -> Sapling's (XZ plane), width,
    # half a turn about Z, then the leafangle tilt
    k = np.diag([scale_x, 1.0, 1.0]) @ mat_x(math.pi / 2.0)
    k = mat_x(-leafangle) @ mat_z(math.pi) @ k
    # one more turn about Z per leaf: Sapling's flip for rotate < 0, or the horizontal fix
    if rotate < 0.0:
        cz = math.pi / 2.0 + np.where(old_after < 0.0, math.pi, 0.0)
    elif leaves > 0 and rotate > 0.0 and horz:
        cz = rotate - old_after
    else:
        cz = np.zeros(n)
    if leaves > 0:
        m = _mul(_zxz(old_before, down + dv, cz), k)
    elif rotate < 0.0:
        m = _mul(_ry(old_before), _mul(_rz(cz), k))
    else:
        m = _mul(_ry(old_before), k)
    frames = np.moveaxis(cp.frame, 0, -1)
    if leaves < 0:
        frames = frames[:, :, src]
    m = _mul(frames, m) * s
    return np.ascontiguousarray(cp.co[src], dtype=np.float64), np.ascontiguousarray(
        np.moveaxis(m, -1, 0)
    )
