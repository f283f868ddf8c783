# SPDX-License-Identifier: GPL-3.0-or-later
"""The clearance rule holds for the body: the hips, not only the ground path, keep the radius
from every footprint (issue: nothing lost, nothing crossed, item 6)."""

import numpy as np

from motion_patches import body_clearance
from motion_patches.environment import Environment, Obstacle
from motion_patches.inplace import to_world
from motion_patches.motion import concatenate
from motion_patches.planner import SegmentPlanner, plan_motions

# A random pillar field (found by a search over seeded random fields) where the shortest ground path
# grazes pillars at exactly the radius and the hips, swaying, come closer.
PILLARS = [
    (5.26335, -0.090543, 0.267846),
    (8.973619, -2.171783, 0.256058),
    (6.279296, -0.382663, 0.299507),
    (5.990745, -0.517826, 0.321703),
    (4.63458, 0.641406, 0.33214),
    (3.045173, -1.041287, 0.386176),
    (9.72817, 2.954333, 0.160631),
    (8.61207, 2.611655, 0.375486),
    (7.71953, 1.053716, 0.329902),
    (6.599087, 1.73052, 0.275482),
    (3.8075, -2.433906, 0.377064),
    (8.039032, -1.936548, 0.355615),
]


def pillar(name, x, y, r):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]  # 12-sided, as the bench draws pillars
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def hips_clearance(patch, plan, env):
    m = concatenate(plan_motions(patch, plan))
    hips = to_world(patch.gait.skeleton, m.ground, m.root_local, m.rotations)[0][:, :2]
    return min(
        float(np.min(np.hypot(hips[:, 0] - x, hips[:, 1] - y))) - r for x, y, r in PILLARS
    ), m


def test_a_plan_whose_hips_come_within_the_radius_is_planned_again_wider(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    for k, p in enumerate(PILLARS):
        env.place(pillar(f"p{k}", *p))
    start, goal = (0.0, 0.0, 0.0), (12.0, -0.798613, 0.0)
    planner = SegmentPlanner(walk_patch, env)
    plan = planner.plan(start, goal)
    ms = plan_motions(walk_patch, plan)
    close = body_clearance.hips_too_close(walk_patch, plan.pieces, ms, env)
    before, _ = hips_clearance(walk_patch, plan, env)
    assert close and before < 0.25 - 0.005  # the ground path keeps 0.25 m, the hips do not
    again, motions = body_clearance.keep_clear(
        planner, plan, ms, start, goal, lambda p: plan_motions(walk_patch, p)
    )
    assert again is not plan and "planned again" in again.stats["body_clearance"]
    after, m = hips_clearance(walk_patch, again, env)
    assert after >= 0.25 - 1e-3, after  # polygon pillars: the hips keep the radius
    assert body_clearance.hips_too_close(walk_patch, again.pieces, motions, env) == []
    assert np.allclose(m.ground[-1, :2], goal[:2], atol=1e-6)


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
