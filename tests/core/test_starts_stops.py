# SPDX-License-Identifier: GPL-3.0-or-later
"""Plans start from and stop in a stand (derived from the walk's double-support frames):
both feet down on the first and the last frame, measured on the joints' positions as a
plan is written (contacts kept where the feet are still, feet locked)."""

import pickle

import numpy as np
import pytest

from motion_patches.kinematics import foot_lock, stand
from motion_patches.kinematics.contacts import foot_joints
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.planning.motions import flat_feet, stand_note
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle

HEIGHT_TOLERANCE = 0.03  # metres an ankle or toe may stand above its flat-footed height
TOE_STEP = 0.01  # metres a toe may move in one frame while the character stands


def pillar(name, x, y, r=0.25):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def scene(walk_patch, name):
    env = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    if name == "open ground":
        return env, (0.5, 0.5, 0.0), (9.0, 3.0, 0.8)
    if name == "pillars":
        for n, (x, y) in enumerate([(3, 0.6), (4.5, 1.5), (3.5, 2.8), (6, 0.2), (6.5, 2.5)]):
            env.place(pillar(f"p{n}", x, y))
        return env, (0.5, 1.3, 0.0), (9.0, 1.3, 0.0)
    if name == "u-turn":  # round the end of a wall, back the way it came
        env.place(
            Obstacle("wall", np.array([[0.5, -0.05], [6.5, -0.05], [6.5, 0.05], [0.5, 0.05]]))
        )
        return env, (3.5, 1.0, 0.0), (3.5, -1.0, np.pi)
    if name == "turn on the spot first":
        return env, (0.0, 0.0, np.pi), (8.0, 0.0, 0.0)
    assert name == "turn on the spot last"
    return env, (0.0, 0.0, 0.0), (8.0, 0.0, np.pi)


def flat_heights(gait):
    """Per foot joint (left ankle, toe, right ankle, toe), its height in the straight loop
    on the frames with that foot's heel and toe both planted (the foot flat): standing."""
    lp = gait.straight
    m = Motion(np.zeros((lp.frames, 3)), lp.root_local, lp.rotations, lp.contacts)
    z = m.world_matrices(gait.skeleton)[:, foot_joints(gait.skeleton)][..., 2, 3]
    c = np.asarray(lp.contacts, bool)
    out = np.zeros(4)
    for side in range(2):
        flat = c[:, 2 * side] & c[:, 2 * side + 1]
        out[2 * side : 2 * side + 2] = np.median(z[flat, 2 * side : 2 * side + 2], axis=0)
    return out


def written(walk_patch, plan):
    """Foot joint positions (F, 4, 3) of the plan as it is written (api/writing.py: feet
    planted where still, and locked) and those planted flags (F, 4)."""
    skel, fps = walk_patch.gait.skeleton, walk_patch.gait.fps
    world = concatenate(plan_motions(walk_patch, plan))
    posed = foot_lock.pose_legs(skel, world)
    still = foot_lock.still_contacts(skel, world, fps, posed)
    world = Motion(world.ground, world.root_local, world.rotations, still)
    locked = Motion(
        world.ground,
        world.root_local,
        foot_lock.lock_feet(skel, world, posed=posed, fps=fps),
        still,
    )
    return locked.world_matrices(skel)[:, foot_joints(skel)][..., :3, 3], still


@pytest.mark.parametrize(
    "name", ["open ground", "pillars", "u-turn", "turn on the spot first", "turn on the spot last"]
)
def test_a_plan_starts_and_ends_standing_on_both_feet(walk_patch, name):
    env, start, goal = scene(walk_patch, name)
    plan = SegmentPlanner(walk_patch, env).plan(start, goal)
    if name.startswith("turn"):
        assert "turn" in [p.kind for p in plan.pieces]
    assert stand_note(walk_patch, plan).startswith("start (derived) and stop (derived)")
    p, planted = written(walk_patch, plan)
    standing = flat_heights(walk_patch.gait)
    for frame in (0, -1):
        up = p[frame, :, 2] - standing
        print(f"{name}, frame {frame}: feet {np.round(100 * up, 1)} cm above standing")
        assert np.abs(up).max() < HEIGHT_TOLERANCE, (frame, up)
    # over the stand's ease in and out, no planted toe moves more than a centimetre a
    # frame (the foot landing from the last step may still be in the air there)
    k = walk_patch.gait.frames // 2
    for part in (slice(0, k + 1), slice(-k - 1, None)):
        toes, on = p[part][:, [1, 3]], planted[part][:, [1, 3]]
        step = np.linalg.norm(np.diff(toes, axis=0), axis=-1)[on[1:] & on[:-1]]
        assert step.max() < TOE_STEP, step.max()


def test_a_stand_is_made_once_per_pose_and_given_as_standing_makes_it(walk_patch):
    gait = walk_patch.gait
    feet = flat_feet(gait)
    lp, skel = gait.straight, gait.skeleton
    root, rot = lp.root_local[3], lp.rotations[3]
    made = stand.standing(skel, root, rot, feet)
    first = stand.stand_of(skel, root, rot, feet)
    again = stand.stand_of(skel, root, rot, feet)
    for a, b, c in zip(made, first, again):
        assert a.tobytes() == b.tobytes() == c.tobytes()
    assert again[1] is not first[1]  # copies: a caller cannot change the one remembered
    kept = feet.__dict__["_stands"]
    assert len(kept) >= 1
    other = stand.stand_of(skel, lp.root_local[9], lp.rotations[9], feet)
    assert len(kept) >= 2 and other[1].tobytes() != first[1].tobytes()
    assert "_stands" not in pickle.loads(pickle.dumps(feet)).__dict__  # made where used
