# SPDX-License-Identifier: GPL-3.0-or-later
"""The lower bounds the segment search leans on stay lower bounds, and its shortcuts
(per-tile heuristic tables, coarse-first connector tests) answer as the plain forms do."""

import numpy as np
import pytest

from motion_patches.patch.node_keys import LOCAL, pack
from motion_patches.planning import dubins
from motion_patches.planning.planner import PlanError, SegmentPlanner
from motion_patches.props.environment import PATH_MARGIN, Environment, Obstacle


def pillar(name, x, y, r=0.3):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def pillar_field(patch, seed, count=40, field=16.0):
    rng = np.random.default_rng(seed)
    env = Environment(patch.side, patch.cells, 0.25)
    for n in range(count):
        x, y = rng.uniform(0.0, field, 2)
        if np.hypot(x - 1.0, y - 1.0) > 1.2 and np.hypot(x - 14.0, y - 12.0) > 1.2:
            env.place(pillar(f"p{n}", x, y, rng.uniform(0.2, 0.4)))
    return env


GOALS = [(14.0, 12.0, h) for h in (-2.5, -0.3, 1.2, 2.9)]


@pytest.mark.parametrize("seed", range(3))
def test_heuristic_never_overestimates_the_rest_of_a_found_path(walk_patch, seed):
    """For every node on a found path h(node) <= the cost of the pieces after it (the
    turn to the goal heading counted in h), so A* stays optimal; on these plans the goal
    heading term is what h holds at some nodes (it is not idle)."""
    binding = 0
    for goal in GOALS:
        planner = SegmentPlanner(walk_patch, pillar_field(walk_patch, seed))
        try:
            plan = planner.plan((1.0, 1.0, 0.3), goal, shorten=False)
        except PlanError:
            continue
        pieces = plan.pieces
        rest = np.cumsum([p.cost for p in pieces][::-1])[::-1]  # cost from piece i on
        keys = [
            int(pack(p.tile[0], p.tile[1], walk_patch.seg_entry[p.segment]))
            for p in pieces
            if p.kind == "segment"
        ]
        remaining = [rest[i] for i, p in enumerate(pieces) if p.kind == "segment"]
        assert keys, "the plan walks no segment"
        h = planner.heuristic(np.array(keys))
        assert np.all(h <= np.array(remaining) + 1e-9), (h - np.array(remaining)).max()
        # Where the goal-heading term raises h above its value for any facing.
        planner.goal = np.array([planner.goal[0], planner.goal[1], np.nan])
        without = planner.heuristic(np.array(keys))
        binding += int(np.sum(h > without + 1e-9))
    assert binding > 0


def test_per_tile_heuristic_table_matches_the_vectorised_heuristic(walk_patch):
    planner = SegmentPlanner(walk_patch, pillar_field(walk_patch, 0))
    planner.goal = np.array([7.3, -2.1, 0.9])
    rng = np.random.default_rng(0)
    i, j = rng.integers(-6, 6, 200), rng.integers(-6, 6, 200)
    keys = pack(i, j, rng.integers(0, LOCAL, 200))
    one = np.array([planner.heuristic_of(int(k)) for k in keys])
    assert np.allclose(one, planner.heuristic(keys), rtol=0, atol=1e-12)
    # Any facing: no goal-heading term.
    planner.goal = np.array([7.3, -2.1, np.nan])
    assert np.allclose(
        [planner.heuristic_of(int(k)) for k in keys], planner.heuristic(keys), atol=1e-12
    )


def test_coarse_first_connector_test_answers_as_testing_every_sample(walk_patch):
    """Dubins words round a pillar field: blocked exactly when some sample comes within
    the radius (+ margin) of a footprint, whichever samples the coarse pass looked at."""
    env = pillar_field(walk_patch, 1, count=60)
    planner = SegmentPlanner(walk_patch, env)
    rng = np.random.default_rng(5)
    n = 300
    p0 = rng.uniform(0.0, 16.0, (n, 2))
    p1 = p0 + rng.uniform(-4.0, 4.0, (n, 2))
    h0, h1 = rng.uniform(-np.pi, np.pi, n), rng.uniform(-np.pi, np.pi, n)
    lengths = dubins.words(p0, h0, p1, h1, 0.8)  # (W, n, 3)
    word = np.nanargmin(np.where(np.isnan(lengths), np.inf, lengths).sum(axis=2), axis=0)
    lens = lengths[word, np.arange(n)]
    _, pos, _, _, first = dubins.samples(p0, h0, word, lens, 0.8)
    every = env.blocked(pos, radius=env.radius + PATH_MARGIN)
    expected = np.logical_or.reduceat(every, first[:-1])
    got = planner.samples_blocked(pos, first)
    assert np.array_equal(got, expected)
    assert 0.2 * n < expected.sum() < 0.9 * n  # both answers are common here


@pytest.mark.parametrize("seed", range(3))
def test_blocked_with_exclude_answers_as_each_footprint_tested(walk_patch, seed):
    """Environment.blocked with ``exclude`` (stitching's tests, where a look-up of the
    footprints near the points may answer before the raster) gives every footprint's own
    distance test's answer, for the radius and a larger one; the points include groups
    near only the excluded footprint (the look-up answers) and groups near others."""
    env = pillar_field(walk_patch, seed, count=30)
    rng = np.random.default_rng(seed)
    names = sorted(env.obstacles)
    looked_up = hits = 0
    for k in range(60):
        exclude = tuple(rng.choice(names, rng.integers(1, 3), replace=False).tolist())
        if k % 2:  # round an excluded pillar
            centre, spread = env.obstacles[exclude[0]].polygon.mean(axis=0), 0.3
        else:
            centre, spread = rng.uniform(0.0, 16.0, 2), rng.choice((0.3, 1.5))
        pts = centre + rng.normal(0.0, spread, (rng.integers(1, 200), 2))
        for radius in (None, 0.5):
            r = env.radius if radius is None else radius
            want = np.zeros(len(pts), bool)
            for n, ob in env.obstacles.items():
                if n not in exclude:
                    want |= ob.within(pts, r)
            got = env.blocked(pts, exclude=exclude, radius=radius)
            assert np.array_equal(got, want)
            hits += want.any()
            near = env.names_in_box(pts.min(axis=0) - r, pts.max(axis=0) + r)
            looked_up += all(n in exclude for n in near)
    print("groups answered by the look-up:", looked_up, "of 120; with a point blocked:", hits)
    assert looked_up >= 20  # the look-up's answer (nothing else near) is exercised
    assert hits >= 20  # and so are points near other footprints
