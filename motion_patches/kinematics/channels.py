# SPDX-License-Identifier: GPL-3.0-or-later
"""Rotation modes: quaternions as the channels a bone of any ``rotation_mode`` plays.

The core works in quaternions; a pose bone plays only the channel of its own mode
(``rotation_quaternion``; ``rotation_euler`` in one of six orders; ``rotation_axis_angle``
as angle, then axis). :func:`rotation_channels` turns quaternions into the values of any
mode, continuous over frames, and :func:`channels_to_quat` goes back; both agree with
``mathutils`` (Blender's ``'XYZ'`` applies X first: R = Rz Ry Rx). Pure numpy, so the keys of
a character can be fitted where there is no Blender (a Dask worker).
"""

import numpy as np
from numpy.typing import ArrayLike

from . import quat

EULER_ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")


_AXES = {"X": 0, "Y": 1, "Z": 2}


_TWO_PI = 2.0 * np.pi


def rotation_path(mode: str) -> str:
    """The pose bone property a ``rotation_mode`` plays."""
    if mode == "QUATERNION":
        return "rotation_quaternion"
    if mode == "AXIS_ANGLE":
        return "rotation_axis_angle"
    if mode in EULER_ORDERS:
        return "rotation_euler"
    raise ValueError(f"unknown rotation mode {mode!r}")


def rest_channels(mode: str) -> np.ndarray:
    """Values of a ``mode``'s channel in the rest pose (Blender's defaults)."""
    if mode == "QUATERNION":
        return np.array([1.0, 0.0, 0.0, 0.0])
    if mode == "AXIS_ANGLE":
        return np.array([0.0, 0.0, 1.0, 0.0])  # angle 0 about +Y
    rotation_path(mode)
    return np.zeros(3)


def euler_to_quat(e: ArrayLike, order: str) -> np.ndarray:
    """Quaternions of Blender Euler angles (..., 3) in rotation ``order`` (e.g. 'XYZ')."""
    e = np.asarray(e, float)
    q = np.zeros(e.shape[:-1] + (4,))
    q[..., 0] = 1.0
    for ax in order:  # Blender's 'XYZ' applies X first: R = Rz Ry Rx
        i = _AXES[ax]
        half = e[..., i] * 0.5
        a = np.zeros(e.shape[:-1] + (4,))
        a[..., 0] = np.cos(half)
        a[..., 1 + i] = np.sin(half)
        q = quat.mul(a, q)
    return q


def axis_angle_to_quat(aa: ArrayLike) -> np.ndarray:
    """Quaternions of Blender axis-angle values (..., 4) = (angle, x, y, z); the axis need
    not be unit (Blender normalises it; a zero axis is no rotation)."""
    aa = np.asarray(aa, float)
    axis = aa[..., 1:]
    n = np.linalg.norm(axis, axis=-1, keepdims=True)
    half = 0.5 * aa[..., :1]
    unit = np.where(n > 1e-12, axis / np.maximum(n, 1e-12), 0.0)
    q = np.concatenate((np.cos(half), np.sin(half) * unit), axis=-1)
    return np.where(n > 1e-12, q, np.array([1.0, 0.0, 0.0, 0.0]))


def channels_to_quat(values: np.ndarray, mode: str) -> np.ndarray:
    """Unit quaternions (..., 4) of a ``mode``'s channel values (..., 3 or 4)."""
    if mode == "QUATERNION":
        return quat.normalize(values)
    if mode == "AXIS_ANGLE":
        return axis_angle_to_quat(values)
    rotation_path(mode)
    return euler_to_quat(values, mode)


def _wrap_near(angle, ref):
    """``angle`` plus the whole turns that bring it within half a turn of ``ref``."""
    return angle + _TWO_PI * np.round((ref - angle) / _TWO_PI)


def _euler_pair(q, order):
    """The two Euler triples (..., 3) in ``order`` of each quaternion (Blender's
    ``mat3_normalized_to_eulo2``: the second takes the middle angle past 90 degrees)."""
    i, j, k = (_AXES[a] for a in order)
    odd = (i, j, k) not in ((0, 1, 2), (1, 2, 0), (2, 0, 1))
    m = quat.to_matrix(q)  # m[..., row, col]

    def at(r, c):
        return m[..., r, c]

    cy = np.hypot(at(i, i), at(j, i))
    e1 = np.empty(np.shape(cy) + (3,))
    e2 = np.empty_like(e1)
    e1[..., i] = np.arctan2(at(k, j), at(k, k))
    e1[..., j] = np.arctan2(-at(k, i), cy)
    e1[..., k] = np.arctan2(at(j, i), at(i, i))
    e2[..., i] = np.arctan2(-at(k, j), -at(k, k))
    e2[..., j] = np.arctan2(-at(k, i), -cy)
    e2[..., k] = np.arctan2(-at(j, i), -at(i, i))
    lock = cy < 1e-9  # gimbal lock: the first and last axes coincide; put it all on the first
    if np.any(lock):
        g = np.zeros_like(e1)
        g[..., i] = np.arctan2(-at(j, k), at(j, j))
        g[..., j] = e1[..., j]
        e1 = np.where(lock[..., None], g, e1)
        e2 = np.where(lock[..., None], g, e2)
    return (-e1, -e2) if odd else (e1, e2)


# A quaternion channel is keyed with one component held at 1 (each frame's quaternion divided
# by it): Blender normalises a pose bone's quaternion before it plays it, so the rotation is
# the same, and that component's curve is one key instead of a sample a frame (a quarter of a
# quaternion bone's bytes). A bone holds the component that stays largest against the
# quaternion's length over the action, if it stays at least this large (w for a bone turning
# less than 120 degrees from rest); under it the others, divided by it, grow fast, and the
# bone keeps its unit quaternion.
HELD = 0.5


def held_channels(q: ArrayLike) -> np.ndarray:
    """Quaternion channels (F, ..., 4) of ``q`` keyed with one component held at exactly 1
    (:data:`HELD`): the rotations Blender plays are the same. A bone (a position of the
    axes between the first and last) none of whose components stays at least
    :data:`HELD` of the length on every frame is left as given."""
    q = np.asarray(q, float)
    if not q.shape[0]:
        return q
    ratio = np.abs(q) / np.linalg.norm(q, axis=-1, keepdims=True)
    least = ratio.min(axis=0)  # (..., 4) each component's smallest share
    k = np.argmax(least, axis=-1)[..., None]  # (..., 1) the one held
    held = np.take_along_axis(least, k, axis=-1) >= HELD
    by = np.take_along_axis(q, np.broadcast_to(k, q.shape[:-1] + (1,)), axis=-1)
    return np.where(held, q / np.where(held, by, 1.0), q)


def matching_channels(q: np.ndarray, mode: str, reference: ArrayLike) -> np.ndarray:
    """:func:`closest_channels` of ``q`` for a correction added to ``reference`` (the sum
    plays ``q``: Blender normalises it): a quaternion is scaled to take the reference's
    value in one component, so that component's correction is zero (its curve one key):
    the component the reference holds at 1 (:func:`held_channels`: it reads exactly +-1),
    else w. Where either's share of it is under :data:`HELD`, the sign nearest."""
    near = closest_channels(q, mode, reference)
    if mode != "QUATERNION":
        return near
    ref = np.broadcast_to(np.asarray(reference, float), near.shape)
    k = np.argmax(np.abs(ref) == 1.0, axis=-1)[..., None]  # none exact: 0, w
    ref_k = np.take_along_axis(ref, k, axis=-1)
    near_k = np.take_along_axis(near, k, axis=-1)
    ok = (np.abs(near_k) >= HELD) & (
        np.abs(ref_k) >= HELD * np.linalg.norm(ref, axis=-1, keepdims=True)
    )
    scaled = near * (ref_k / np.where(ok, near_k, 1.0))
    np.put_along_axis(scaled, k, ref_k, axis=-1)  # exactly: that correction is zero
    return np.where(ok, scaled, near)


def closest_channels(q: np.ndarray, mode: str, reference: ArrayLike) -> np.ndarray:
    """Channel values of ``mode`` for quaternions ``q`` (..., 4), each the representation of
    its rotation nearest ``reference`` (same leading shape): quaternion sign, Euler triple
    (either solution, any whole turns per angle), axis-angle (axis sign, whole turns)."""
    q = quat.normalize(q)
    ref = np.asarray(reference, float)
    if mode == "QUATERNION":
        return np.where(np.sum(q * ref, axis=-1, keepdims=True) < 0, -q, q)
    if mode == "AXIS_ANGLE":
        angle, v, s, ref_axis = _axis_angle(q, ref)
        axis = np.where(s > 1e-12, v / np.maximum(s, 1e-12), ref_axis)  # no rotation: any axis
        flip = np.sum(axis * ref_axis, axis=-1) < 0
        axis = np.where(flip[..., None], -axis, axis)
        angle = _wrap_near(np.where(flip, -angle, angle), ref[..., 0])
        return np.concatenate((angle[..., None], axis), axis=-1)
    pair = [_wrap_near(e, ref) for e in _euler_pair(q, mode)]
    d = [np.sum(np.abs(e - ref), axis=-1, keepdims=True) for e in pair]
    return np.where(d[1] < d[0], pair[1], pair[0])


def rotation_channels(q: ArrayLike, mode: str, first: np.ndarray | None = None) -> np.ndarray:
    """Channel values (F, ..., 3 or 4) of ``mode`` for quaternions ``q`` (F, ..., 4), made
    continuous over frames (axis 0): each frame takes the representation nearest the
    previous one, so no key jumps by a turn, flips an Euler solution or an axis-angle
    axis. The first frame is nearest ``first`` (default: the rest values).

    Vectorised over frames: the frame-by-frame choice (:func:`closest_channels` of each
    frame against the last) depends only on which Euler solution, or which axis sign, the
    last frame took, never on its whole turns; so the choices are a chain of two-state
    steps (:func:`_chained_choice`, :func:`quat.make_continuous`) and the turns a
    cumulative sum of each step's nearest whole turn (:func:`_continuous_turns`)."""
    q = np.asarray(q, float)
    rest = rest_channels(mode)
    prev = np.broadcast_to(rest if first is None else first, q.shape[1:-1] + rest.shape)
    if mode == "QUATERNION":
        return quat.make_continuous(closest_channels(q, mode, np.broadcast_to(prev, q.shape)))
    if q.shape[0] == 0:
        return np.empty(q.shape[:-1] + rest.shape)
    if mode == "AXIS_ANGLE":
        return _continuous_axis_angle(quat.normalize(q), prev)
    rotation_path(mode)
    pair = np.stack(_euler_pair(quat.normalize(q), mode))  # (2, F, ..., 3) principal
    # distance of solution a on frame f to solution b on frame f - 1, angles wrapped
    step = np.stack(
        [np.sum(np.abs(_turn(pair[b, :-1] - pair[:, 1:])), axis=-1) for b in (0, 1)], axis=1
    )  # (2 a, 2 b, F - 1, ...)
    start = np.sum(np.abs(_turn(prev - pair[:, 0])), axis=-1)  # (2, ...)
    choice = _chained_choice(start[1] < start[0], step[1] < step[0])  # (F, ...) bool
    chosen = np.where(choice[..., None], pair[1], pair[0])
    return _continuous_turns(chosen, prev)


def _turn(x):
    """``x`` less the whole turns nearest it: the wrapped difference, in [-pi, pi]."""
    return x - _TWO_PI * np.round(x / _TWO_PI)


def _chained_choice(first, takes):
    """(F, ...) bool: frame 0 takes ``first``; frame f takes ``takes[:, f - 1]`` (2, F - 1,
    ...) at the index of what frame f - 1 took (a two-state chain, composed in log2(F)
    doubling passes instead of a loop over frames)."""
    # map of each step: what frame f takes if frame f - 1 took False (m0) or True (m1)
    m0 = np.concatenate((first[None], takes[0]))
    m1 = np.concatenate((first[None], takes[1]))
    # frame 0's map is constant (it takes ``first`` whatever came before)
    n, span = m0.shape[0], 1
    while span < n:
        # compose each map with the one ``span`` frames before it
        p0, p1 = m0[:-span], m1[:-span]
        m0[span:], m1[span:] = (
            np.where(p0, m1[span:], m0[span:]),
            np.where(p1, m1[span:], m0[span:]),
        )
        span *= 2
    return m0  # frame 0's map is constant, so every composed map is too


def _continuous_turns(values, first):
    """``values`` (F, ..., C) plus the whole turns that bring each frame within half a turn
    of the frame before (the first of ``first``): :func:`_wrap_near` frame by frame."""
    turns = np.round((first - values[0]) / _TWO_PI)[None]
    steps = np.round((values[:-1] - values[1:]) / _TWO_PI)
    return values + _TWO_PI * np.cumsum(np.concatenate((turns, steps)), axis=0)


def _axis_angle(q, reference):
    """Angle (...), vector part (..., 3) and its length (..., 1) of unit quaternions ``q``,
    and the unit axis of the axis-angle channels ``reference`` (+Y where it has none)."""
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s[..., 0], q[..., 0])
    ref = reference[..., 1:]
    rn = np.linalg.norm(ref, axis=-1, keepdims=True)
    return angle, v, s, np.where(rn > 1e-12, ref / np.maximum(rn, 1e-12), [0.0, 1.0, 0.0])


def _continuous_axis_angle(q, first):
    """Axis-angle channels (F, ..., 4) of unit quaternions ``q``, continuous from
    ``first``: each axis takes the sign nearest the last frame's (a frame with no
    rotation keeps the last axis), each angle follows its axis's sign and the turns
    nearest the last angle."""
    angle, v, s, ref = _axis_angle(q, first)
    has = s[..., 0] > 1e-12
    axis = np.where(has[..., None], v / np.maximum(s, 1e-12), 0.0)
    # a frame without an axis carries the last one on (or ``first``'s, before any)
    axes = np.concatenate((ref[None], axis))
    idx = np.arange(axes.shape[0]).reshape((-1,) + (1,) * (axes.ndim - 2))
    last = np.maximum.accumulate(np.where(np.concatenate((np.ones_like(has[:1]), has)), idx, 0))
    axes = np.take_along_axis(axes, last[..., None], axis=0)
    signed = quat.make_continuous(axes, axis=0)[1:]  # each sign nearest the one before
    flip = has & (np.sum(signed * axes[1:], axis=-1) < 0)  # a carried axis is not flipped
    angle = np.where(flip, -angle, angle)
    values = np.concatenate((angle[..., None], signed), axis=-1)
    values[..., 0] = _continuous_turns(values[..., :1], first[..., :1])[..., 0]
    return values
