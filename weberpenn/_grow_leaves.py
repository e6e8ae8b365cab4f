"""Leaf placement for :mod:`weberpenn.grow` (Sapling's ``genLeafMesh``, as transforms).

Sapling's leaf template lies in its local XZ plane (length along +Z); the Skeleton
contract's template lies in XY (length along +Y), so every matrix ends with a quarter
turn about X that takes the contract's template onto Sapling's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ._grow_math import mat_x, mat_y, mat_z


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
        if rotate < 0.0:
            before = _alternate(0.0, step, c + 1)
            old_before, old_after = before[:-1], before[1:]
        else:
            old_before = np.arange(c) * step
            old_after = old_before + step
        rot_mat = mat_z(old_before)
        offset = cp.offset
        dv = -down_v * offset if down_v > 0.0 else np.full(c, down_v)
        down_mat = mat_x(down + dv)
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
        old_before = np.tile(ob, c)
        old_after = np.tile(oa, c)
        rot_mat = mat_y(np.zeros_like(old_before) if (nl == 1 and rotate >= 0.0) else old_before)
        offset = cp.offset[src]
        down_mat = None
        if nl > 1 and rotate != 0.0:
            f = 1.0 - np.abs((old_after - rotate / (nl - 1)) / (rotate / 2.0))
        else:
            f = offset

    s = scale * (1.0 - (1.0 - f) * -scale_t) if scale_t < 0.0 else scale * (1.0 - f * scale_t)
    s = s * scale_v
    n = len(src)
    sm = np.zeros((n, 3, 3))
    sm[:, 0, 0] = scale_x * s
    sm[:, 1, 1] = s
    sm[:, 2, 2] = s
    # template of the Skeleton contract (XY plane) -> Sapling's (XZ plane)
    m = sm @ mat_x(np.full(n, math.pi / 2.0))
    m = mat_z(np.full(n, math.pi)) @ m
    m = mat_x(np.full(n, -leafangle)) @ m
    if rotate < 0.0:
        m = mat_z(np.full(n, math.pi / 2.0)) @ m
        m = np.where((old_after < 0.0)[:, None, None], mat_z(np.full(n, math.pi)) @ m, m)
    if leaves > 0 and rotate > 0.0 and horz:
        m = mat_z(-old_after + rotate) @ m
    if down_mat is not None:
        m = down_mat @ m
    m = rot_mat @ m
    m = cp.frame[src] @ m
    return np.ascontiguousarray(cp.co[src], dtype=np.float64), np.ascontiguousarray(m)
