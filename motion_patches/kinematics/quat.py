# SPDX-License-Identifier: GPL-3.0-or-later
"""Quaternion helpers on numpy arrays (w, x, y, z order, as Blender stores them).

Every function is vectorised over leading axes so per-frame, per-joint data stays in
arrays; no per-frame Python objects.
"""

import numpy as np
from numpy.typing import ArrayLike


def normalize(q: np.ndarray) -> np.ndarray:
    """``q`` (..., N) scaled to unit length along its last axis. The squares are summed
    component by component, in order: the same sums as ``np.linalg.norm`` (bit for bit)
    at a third of its cost on short vectors."""
    q = np.asarray(q, dtype=float)
    parts = np.moveaxis(q, -1, 0)
    total = parts[0] * parts[0]
    for c in parts[1:]:
        total = total + c * c
    return q / np.sqrt(total)[..., None]


def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    a, b = np.asarray(a, float), np.asarray(b, float)
    aw, ax, ay, az = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bw, bx, by, bz = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bw - ax * bx - ay * by - az * bz
    out[..., 1] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 2] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 3] = aw * bz + ax * by - ay * bx + az * bw
    return out


def conj(q: np.ndarray) -> np.ndarray:
    q = np.asarray(q, float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4)."""
    w, x, y, z = np.moveaxis(normalize(q), -1, 0)
    m = np.empty(np.shape(w) + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - w * z)
    m[..., 0, 2] = 2 * (x * z + w * y)
    m[..., 1, 0] = 2 * (x * y + w * z)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - w * x)
    m[..., 2, 0] = 2 * (x * z - w * y)
    m[..., 2, 1] = 2 * (y * z + w * x)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) with w >= 0 from rotation matrices (..., 3, 3)."""
    m = np.asarray(m, float)
    shape = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    q = np.empty((m.shape[0], 4))
    tr = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    # Choose the numerically largest of w, x, y, z per matrix.
    cand = np.stack((tr, m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]), axis=1)
    k = np.argmax(cand, axis=1)
    for case in range(4):
        sel = k == case
        if not np.any(sel):
            continue
        r = m[sel]
        if case == 0:
            s = np.sqrt(1.0 + tr[sel]) * 2
            q[sel] = np.stack(
                (
                    0.25 * s,
                    (r[:, 2, 1] - r[:, 1, 2]) / s,
                    (r[:, 0, 2] - r[:, 2, 0]) / s,
                    (r[:, 1, 0] - r[:, 0, 1]) / s,
                ),
                1,
            )
        elif case == 1:
            s = np.sqrt(1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2]) * 2
            q[sel] = np.stack(
                (
                    (r[:, 2, 1] - r[:, 1, 2]) / s,
                    0.25 * s,
                    (r[:, 0, 1] + r[:, 1, 0]) / s,
                    (r[:, 0, 2] + r[:, 2, 0]) / s,
                ),
                1,
            )
        elif case == 2:
            s = np.sqrt(1.0 + r[:, 1, 1] - r[:, 0, 0] - r[:, 2, 2]) * 2
            q[sel] = np.stack(
                (
                    (r[:, 0, 2] - r[:, 2, 0]) / s,
                    (r[:, 0, 1] + r[:, 1, 0]) / s,
                    0.25 * s,
                    (r[:, 1, 2] + r[:, 2, 1]) / s,
                ),
                1,
            )
        else:
            s = np.sqrt(1.0 + r[:, 2, 2] - r[:, 0, 0] - r[:, 1, 1]) * 2
            q[sel] = np.stack(
                (
                    (r[:, 1, 0] - r[:, 0, 1]) / s,
                    (r[:, 0, 2] + r[:, 2, 0]) / s,
                    (r[:, 1, 2] + r[:, 2, 1]) / s,
                    0.25 * s,
                ),
                1,
            )
    q = normalize(q)
    q[q[:, 0] < 0] *= -1
    return q.reshape(shape + (4,))


def about_z(angle: ArrayLike) -> np.ndarray:
    """Quaternions of rotations by ``angle`` (radians) about +Z."""
    a = np.asarray(angle, float) * 0.5
    z = np.zeros_like(a)
    return np.stack((np.cos(a), z, z, np.sin(a)), axis=-1)


def make_continuous(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Flip signs along ``axis`` so consecutive quaternions lie in one hemisphere.

    Blender interpolates quaternion channels component-wise, so a sign flip between keys
    would swing the bone through a wrong pose; this keeps keyed curves smooth.
    """
    q = np.array(q, float)
    if q.size == 0:  # no joint: nothing to flip
        return q
    q = np.moveaxis(q, axis, 0)
    if q.shape[0] < 2:
        return np.moveaxis(q, 0, axis)
    # Frame i flips when an odd number of the steps since the last step with a zero dot
    # product (which keeps its sign) have a negative one: the loop "flip q[i] when it
    # points away from the flipped q[i-1]" as cumulative sums.
    d = np.sum(q[1:] * q[:-1], axis=-1)
    if not (d < 0).any():  # already continuous (most channels): nothing flips
        return np.moveaxis(q, 0, axis)
    flips = np.concatenate((np.zeros((1,) + d.shape[1:], int), np.cumsum(d < 0, axis=0)))
    idx = np.arange(q.shape[0]).reshape((-1,) + (1,) * (d.ndim - 1))
    zero = np.concatenate((np.ones((1,) + d.shape[1:], bool), d == 0))
    last = np.maximum.accumulate(np.where(zero, idx, 0), axis=0)
    odd = (flips - np.take_along_axis(flips, last, axis=0)) % 2 == 1
    q[odd] *= -1
    return np.moveaxis(q, 0, axis)


def slerp(a: np.ndarray, b: np.ndarray, t: ArrayLike) -> np.ndarray:
    """Spherical interpolation, t broadcast over leading axes (shortest arc)."""
    if np.size(a) == 0:  # no joint (a motion measured without its body): nothing to do
        return np.zeros(np.broadcast_shapes(np.shape(a), np.shape(b)))
    a = normalize(a)
    b = normalize(b)
    t = np.asarray(t, float)
    # Per quaternion, component by component: the same sums as summing the last axis
    # (see :func:`normalize`), without broadcasting (..., 1) weights over (..., 4) arrays
    # (numpy's slowest case: half the time of a slerp went there).
    d = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]
    d = d + a[..., 3] * b[..., 3]
    away = d < 0
    if away.any():  # (skipped where it would change nothing)
        b = np.where(away[..., None], -b, b)
        d = np.abs(d)
    close = d > 0.9995
    theta = np.arccos(np.clip(d, -1.0, 1.0))
    s = np.sin(theta)
    s = np.where(close, 1.0, s)
    wa = np.where(close, 1.0 - t, np.sin((1.0 - t) * theta) / s)
    wb = np.where(close, t, np.sin(t * theta) / s)
    shape = np.broadcast_shapes(wa.shape, a.shape[:-1], b.shape[:-1])
    out = np.empty(shape + (4,))
    for k in range(4):
        out[..., k] = wa * a[..., k] + wb * b[..., k]
    return normalize(out)


def log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) (axis * angle) of unit quaternions."""
    q = normalize(q)
    q = np.where(q[..., :1] < 0, -q, q)
    v = q[..., 1:]
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    ang = 2.0 * np.arctan2(n, q[..., :1])
    scale = np.where(n > 1e-12, ang / np.maximum(n, 1e-12), 2.0)
    return v * scale


def exp(r: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation vectors (..., 3)."""
    r = np.asarray(r, float)
    ang = np.linalg.norm(r, axis=-1, keepdims=True)
    half = 0.5 * ang
    k = np.where(ang > 1e-12, np.sin(half) / np.maximum(ang, 1e-12), 0.5)
    return np.concatenate((np.cos(half), r * k), axis=-1)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angle (radians) taking a to b, shortest arc."""
    d = np.abs(np.sum(normalize(a) * normalize(b), axis=-1))
    return 2.0 * np.arccos(np.clip(d, 0.0, 1.0))
