# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np

from motion_patches.planning.high_level import TilePlanner
from motion_patches.planning.planner import SegmentPlanner
from motion_patches.props.environment import Environment, Obstacle


def box(name, x0, y0, x1, y1):
    return Obstacle(name, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))


def test_open_ground_tile_path_is_a_shortest_grid_path(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    s = walk_patch.side
    tiles = TilePlanner(walk_patch, env).plan((0.5 * s, 0.5 * s), (4.5 * s, 2.5 * s))
    assert tiles[0] == (0, 0) and tiles[-1] == (4, 2)
    assert len(tiles) == 4 + 2 + 1
    assert all(abs(a[0] - b[0]) + abs(a[1] - b[1]) == 1 for a, b in zip(tiles, tiles[1:]))


def test_avoidance_probability_drops_in_a_blocked_tile(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    s = walk_patch.side
    env.place(box("wall", 1.0 * s, 0.0, 1.0 * s + 0.3, s))  # a wall across tile (1, 0), x = side
    tp = TilePlanner(walk_patch, env)
    open_u, wall_u = tp.upsilon((3, 3)), tp.upsilon((1, 0))
    assert open_u[3, 1] == 1.0  # west -> east on open ground
    assert wall_u[3, 1] < 0.2  # west -> east through the wall
    assert np.isinf(tp.edge_cost((1, 0), 3, 1)) or tp.edge_cost((1, 0), 3, 1) > 5 * s


def test_tile_probabilities_are_computed_only_for_expanded_tiles(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    s = walk_patch.side
    tp = TilePlanner(walk_patch, env)
    tp.plan((0.5 * s, 0.5 * s), (6.5 * s, 0.5 * s), region=(-20, -20, 20, 20))
    assert tp.tiles_evaluated <= 12  # a straight corridor, not the 41 x 41 region


def test_corridor_search_reaches_the_goal_like_the_full_search(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    full = SegmentPlanner(walk_patch, env).plan((0.5, 0.5, 0), (9.0, 4.0, 0.5))
    corr = SegmentPlanner(walk_patch, env).plan((0.5, 0.5, 0), (9.0, 4.0, 0.5), use_corridor=True)
    assert corr.stats["high_level_tiles"] > 0
    assert corr.cost >= full.cost - 1e-9  # the full search is optimal
    assert corr.cost <= 1.3 * full.cost
