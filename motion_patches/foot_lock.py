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
"""

import numpy as np

from . import quat
from .contacts import CONTACT_SPEED, foot_joints, runs
from .inplace import to_world

BLEND_FRAMES = 4  # frames the correction takes to ease in before and out after a contact
STILL_FACTOR = 2.0  # x contacts.CONTACT_SPEED: a planted joint moving faster is not planted,
STILL_SHARE = 0.5  # nor one moving faster than this share of the body's pace, when that is more
STRETCH = 0.985  # the straightest a locked leg gets, as a fraction of thigh + shin


def leg_chains(skel):
    """[(hip, knee, ankle, toe) joint indices] per side, left then right. The knee is the
    joint above the ankle and the hip the joint above the knee, skipping limb segments
    (Rigify's ``DEF-shin.L.001`` under ``DEF-shin.L``)."""
    from .retarget import segment_parent

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


def still_contacts(skel, world, fps):
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
    contacts (the lock, the plan record, Analyse) leave it out."""
    planted = np.array(world.contacts, bool)
    if world.frames < 3:
        return planted
    chains = leg_chains(skel)
    sub, idx = _leg_skeleton(skel, chains)
    pos, rot = to_world(sub, world.ground, world.root_local, world.rotations[:, idx])
    _, p = _leg_world(sub, _rest_offsets(sub), pos, rot)
    at = {int(j): i for i, j in enumerate(idx)}
    limit = np.maximum(
        STILL_FACTOR * CONTACT_SPEED / fps, STILL_SHARE * _speeds(world.ground[:, :2])
    )
    for s, (_, _, ankle, toe) in enumerate(chains):
        for c, joint in ((2 * s, ankle), (2 * s + 1, toe)):
            planted[:, c] &= _speeds(p[:, at[joint], :2]) <= limit
    return planted


def planted_offsets(ankle_xy, toe_xy, ankle_on, toe_on, blend=BLEND_FRAMES):
    """(F, 2) horizontal corrections of the ankle that pin a foot while it is planted.

    On frames where the ankle is planted it is moved to the mean position of its run. On
    frames where only the toe is (heel up, or a toe landing), the foot is moved so the toe
    stays where the corrected foot had it on the neighbouring ankle-planted frame (or at
    the mean of its run when there is none), so the correction is continuous within a
    contact. Outside contacts the correction of the nearest contact frame fades out with a
    smoothstep over ``blend`` frames."""
    n = len(ankle_xy)
    ankle_on = np.asarray(ankle_on, bool)
    toe_only = np.asarray(toe_on, bool) & ~ankle_on
    d = np.zeros((n, 2))
    a, b = runs(ankle_on)
    if a.size:
        held = _run_means(ankle_xy, a, b)
        d[ankle_on] = np.repeat(held, b - a, axis=0) - ankle_xy[ankle_on]
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
    if not on.any():
        return d
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


def _run_means(xy, starts, ends):
    """(R, 2) mean of ``xy`` (F, 2) over each run [start, end), in one reduction."""
    padded = np.vstack((xy, np.zeros((1, xy.shape[1]))))  # an end may be F
    sums = np.add.reduceat(padded, np.stack((starts, ends), 1).ravel(), axis=0)[::2]
    return sums / (ends - starts)[:, None]


def _rotation_between(u, v):
    """(F, 3, 3) rotations taking unit vectors u to v along the shortest arc."""
    axis = np.cross(u, v)
    s = np.linalg.norm(axis, axis=-1)
    c = np.clip(np.sum(u * v, axis=-1), -1.0, 1.0)
    angle = np.arctan2(s, c)
    axis = np.where(s[:, None] > 1e-9, axis / np.maximum(s, 1e-12)[:, None], [1.0, 0.0, 0.0])
    return quat.to_matrix(quat.exp(axis * angle[:, None]))


def two_bone_ik(hip, knee, ankle, target, hinge, forward=None):
    """(F, 3, 3) world rotations (thigh, shin) that move ``ankle`` to ``target``.

    The knee angle is set for the hip-target distance (clamped to what the leg reaches
    without locking straight), bending about the leg's plane (``hinge`` where the leg is
    straight), then the whole leg swings about the hip onto the target. Of the two senses
    of bending, the one that reaches the distance wins; where both do (a straight leg) the
    one that puts the knee towards ``forward`` (F, 3). Returns (R_thigh, R_shin):
    left-multiply the thigh's and the shin's world rotations by them."""
    a, b = knee - hip, ankle - knee
    l1, l2 = np.linalg.norm(a, axis=-1), np.linalg.norm(b, axis=-1)
    d0 = np.clip(np.linalg.norm(ankle - hip, axis=-1), np.abs(l1 - l2) + 1e-4, l1 + l2 - 1e-4)
    # Never snap the knee straight: the leg stretches at most to STRETCH of its length
    # (or as far as the recorded pose already did); a farther target is left a little short.
    reach = np.maximum(d0, STRETCH * (l1 + l2))
    d1 = np.clip(np.linalg.norm(target - hip, axis=-1), np.abs(l1 - l2) + 1e-4, reach)

    def interior(d):
        return np.arccos(np.clip((l1**2 + l2**2 - d**2) / (2 * l1 * l2), -1.0, 1.0))

    # The knee's angle now, from the bones themselves (exact even for a straight leg).
    now = np.arccos(np.clip(np.sum(-a * b, axis=-1) / (l1 * l2), -1.0, 1.0))
    delta = interior(d1) - now
    n = np.cross(a, b)
    ns = np.linalg.norm(n, axis=-1)
    n = np.where(ns[:, None] > 1e-6, n / np.maximum(ns, 1e-12)[:, None], hinge)
    v = target - hip
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    bend = quat.to_matrix(quat.exp(n * delta[:, None]))
    options = []
    for r_knee in (bend, np.swapaxes(bend, -1, -2)):  # the other sense: the inverse turn
        u = a + np.einsum("fij,fj->fi", r_knee, b)
        err = np.abs(np.linalg.norm(u, axis=-1) - d1)
        swing = _rotation_between(u / np.linalg.norm(u, axis=-1, keepdims=True), v)
        knee_dir = np.einsum("fij,fj->fi", swing, a)
        knee_dir -= np.sum(knee_dir * v, axis=-1, keepdims=True) * v
        ahead = np.zeros(len(a)) if forward is None else np.sum(knee_dir * forward, axis=-1)
        options.append((err, ahead, swing, r_knee))
    (e1, f1, s1, k1), (e2, f2, s2, k2) = options
    second = np.where(np.abs(e1 - e2) > 1e-7, e2 < e1, f2 > f1)[:, None, None]
    swing = np.where(second, s2, s1)
    return swing, swing @ np.where(second, k2, k1)


def _leg_skeleton(skel, chains):
    """(sub-skeleton, its joint indices in ``skel``): the leg chains' joints, their limb
    segments and every ancestor of them, parents before children. Forward kinematics on it
    gives the same matrices for those joints as on the whole skeleton (a third of the
    bones of a CMU rig: the arms, spine and head never reach the legs)."""
    from .skeleton import Skeleton

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
    inverses taken in one call)."""
    out = sub.rest.copy()
    child = np.flatnonzero(sub.parents >= 0)
    out[child] = np.linalg.inv(sub.rest[sub.parents[child]]) @ sub.rest[child]
    return out


def _leg_world(sub, rest_offsets, root_pos, rotations):
    """World rotations (F, K, 3, 3) and positions (F, K, 3) of the bones of ``sub``
    (:func:`~motion_patches.skeleton.forward_kinematics` in rotations and positions)."""
    basis = quat.to_matrix(rotations)
    nf, nk = basis.shape[:2]
    g = np.empty((nf, nk, 3, 3))
    p = np.empty((nf, nk, 3))
    for j, parent in enumerate(sub.parents):
        if parent < 0:
            g[:, j] = sub.rest[j, :3, :3] @ basis[:, j]
            p[:, j] = root_pos
            continue
        lr = rest_offsets[j]
        g[:, j] = g[:, parent] @ (lr[:3, :3] @ basis[:, j])
        p[:, j] = g[:, parent] @ lr[:3, 3] + p[:, parent]
    return g, p


def lock_feet(skel, world, blend=BLEND_FRAMES, offsets=None):
    """Rotation channels (F, J, 4) of ``world`` (a Motion) with planted feet pinned.

    Only the hip (thigh) and knee (shin) channels of each leg change, and the ankle's so
    that the foot keeps its world orientation. Both legs are solved at once over all
    frames, on the legs' bones alone (:func:`_leg_skeleton`). ``offsets`` is a function
    (side, ankle xy (F, 2), toe xy (F, 2)) -> (F, 2) horizontal ankle corrections
    replacing :func:`planted_offsets` (a turn in place moves its feet its own way). A plan
    pins its feet on :func:`still_contacts`."""
    corrections = offsets
    chains = leg_chains(skel)
    sub, idx = _leg_skeleton(skel, chains)
    at = {int(j): i for i, j in enumerate(idx)}
    rest = _rest_offsets(sub)
    pos, rot = to_world(sub, world.ground, world.root_local, world.rotations[:, idx])
    g, p = _leg_world(sub, rest, pos, rot)
    n = world.frames
    legs = np.array([[at[j] for j in chain] for chain in chains])  # (2, 4) in ``sub``
    hip, knee, ankle, toe = legs.T  # (2,) each: left, right
    d = np.stack(
        [
            planted_offsets(
                p[:, ankle[s], :2],
                p[:, toe[s], :2],
                world.contacts[:, 2 * s],
                world.contacts[:, 2 * s + 1],
                blend,
            )
            if corrections is None
            else corrections(s, p[:, ankle[s], :2], p[:, toe[s], :2])
            for s in range(2)
        ]
    )  # (2, F, 2)
    moving = np.linalg.norm(d, axis=-1) > 1e-7  # (2, F)
    if not moving.any():
        return quat.make_continuous(world.rotations.copy(), axis=0)

    def both(a):  # (F, 2, ...) -> (2F, ...): the legs one after the other
        return np.swapaxes(a, 0, 1).reshape((2 * n,) + a.shape[2:])

    target = both(p[:, ankle]).copy()
    target[:, :2] += d.reshape(2 * n, 2)
    hinge = both(g[:, hip, :, 0])  # the thigh's X axis: the knee's hinge in a rest-like leg
    h = world.ground[:, 2]
    forward = np.tile(np.column_stack((np.cos(h), np.sin(h), np.zeros_like(h))), (2, 1))
    r_thigh, r_shin = two_bone_ik(
        both(p[:, hip]), both(p[:, knee]), both(p[:, ankle]), target, hinge, forward
    )
    still = ~moving.reshape(2 * n)
    r_thigh[still] = np.eye(3)
    r_shin[still] = np.eye(3)
    r_thigh, r_shin = r_thigh.reshape(2, n, 3, 3), r_shin.reshape(2, n, 3, 3)
    changed = []
    for s, (c_hip, c_knee, c_ankle, _) in enumerate(chains):
        if not moving[s].any():
            continue
        thigh_bones = [c_hip, *_segments(skel, c_knee, c_hip)]  # limb segments turn with it
        shin_bones = [c_knee, *_segments(skel, c_ankle, c_knee)]
        for bones, r in ((thigh_bones, r_thigh[s]), (shin_bones, r_shin[s])):
            k = [at[j] for j in bones]
            g[:, k] = r[:, None] @ g[:, k]
        # the foot keeps its world rotation (g at the ankle unchanged); its children follow
        changed += thigh_bones + shin_bones + [c_ankle]
    # Pose channels of the changed bones only (local_rotations_from_global, per bone).
    k = np.array([at[j] for j in changed])
    parent_rest = g[:, sub.parents[k]] @ rest[k, :3, :3]  # (F, K, 3, 3)
    local = quat.make_continuous(
        quat.from_matrix(np.swapaxes(parent_rest, -1, -2) @ g[:, k]), axis=0
    )
    out = world.rotations.copy()
    out[:, changed] = local
    # the whole pose made continuous, as the channels were; the changed bones are already,
    # and of the others only those that flip somewhere need the pass
    flips = np.any(np.einsum("fjc,fjc->fj", out[1:], out[:-1]) < 0, axis=0)
    flips[changed] = False
    if flips.any():
        out[:, flips] = quat.make_continuous(out[:, flips], axis=0)
    return out
