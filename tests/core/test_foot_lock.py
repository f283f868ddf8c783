# SPDX-License-Identifier: GPL-3.0-or-later
"""Foot locking: planted feet of a planned walk stay put, nothing else moves or pops."""

import numpy as np
import pytest

from motion_patches.kinematics import foot_lock, quat
from motion_patches.kinematics.contacts import foot_joints
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment
from motion_patches.quality import metrics


@pytest.fixture(scope="module")
def walk(walk_patch):
    """A planned walk that turns (start facing +Y, goal 8 m east facing south)."""
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    plan = SegmentPlanner(walk_patch, env).plan((0.0, 0.0, np.pi / 2), (8.0, 2.0, -np.pi / 2))
    return concatenate(plan_motions(walk_patch, plan))


def skate(skel, motion, fps=30.0):
    m = motion.world_matrices(skel)
    return metrics.foot_skate(m[:, foot_joints(skel)][..., :3, 3], fps, motion.contacts)


def test_locked_feet_skate_far_less_than_the_followed_curve(walk_patch, walk):
    skel = walk_patch.gait.skeleton
    locked = Motion(walk.ground, walk.root_local, foot_lock.lock_feet(skel, walk), walk.contacts)
    before, after = skate(skel, walk), skate(skel, locked)
    assert before["mean_cm_per_s"] > 10  # the synthesis alone skates
    assert after["mean_cm_per_s"] < 0.4 * before["mean_cm_per_s"]
    assert after["p95_cm_per_s"] < before["p95_cm_per_s"]


def test_only_the_legs_change_and_the_feet_keep_their_orientation(walk_patch, walk):
    skel = walk_patch.gait.skeleton
    rot = foot_lock.lock_feet(skel, walk)
    legs = {j for chain in foot_lock.leg_chains(skel) for j in chain[:3]}
    others = [j for j in range(len(skel.names)) if j not in legs]
    assert np.allclose(np.abs(np.sum(rot[:, others] * walk.rotations[:, others], axis=-1)), 1.0)
    a = walk.world_matrices(skel)
    b = Motion(walk.ground, walk.root_local, rot, walk.contacts).world_matrices(skel)
    for hip, knee, ankle, toe in foot_lock.leg_chains(skel):
        assert np.allclose(a[:, ankle, :3, :3], b[:, ankle, :3, :3], atol=1e-6)
        assert np.allclose(a[:, hip, :3, 3], b[:, hip, :3, 3])  # the hips do not move
        # the foot is carried whole: the toe moves exactly as the ankle does
        assert np.allclose(
            b[:, toe, :3, 3] - b[:, ankle, :3, 3], a[:, toe, :3, 3] - a[:, ankle, :3, 3], atol=1e-6
        )


def test_locking_adds_no_pop(walk_patch, walk):
    """The largest per-frame change of a leg channel grows by a few degrees at most."""
    skel = walk_patch.gait.skeleton
    rot = foot_lock.lock_feet(skel, walk)
    legs = [j for chain in foot_lock.leg_chains(skel) for j in chain[:3]]

    def steps(r):
        return np.degrees(quat.angle_between(r[1:, legs], r[:-1, legs])).max()

    assert steps(rot) < steps(walk.rotations) + 5.0


def test_planted_offsets_ease_in_and_out():
    n = 30
    ankle = np.column_stack((np.linspace(0, 0.3, n), np.zeros(n)))  # sliding 1 cm a frame
    on = np.zeros(n, bool)
    on[10:20] = True
    d = foot_lock.planted_offsets(ankle, ankle, on, np.zeros(n, bool), blend=4)
    pinned = ankle[10:20] + d[10:20]
    assert np.allclose(pinned, pinned[0])  # held still while planted
    assert np.allclose(d[:5], 0) and np.allclose(d[25:], 0)  # untouched far from it
    assert np.all(np.abs(np.diff(d[:, 0])) <= 0.045)  # no jump into or out of it


def test_a_straight_leg_bends_its_knee_forward():
    """Hip above knee above ankle, the target a little closer: both senses of bending
    reach it; the knee must go the way the character faces (+X), never backwards."""
    hip, knee, ankle = (np.array([[0.0, 0.0, z]]) for z in (1.0, 0.55, 0.1))
    target = np.array([[0.0, 0.0, 0.2]])
    for forward in (np.array([[1.0, 0.0, 0.0]]), np.array([[-1.0, 0.0, 0.0]])):
        r_thigh, r_shin = foot_lock.two_bone_ik(
            hip, knee, ankle, target, np.array([[0.0, 1.0, 0.0]]), forward
        )
        new_knee = hip[0] + r_thigh[0] @ (knee - hip)[0]
        new_ankle = new_knee + r_shin[0] @ (ankle - knee)[0]
        assert np.allclose(new_ankle, target[0], atol=1e-6)
        assert np.sign(new_knee[0]) == np.sign(forward[0, 0]) and abs(new_knee[0]) > 0.05


def planted_offsets_frame_by_frame(ankle_xy, toe_xy, ankle_on, toe_on):
    """planted_offsets' corrections on planted frames, written contact by contact and frame
    by frame: the longest heel run of a contact held at its mean; from it outwards, each
    frame keeps the heel where it was on the frame next to it while the heel stays down on
    both, else the toe (a toe-only frame, a hand-over); a contact with its heel never down
    holds its toe at its mean."""
    from motion_patches.kinematics.contacts import runs

    d = np.zeros((len(ankle_xy), 2))
    for start, end in zip(*runs(ankle_on | toe_on)):
        heel = ankle_on[start:end]
        if not heel.any():
            d[start:end] = toe_xy[start:end].mean(axis=0) - toe_xy[start:end]
            continue
        ha, hb = (x + start for x in runs(heel))
        k = int(np.argmax(hb - ha))
        d[ha[k] : hb[k]] = ankle_xy[ha[k] : hb[k]].mean(axis=0) - ankle_xy[ha[k] : hb[k]]
        for f, near in [(f, f - 1) for f in range(hb[k], end)] + [
            (f, f + 1) for f in range(ha[k] - 1, start - 1, -1)
        ]:
            joint = ankle_xy if ankle_on[f] and ankle_on[near] else toe_xy
            d[f] = joint[near] + d[near] - joint[f]
    return d


@pytest.mark.parametrize("seed", range(6))
def test_planted_offsets_hold_each_contact_as_frame_by_frame(seed):
    """Random contacts (runs touching the ends, toe-only runs before, after and between
    heel runs, a heel coming down twice in one contact): on every planted frame the
    correction is the frame-by-frame one."""
    rng = np.random.default_rng(seed)
    n = 300
    ankle = np.cumsum(rng.normal(size=(n, 2)) * 0.01, axis=0)
    toe = ankle + rng.normal(size=(n, 2)) * 0.01 + [0.15, 0.0]
    ankle_on = np.repeat(rng.random(n // 10) < 0.5, 10)
    toe_on = np.repeat(rng.random(n // 5) < 0.5, 5) | ankle_on
    toe_on[:3] = True  # a toe-only run at the start (when the heel is not down there)
    ankle_on[toe_on & (rng.random(n) < 0.05)] ^= True  # heels flickering within contacts
    want = planted_offsets_frame_by_frame(ankle, toe, ankle_on, toe_on)
    got = foot_lock.planted_offsets(ankle, toe, ankle_on, toe_on, blend=4)
    on = ankle_on | toe_on
    assert on.any() and (toe_on & ~ankle_on).any()
    assert np.allclose(got[on], want[on], atol=1e-12)


def test_a_heel_down_twice_in_one_contact_hands_over_without_a_jump():
    """A planted foot sliding 1 cm a frame whose heel is up for two frames mid-contact (the
    synthesis moved it fast there): the toe stays put through both hand-overs. Each heel
    run held at its own mean put the toe down 10 cm from where it stood."""
    n = 40
    ankle = np.column_stack((np.linspace(0.0, 0.39, n), np.zeros(n)))
    toe = ankle + [0.15, 0.0]
    ankle_on = np.zeros(n, bool)
    ankle_on[10:18] = ankle_on[20:30] = True
    toe_on = np.zeros(n, bool)
    toe_on[10:32] = True
    d = foot_lock.planted_offsets(ankle, toe, ankle_on, toe_on, blend=4)
    held_toe = (toe + d)[10:32]
    assert np.abs(np.diff(held_toe, axis=0)).max() < 1e-12  # the toe never moves
    assert np.allclose((ankle + d)[20:30], ankle[20:30].mean(axis=0))  # the longest run's mean
    # the old rule, each heel run at its own mean, jumped the toe at the heel's return
    own = ankle[10:18].mean(axis=0) - ankle[17], ankle[20:30].mean(axis=0) - ankle[20]
    assert np.linalg.norm((toe[17] + own[0]) - (toe[20] + own[1])) > 0.09


def test_the_legs_world_matrices_are_the_whole_skeletons(walk_patch, walk):
    """lock_feet's forward kinematics on the legs alone gives the armature's matrices."""
    from motion_patches.kinematics.inplace import to_world

    skel = walk_patch.gait.skeleton
    chains = foot_lock.leg_chains(skel)
    sub, idx = foot_lock._leg_skeleton(skel, chains)
    assert len(idx) < len(skel.names)
    pos, rot = to_world(sub, walk.ground, walk.root_local, walk.rotations[:, idx])
    g, p = foot_lock._leg_world(sub, foot_lock._rest_offsets(sub), pos, np.swapaxes(rot, 0, 1))
    m = np.swapaxes(walk.world_matrices(skel)[:, idx], 0, 1)  # bone first, as _leg_world
    assert np.allclose(g, m[..., :3, :3], atol=1e-12)
    assert np.allclose(p, m[..., :3, 3], atol=1e-12)


def test_locked_channels_are_continuous_where_the_input_flips(walk_patch, walk):
    """A bone the lock leaves alone whose quaternions change sign mid-walk (the same
    rotation) comes out continuous, as the whole pose did: only its sign changes."""
    skel = walk_patch.gait.skeleton
    legs = {j for chain in foot_lock.leg_chains(skel) for j in chain}
    other = next(j for j in range(1, len(skel.names)) if j not in legs)
    flipped = walk.rotations.copy()
    flipped[walk.frames // 2 :, other] *= -1
    rot = foot_lock.lock_feet(skel, Motion(walk.ground, walk.root_local, flipped, walk.contacts))
    assert np.all(np.sum(rot[1:] * rot[:-1], axis=-1) >= 0)
    assert np.allclose(rot[:, other], quat.make_continuous(flipped[:, other], axis=0))
    assert np.allclose(rot, foot_lock.lock_feet(skel, walk))


def _turn(axis, angle):
    """3x3 rotation by ``angle`` about unit ``axis`` (one frame, Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def ik_one_frame(hip, knee, ankle, target, hinge, forward):
    """two_bone_ik's rule for one frame, written with scalars and 3x3 matrices."""
    a, b = knee - hip, ankle - knee
    l1, l2 = np.linalg.norm(a), np.linalg.norm(b)
    d0 = min(max(np.linalg.norm(ankle - hip), abs(l1 - l2) + 1e-4), l1 + l2 - 1e-4)
    reach = max(d0, foot_lock.STRETCH * (l1 + l2))
    d1 = min(max(np.linalg.norm(target - hip), abs(l1 - l2) + 1e-4), reach)
    interior = np.arccos(np.clip((l1 * l1 + l2 * l2 - d1 * d1) / (2 * l1 * l2), -1.0, 1.0))
    now = np.arccos(np.clip(np.dot(-a, b) / (l1 * l2), -1.0, 1.0))
    n = np.cross(a, b)
    n = n / np.linalg.norm(n) if np.linalg.norm(n) > 1e-6 else hinge
    v = (target - hip) / np.linalg.norm(target - hip)
    best = None
    for sense in (1.0, -1.0):
        r_knee = _turn(n, sense * (interior - now))
        u = a + r_knee @ b
        err = abs(np.linalg.norm(u) - d1)
        u = u / np.linalg.norm(u)
        axis, c = np.cross(u, v), np.clip(np.dot(u, v), -1.0, 1.0)
        s = np.linalg.norm(axis)
        swing = _turn(axis / s if s > 1e-9 else np.array([1.0, 0.0, 0.0]), np.arctan2(s, c))
        knee_dir = swing @ a
        knee_dir = knee_dir - np.dot(knee_dir, v) * v
        option = (err, np.dot(knee_dir, forward), swing, swing @ r_knee)
        if best is None or (
            option[1] > best[1] if abs(option[0] - best[0]) <= 1e-7 else option[0] < best[0]
        ):
            best = option
    return best[2], best[3]


def lock_feet_frame_by_frame(skel, world, blend=foot_lock.BLEND_FRAMES, fps=None):
    """lock_feet as a loop over frames and legs: the whole skeleton's world matrices, the
    IK of each frame on its own, the turned bones' channels from their new world
    rotations (skeleton.local_rotations_from_global); with ``fps`` the ankle's target also
    raised by the swing lift, a heel rising at the end of its run handed over to the toe
    and the foot's heading held while its heel is down (the leg turned about the line from
    the hip to the ankle's target, the foot about the vertical)."""
    from motion_patches.kinematics.skeleton import local_rotations_from_global

    m = world.world_matrices(skel)
    g, p = m[..., :3, :3].copy(), m[..., :3, 3]
    chains = foot_lock.leg_chains(skel)
    changed = []
    up = np.array([0.0, 0.0, 1.0])
    for s, (hip, knee, ankle, toe) in enumerate(chains):
        heel_on, toe_on = world.contacts[:, 2 * s], world.contacts[:, 2 * s + 1]
        yaw = np.zeros(world.frames)
        toe_p = p[:, toe].copy()
        if fps is not None:
            heel_on = foot_lock.heel_down(p[:, ankle, 2], heel_on, toe_on)
            yaw = foot_lock.held_yaw(p[:, ankle, :2], p[:, toe, :2], heel_on, toe_on, blend)
            for f in range(world.frames):
                toe_p[f] = p[f, ankle] + _turn(up, yaw[f]) @ (p[f, toe] - p[f, ankle])
        d = foot_lock.planted_offsets(p[:, ankle, :2], toe_p[:, :2], heel_on, toe_on, blend)
        d = np.column_stack((d, np.zeros(world.frames)))
        if fps is not None:
            d[:, 2] = foot_lock.swing_lift(toe_p + d, heel_on, toe_on, fps)
        thigh = [hip] + foot_lock._segments(skel, knee, hip)
        shin = [knee] + foot_lock._segments(skel, ankle, knee)
        moved = False
        for f in range(world.frames):
            if np.linalg.norm(d[f]) <= 1e-7 and abs(yaw[f]) <= 1e-9:
                continue
            moved = True
            target = p[f, ankle] + d[f]
            h = world.ground[f, 2]
            r_thigh, r_shin = ik_one_frame(
                p[f, hip],
                p[f, knee],
                p[f, ankle],
                target,
                g[f, hip, :, 0],
                np.array([np.cos(h), np.sin(h), 0.0]),
            )
            axis = (target - p[f, hip]) / np.linalg.norm(target - p[f, hip])
            twist = _turn(axis, yaw[f])
            for j in thigh:
                g[f, j] = twist @ r_thigh @ g[f, j]
            for j in shin:
                g[f, j] = twist @ r_shin @ g[f, j]
            g[f, ankle] = _turn(up, yaw[f]) @ g[f, ankle]
        if moved:
            changed += thigh + shin + [ankle]
    local = local_rotations_from_global(skel, g)
    return local, changed


@pytest.mark.parametrize("fps", [None, 30.0], ids=["pinned", "swings-lifted"])
@pytest.mark.parametrize("blend", [foot_lock.BLEND_FRAMES, 1])
def test_the_vectorised_lock_is_the_frame_by_frame_one(walk_patch, walk, blend, fps):
    """On a planned walk of real capture (CMU 16_15 + 16_18, turning), lock_feet (both
    legs and all frames at once, the turns applied to the channels as quaternions) gives
    the rotations of the lock written frame by frame on the whole skeleton: the changed
    bones' channels to 1e-9, every other channel untouched (bar its sign); with the
    frame rate, the swinging feet lifted as well."""
    skel = walk_patch.gait.skeleton
    got = foot_lock.lock_feet(skel, walk, blend, fps=fps)
    want, changed = lock_feet_frame_by_frame(skel, walk, blend, fps)
    assert len(changed) == 6  # thigh, shin and ankle of both legs
    assert not np.allclose(np.abs(np.sum(want * walk.rotations, axis=-1))[:, changed], 1.0)
    dots = np.abs(np.sum(got[:, changed] * want[:, changed], axis=-1))
    assert np.all(np.abs(dots - 1.0) < 1e-9)
    others = [j for j in range(len(skel.names)) if j not in changed]
    assert np.array_equal(np.abs(got[:, others]), np.abs(walk.rotations[:, others]))


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("blend", [1, 4])
def test_both_feet_at_once_are_each_foot_alone(walk_patch, walk, seed, blend):
    """The feet's planted offsets found in one call (one foot after the other, a gap of
    unplanted frames between) are, to the bit, each foot's own: on the planned walk's feet
    and contacts and on random contacts running into the ends of the motion."""
    skel = walk_patch.gait.skeleton
    p = walk.world_matrices(skel)[..., :3, 3]
    feet = foot_lock.leg_chains(skel)
    ankle = np.stack([p[:, c[2], :2] for c in feet])
    toe = np.stack([p[:, c[3], :2] for c in feet])
    contacts = walk.contacts.copy()
    if seed:
        rng = np.random.default_rng(seed)
        contacts = np.repeat(rng.random((walk.frames // 6 + 1, 4)) < 0.5, 6, axis=0)
        contacts = contacts[: walk.frames]
        contacts[:, 1::2] |= contacts[:, ::2]
        contacts[-3:, 0] = contacts[:2, 3] = True  # planted at the ends
    # the left foot lifted just before the end, the right put down just after the start:
    # each fades within ``blend`` frames of where the other's frames begin when joined
    contacts[-8:-2, :2] = [[True, True]] * 5 + [[False, True]]
    contacts[-2:, :2] = False
    contacts[:2, 2:] = False
    contacts[2:8, 2:] = True
    got = foot_lock._both_planted_offsets(ankle, toe, contacts, blend)
    for s in range(2):
        want = foot_lock.planted_offsets(
            ankle[s], toe[s], contacts[:, 2 * s], contacts[:, 2 * s + 1], blend
        )
        assert np.array_equal(got[s], want)
        assert np.any(want != 0)


def swinging_foot(dip=0.03):
    """Toe positions (F, 3) of one foot: planted at 2 cm, a swing 0.7 m forward (up to
    2.5 m/s, easing in and out) that dips ``dip`` below the planted height (a retargeted
    leg's; a negative dip rises), planted again; the ankle and toe contact flags (F,)."""
    plant, swing = 15, 12
    t = (np.arange(swing) + 1) / (swing + 1)
    x = np.concatenate((np.zeros(plant), 0.35 * (1 - np.cos(np.pi * t)), np.full(plant, 0.7)))
    z = np.concatenate(
        (np.full(plant, 0.02), 0.02 - dip * np.sqrt(np.sin(np.pi * t)), np.full(plant, 0.02))
    )
    toe = np.column_stack((x, np.zeros_like(x), z))
    on = np.ones(len(x), bool)
    on[plant : plant + swing] = False
    return toe, on, on.copy()


def test_a_swinging_toe_is_lifted_clear_of_its_planted_height():
    """A swing dipping 3 cm through the floor of its plants is lifted to at least
    SWING_CLEARANCE above it wherever the toe moves faster than SWING_SPEED[1], eased in
    and out (no step of the lift over a fifth of the most needed, 2 * LIFT_FRAMES + 1
    frames taking it up); far from the swing nothing moves."""
    fps = 30.0
    toe, heel_on, toe_on = swinging_foot()
    lift = foot_lock.swing_lift(toe, heel_on, toe_on, fps)
    z = toe[:, 2] + lift
    step = np.linalg.norm(np.diff(toe[:, :2], axis=0), axis=1) * fps
    fast = np.zeros(len(toe), bool)
    fast[1:] |= step > foot_lock.SWING_SPEED[1]
    fast[:-1] |= step > foot_lock.SWING_SPEED[1]
    fast &= ~toe_on
    assert fast.sum() > 5
    assert np.all(z[fast] >= 0.02 + foot_lock.SWING_CLEARANCE - 1e-12)
    most = 0.03 + foot_lock.SWING_CLEARANCE
    assert np.abs(np.diff(lift)).max() <= most / (2 * foot_lock.LIFT_FRAMES + 1) + 1e-12
    r = 2 * foot_lock.LIFT_FRAMES
    assert np.all(lift[: 15 - r] == 0) and np.all(lift[27 + r :] == 0)
    assert lift.max() <= most + 1e-12


def test_a_toe_swinging_clear_or_never_planted_is_not_lifted():
    fps = 30.0
    toe, heel_on, toe_on = swinging_foot(dip=-0.05)  # rises 5 cm: clear of the floor
    assert not foot_lock.swing_lift(toe, heel_on, toe_on, fps).any()
    toe, heel_on, toe_on = swinging_foot()
    never = np.zeros(len(toe), bool)
    assert not foot_lock.swing_lift(toe, never, never, fps).any()


def test_a_slow_toe_is_kept_out_of_the_floor_only():
    """A toe dipping while it barely moves (setting down, turning on the spot) is not a
    swing: slower than SWING_SPEED[0] it is lifted out of the floor of its plants, not
    SWING_CLEARANCE above them."""
    toe, heel_on, toe_on = swinging_foot()
    toe[:, 0] *= 0.15  # under 0.4 m/s
    z = toe[:, 2] + foot_lock.swing_lift(toe, heel_on, toe_on, 30.0)
    assert z.min() >= 0.02 - 1e-12
    deepest = np.argmin(toe[:, 2])
    assert z[deepest] < 0.02 + 0.5 * foot_lock.SWING_CLEARANCE


def test_a_rising_heel_hands_over_to_the_toe():
    """The frames ending a heel run with the heel more than HEEL_RISE above the lowest it
    was in the run, the toe planted, are the toe's alone; a heel rising with its toe off the
    floor, one that comes down again or one still down on the motion's last frame keeps its
    frames, and a run keeps its first frame (a heel coming down from above)."""
    z = np.array([0.2, 0.1, 0.08, 0.08, 0.08, 0.08, 0.085, 0.088, 0.11, 0.13, 0.16])
    heel = np.array([0, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0], bool)
    toe = np.ones(len(z), bool)
    got = foot_lock.heel_down(z, heel, toe)
    assert np.array_equal(np.flatnonzero(got), np.arange(1, 8))  # up 3 cm from frame 8
    assert np.array_equal(foot_lock.heel_down(z, heel, np.zeros(len(z), bool)), heel)
    dip = z.copy()
    dip[9] = 0.08  # down again on the run's last frame: the frames before it stay
    assert np.array_equal(foot_lock.heel_down(dip, heel, toe), heel)
    assert np.array_equal(foot_lock.heel_down(np.full(3, 0.5), [1, 0, 0], toe[:3]), [1, 0, 0])
    # a heel down to the motion's last frame is a stand (a back foot's heel up): it stays
    assert np.array_equal(foot_lock.heel_down(z[:10], heel[:10], toe[:10]), heel[:10])


def test_a_planted_foot_keeps_its_heading():
    """A foot yawing while its heel is down is held at the mean heading of its heel-down
    frames, never turned more than HELD_TURN, the turn fading out over the blend frames
    around them (outside them nothing turns); a contact on its toe alone is not held."""
    n, blend = 40, foot_lock.BLEND_FRAMES
    heel = np.zeros(n, bool)
    heel[10:26] = True
    toe_on = heel.copy()
    toe_on[26:30] = True  # heel up, on the toe
    ankle = np.zeros((n, 2))
    for drift in (np.radians(12.0), np.radians(60.0)):  # over the heel run
        heading = np.linspace(-0.5, 0.5, n) * drift * n / 16
        toe = np.column_stack((np.cos(heading), np.sin(heading))) * 0.12
        yaw = foot_lock.held_yaw(ankle, toe, heel, toe_on, blend)
        held = heading + yaw
        mean = heading[heel].mean()
        want = heading[heel] + np.clip(
            mean - heading[heel], -foot_lock.HELD_TURN, foot_lock.HELD_TURN
        )
        assert np.allclose(held[heel], want)
        assert np.abs(yaw).max() <= foot_lock.HELD_TURN + 1e-12
        assert np.all(yaw[: 10 - blend] == 0) and np.all(yaw[26 + blend :] == 0)
        # eased: a step no larger than the smoothstep's steepest plus the heading's own
        ease = 1.5 / (blend + 1) * foot_lock.HELD_TURN + np.abs(np.diff(heading)).max()
        assert np.abs(np.diff(yaw)).max() <= ease
    assert np.ptp(held[heel]) > 0  # a 60 deg drift is held only 10 deg either way
    tip = foot_lock.held_yaw(ankle, toe, np.zeros(n, bool), toe_on, blend)
    assert not tip.any()


def test_written_feet_do_not_sweep_their_toes_while_the_heel_is_down(walk_patch, walk):
    """On the planned walk that turns, locked as a plan is written (with its frame rate):
    the foot's heading on its heel-down frames is the held one (the synthesised heading
    turned by held_yaw), and the toe slides less than half as fast there as under the pin
    alone, whose foot keeps yawing with the body (the toe 12 cm out sweeping across)."""
    skel, fps = walk_patch.gait.skeleton, 30.0
    _, posed = foot_lock.pose_legs(skel, walk)
    legs = foot_lock._legs(skel)
    pinned = Motion(walk.ground, walk.root_local, foot_lock.lock_feet(skel, walk), walk.contacts)
    written = Motion(
        walk.ground, walk.root_local, foot_lock.lock_feet(skel, walk, fps=fps), walk.contacts
    )
    wp, ww = pinned.world_matrices(skel)[..., :3, 3], written.world_matrices(skel)[..., :3, 3]
    for s, (_, _, ankle, toe) in enumerate(foot_lock.leg_chains(skel)):
        a, t = legs.legs[s, 2], legs.legs[s, 3]
        heel = foot_lock.heel_down(
            posed[a, :, 2], walk.contacts[:, 2 * s], walk.contacts[:, 2 * s + 1]
        )
        yaw = foot_lock.held_yaw(
            posed[a, :, :2], posed[t, :, :2], heel, walk.contacts[:, 2 * s + 1]
        )
        v0, v = posed[t, :, :2] - posed[a, :, :2], ww[:, toe, :2] - ww[:, ankle, :2]
        want = np.arctan2(v0[:, 1], v0[:, 0]) + yaw
        got = np.arctan2(v[:, 1], v[:, 0])
        assert np.allclose(np.angle(np.exp(1j * (got - want)))[heel], 0.0, atol=1e-6)
        both = heel[1:] & heel[:-1]

        def slide(w):
            return np.linalg.norm(np.diff(w[:, toe, :2], axis=0), axis=1)[both].mean()

        assert slide(ww) < 0.5 * slide(wp)
