# SPDX-License-Identifier: GPL-3.0-or-later
"""Turning on the spot: the end of a walk turned to the goal's heading where it stands.

A walk can only arrive at a goal facing a given way by curving into it, no tighter than
the gait's sharpest turn (0.59 m for CMU subject 16): a goal faced away from the way in
costs a loop of several metres, and a goal with a prop just behind it cannot be reached
at all. People stop and turn round on the spot instead. The shared mocap has no clip of a
turn in place, so one is DERIVED from the walk's own sharpest turn loop (16_18's 77-82
degree turning cycles): its poses and its heading change frame by frame are played as
recorded, but the ground frame does not advance (the stride's travel is removed), and
each foot is pinned by two-bone IK where it is put down, under the body, moving between
contacts along its recorded lift (:func:`stride_removed`): short steps turning the body,
at the pace and with the posture of the recorded turn. It is labelled so wherever it
shows ("turn in place (derived)").
"""

import numpy as np

from ..kinematics import foot_lock
from ..kinematics.contacts import runs
from ..kinematics.motion import Motion
from ..kinematics.poses import pose_features
from ..patch.layers import has_flight

MIN_SHARE = 0.75  # the turn may end on a double-support frame from this share of the angle
SWAY = 0.5  # share of the stride's horizontal hip sway kept when stepping on the spot


MIN_LOOP_TURN = np.radians(30.0)  # a loop turning less per cycle cannot turn on the spot


def can_turn(gait, kmin, kmax):
    """True when the gait has a loop turning at least ``MIN_LOOP_TURN`` per cycle each way
    within the curvature range ``kmin``..``kmax`` the patch was baked to follow: a patch
    of a lone straight walk (or one limited to straight segments) has nothing to turn on
    the spot with. Nor does a run (a gait with a flight phase): a runner slows to a walk to
    turn round, which a plan in the run layer alone cannot."""
    if has_flight(gait):
        return False
    for sign, limit in ((1.0, kmax), (-1.0, kmin)):
        ok = [
            sign * lp.turn >= MIN_LOOP_TURN and abs(lp.curvature) <= abs(limit) * 1.01
            for lp in gait.loops
        ]
        if not any(ok):
            return False
    return True


def turn_loop(gait, delta):
    """The gait's sharpest loop turning the way of ``delta`` (radians, + = left)."""
    k = np.array([lp.curvature for lp in gait.loops])
    return gait.loops[int(np.argmax(k) if delta > 0 else np.argmin(k))]


def matching_phase(loop, root_local, rotations):
    """The frame of ``loop`` whose pose is nearest a pose (root (3,), rotations (J, 4)):
    the phase the turn continues from, so the feet carry on the stride they were in."""
    f = pose_features(loop.root_local, loop.rotations)
    x = pose_features(root_local[None], rotations[None])[0]
    return int(np.argmin(np.sum((f - x) ** 2, axis=1)))


def _both_planted(loop):
    c = np.asarray(loop.contacts, bool)
    return (c[:, 0] | c[:, 1]) & (c[:, 2] | c[:, 3])


def turn_phases(gait, delta, phase=0):
    """(phases (K,), heading steps (K - 1,)) of a turn in place by ``delta`` starting on
    loop frame ``phase``: the sharpest loop's frames in order, its recorded heading change
    per frame scaled so the total is exactly ``delta``; it ends on the first frame with
    both feet planted once ``MIN_SHARE`` of the angle is turned (standing, not mid-step)."""
    loop = turn_loop(gait, delta)
    n = loop.frames
    step = np.abs(loop.turn) * np.diff(loop.distance) / loop.cycle_distance  # (n,)
    both = _both_planted(loop)
    target, turned, k = abs(float(delta)), 0.0, int(phase)
    phases, steps = [k], []
    limit = int(np.ceil(target / max(abs(loop.turn), 1e-6) * n)) + 2 * n
    while len(steps) < limit:
        turned += step[k % n]
        steps.append(step[k % n])
        k += 1
        phases.append(k)
        if turned >= (MIN_SHARE if both[k % n] else 2.0 - MIN_SHARE) * target:
            break  # on both feet once most of the way round, else a little past it
    steps = np.array(steps) * (target / max(turned, 1e-12)) * np.sign(delta)
    return np.array(phases) % n, steps


def frames_needed(gait, delta):
    """Frames of a turn in place by ``delta`` from the loop's first frame (for its cost)."""
    return turn_phases(gait, delta)[0].size


def turn_motion(gait, xy, heading, delta, previous=None):
    """Motion of turning on the spot at ``xy`` from ``heading`` by ``delta``; with the
    ``previous`` motion (what the character did before) the turn starts on the loop frame
    nearest its last pose. Not eased: the caller eases it in and out (:mod:`.retime`)."""
    loop = turn_loop(gait, delta)
    phase = (
        0
        if previous is None
        else matching_phase(loop, previous.root_local[-1], previous.rotations[-1])
    )
    ph, steps = turn_phases(gait, delta, phase)
    h = heading + np.concatenate(([0.0], np.cumsum(steps)))
    ground = np.column_stack((np.full(ph.size, xy[0]), np.full(ph.size, xy[1]), h))
    root = loop.root_local[ph].copy()
    root[:, :2] *= SWAY  # stepping on the spot shifts the weight less than striding
    m = Motion(ground, root, loop.rotations[ph].copy(), loop.contacts[ph])
    return stride_removed(gait.skeleton, m)


def stride_removed(skel, motion):
    """The motion with each foot pinned where it is put down: the ground frame no longer
    advances, so the recorded stride would sweep a planted foot back under the body. A
    contact (heel or toe) is held at the ankle's position on its middle frame (the first
    one on the first frame: where the walk before left the foot), and between contacts
    the correction passes smoothly from one to the next, so the foot lifts and steps to
    its new place along its recorded swing height."""

    def offsets(side, ankle_xy, toe_xy):
        c = motion.contacts
        on = np.asarray(c[:, 2 * side] | c[:, 2 * side + 1], bool)
        n = len(ankle_xy)
        d = np.zeros((n, 2))
        starts, ends = runs(on)
        if starts.size == 0:
            return d
        for a, b in zip(starts, ends):
            anchor = ankle_xy[0] if a == 0 else ankle_xy[(a + b - 1) // 2]
            d[a:b] = anchor - ankle_xy[a:b]
        # between contacts (and before the first, after the last): smooth passage from
        # the correction of the contact frame before (none before the first) to the one after
        pairs = [(-1, starts[0])] + list(zip(ends[:-1] - 1, starts[1:])) + [(ends[-1] - 1, n)]
        for prev, nxt in pairs:
            if nxt - prev <= 1:
                continue
            d0 = np.zeros(2) if prev < 0 else d[prev]
            d1 = d[nxt] if nxt < n else d0
            t = (np.arange(prev + 1, nxt) - prev) / float(nxt - prev)
            w = t * t * (3.0 - 2.0 * t)
            d[prev + 1 : nxt] = d0 + w[:, None] * (d1 - d0)
        return d

    rot = foot_lock.lock_feet(skel, motion, offsets=offsets)
    return Motion(motion.ground, motion.root_local, rot, motion.contacts)
