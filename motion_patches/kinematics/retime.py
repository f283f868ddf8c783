# SPDX-License-Identifier: GPL-3.0-or-later
"""Starts and stops: a planned walk eased in from standing and out to standing.

Space-curve following plays the gait at its recorded pace, so a plan would start and stop
at full walking speed. There is no recorded start or stop clip for the walking subject, so
the first and last locomotion pieces are time-warped instead: the same frames of the same
motion are played slower, the playback rate rising from nearly zero to the recorded pace
over the first piece and falling back over the last one. A time warp keeps the relation
between the root on its curve and the pose, so a planted foot stays planted (it is planted
for the same stretch of the gait, only for longer). The rate follows a smoothstep, so speed
and acceleration are continuous where the warped piece meets the next one.
"""

import numpy as np

from . import quat
from .motion import Motion

MIN_RATE = 0.04  # playback rate on the first / last frame (of the recorded pace)


def warp_phases(
    frames: int,
    ease_in: bool = False,
    ease_out: bool = False,
    ramp: float | None = None,
    min_rate: float = MIN_RATE,
) -> np.ndarray:
    """Fractional frame positions (K,) at which to sample a motion of ``frames`` frames so
    that its playback rate rises from ``min_rate`` to 1 over ``ramp`` frames of time
    (``ease_in``) and / or falls back to ``min_rate`` over the last ``ramp`` (``ease_out``);
    a smoothstep in time, 1 in between. The first and last positions are 0 and frames - 1.
    A piece too short for full ramps gets shorter ones."""
    span = float(frames - 1)
    if span <= 0 or not (ease_in or ease_out):
        return np.arange(frames, dtype=float)
    ramps = int(ease_in) + int(ease_out)
    ramp = float(ramp if ramp is not None else span)
    area = 0.5 * (1.0 + min_rate)  # phase covered per frame of a ramp
    ramp = min(ramp, span / (ramps * area))
    plateau = span - ramps * ramp * area
    total = ramps * ramp + plateau
    t = np.linspace(0.0, total, max(int(total * 8), 64) + 1)
    rate = np.ones_like(t)
    if ease_in:
        a = np.clip(t / ramp, 0.0, 1.0)
        rate = np.minimum(rate, min_rate + (1.0 - min_rate) * a * a * (3.0 - 2.0 * a))
    if ease_out:
        a = np.clip((total - t) / ramp, 0.0, 1.0)
        rate = np.minimum(rate, min_rate + (1.0 - min_rate) * a * a * (3.0 - 2.0 * a))
    x = np.concatenate(([0.0], np.cumsum(np.diff(t) * 0.5 * (rate[1:] + rate[:-1]))))
    x *= span / x[-1]
    count = max(int(np.ceil(total - 1e-9)), 1)
    u = np.interp(np.linspace(0.0, total, count + 1), t, x)
    u[0], u[-1] = 0.0, span
    return u


def resample(motion: Motion, u: np.ndarray) -> Motion:
    """The motion sampled at fractional frame positions ``u`` (K,): ground and root
    linear, rotations slerped between neighbouring frames, contacts of the nearer frame."""
    lo = np.clip(np.floor(u).astype(int), 0, motion.frames - 1)
    hi = np.minimum(lo + 1, motion.frames - 1)
    w = (u - lo)[:, None]
    g0, g1 = motion.ground[lo], motion.ground[hi]
    dh = (g1[:, 2] - g0[:, 2] + np.pi) % (2 * np.pi) - np.pi
    ground = g0 + w * (g1 - g0)
    ground[:, 2] = g0[:, 2] + w[:, 0] * dh
    root = motion.root_local[lo] + w * (motion.root_local[hi] - motion.root_local[lo])
    joints = motion.rotations.shape[1]
    rot = quat.slerp(motion.rotations[lo], motion.rotations[hi], np.repeat(w, joints, axis=1))
    near = np.where(w[:, 0] < 0.5, lo, hi)
    return Motion(ground, root, quat.make_continuous(rot, axis=0), motion.contacts[near])


def eased(
    motion: Motion, ease_in: bool = False, ease_out: bool = False, ramp: float | None = None
) -> Motion:
    """``motion`` starting from standing (``ease_in``) and / or stopping (``ease_out``),
    each ramp ``ramp`` frames long (default: as long as the motion)."""
    if not (ease_in or ease_out) or motion.frames < 3:
        return motion
    return resample(motion, warp_phases(motion.frames, ease_in, ease_out, ramp))


def _ramp_area(a):
    """Phase covered over the first ``a`` (0..1) of a unit ramp whose rate falls from 1 to 0
    along a smoothstep: the integral of 1 - (3 x^2 - 2 x^3)."""
    return a - a**3 + 0.5 * a**4


def hold_phases(frames: int, at: float, hold: int, ramp: float) -> np.ndarray:
    """Fractional frame positions (K,) that play a motion of ``frames`` frames at its pace,
    slow to a stop on frame ``at`` over ``ramp`` frames of time (a smoothstep in rate),
    stay there ``hold`` frames and speed up again over ``ramp``: an idle hold. Held on a
    double-support frame both feet stay planted, since a time warp only replays the same
    poses slower. ``at`` must leave ``ramp / 2`` frames of the motion either side; the
    result has ``frames + hold + ramp`` positions (``ramp`` even: whole frames)."""
    ramp, hold, at = int(ramp), int(hold), float(at)
    if hold <= 0:
        return np.arange(frames, dtype=float)
    if ramp % 2 or at - ramp / 2 < 0 or at + ramp / 2 > frames - 1:
        raise ValueError(
            f"a hold at frame {at:g} needs an even ramp ({ramp}) with half of it "
            f"inside the motion's {frames} frames on both sides"
        )
    t = np.arange(frames + hold + ramp, dtype=float)
    a0 = at - ramp / 2  # the slow-down starts here (rate 1 before)
    a1, a2 = a0 + ramp, a0 + ramp + hold  # stopped from a1 to a2, then speeding up
    u = t.copy()
    if ramp:
        down = (t > a0) & (t < a1)
        u[down] = a0 + ramp * _ramp_area((t[down] - a0) / ramp)
        up = (t >= a2) & (t < a2 + ramp)
        u[up] = at + ramp * (0.5 - _ramp_area(1.0 - (t[up] - a2) / ramp))
    u[(t >= a1) & (t < a2)] = at
    after = t >= a2 + ramp
    u[after] = t[after] - hold - ramp
    return u


def held(motion: Motion, at: float, hold: int, ramp: float) -> Motion:
    """``motion`` with an idle hold of ``hold`` frames on frame ``at`` (:func:`hold_phases`)."""
    return resample(motion, hold_phases(motion.frames, at, hold, ramp))
