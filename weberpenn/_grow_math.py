"""Vectorised rotation helpers for :mod:`weberpenn.grow` (Blender conventions, matrix form).

Every function works on batches: vectors are ``(N, 3)`` arrays, frames are ``(N, 3, 3)``
rotation matrices whose columns are the images of the local X, Y and Z axes (so
``frame @ v`` takes a local vector to world space, like ``v.rotate(quat)`` in Blender).
Rotations are right-handed, as Blender's ``Matrix.Rotation(angle, 3, axis)``.
"""

from __future__ import annotations

import numpy as np

TAU = 2.0 * np.pi
_FLT_EPS16 = 16.0 * float(np.finfo(np.float32).eps)


def run_rank(ids: np.ndarray) -> np.ndarray:
    """Position of each element within its run of equal consecutive ``ids`` (0, 1, ...)."""
    ids = np.asarray(ids)
    if len(ids) == 0:
        return np.zeros(0, dtype=np.int64)
    new_run = np.concatenate([[True], ids[1:] != ids[:-1]])
    starts = np.nonzero(new_run)[0]
    return np.arange(len(ids)) - starts[np.cumsum(new_run) - 1]


def normalize(v: np.ndarray) -> np.ndarray:
    """Unit vectors (zero vectors stay zero)."""
    n = np.sqrt(np.einsum("ij,ij->i", v, v))
    return v / np.where(n > 0.0, n, 1.0)[:, None]


def rot_x(v: np.ndarray, a: np.ndarray | float) -> np.ndarray:
    """Rotate vectors about the X axis by angles ``a``."""
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    out = np.empty((len(v), 3))
    out[:, 0] = x + 0.0 * c
    out[:, 1] = c * y - s * z
    out[:, 2] = s * y + c * z
    return out


def rot_y(v: np.ndarray, a: np.ndarray | float) -> np.ndarray:
    """Rotate vectors about the Y axis by angles ``a``."""
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    out = np.empty((len(v), 3))
    out[:, 0] = c * x + s * z
    out[:, 1] = y + 0.0 * c
    out[:, 2] = -s * x + c * z
    return out


def rot_z(v: np.ndarray, a: np.ndarray | float) -> np.ndarray:
    """Rotate vectors about the Z axis by angles ``a``."""
    c, s = np.cos(a), np.sin(a)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    out = np.empty((len(v), 3))
    out[:, 0] = c * x - s * y
    out[:, 1] = s * x + c * y
    out[:, 2] = z + 0.0 * c
    return out


def rot_axis(v: np.ndarray, axis: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Rotate vectors about (normalised) per-row axes by angles ``a`` (Rodrigues)."""
    k = normalize(axis)
    c, s = np.cos(a)[:, None], np.sin(a)[:, None]
    kv = np.einsum("ij,ij->i", k, v)[:, None]
    kx, ky, kz = k[:, 0], k[:, 1], k[:, 2]
    vx, vy, vz = v[:, 0], v[:, 1], v[:, 2]
    kxv = np.empty_like(v)  # k x v without np.cross's axis shuffling
    kxv[:, 0] = ky * vz - kz * vy
    kxv[:, 1] = kz * vx - kx * vz
    kxv[:, 2] = kx * vy - ky * vx
    return v * c + kxv * s + k * kv * (1.0 - c)


def apply(frames: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``frames[i] @ v[i]`` for every row."""
    return np.einsum("nij,nj->ni", frames, v)


def _mat_about(a: np.ndarray, axis: int) -> np.ndarray:
    """Batch of rotation matrices by angles ``a`` about coordinate ``axis`` (0, 1, 2)."""
    a = np.asarray(a, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    i, j = (axis + 1) % 3, (axis + 2) % 3  # the plane it turns, in right-handed order
    m = np.zeros(a.shape + (3, 3))
    m[..., axis, axis] = 1.0
    m[..., i, i], m[..., i, j] = c, -s
    m[..., j, i], m[..., j, j] = s, c
    return m


def mat_x(a: np.ndarray) -> np.ndarray:
    """Batch of rotation matrices about X."""
    return _mat_about(a, 0)


def mat_y(a: np.ndarray) -> np.ndarray:
    """Batch of rotation matrices about Y."""
    return _mat_about(a, 1)


def mat_z(a: np.ndarray) -> np.ndarray:
    """Batch of rotation matrices about Z."""
    return _mat_about(a, 2)


def quat_to_mat(w: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Rotation matrices of unit quaternions (w, x, y, z)."""
    m = np.empty(w.shape + (3, 3))
    m[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    m[..., 0, 1] = 2.0 * (x * y - w * z)
    m[..., 0, 2] = 2.0 * (x * z + w * y)
    m[..., 1, 0] = 2.0 * (x * y + w * z)
    m[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    m[..., 1, 2] = 2.0 * (y * z - w * x)
    m[..., 2, 0] = 2.0 * (x * z - w * y)
    m[..., 2, 1] = 2.0 * (y * z + w * x)
    m[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return m


def _track_closed_form(
    d: np.ndarray, special: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """X axis (N, 3), Y axis components (3 arrays) and Z axis components of the closed-form
    track frame: Z is ``d`` normalised, Y is world up made perpendicular to it, X = Y x Z.
    Rows marked ``special`` (near the vertical) get placeholder values."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    ln = np.sqrt(x * x + y * y + z * z)
    ln = np.where(special, 1.0, ln)
    zx, zy, zz = x / ln, y / ln, z / ln
    yx, yy, yz = -zz * zx, -zz * zy, 1.0 - zz * zz
    yl = np.sqrt(yx * yx + yy * yy + yz * yz)
    yl = np.where(special, 1.0, yl)
    yx, yy, yz = yx / yl, yy / yl, yz / yl
    ax = np.empty_like(d)
    ax[:, 0] = yy * zz - yz * zy
    ax[:, 1] = yz * zx - yx * zz
    ax[:, 2] = yx * zy - yy * zx
    return ax, np.stack([yx, yy, yz], axis=1), np.stack([zx, zy, zz], axis=1), yz


def _near_vertical(d: np.ndarray) -> np.ndarray:
    return (np.abs(d[:, 0]) + np.abs(d[:, 1])) < 1e-4


def track_frames(d: np.ndarray) -> np.ndarray:
    """Frames of ``Vector.to_track_quat('Z', 'Y')`` for each row of ``d``.

    Away from the vertical Blender's result is the frame whose Z is ``d`` and whose Y is
    world up made perpendicular to ``d``; that closed form is used there, and Blender's
    quaternion construction (:func:`_track_frames_exact`) near the vertical.
    """
    d = np.asarray(d, dtype=np.float64)
    special = _near_vertical(d)
    ax, ay, az, _ = _track_closed_form(d, special)
    m = np.stack([ax, ay, az], axis=2)
    if special.any():
        m[special] = _track_frames_exact(d[special])
    return m


def track_x_and_yz(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``track_frames(d)[:, :, 0]`` and ``track_frames(d)[:, 2, 1]`` without the full frames
    (the per-segment attraction step needs only these)."""
    d = np.asarray(d, dtype=np.float64)
    special = _near_vertical(d)
    if special.any():
        t = track_frames(d)
        return t[:, :, 0], t[:, 2, 1]
    ax, _, _, yz = _track_closed_form(d, special)
    return ax, yz


def _track_frames_exact(d: np.ndarray) -> np.ndarray:
    """Frames of ``Vector.to_track_quat('Z', 'Y')``, step by step as Blender computes them.

    Follows Blender's ``vec_to_quat`` step by step: the shortest rotation taking +Z to
    ``d`` (about a horizontal axis; +X when ``d`` is near vertical), then a twist about
    ``d`` that brings the local Y axis towards world up.  A zero vector gives the
    identity.  (For ``d`` exactly +Z the twist is half a turn, as in Blender.)
    """
    d = np.asarray(d, dtype=np.float64)
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    ln = np.sqrt(x * x + y * y + z * z)
    ok = ln > 0.0
    lns = np.where(ok, ln, 1.0)
    nx = -y
    ny = x.copy()
    small = (np.abs(x) + np.abs(y)) < 1e-4
    nx = np.where(small, 1.0, nx)
    nn = np.sqrt(nx * nx + ny * ny)
    nn = np.where(nn > 0.0, nn, 1.0)
    nx, ny = nx / nn, ny / nn
    half = 0.5 * np.arccos(np.clip(z / lns, -1.0, 1.0))
    s1 = np.sin(half)
    w1, x1, y1 = np.cos(half), nx * s1, ny * s1
    # image of +Z under q1 (third column of its matrix), as Blender's fp = mat[2]
    fx = 2.0 * (x1 * 0.0 + w1 * y1)
    fy = 2.0 * (y1 * 0.0 - w1 * x1)
    ang = -0.5 * np.arctan2(-fx, -fy)
    c2 = np.cos(ang)
    s2 = np.sin(ang) / lns
    w2, x2, y2, z2 = c2, x * s2, y * s2, z * s2
    # q = q2 * q1 (q1 has no z component)
    w = w2 * w1 - x2 * x1 - y2 * y1
    qx = w2 * x1 + x2 * w1 - z2 * y1
    qy = w2 * y1 + y2 * w1 + z2 * x1
    qz = x2 * y1 - y2 * x1 + z2 * w1
    m = quat_to_mat(w, qx, qy, qz)
    if not ok.all():
        m[~ok] = np.eye(3)
    return m


def declination(frames: np.ndarray) -> np.ndarray:
    """Angle (radians) between each frame's Z axis and world +Z."""
    return np.arccos(np.clip(frames[:, 2, 2], -1.0, 1.0))


def euler_frames_no_roll(d: np.ndarray) -> np.ndarray:
    """Sapling's trunk frame: Euler XYZ (-rx, ry, 0) pointing +Z along ``d`` (no roll)."""
    dn = normalize(d)
    zero = ~np.any(dn != 0.0, axis=1)
    if zero.any():
        dn[zero] = (0.0, 0.0, 1.0)
    ry = np.arctan2(dn[:, 0], dn[:, 2])
    az = dn[:, 0] * np.sin(ry) + dn[:, 2] * np.cos(ry)
    rx = np.arctan2(dn[:, 1], az)
    return mat_y(ry) @ mat_x(-rx)


def euler_to_mat(e: np.ndarray) -> np.ndarray:
    """Matrices of XYZ Euler angles (N, 3): Rz @ Ry @ Rx."""
    return mat_z(e[:, 2]) @ mat_y(e[:, 1]) @ mat_x(e[:, 0])


def _compatible_eul(e: np.ndarray, old: np.ndarray) -> np.ndarray:
    """Blender's ``compatible_eul``: move angles by whole turns towards ``old``."""
    e = e.copy()
    de = e - old
    hi = de > 5.1
    lo = de < -5.1
    if hi.any():
        e = np.where(hi, e - np.floor(de / TAU + 0.5) * TAU, e)
    if lo.any():
        e = np.where(lo, e + np.floor(-de / TAU + 0.5) * TAU, e)
    de = e - old
    ade = np.abs(de)
    big, small = ade > 3.2, ade < 1.6
    if not big.any():  # no flip can happen: skip the per-axis pass
        return e
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        flip = big[:, i] & small[:, j] & small[:, k]
        e[:, i] = np.where(flip, np.where(de[:, i] > 0.0, e[:, i] - TAU, e[:, i] + TAU), e[:, i])
    return e


def euler_compat(m: np.ndarray, compat_z: np.ndarray) -> np.ndarray:
    """``Quaternion.to_euler('XYZ', Euler((0, 0, compat_z)))`` for frames ``m``."""
    r00, r10, r20 = m[:, 0, 0], m[:, 1, 0], m[:, 2, 0]
    r21, r22, r12, r11 = m[:, 2, 1], m[:, 2, 2], m[:, 1, 2], m[:, 1, 1]
    cy = np.hypot(r00, r10)
    big = cy > _FLT_EPS16
    n = len(m)
    both = np.empty((2 * n, 3))  # both Euler solutions, made compatible in one batch
    e1, e2 = both[:n], both[n:]
    e1[:, 0] = np.where(big, np.arctan2(r21, r22), np.arctan2(-r12, r11))
    e1[:, 1] = np.arctan2(-r20, cy)
    e1[:, 2] = np.where(big, np.arctan2(r10, r00), 0.0)
    e2[:, 0] = np.where(big, np.arctan2(-r21, -r22), e1[:, 0])
    e2[:, 1] = np.where(big, np.arctan2(-r20, -cy), e1[:, 1])
    e2[:, 2] = np.where(big, np.arctan2(-r10, -r00), 0.0)
    old2 = np.zeros((2 * n, 3))
    old2[:n, 2] = compat_z
    old2[n:, 2] = compat_z
    both = _compatible_eul(both, old2)
    e1, e2, old = both[:n], both[n:], old2[:n]
    d1 = np.abs(e1 - old).sum(axis=1)
    d2 = np.abs(e2 - old).sum(axis=1)
    return np.where((d1 > d2)[:, None], e2, e1)


def anglemean(a1: np.ndarray, a2: np.ndarray, fac: np.ndarray | float) -> np.ndarray:
    """Sapling's blend of two azimuths through their unit vectors."""
    x1, y1 = np.sin(a1), np.cos(a1)
    x2, y2 = np.sin(a2), np.cos(a2)
    return np.arctan2(x1 + (x2 - x1) * fac, y1 + (y2 - y1) * fac)
