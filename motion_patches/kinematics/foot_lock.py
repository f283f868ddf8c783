# SPDX-License-Identifier: GPL-3.0-or-later
"""Foot locking: keep a planted foot where it was put down.

Space-curve following turns and bends the recorded walk, so a foot that was planted in the
source slides a little on the ground (skate). This pass pins each planted foot: during a
run of frames where a foot is planted, its ankle is held at the mean position of that run
and, once the heel is up, its toe where the held foot put it, and the leg reaches it by
two-bone IK (the knee bends or opens, then the thigh swings). The hips, the body above them
and the foot's own world orientation are kept, so only the thigh and shin channels change
and bone lengths cannot.
The correction eases in and out over a few frames around each run, so nothing pops.

As a plan is written (with its frame rate) the foot is held whole while its heel is down:
its heading too (:func:`held_yaw`: the body keeps turning above a planted foot, and a foot
pinned by its ankle but still yawing swept its toe across the floor), the leg turned in its
hip socket to carry it; and a heel rising at the end of its run hands over to the toe
(:func:`heel_down`), which a foot rolling off the floor turns about.

The lock is solved on the skeleton that plays the motion, from the motion as played there:
a character on another rig than the patch's is locked on its own legs, in metres, after
retargeting. Such a rig's swinging toes pass lower than the recording's (other thigh and
shin lengths under the same joint turns), through the floor; :func:`swing_lift` raises a
swinging foot to clear its own planted height as the recording's toes do.
"""

from collections.abc import Callable

import numpy as np

from . import quat
from .contacts import CONTACT_SPEED, foot_joints, runs
from .inplace import root_channel_to_ground, root_positions
from .motion import Motion
from .retarget import segment_parent
from .skeleton import Skeleton, affine_inverse, per_skeleton

BLEND_FRAMES = 4  # frames the correction takes to ease in before and out after a contact
STILL_FACTOR = 2.0  # x contacts.CONTACT_SPEED: a planted joint moving faster is not planted,
STILL_SHARE = 0.5  # nor one moving faster than this share of the body's pace, when that is more
STRETCH = 0.985  # the straightest a locked leg gets, as a fraction of thigh + shin
SWING_CLEARANCE = 0.015  # metres a swinging toe is kept above its planted height (recorded
# walks keep 1.1 to 1.6 cm: CMU 16_15, 02_01)
SWING_SPEED = (0.5, 1.0)  # m/s: a toe slower than the first is not swinging, one faster
# than the second is in full
LIFT_FRAMES = 2  # frames either side a swing's lift is spread over
HEEL_RISE = 0.01  # metres a heel rises above its lowest in a run before the toe holds
HELD_TURN = np.radians(10.0)  # the most a planted foot's heading is held against the body's


def leg_chains(skel: Skeleton) -> list[tuple[int, int, int, int]]:
    """[(hip, knee, ankle, toe) joint indices] per side, left then right. The knee is the
    joint above the ankle and the hip the joint above the knee, skipping limb segments
    (Rigify's ``DEF-shin.L.001`` under ``DEF-shin.L``)."""
    feet = foot_joints(skel)
    out = []
    for ankle, toe in ((feet[0], feet[1]), (feet[2], feet[3])):
        knee = segment_parent(skel, int(ankle))
        hip = segment_parent(skel, knee)
        out.append((hip, knee, int(ankle), int(toe)))
    return out


def _segments(skel, lower, upper):
    """Bones strictly between joint ``lower`` and its ancestor ``upper`` (limb segments)."""
    out, j = [], int(skel.parents[lower])
    while j >= 0 and j != upper:
        out.append(j)
        j = int(skel.parents[j])
    return out


def _speeds(xy):
    """(F,) distance a point moves per frame (central differences; one-sided at the ends)."""
    xy = np.asarray(xy, float)
    v = np.empty(len(xy))
    v[1:-1] = np.linalg.norm(xy[2:] - xy[:-2], axis=1) / 2.0
    v[0], v[-1] = np.linalg.norm(xy[1] - xy[0]), np.linalg.norm(xy[-1] - xy[-2])
    return v


def still_contacts(
    skel: Skeleton, world: Motion, fps: float, posed: tuple[np.ndarray, np.ndarray] | None = None
) -> np.ndarray:
    """(F, 4) planted flags of ``world`` (a Motion; left ankle, toe, right ankle, toe) kept
    only on frames where that joint, as synthesised, moves no faster than ``STILL_FACTOR``
    x ``contacts.CONTACT_SPEED`` (the speed above which the source clips' contacts call a
    joint moving) or, where the body moves faster, ``STILL_SHARE`` of the body's pace (a
    run's planted foot slides faster than a walker's and is still planted).

    Flags carried through a blend (a walk eased out of a turn on the spot, a run eased into
    a standing jump and out of its landing) outlast the foot's stillness: there the foot
    moves 2-5 m/s while labelled planted. Pinned, it built a correction of 15-20 cm the leg
    could not reach and had to let go of within a few frames (a knee turning 30 deg in one
    frame); such a foot is not planted by the clips' own measure either, so the plan's
    contacts (the lock, the plan record, Analyse) leave it out. ``posed``: the legs
    already posed (:func:`pose_legs`), shared with :func:`lock_feet`."""
    planted = np.array(world.contacts, bool)
    if world.frames < 3:
        return planted
    p = (posed or pose_legs(skel, world))[1]
    limit = np.maximum(
        STILL_FACTOR * CONTACT_SPEED / fps, STILL_SHARE * _speeds(world.ground[:, :2])
    )
    _, _, ankle, toe = _legs(skel).legs.T  # (2,) each: left, right
    for s in range(2):
        for c, joint in ((2 * s, ankle[s]), (2 * s + 1, toe[s])):
            planted[:, c] &= _speeds(p[joint, :, :2]) <= limit
    return planted


def planted_offsets(
    ankle_xy: np.ndarray,
    toe_xy: np.ndarray,
    ankle_on: np.ndarray,
    toe_on: np.ndarray,
    blend: int = BLEND_FRAMES,
) -> np.ndarray:
    """(F, 2) horizontal corrections of the ankle that pin a foot while it is planted.

    On frames where the ankle is planted it is moved to the mean position of its run. On
    frames where only the toe is (heel up, or a toe landing), the foot is moved so the toe
    stays where the corrected foot had it on the neighbouring ankle-planted frame (or at
    the mean of its run when there is none), so the correction is continuous within a
    contact. A contact whose heel is down in several runs (it lifts for a frame or two
    and comes down again) is held by its longest one, each other run where the toe was
    on the frame before (after): the heel comes down where the pinned toe puts it, not at
    a mean of its own (which jumped the toe by the foot's slide between them). Outside
    contacts the correction of the nearest contact frame fades out with a smoothstep over
    ``blend`` frames."""
    n = len(ankle_xy)
    ankle_on = np.asarray(ankle_on, bool)
    toe_only = np.asarray(toe_on, bool) & ~ankle_on
    d = np.zeros((n, 2))
    a, b = runs(ankle_on)
    if a.size:
        held = _run_means(ankle_xy, a, b)
        d[ankle_on] = np.repeat(held, b - a, axis=0) - ankle_xy[ankle_on]
    heel_starts = a
    a, b = runs(toe_only)
    if a.size:
        heel_off = (a > 0) & ankle_on[np.maximum(a - 1, 0)]  # the toe stays where it was
        toe_first = ~heel_off & (b < n) & ankle_on[np.minimum(b, n - 1)]  # lands at the heel
        near = np.where(heel_off, a - 1, np.minimum(b, n - 1))
        anchor = np.where(
            (heel_off | toe_first)[:, None], toe_xy[near] + d[near], _run_means(toe_xy, a, b)
        )
        d[toe_only] = np.repeat(anchor, b - a, axis=0) - toe_xy[toe_only]
    on = ankle_on | toe_only
    if heel_starts.size > 1:  # contacts whose heel comes down more than once
        plant_a, plant_b = runs(on)
        plant = np.searchsorted(plant_a, heel_starts, side="right") - 1
        for k in np.flatnonzero(np.bincount(plant, minlength=plant_a.size) > 1):
            _chain(d, ankle_xy, toe_xy, ankle_on, int(plant_a[k]), int(plant_b[k]))
    return _faded(d, on, blend)


def _chain(d, ankle_xy, toe_xy, ankle_on, start, end):
    """Corrections ``d`` of one contact (frames ``start`` to ``end``) whose heel is down in
    several runs, made continuous at the toe: the longest heel run held at its mean, every
    other run (heel or toe only), outwards from it, keeping the toe where the corrected toe
    was on the frame next to it."""
    heel = ankle_on[start:end]
    cut = np.flatnonzero(np.diff(heel.astype(int))) + 1 + start
    bounds = np.concatenate(([start], cut, [end]))
    parts = list(zip(bounds[:-1], bounds[1:]))
    heels = [i for i, (a, _) in enumerate(parts) if ankle_on[a]]
    main = max(heels, key=lambda i: (parts[i][1] - parts[i][0], -i))
    a, b = parts[main]
    d[a:b] = ankle_xy[a:b].mean(axis=0) - ankle_xy[a:b]
    order = [(i, -1) for i in range(main + 1, len(parts))]
    order += [(i, 1) for i in range(main - 1, -1, -1)]
    for i, side in order:
        a, b = parts[i]
        near = a - 1 if side < 0 else b  # the frame next to it, corrected already
        edge = a if side < 0 else b - 1  # its own frame on that side
        toe = toe_xy[near] + d[near]  # where the toe stays at the hand-over
        if ankle_on[a]:
            d[a:b] = ankle_xy[edge] + (toe - toe_xy[edge]) - ankle_xy[a:b]
        else:
            d[a:b] = toe - toe_xy[a:b]


def _faded(d, on, blend=BLEND_FRAMES):
    """``d`` (F, K), set on the planted frames ``on``, with the correction of the nearest
    planted frame fading out over ``blend`` frames (smoothstep) outside them."""
    if not on.any():
        return d
    n = len(d)
    idx = np.arange(n)
    planted = idx[on]
    k = np.searchsorted(planted, idx)
    after = planted[np.clip(k, 0, planted.size - 1)]
    before = planted[np.clip(k - 1, 0, planted.size - 1)]

    def fade(gap):
        t = np.clip(1.0 - gap / float(blend + 1), 0.0, 1.0)
        return t * t * (3 - 2 * t)

    wb = np.where(before <= idx, fade(np.abs(idx - before)), 0.0)
    wa = np.where(after >= idx, fade(np.abs(after - idx)), 0.0)
    total = wb + wa
    # Between two contacts close together the corrections of both blend (never a jump
    # from one to the other); a single one fades out alone.
    scale = np.where(total > 1.0, 1.0 / np.maximum(total, 1e-12), 1.0)
    out = d[before] * (wb * scale)[:, None] + d[after] * (wa * scale)[:, None]
    out[on] = d[on]
    return out


def swing_lift(toe: np.ndarray, ankle_on: np.ndarray, toe_on: np.ndarray, fps: float) -> np.ndarray:
    """(F,) heights a foot is lifted by (its toe's world positions (F, 3), already moved by
    the horizontal pin) so that a swinging toe clears the floor of the rig that plays it.

    The toe's planted height is measured on that rig, from the motion as it plays there:
    the median over its contacts of the toe's mean height in each. A rig with other leg
    proportions than the patch's swings its toe lower (a longer thigh over a shorter shin
    drops a bent leg's foot), through the floor; the source's toes stay 1.1 to 1.6 cm
    above. So a toe off the floor is kept out of it, and ``SWING_CLEARANCE`` above it
    while it swings: in full faster than ``SWING_SPEED[1]``, not at all under
    ``SWING_SPEED[0]`` (a toe lifting off or setting down is near the floor). A toe still
    labelled planted that moves that fast is leaving or landing: it clears the floor as
    much. The lift is spread over ``LIFT_FRAMES`` either side, never less than needed, so
    it eases in and out (it may begin a frame or two before the toe leaves the floor). A
    foot never planted is not lifted."""
    ankle_on, toe_on = np.asarray(ankle_on, bool), np.asarray(toe_on, bool)
    on = ankle_on | toe_on
    lift = np.zeros(len(toe))
    if not toe_on.any() or len(toe) < 2:
        return lift
    z = toe[:, 2]
    a, b = runs(on)
    ends = np.stack((a, b), 1).ravel()
    count = np.add.reduceat(np.append(toe_on, False).astype(float), ends)[::2]
    total = np.add.reduceat(np.append(z * toe_on, 0.0), ends)[::2]
    floor = float(np.median(total[count > 0] / count[count > 0]))
    step = np.linalg.norm(np.diff(toe[:, :2], axis=0), axis=1) * fps
    speed = np.maximum(np.append(step, 0.0), np.insert(step, 0, 0.0))  # m/s, either side
    t = np.clip((speed - SWING_SPEED[0]) / (SWING_SPEED[1] - SWING_SPEED[0]), 0.0, 1.0)
    swing = t * t * (3 - 2 * t)
    need = np.maximum(floor + SWING_CLEARANCE * swing - z, 0.0)
    need[on] = (swing * np.maximum(floor + SWING_CLEARANCE - z, 0.0))[on]
    if not need.any():
        return lift
    # the most needed within LIFT_FRAMES, averaged over as many: never less than needed,
    # and a step of the lift at most a fifth of the most needed
    r = LIFT_FRAMES
    window = np.lib.stride_tricks.sliding_window_view(np.pad(need, r), 2 * r + 1)
    top = np.pad(window.max(axis=1), r, mode="edge")
    return np.lib.stride_tricks.sliding_window_view(top, 2 * r + 1).mean(axis=1)


def heel_down(ankle_z: np.ndarray, ankle_on: np.ndarray, toe_on: np.ndarray) -> np.ndarray:
    """(F,) ``ankle_on`` without the frames that end a heel run with the heel up: more than
    ``HEEL_RISE`` above the lowest it was in the run, the toe planted, to the run's end (its
    first frame stays). A foot rolling onto its toe turns about the toe, not the ankle: an
    ankle pinned while its heel rises drags the toe back along the floor (the speed the
    contacts are labelled by lets a rising ankle stay planted for a few frames). A run
    reaching the motion's last frame is the stand it ends in (a back foot's heel raised):
    handed to the toe, its ankle ended 0.8 cm further from standing in the demo."""
    ankle_on = np.asarray(ankle_on, bool).copy()
    a, b = runs(ankle_on)
    if not a.size:
        return ankle_on
    z = np.asarray(ankle_z, float)
    n = len(z)
    ends = np.stack((a, b), 1).ravel()
    lowest = np.minimum.reduceat(np.append(z, np.inf), ends)[::2]
    run = np.repeat(np.arange(a.size), b - a)
    frames = np.flatnonzero(ankle_on)
    up = (z[frames] > lowest[run] + HEEL_RISE) & np.asarray(toe_on, bool)[frames]
    # the last frame of each run that is down (or its first): the heel is up after it
    down = np.full(n + 1, -1)
    down[frames] = np.where(up, -1, frames)
    last = np.maximum(np.maximum.reduceat(down, ends)[::2], a)
    last[b == n] = n  # a heel still down on the motion's last frame stands: it stays
    ankle_on[frames[frames > last[run]]] = False
    return ankle_on


def held_yaw(
    ankle_xy: np.ndarray,
    toe_xy: np.ndarray,
    ankle_on: np.ndarray,
    toe_on: np.ndarray,
    blend: int = BLEND_FRAMES,
) -> np.ndarray:
    """(F,) turns (radians, about the vertical through the ankle) that keep a foot from
    yawing while its heel is down: each contact's foot is held at the mean heading (ankle
    to toe) of its heel-down frames, never turned more than ``HELD_TURN`` (a foot the body
    turns further pivots), the turn fading out over ``blend`` frames outside them (on its
    toe alone a foot pivots about the toe, which the turn does not move).

    Space-curve following turns the body, and the foot with it, on every frame: pinned by
    its ankle, a foot still yawing swept its toe 3 to 9 cm/s across the floor (the subject-16
    walk patch yaws a planted left foot 10 degrees in a stance on a straight line)."""
    ankle_on = np.asarray(ankle_on, bool)
    v = np.asarray(toe_xy, float) - np.asarray(ankle_xy, float)
    heading = np.unwrap(np.arctan2(v[:, 1], v[:, 0]))
    turn = np.zeros((len(v), 1))
    on = ankle_on | np.asarray(toe_on, bool)
    a, b = runs(on)
    if a.size:
        ends = np.stack((a, b), 1).ravel()
        count = np.add.reduceat(np.append(ankle_on, False).astype(float), ends)[::2]
        total = np.add.reduceat(np.append(heading * ankle_on, 0.0), ends)[::2]
        mean = (total / np.maximum(count, 1.0))[np.repeat(np.arange(a.size), b - a)]
        frames = np.flatnonzero(on)  # the contacts' frames, in order: one mean each
        heel = ankle_on[frames]
        turn[frames[heel], 0] = mean[heel] - heading[frames[heel]]
    return _faded(np.clip(turn, -HELD_TURN, HELD_TURN), ankle_on, blend)[:, 0]


def _turned(ankle_xy, toe_xy, yaw):
    """``toe_xy`` (..., F, 2) turned by ``yaw`` (..., F) about ``ankle_xy``."""
    v = toe_xy - ankle_xy
    c, s = np.cos(yaw), np.sin(yaw)
    return ankle_xy + np.stack((c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]), -1)


def _both_planted_offsets(ankle_xy, toe_xy, contacts, blend=BLEND_FRAMES):
    """(2, F, 2) :func:`planted_offsets` of both feet (ankle and toe xy (2, F, 2), the
    motion's contacts (F, 4)) in one call: the feet one after the other, ``blend`` + 1
    unplanted frames between them, so no run, anchor or fade reaches from one to the
    other (a fade ends ``blend`` + 1 frames from its contact) and each foot gets what it
    gets alone."""
    n, gap = ankle_xy.shape[1], blend + 1

    def joined(a, fill):  # (2, F, ...) -> (2F + gap, ...)
        pad = np.full((gap,) + a.shape[2:], fill, dtype=a.dtype)
        return np.concatenate((a[0], pad, a[1]))

    on = np.asarray(contacts, bool).T.reshape(2, 2, n)  # (side, ankle/toe, F)
    d = planted_offsets(
        joined(ankle_xy, 0.0),
        joined(toe_xy, 0.0),
        joined(on[:, 0], False),
        joined(on[:, 1], False),
        blend,
    )
    return np.stack((d[:n], d[n + gap :]))


def _run_means(xy, starts, ends):
    """(R, 2) mean of ``xy`` (F, 2) over each run [start, end), in one reduction."""
    padded = np.vstack((xy, np.zeros((1, xy.shape[1]))))  # an end may be F
    sums = np.add.reduceat(padded, np.stack((starts, ends), 1).ravel(), axis=0)[::2]
    return sums / (ends - starts)[:, None]


def _dot(u, v):
    """(...,) dot products of (..., 3) vectors."""
    return np.einsum("...i,...i->...", u, v)


def _unit(v):
    """(..., 3) vectors scaled to length one, and their lengths (...,)."""
    n = np.sqrt(_dot(v, v))
    return v / n[..., None], n


def _rotate(axis, cos, sin, v):
    """(..., 3) vectors ``v`` turned about unit ``axis`` (..., 3) by the angle whose cosine
    and sine are given (Rodrigues' formula: no matrices built)."""
    along = _dot(axis, v) * (1.0 - cos)
    return v * cos[..., None] + np.cross(axis, v) * sin[..., None] + axis * along[..., None]


def _axis_angle_quat(axis, angle):
    """(F, 4) unit quaternions of turns by ``angle`` (F,) about unit ``axis`` (F, 3)."""
    half = 0.5 * angle
    return np.concatenate((np.cos(half)[:, None], axis * np.sin(half)[:, None]), axis=1)


def _ik_turns(hip, knee, ankle, target, hinge, forward=None):
    """The two-bone IK of :func:`two_bone_ik` as quaternions (F, 4): (swing, knee).

    The thigh turns by ``swing``, the shin by ``swing * knee``; both are built from an
    axis and an angle per frame, and the candidate legs are turned with Rodrigues'
    formula, so no (F, 3, 3) matrix is made (the lock needs the turns, not matrices).
    Both senses of bending are tried at once (a leading axis of two)."""
    a, b = knee - hip, ankle - knee
    l1, l2 = np.sqrt(_dot(a, a)), np.sqrt(_dot(b, b))
    ah = ankle - hip
    d0 = np.clip(np.sqrt(_dot(ah, ah)), np.abs(l1 - l2) + 1e-4, l1 + l2 - 1e-4)
    # Never snap the knee straight: the leg stretches at most to STRETCH of its length
    # (or as far as the recorded pose already did); a farther target is left a little short.
    reach = np.maximum(d0, STRETCH * (l1 + l2))
    v, dist = _unit(target - hip)
    d1 = np.clip(dist, np.abs(l1 - l2) + 1e-4, reach)
    interior = np.arccos(np.clip((l1**2 + l2**2 - d1**2) / (2 * l1 * l2), -1.0, 1.0))
    # The knee's angle now, from the bones themselves (exact even for a straight leg).
    now = np.arccos(np.clip(_dot(-a, b) / (l1 * l2), -1.0, 1.0))
    delta = interior - now
    n = np.cross(a, b)
    ns = np.sqrt(_dot(n, n))
    n = np.where(ns[:, None] > 1e-6, n / np.maximum(ns, 1e-12)[:, None], hinge)
    cd, sd = np.cos(delta), np.sin(delta)
    sense = np.array([1.0, -1.0])[:, None]  # the other sense: the inverse turn
    u, ul = _unit(a + _rotate(n, cd, sense * sd, b))  # (2, F, 3), (2, F)
    err = np.abs(ul - d1)
    # the swing: the shortest arc taking u onto v
    axis = np.cross(u, v)
    s = np.sqrt(_dot(axis, axis))
    angle = np.arctan2(s, np.clip(_dot(u, v), -1.0, 1.0))
    axis = np.where(s[..., None] > 1e-9, axis / np.maximum(s, 1e-12)[..., None], [1.0, 0.0, 0.0])
    if forward is None:
        ahead = np.zeros_like(err)
    else:
        knee_dir = _rotate(axis, np.cos(angle), np.sin(angle), a)
        knee_dir -= _dot(knee_dir, v)[..., None] * v
        ahead = _dot(knee_dir, forward)
    second = np.where(np.abs(err[0] - err[1]) > 1e-7, err[1] < err[0], ahead[1] > ahead[0])
    swing = _axis_angle_quat(
        np.where(second[:, None], axis[1], axis[0]), np.where(second, angle[1], angle[0])
    )
    bend = _axis_angle_quat(n, np.where(second, -delta, delta))
    return swing, bend


def two_bone_ik(
    hip: np.ndarray,
    knee: np.ndarray,
    ankle: np.ndarray,
    target: np.ndarray,
    hinge: np.ndarray,
    forward: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(F, 3, 3) world rotations (thigh, shin) that move ``ankle`` to ``target``.

    The knee angle is set for the hip-target distance (clamped to what the leg reaches
    without locking straight), bending about the leg's plane (``hinge`` where the leg is
    straight), then the whole leg swings about the hip onto the target. Of the two senses
    of bending, the one that reaches the distance wins; where both do (a straight leg) the
    one that puts the knee towards ``forward`` (F, 3). Returns (R_thigh, R_shin):
    left-multiply the thigh's and the shin's world rotations by them."""
    swing, bend = _ik_turns(hip, knee, ankle, target, hinge, forward)
    return quat.to_matrix(swing), quat.to_matrix(quat.mul(swing, bend))


def _leg_skeleton(skel, chains):
    """(sub-skeleton, its joint indices in ``skel``): the leg chains' joints, their limb
    segments and every ancestor of them, parents before children. Forward kinematics on it
    gives the same matrices for those joints as on the whole skeleton (a third of the
    bones of a CMU rig: the arms, spine and head never reach the legs)."""
    keep = set()
    for chain in chains:
        for j in chain:
            while j >= 0 and j not in keep:
                keep.add(int(j))
                j = int(skel.parents[j])
    idx = np.array(sorted(keep))  # parents come before children in a Skeleton
    where = {int(j): i for i, j in enumerate(idx)}
    parents = np.array([where.get(int(skel.parents[j]), -1) for j in idx])
    return Skeleton([skel.names[j] for j in idx], parents, skel.rest[idx]), idx


def _rest_offsets(sub):
    """(K, 4, 4) rest matrix of each bone of ``sub`` relative to its parent's
    (:meth:`Skeleton.local_rest <motion_patches.skeleton.Skeleton.local_rest>`, the
    inverses in closed form, :func:`~.skeleton.affine_inverse`)."""
    out = sub.rest.copy()
    child = np.flatnonzero(sub.parents >= 0)
    out[child] = affine_inverse(sub.rest[sub.parents[child]]) @ sub.rest[child]
    return out


def _depths(parents):
    """Bone indices grouped by depth below the root, shallowest first (both legs' bones
    of one depth are posed together)."""
    depth = np.zeros(len(parents), int)
    for j, parent in enumerate(parents):  # parents come before children
        depth[j] = depth[parent] + 1 if parent >= 0 else 0
    return [np.flatnonzero(depth == d) for d in range(depth.max() + 1)]


def _leg_world(sub, rest_offsets, root_pos, rotations):
    """World rotations (K, F, 3, 3) and positions (K, F, 3) of the bones of ``sub`` from
    its root position (F, 3) and rotation channels (K, F, 4) (root channel in the world;
    :func:`~motion_patches.kinematics.skeleton.forward_kinematics` in rotations and positions). Bone
    first, so each bone's frames are one contiguous block for the products; the bones of
    one depth (the left and the right leg's) in one product."""
    basis = quat.to_matrix(rotations)
    nk, nf = basis.shape[:2]
    g = np.empty((nk, nf, 3, 3))
    p = np.empty((nk, nf, 3))
    roots, *levels = _depths(sub.parents)
    for j in roots:
        g[j] = sub.rest[j, :3, :3] @ basis[j]
        p[j] = root_pos
    for js in levels:
        parent = sub.parents[js]
        lr = rest_offsets[js]  # (n, 4, 4)
        gp = g[parent]
        g[js] = gp @ (lr[:, None, :3, :3] @ basis[js])
        p[js] = np.einsum("nfij,nj->nfi", gp, lr[:, :3, 3]) + p[parent]
    return g, p


class _Legs:
    """What :func:`lock_feet` needs of a skeleton that does not change with the motion:
    the leg chains, the legs' sub-skeleton and its rest offsets, and per side the bones
    whose channels the lock rewrites (made once per skeleton, :func:`_legs`)."""

    def __init__(self, skel):
        self.chains = leg_chains(skel)
        self.sub, self.idx = _leg_skeleton(skel, self.chains)
        self.at = {int(j): i for i, j in enumerate(self.idx)}
        self.rest = _rest_offsets(self.sub)
        self.root = self.sub.root
        self.legs = np.array([[self.at[j] for j in chain] for chain in self.chains])  # (2, 4)
        # per side: [(bone in skel, its turn: "thigh", "shin", "ankle" or None for a limb
        # segment that turns with its parent)], the bones in the order the lock wrote them
        self.bones = []
        for c_hip, c_knee, c_ankle, _ in self.chains:
            thigh = [(c_hip, "thigh")] + [(j, None) for j in _segments(skel, c_knee, c_hip)]
            shin = [(c_knee, "shin")] + [(j, None) for j in _segments(skel, c_ankle, c_knee)]
            self.bones.append(thigh + shin + [(c_ankle, "ankle")])


def pose_legs(skel: Skeleton, world: Motion) -> tuple[np.ndarray, np.ndarray]:
    """The legs' bones posed as in ``world`` (a Motion): world rotations (B, F, 3, 3) and
    positions (B, F, 3), for :func:`still_contacts` and :func:`lock_feet` to share."""
    return _leg_positions(_legs(skel), world, with_frames=True)


def _leg_positions(legs, world, with_frames=False):
    """World positions (B, F, 3) of the legs' bones (``legs``: :func:`_legs`) posed as in
    ``world``; with ``with_frames`` (world rotations (B, F, 3, 3), positions)."""
    sub, idx, rest = legs.sub, legs.idx, legs.rest
    ground = np.asarray(world.ground, float)
    pos = root_positions(ground, world.root_local)
    rot = np.ascontiguousarray(np.swapaxes(world.rotations[:, idx], 0, 1), dtype=float)
    rot[legs.root] = root_channel_to_ground(sub, rot[legs.root], -ground[:, 2])  # to_world's
    g, p = _leg_world(sub, rest, pos, rot)
    return (g, p) if with_frames else p


@per_skeleton
def _legs(skel):
    """The :class:`_Legs` of ``skel``, made on its first lock (a crowd's characters share
    one skeleton)."""
    return _Legs(skel)


def locked_bones(skel: Skeleton) -> np.ndarray:
    """Indices of the bones whose channels :func:`lock_feet` may change beyond a sign:
    each leg's thigh, shin and ankle and the limb segments between them."""
    return np.array(sorted(j for side in _legs(skel).bones for j, _ in side))


def lock_feet(
    skel: Skeleton,
    world: Motion,
    blend: int = BLEND_FRAMES,
    offsets: Callable[[int, np.ndarray, np.ndarray], np.ndarray] | None = None,
    posed: tuple[np.ndarray, np.ndarray] | None = None,
    fps: float | None = None,
) -> np.ndarray:
    """Rotation channels (F, J, 4) of ``world`` (a Motion) with planted feet pinned.

    Only the hip (thigh) and knee (shin) channels of each leg change, and the ankle's so
    that the foot keeps its world orientation (with ``fps``, turned about the vertical by
    :func:`held_yaw`). Both legs are solved at once, on every
    frame a correction applies to, on the legs' bones alone (:func:`_leg_skeleton`).
    ``offsets`` is a function
    (side, ankle xy (F, 2), toe xy (F, 2)) -> (F, 2) horizontal ankle corrections
    replacing :func:`planted_offsets` (a turn in place moves its feet its own way). A plan
    pins its feet on :func:`still_contacts`; ``posed``: the legs posed (:func:`pose_legs`).
    With ``fps`` (the motion's frame rate), as a plan is written, swinging toes are also
    kept clear of the floor (:func:`swing_lift`), a heel rising at the end of its run hands
    over to the toe (:func:`heel_down`) and a foot keeps its heading while its heel is down
    (:func:`held_yaw`: the whole leg turned about the line from the hip to the ankle's
    target, the foot about the vertical). ``skel`` is the skeleton that plays the motion
    (a character's own rig, in metres) and ``world`` the motion as played on it: the lock
    is solved on that rig's legs and proportions, from its own feet.

    The new channels are the old ones turned: a bone whose world rotation is left-
    multiplied by a turn T, under a parent turned by P, gets the channel
    ``(M^-1 P^-1 T M) * channel`` (M: its parent's world rotation times its rest offset,
    both before the lock), so the IK's turns are applied as quaternions, frames at once,
    with no matrix converted back."""
    corrections = offsets
    legs = _legs(skel)
    sub, rest = legs.sub, legs.rest
    n = world.frames
    ground = np.asarray(world.ground, float)
    g, p = posed or _leg_positions(legs, world, with_frames=True)
    hip, knee, ankle, toe = legs.legs.T  # (2,) each: left, right
    yaw = np.zeros((2, n))
    if corrections is None:
        c = np.array(world.contacts, bool)
        toe_xy = p[toe, :, :2]
        if fps is not None:
            for s in range(2):
                c[:, 2 * s] = heel_down(p[ankle[s], :, 2], c[:, 2 * s], c[:, 2 * s + 1])
                yaw[s] = held_yaw(
                    p[ankle[s], :, :2], toe_xy[s], c[:, 2 * s], c[:, 2 * s + 1], blend
                )
            toe_xy = _turned(p[ankle, :, :2], toe_xy, yaw)
        d = _both_planted_offsets(p[ankle, :, :2], toe_xy, c, blend)
    else:
        d = np.stack([corrections(s, p[ankle[s], :, :2], p[toe[s], :, :2]) for s in range(2)])
    if fps is not None and corrections is None:
        moved = p[toe].copy()
        moved[..., :2] = toe_xy + d
        dz = [swing_lift(moved[s], c[:, 2 * s], c[:, 2 * s + 1], fps) for s in range(2)]
        d = np.concatenate((d, np.stack(dz)[..., None]), axis=-1)
    moving = (np.sqrt(np.einsum("sfi,sfi->sf", d, d)) > 1e-7) | (np.abs(yaw) > 1e-9)  # (2, F)
    if not moving.any():
        return quat.make_continuous(world.rotations.copy(), axis=0)

    def both(a):  # (2, F, ...) -> (2F, ...): the legs one after the other
        return a.reshape((2 * n,) + a.shape[2:])

    rows = np.flatnonzero(moving.reshape(2 * n))  # the IK where a correction applies
    target = both(p[ankle])[rows]
    target[:, : d.shape[-1]] += both(d)[rows]
    hinge = both(g[hip, :, :, 0])[rows]  # the thigh's X axis: the knee's hinge in a rest-like leg
    h = ground[:, 2]
    forward = np.column_stack((np.cos(h), np.sin(h), np.zeros_like(h)))[rows % n]
    swing = np.zeros((2 * n, 4))
    swing[:, 0] = 1.0
    bend = swing.copy()
    swing[rows], bend[rows] = _ik_turns(
        both(p[hip])[rows], both(p[knee])[rows], both(p[ankle])[rows], target, hinge, forward
    )
    # a held heading turns the whole leg about the line from the hip to the ankle's target
    # (the thigh rotates in its socket, the knee with it; the ankle stays on the target)
    axis, _ = _unit(target - both(p[hip])[rows])
    swing[rows] = quat.mul(_axis_angle_quat(axis, both(yaw)[rows]), swing[rows])
    swing, bend = swing.reshape(2, n, 4), bend.reshape(2, n, 4)
    changed = [j for side in range(2) if moving[side].any() for j, _ in legs.bones[side]]
    out = world.rotations.copy()
    local = out[:, changed].astype(float)  # (F, K, 4)
    # the turn of each bone relative to its parent's (thigh: the swing; shin: the bend under
    # the swung thigh; ankle: back to its world rotation, turned by the held heading; limb
    # segments: none)
    # the foot's held heading: a turn about the world's vertical (the ankle's world turn)
    held = np.zeros((2, n, 4))
    held[..., 0], held[..., 3] = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    rel = {"thigh": swing, "shin": bend, "ankle": quat.mul(quat.conj(quat.mul(swing, bend)), held)}
    at, turns, sides, kinds = [], [], [], []  # the turned bones: place in local, bone in sub
    for i, (side, (j, turn)) in enumerate(
        (side, b) for side in range(2) if moving[side].any() for b in legs.bones[side]
    ):
        if turn is not None:
            at.append(i)
            turns.append(legs.at[j])
            sides.append(side)
            kinds.append(turn)
    t = np.stack([rel[kind][side] for kind, side in zip(kinds, sides)])  # (T, F, 4)
    # M^-1 T M (M = the parent's world rotation times the bone's rest offset): the turn's
    # axis taken into the bone's parent-rest frame, rest^T g^T axis; all turned bones at once
    axis = np.einsum("tfji,tfj->tfi", g[sub.parents[turns]], t[..., 1:]) @ rest[turns, :3, :3]
    t[..., 1:] = axis
    local[:, at] = quat.mul(np.swapaxes(t, 0, 1), local[:, at])
    local /= np.sqrt(np.einsum("fkc,fkc->fk", local, local))[..., None]
    local = quat.make_continuous(local, axis=0)
    local[:, local[0, :, 0] < 0] *= -1  # the first frame's w >= 0, as quat.from_matrix gives
    out[:, changed] = local
    # the whole pose made continuous, as the channels were; the changed bones are already,
    # and of the others only those that flip somewhere need the pass
    flips = np.any(np.einsum("fjc,fjc->fj", out[1:], out[:-1]) < 0, axis=0)
    flips[changed] = False
    if flips.any():
        out[:, flips] = quat.make_continuous(out[:, flips], axis=0)
    return out
