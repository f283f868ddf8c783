# SPDX-License-Identifier: GPL-3.0-or-later
"""The clearance rule holds for the body: the hips, not only the ground path, keep the radius
from every footprint (issue: nothing lost, nothing crossed, item 6)."""

import numpy as np

from motion_patches.kinematics.inplace import to_world
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning import body_clearance
from motion_patches.planning.planner import PlanError, SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle


def pillar(name, x, y, r):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]  # 12-sided, as the bench draws pillars
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def fields(walk_patch, count, seed=1):
    """Seeded random pillar fields: (environment, pillars, goal) with 12 pillars between a
    start at the origin and a goal 12 m away."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        env = Environment(walk_patch.side, walk_patch.cells, 0.25)
        pillars = []
        for k in range(12):
            x, y = rng.uniform((2, -3), (10, 3))
            r = rng.uniform(0.15, 0.4)
            pillars.append((x, y, r))
            env.place(pillar(f"p{k}", x, y, r))
        yield env, pillars, (12.0, float(rng.uniform(-2, 2)), 0.0)


def hips_clearance(patch, plan, pillars):
    m = concatenate(plan_motions(patch, plan))
    hips = to_world(patch.gait.skeleton, m.ground, m.root_local, m.rotations)[0][:, :2]
    d = min(float(np.min(np.hypot(hips[:, 0] - x, hips[:, 1] - y))) - r for x, y, r in pillars)
    return d, m


def test_a_plan_whose_hips_come_within_the_radius_is_planned_again_wider(walk_patch):
    """Among seeded random pillar fields, plans whose shortest ground path grazes pillars at
    exactly the radius bring the swaying hips closer; each is planned again keeping the
    sway more, and then its hips keep the radius."""
    start = (0.0, 0.0, 0.0)
    fixed = 0
    for env, pillars, goal in fields(walk_patch, 80):
        planner = SegmentPlanner(walk_patch, env)
        try:
            plan = planner.plan(start, goal)
        except PlanError:
            continue
        ms = plan_motions(walk_patch, plan)
        close = body_clearance.hips_too_close(walk_patch, plan.pieces, ms, env)
        if not close:
            continue
        before, _ = hips_clearance(walk_patch, plan, pillars)
        assert before < 0.25  # the ground path keeps 0.25 m, the hips do not
        again, motions = body_clearance.keep_clear(
            planner, plan, ms, start, goal, lambda p: plan_motions(walk_patch, p)
        )
        assert again is not plan and "planned again" in again.stats["body_clearance"]
        after, m = hips_clearance(walk_patch, again, pillars)
        assert after >= 0.25 - 1e-3, after  # polygon pillars: the hips keep the radius
        assert body_clearance.hips_too_close(walk_patch, again.pieces, motions, env) == []
        assert np.allclose(m.ground[-1, :2], goal[:2], atol=1e-6)
        fixed += 1
        if fixed == 2:
            break
    print(f"\n{fixed} plans re-planned wider, their hips then clear")
    assert fixed >= 1  # the case exists on these fields


def test_a_plan_that_keeps_clear_is_left_alone(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    env.place(pillar("p", 5.0, 3.0, 0.3))
    planner = SegmentPlanner(walk_patch, env)
    plan = planner.plan((0.0, 0.0, 0.0), (10.0, 0.0, 0.0))
    ms = plan_motions(walk_patch, plan)
    same, _ = body_clearance.keep_clear(
        planner, plan, ms, (0.0, 0.0, 0.0), (10.0, 0.0, 0.0), lambda p: plan_motions(walk_patch, p)
    )
    assert same is plan and "body_clearance" not in plan.stats
    sway = body_clearance.sway(walk_patch.gait)
    print(f"\nthe hips sway at most {sway * 100:.0f} cm from the ground path (CMU 16 walk)")
    assert 0.05 < sway < 0.2
