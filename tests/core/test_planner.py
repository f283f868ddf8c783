# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np
import pytest

from motion_patches.kinematics import contacts
from motion_patches.kinematics.inplace import to_world
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning.planner import PlanError, SegmentPlanner, piece_motion, plan_motions
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import metrics


def pillar(name, x, y, r=0.25):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def planned_motion(patch, plan):
    return concatenate([piece_motion(patch, p) for p in plan.pieces])


@pytest.fixture
def open_ground(walk_patch):
    return Environment(walk_patch.side, walk_patch.cells, radius=0.25)


def test_plan_on_open_ground_ends_exactly_on_the_goal(walk_patch, open_ground):
    plan = SegmentPlanner(walk_patch, open_ground).plan((0.5, 0.5, 0.0), (9.0, 3.0, 0.8))
    m = planned_motion(walk_patch, plan)
    assert np.allclose(m.ground[-1, :2], (9.0, 3.0), atol=1e-6)
    assert np.isclose(m.ground[-1, 2] % (2 * np.pi), 0.8, atol=1e-6)
    assert np.allclose(m.ground[0], (0.5, 0.5, 0.0), atol=1e-6)
    assert plan.pieces[-1].kind == "goal"
    # The search went through the node graph; on open ground the found path is then
    # shortened (here: a start connector straight into a goal connector).
    assert plan.stats["pieces_searched"] >= len(plan.pieces)
    assert plan.stats["cost_shortened"] <= plan.cost + 1e-9
    searched = SegmentPlanner(walk_patch, open_ground).plan(
        (0.5, 0.5, 0.0), (9.0, 3.0, 0.8), shorten=False
    )
    assert [p.kind for p in searched.pieces][0] == "start"
    assert any(p.kind == "segment" for p in searched.pieces)
    m = planned_motion(walk_patch, searched)
    assert np.allclose(m.ground[-1, :2], (9.0, 3.0), atol=1e-6)
    assert np.allclose(m.ground[0], (0.5, 0.5, 0.0), atol=1e-6)


def test_the_hips_stop_over_the_goal_point(walk_patch, open_ground):
    """The stop ends wherever the stride does; the body is brought over the goal point
    (the ground path still ends on it, the hips too, the last steps still slow)."""
    skel, fps = walk_patch.gait.skeleton, walk_patch.gait.fps
    off_by_itself = []
    for goal in [(9.0, 3.0, 0.8), (6.0, -4.0, -2.5), (11.0, 0.7, 0.0), (3.0, 7.0, 2.0)]:
        plan = SegmentPlanner(walk_patch, open_ground).plan((0.5, 0.5, 0.0), goal)
        m = concatenate(plan_motions(walk_patch, plan))
        raw = concatenate(plan_motions(walk_patch, plan, standing=False))
        hips = to_world(skel, m.ground, m.root_local, m.rotations)[0]
        hips_raw = to_world(skel, raw.ground, raw.root_local, raw.rotations)[0]
        assert np.allclose(m.ground[-1, :2], goal[:2], atol=1e-6)
        assert np.linalg.norm(hips[-1, :2] - goal[:2]) < 1e-6
        assert np.linalg.norm(hips[-1, :2] - hips[-2, :2]) * fps < 0.2
        assert np.linalg.norm(np.diff(hips[:, :2], axis=0), axis=1).max() < 0.08
        off_by_itself.append(np.linalg.norm(hips_raw[-1, :2] - goal[:2]))
    # Not so by itself: where the stride ends leaves the hips off the goal point.
    assert max(off_by_itself) > 0.01


def test_planned_ground_path_is_continuous(walk_patch, open_ground):
    plan = SegmentPlanner(walk_patch, open_ground).plan((0.5, 0.5, 1.0), (-4.0, 6.0, 2.0))
    m = planned_motion(walk_patch, plan)
    step = np.linalg.norm(np.diff(m.ground[:, :2], axis=0), axis=1)
    assert step.max() < 0.08  # metres per frame: no jump between pieces
    assert np.abs(np.diff(m.ground[:, 2])).max() < 0.1


def test_plan_avoids_pillars_with_the_character_radius(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    for n, (x, y) in enumerate([(3, 0.6), (4.5, 1.5), (3.5, 2.8), (6, 0.2), (6.5, 2.5)]):
        env.place(pillar(f"p{n}", x, y))
    plan = SegmentPlanner(walk_patch, env).plan((0.5, 1.3, 0.0), (9.0, 1.3, 0.0))
    m = planned_motion(walk_patch, plan)
    assert not env.blocked(m.ground[:, :2]).any()


def test_planned_walk_keeps_foot_skate_low(walk_patch, open_ground, walk_gait):
    plan = SegmentPlanner(walk_patch, open_ground).plan((0.5, 0.5, 0.0), (9.0, 5.0, 1.0))
    m = planned_motion(walk_patch, plan)
    fj = contacts.foot_joints(walk_gait.skeleton)
    fp = m.world_matrices(walk_gait.skeleton)[:, fj][..., :3, 3]
    skate = metrics.foot_skate(fp, walk_gait.fps, m.contacts)
    assert skate["mean_cm_per_frame"] < 1.0


def test_weights_change_the_plan_cost_consistently(walk_patch, open_ground):
    a = SegmentPlanner(walk_patch, open_ground, 1.0, 0.5, 0.2).plan((0.5, 0.5, 0), (8, 4, 0))
    b = SegmentPlanner(walk_patch, open_ground, 2.0, 1.0, 0.4).plan((0.5, 0.5, 0), (8, 4, 0))
    assert np.isclose(b.cost, 2 * a.cost, rtol=1e-6)


def test_enclosed_goal_is_unreachable_with_a_clear_message(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    ring = [(6 + 1.6 * np.cos(a), 6 + 1.6 * np.sin(a)) for a in np.linspace(0, 2 * np.pi, 25)[:-1]]
    for n, (x, y) in enumerate(ring):
        env.place(pillar(f"r{n}", x, y, 0.3))
    with pytest.raises(PlanError, match="unreachable|no walkable way"):
        SegmentPlanner(walk_patch, env).plan((0.5, 0.5, 0), (6.0, 6.0, 0.0))


def test_goal_inside_an_obstacle_is_refused(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    env.place(pillar("p", 5, 5, 0.5))
    with pytest.raises(PlanError, match="goal .* inside"):
        SegmentPlanner(walk_patch, env).plan((0.5, 0.5, 0), (5.0, 5.0, 0.0))


def test_a_goal_facing_out_of_a_dead_end_is_reached_by_turning_on_the_spot(walk_patch):
    """The goal stands deep in a dead-end corridor facing its mouth: no walk can curve
    round in there, so without turning on the spot the exact facing is refused; with any
    facing the walk ends facing in; by default it walks in and turns round where it
    stands (the derived turn in place), ending on the goal facing the mouth."""
    from motion_patches.planning.planner import plan_motions

    def box(name, x0, y0, x1, y1):
        return Obstacle(name, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))

    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    for ob in (
        box("N", 3.0, 0.6, 6.6, 0.9),
        box("S", 3.0, -0.9, 6.6, -0.6),
        box("End", 6.3, -0.9, 6.6, 0.9),
    ):
        env.place(ob)
    planner = SegmentPlanner(walk_patch, env)
    start = (-2.0, 0.0, 0.0)
    with pytest.raises(PlanError):
        planner.plan(start, (5.4, 0.0, np.pi), turn_in_place=False)
    plan = planner.plan(start, (5.4, 0.0, np.nan))
    assert abs(plan.goal[2]) < np.radians(30)  # it walks in and stops facing the end wall
    world = concatenate(plan_motions(walk_patch, plan))
    assert np.linalg.norm(world.ground[-1, :2] - (5.4, 0.0)) < 0.01
    assert not env.blocked(world.ground[:, :2]).any()
    plan = planner.plan(start, (5.4, 0.0, np.pi))
    assert [p.kind for p in plan.pieces][-1] == "turn"
    world = concatenate(plan_motions(walk_patch, plan))
    assert np.linalg.norm(world.ground[-1, :2] - (5.4, 0.0)) < 0.01
    heading = (world.ground[-1, 2] - np.pi + np.pi) % (2 * np.pi) - np.pi
    assert abs(np.degrees(heading)) < 5.0
    assert not env.blocked(world.ground[:, :2]).any()
