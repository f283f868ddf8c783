# SPDX-License-Identifier: GPL-3.0-or-later
"""Every "no path" names its cause (issue 15, item 5): the props in the way, the patch, or
the search limit (motion_patches.causes)."""

import numpy as np
import pytest

from motion_patches.planning import causes
from motion_patches.planning.planner import SegmentPlanner
from motion_patches.props.environment import Environment, Obstacle


def box(name, x0, y0, x1, y1):
    return Obstacle(name, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))


def pillar(name, x, y, r=0.3):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def env_with(patch, *obstacles):
    env = Environment(patch.side, patch.cells, radius=0.25)
    for ob in obstacles:
        env.place(ob)
    return env


def no_path(patch, env, start, goal, **kw):
    with pytest.raises(causes.NoPath) as err:
        causes.plan_explained(
            SegmentPlanner(patch, env), np.array(start, float), np.array(goal, float), **kw
        )
    return err.value


def test_a_wall_across_the_way_is_named(walk_patch):
    err = no_path(
        walk_patch, env_with(walk_patch, box("Wall", 3.0, -30, 3.3, 30)), (0, 0, 0), (6, 0, 0)
    )
    assert (err.cause, err.props) == ("props", ["Wall"])
    assert "Cause: 'Wall' walls the goal off from the start" in str(err)


def test_pillars_closing_a_pocket_round_the_start_are_named(walk_patch):
    ring = [
        pillar(f"r{n}", 1.8 * np.cos(a), 1.8 * np.sin(a))
        for n, a in enumerate(np.linspace(0, 2 * np.pi, 17)[:-1])
    ]
    err = no_path(walk_patch, env_with(walk_patch, *ring), (0, 0, 0), (6, 0, 0))
    assert err.cause == "props" and err.props
    assert set(err.props) <= {ob.name for ob in ring}
    assert all(repr(n) in str(err) for n in err.props[: causes.NAMED])


def test_a_patch_that_cannot_turn_is_blamed_not_the_props(walk_patch):
    """Only the straight segments kept and the turns limited to a 50 m radius: no walk
    makes a 90 degree turn even on open ground, so the patch is the cause."""
    straight = walk_patch.without(np.flatnonzero(walk_patch.seg_turn > 1e-3))
    straight.stats = dict(walk_patch.stats, curvature_limits=[-0.02, 0.02])
    err = no_path(
        straight, env_with(straight, pillar("Near", 2.0, 3.5)), (0, 0, 0), (4, 4, np.pi / 2)
    )
    assert (err.cause, err.props) == ("patch", [])
    assert "Cause: the locomotion patch: even on open ground" in str(err)
    assert "50.00 m" in str(err) and "turn clip" in str(err)


def test_a_search_stopped_by_its_node_limit_says_so(walk_patch):
    err = no_path(walk_patch, env_with(walk_patch), (0, 0, 0), (20, 5, 0), max_expansions=3)
    assert err.cause == "search limit"
    assert "Cause: the search limit: the search stopped after 3 nodes" in str(err)


def test_a_found_path_is_untouched_by_the_explaining(walk_patch):
    env = env_with(walk_patch, pillar("p", 3, 0.2))
    planner = SegmentPlanner(walk_patch, env)
    plan = causes.plan_explained(planner, np.array([0.0, 0, 0]), np.array([6.0, 0, 0]))
    again = SegmentPlanner(walk_patch, env).plan(np.array([0.0, 0, 0]), np.array([6.0, 0, 0]))
    assert plan.cost == pytest.approx(again.cost)
    assert "expand" not in vars(planner)  # the counting wrapper is gone
