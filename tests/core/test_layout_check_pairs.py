# SPDX-License-Identifier: GPL-3.0-or-later
"""A layout check's pairs planned from the patch and the footprints alone
(:mod:`motion_patches.planning.layout_check`): the figures of the full motion, kept planners
and figures reused only for the same world, and the same answers on a Dask worker."""

import numpy as np
import pytest

from motion_patches.kinematics import quat
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning import layout_check
from motion_patches.planning.pieces import Piece
from motion_patches.planning.planner import SegmentPlanner, piece_motion, plan_motions
from motion_patches.props.environment import Environment, Obstacle


def box(name, x, y, half=0.3):
    return Obstacle(name, np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half + (x, y))


PILLARS = [box(f"P{n}", 2.0 + 1.5 * (n % 4), -2.0 + 1.5 * (n // 4)) for n in range(12)]
WALL = [Obstacle("Wall", np.array([[2.0, -0.5], [2.2, -0.5], [2.2, 4.0], [2.0, 4.0]]))]
PAIRS = [  # (obstacles, start, goal): open ground, round pillars, a U-turn round a wall's end
    ([], (0.0, 0.0, 0.0), (6.0, 2.0, 0.5)),
    ([], (0.0, 0.0, 0.0), (-3.0, 0.5, np.pi)),  # the goal behind: turns on the spot
    (PILLARS, (0.0, 0.0, 0.0), (8.5, 1.0, 0.0)),
    (WALL, (0.0, 1.0, 0.0), (3.5, 1.5, np.pi)),
]


def planned(patch, obstacles, start, goal):
    env = Environment(patch.side, patch.cells, 0.25)
    for ob in obstacles:
        env.place(ob)
    planner = SegmentPlanner(patch, env, 1.0, 0.0, 0.0, turn_in_place=True)
    return planner.plan(np.array(start), np.array(goal))


@pytest.mark.parametrize("obstacles, start, goal", PAIRS, ids=["open", "behind", "pillars", "u"])
def test_motion_without_poses_has_the_frames_and_ground_of_the_full_one(
    walk_patch, obstacles, start, goal
):
    plan = planned(walk_patch, obstacles, start, goal)
    full = concatenate(plan_motions(walk_patch, plan))
    light = concatenate(plan_motions(walk_patch, plan, poses=False))
    assert light.frames == full.frames
    np.testing.assert_array_equal(light.ground, full.ground)
    # the hips' sway the same; their height settles into the stand with the body only
    np.testing.assert_array_equal(light.root_local[:, :2], full.root_local[:, :2])
    assert light.rotations.shape[1] == 0 < full.rotations.shape[1]
    if goal[2] == np.pi and not obstacles:
        assert any(p.kind == "turn" for p in plan.pieces)


def test_a_pieces_last_frame_alone_is_the_last_frame_of_its_whole_motion(walk_patch):
    """What a turn after a piece starts from (a light plan poses that frame alone): the
    connectors of a plan that ends turning, a segment and a part of one."""
    plan = planned(walk_patch, *PAIRS[3])
    assert [p.kind for p in plan.pieces][-1] == "turn"
    pieces = [p for p in plan.pieces if p.kind != "turn"] + [
        Piece("segment", segment=7, tile=(1, -2)),
        Piece("part", segment=7, tile=(1, -2), frames=(2, 12)),
    ]
    for piece in pieces:
        for standing in (False, True):
            whole = piece_motion(walk_patch, piece, standing)
            last = piece_motion(walk_patch, piece, standing, last=True)
            assert last.frames == 1
            np.testing.assert_array_equal(last.ground[0], whole.ground[-1])
            np.testing.assert_array_equal(last.root_local[0], whole.root_local[-1])
            np.testing.assert_array_equal(last.contacts[0], whole.contacts[-1])
            # each rotation as the same quaternion (a whole motion's signs are made continuous)
            np.testing.assert_array_equal(
                quat.log(last.rotations[0]), quat.log(whole.rotations[-1])
            )


def test_interaction_clips_keep_frames_and_ground_without_poses(walk_patch, stand_walk_sit):
    plan = stand_walk_sit[0]
    full = concatenate(plan_motions(walk_patch, plan))
    light = concatenate(plan_motions(walk_patch, plan, poses=False))
    assert light.frames == full.frames
    np.testing.assert_array_equal(light.ground, full.ground)


def tasks_and_worlds(obstacles_sets, pairs):
    worlds, tasks = {}, []
    for obstacles, (start, goal) in zip(obstacles_sets, pairs):
        w = layout_check.world(obstacles, 0.25, 1.0, 0.0, 0.0, True)
        worlds[w.key] = w
        tasks.append({"world": w.key, "start": list(start), "goal": list(goal), "margin": 3})
    return tasks, worlds


def test_pairs_get_the_figures_of_a_fresh_plan_and_an_unchanged_world_reuses_them(walk_patch):
    layout_check.forget()
    obstacles, start, goal = PAIRS[2]
    tasks, worlds = tasks_and_worlds([obstacles], [(start, goal)])
    first = layout_check.plan_pair(tasks[0], walk_patch, worlds)
    plan = planned(walk_patch, obstacles, start, goal)
    motion = concatenate(plan_motions(walk_patch, plan))
    assert first["reachable"] and not first["reused"]
    assert first["cost"] == pytest.approx(plan.cost, abs=0)
    assert first["seconds"] == (motion.frames - 1) / walk_patch.gait.fps
    steps = np.diff(motion.ground[:, :2], axis=0)
    assert first["length_m"] == pytest.approx(np.linalg.norm(steps, axis=1).sum(), abs=0)
    again = layout_check.plan_pair(tasks[0], walk_patch, worlds)
    assert again["reused"] and {**again, "reused": False} == first
    # the figures forgotten, the planner kept: planned again by it, to the same figures
    planner = layout_check.planner_in(walk_patch, worlds[tasks[0]["world"]])[1]
    layout_check.forget(planners=False)
    warm = layout_check.plan_pair(tasks[0], walk_patch, worlds)
    assert layout_check.planner_in(walk_patch, worlds[tasks[0]["world"]])[1] is planner
    assert not warm["reused"]
    assert {k: v for k, v in warm.items() if k != "plan_seconds"} == {
        k: v for k, v in first.items() if k != "plan_seconds"
    }
    # a pillar moved 1 cm: another world, planned again
    moved = [box("P0", PILLARS[0].polygon[:, 0].mean() + 0.01, PILLARS[0].polygon[:, 1].mean())]
    tasks2, worlds2 = tasks_and_worlds([moved + obstacles[1:]], [(start, goal)])
    assert tasks2[0]["world"] != tasks[0]["world"]
    assert not layout_check.plan_pair(tasks2[0], walk_patch, worlds2)["reused"]


def test_a_closed_goal_names_its_props(walk_patch):
    cage = [
        box(f"C{k}", 5 + 1.2 * np.cos(a), 1.2 * np.sin(a), 0.35)
        for k, a in enumerate(np.linspace(0, 2 * np.pi, 13)[:-1])
    ]
    tasks, worlds = tasks_and_worlds([cage], [((0.0, 0.0, 0.0), (5.0, 0.0, 0.0))])
    got = layout_check.plan_pair(tasks[0], walk_patch, worlds)
    assert not got["reachable"] and got["error"]
    assert got["blocked"] and all(n.startswith("C") for n in got["blocked"])


def test_a_world_s_key_follows_its_props_clips():
    from motion_patches.kinematics.motion import Motion
    from motion_patches.props.object_patch import ObjectPatch, PatchClip

    def prop(effort=1.0, lift=0.0):
        n = 5
        ground = np.column_stack((np.linspace(-1, 1, n), np.zeros(n), np.zeros(n)))
        root = np.tile([0.0, 0.0, 1.0 + lift], (n, 1))
        motion = Motion(ground, root, np.tile([1.0, 0, 0, 0], (n, 2, 1)), np.zeros((n, 4), bool))
        square = np.array([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]])
        clip = PatchClip("hop", "traversal", motion, effort)
        return ObjectPatch("Bench", square, [clip], (2.0, 0.0, 0.0))

    def key(*props):
        return layout_check.world(PILLARS, 0.25, 1.0, 0.0, 0.0, True, props).key

    assert key(prop()) == key(prop())  # the same content, other objects: one planner
    assert len({key(), key(prop()), key(prop(effort=2.0)), key(prop(lift=0.1))}) == 4
