# SPDX-License-Identifier: GPL-3.0-or-later
"""Turning on the spot (derived from the walk's sharpest turn loop of CMU 16_18)."""

import numpy as np
import pytest

from motion_patches.kinematics import contacts, retime
from motion_patches.kinematics.foot_lock import leg_chains
from motion_patches.kinematics.motion import concatenate
from motion_patches.patch import gait as gait_mod
from motion_patches.planning import turn_in_place
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment
from motion_patches.quality import metrics, validate


def _skate(gait, m):
    fj = contacts.foot_joints(gait.skeleton)
    fp = m.world_matrices(gait.skeleton)[:, fj][..., :3, 3]
    return metrics.foot_skate(fp, gait.fps, m.contacts)["mean_cm_per_frame"]


@pytest.mark.parametrize("degrees", [180.0, -180.0, 90.0, -135.0, 45.0])
def test_a_turn_in_place_turns_exactly_and_keeps_its_feet(walk_gait, degrees):
    delta = np.radians(degrees)
    m = turn_in_place.turn_motion(walk_gait, (1.0, 2.0), 0.3, delta)
    assert m.ground[-1, 2] - m.ground[0, 2] == pytest.approx(delta, abs=1e-9)
    assert np.allclose(m.ground[:, :2], (1.0, 2.0))  # the ground frame stays on the spot
    steps = np.abs(np.diff(m.ground[:, 2]))
    loop = turn_in_place.turn_loop(walk_gait, delta)
    own = abs(loop.turn) * np.diff(loop.distance).max() / loop.cycle_distance
    assert steps.max() <= own / turn_in_place.MIN_SHARE + 1e-9  # the recorded turning pace
    w = m.world_matrices(walk_gait.skeleton)
    assert np.abs(w[:, 0, :2, 3] - (1.0, 2.0)).max() < 0.15  # the hips sway, no more
    # planted feet stay put (the stride's travel is taken out by IK), lower than the walk
    walked, turned = _skate(walk_gait, planned_walk(walk_gait)), _skate(walk_gait, m)
    eased = retime.eased(m, True, True, walk_gait.frames).frames / walk_gait.fps
    print(
        f"turn {degrees:+.0f} deg in place: {eased:.1f} s eased in and out, planted skate "
        f"{turned:.2f} cm/frame (a straight walk {walked:.2f})"
    )
    assert turned < walked
    c = m.contacts
    assert ((c[:, 0] | c[:, 1]) & (c[:, 2] | c[:, 3]))[-1]  # ends with both feet down
    for hip, knee, ankle, _ in leg_chains(walk_gait.skeleton):  # IK kept bone lengths
        for a, b in ((hip, knee), (knee, ankle)):
            length = np.linalg.norm(w[:, b, :3, 3] - w[:, a, :3, 3], axis=1)
            assert np.ptp(length) < 1e-6


def planned_walk(gait):
    from motion_patches.patch.curves import Curve
    from motion_patches.patch.synthesis import follow

    s = np.linspace(0.0, 4.0, 200)
    curve = Curve(s, np.column_stack((s, np.zeros_like(s))), np.zeros_like(s), np.zeros_like(s))
    return follow(gait, curve)


def test_a_lone_straight_walk_cannot_turn_on_the_spot(walk16):
    straight = gait_mod.build_gait("walk", walk16, ())
    assert not turn_in_place.can_turn(straight, -1.0, 1.0)


@pytest.mark.parametrize(
    "start, goal",
    [
        ((0.0, 0.0, np.pi), (8.0, 0.0, 0.0)),  # start facing away from the goal
        ((0.0, 0.0, 0.0), (8.0, 0.0, np.pi)),  # goal facing back the way in
        ((0.0, 0.0, -np.pi / 2), (0.0, 8.0, -np.pi / 2)),  # both facing -Y, goal at +Y
    ],
)
def test_a_walk_facing_away_turns_on_the_spot_and_goes_straight(walk_patch, start, goal):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    planner = SegmentPlanner(walk_patch, env)
    plan = planner.plan(start, goal)
    looped = planner.plan(start, goal, turn_in_place=False)
    assert "turn" in [p.kind for p in plan.pieces]
    motions = plan_motions(walk_patch, plan)
    world = concatenate(motions)
    g = world.ground
    length = np.sum(np.linalg.norm(np.diff(g[:, :2], axis=0), axis=1))
    straight = np.hypot(goal[0] - start[0], goal[1] - start[1])
    looped_length = np.sum(
        np.linalg.norm(
            np.diff(concatenate(plan_motions(walk_patch, looped)).ground[:, :2], axis=0), axis=1
        )
    )
    assert length < 1.02 * straight < looped_length
    assert np.linalg.norm(g[-1, :2] - goal[:2]) < 0.01
    assert abs(metrics.angle_difference(g[-1, 2], goal[2])) < np.radians(5)
    assert validate.plan_glitches(walk_patch, plan, motions) == []
    fps = walk_patch.gait.fps
    speed = np.linalg.norm(np.diff(g[:, :2], axis=0), axis=1) * fps
    assert speed[0] < 0.2 and speed[-1] < 0.2
