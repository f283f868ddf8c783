# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np

from motion_patches.patch import curves
from motion_patches.patch.locomotion_patch import cell_mask
from motion_patches.props.environment import FULL, Environment, Obstacle, convex_hull


def test_hermite_starts_and_ends_on_its_nodes_along_their_headings():
    c = curves.hermite_curve((0, 0), curves.unit(0), (2, 1), curves.unit(np.pi / 2), 1.0)
    assert np.allclose(c.pos[0], (0, 0)) and np.allclose(c.pos[-1], (2, 1))
    assert np.isclose(c.heading[0], 0.0, atol=1e-6)
    assert np.isclose(c.heading[-1], np.pi / 2, atol=1e-6)


def test_fit_scale_reaches_the_requested_length():
    p0, p1 = np.array([[0.0, 0.0]]), np.array([[2.0, 1.0]])
    d0, d1 = curves.unit(np.array([0.0])), curves.unit(np.array([np.pi / 2]))
    for target in (2.6, 3.0, 3.5):
        sc = curves.fit_scale(p0, d0, p1, d1, target)
        c = curves.hermite_curve(p0[0], d0[0], p1[0], d1[0], sc[0])
        assert abs(c.length - target) < 5e-3


def test_fit_scale_reports_impossible_lengths_as_nan():
    sc = curves.fit_scale([[0, 0]], [[1, 0]], [[2, 0]], [[1, 0]], 1.0)  # shorter than the chord
    assert np.isnan(sc[0])


def test_curvature_of_a_quarter_circle_is_one_over_radius():
    # A Hermite quarter circle of radius 2 (tangent scale 0.5523 * chord / sqrt2 ~ standard).
    r = 2.0
    k = 4 / 3 * (np.sqrt(2) - 1) * r / (r * np.sqrt(2))
    c = curves.hermite_curve((r, 0), curves.unit(np.pi / 2), (0, r), curves.unit(np.pi), 3 * k)
    assert np.allclose(c.kappa, 1 / r, rtol=0.03)


def test_arc_projection_inverts_arc_frame():
    s = np.linspace(0, 2, 9)
    pos, _ = curves.arc_frame(np.array([1.0, 2.0]), 0.3, 0.7, s)
    assert np.allclose(curves.arc_project(np.array([1.0, 2.0]), 0.3, 0.7, pos), s)


def test_cell_mask_of_a_line_along_the_bottom_row():
    pts = np.column_stack((np.linspace(0.01, 7.99, 50), np.full(50, 0.5)))[None]
    assert int(cell_mask(pts, 8.0, 8)[0]) == 0xFF


def test_tile_occlusion_bitfield_and_eq8():
    env = Environment(side=8.0, cells=8, radius=0.0)
    env.place(Obstacle("box", np.array([[3.2, 3.2], [3.8, 3.2], [3.8, 3.8], [3.2, 3.8]])))
    free = env.free_cells((0, 0))
    cell = 3 * 8 + 3
    assert int(free) == int(FULL) & ~(1 << cell)
    through = np.uint64(1 << cell) | np.uint64(1 << (cell + 1))
    beside = np.uint64(1 << (cell + 8))
    assert (through & free) != through  # occluded (Eq. 8)
    assert (beside & free) == beside


def test_radius_grows_occlusion_into_neighbouring_cells_and_tiles():
    env = Environment(side=8.0, cells=8, radius=0.5)
    env.place(Obstacle("post", np.array([[7.7, 3.2], [7.9, 3.2], [7.9, 3.4], [7.7, 3.4]])))
    assert (1, 0) in {t for t in [(1, 0)] if env.members(t)}
    assert int(env.free_cells((1, 0))) != int(FULL)  # within 0.5 m of the next tile
    assert int(env.free_cells((0, 1))) == int(FULL)


def test_moving_an_obstacle_only_updates_membership_until_asked():
    env = Environment(side=2.0, cells=8, radius=0.2)
    sq = np.array([[0.2, 0.2], [0.6, 0.2], [0.6, 0.6], [0.2, 0.6]])
    env.place(Obstacle("a", sq))
    before = env.occlusion_computations
    env.place(Obstacle("a", sq + 4.0))
    assert env.occlusion_computations == before
    assert env.members((0, 0)) == set() and "a" in env.members((2, 2))
    assert int(env.free_cells((0, 0))) == int(FULL)


def test_convex_hull_of_a_square_with_inner_points():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [0.2, 0.7]])
    hull = convex_hull(pts)
    assert len(hull) == 4
    area = 0.5 * np.sum(hull[:, 0] * np.roll(hull[:, 1], -1) - np.roll(hull[:, 0], -1) * hull[:, 1])
    assert np.isclose(area, 1.0)


def test_a_thin_fence_across_a_cell_occludes_it_even_with_a_tiny_radius():
    env = Environment(side=8.0, cells=8, radius=0.05)
    env.place(Obstacle("fence", np.array([[2.1, 3.49], [5.9, 3.49], [5.9, 3.51], [2.1, 3.51]])))
    free = int(env.free_cells((0, 0)))
    for ix in range(2, 6):
        assert not free >> (3 * 8 + ix) & 1


def test_vectorised_cell_occlusion_matches_the_pairwise_polygon_test():
    from motion_patches.props.environment import cells_within, polygons_within

    rng = np.random.default_rng(5)
    c = 0.3
    ix, iy = np.meshgrid(np.arange(8), np.arange(8), indexing="xy")
    x0, y0 = ix.ravel() * c, iy.ravel() * c
    for _ in range(30):
        pts = rng.uniform(-0.5, 2.9, size=(6, 2)) * rng.uniform(0.05, 1.0)
        poly = convex_hull(pts + rng.uniform(0, 2, 2))
        if len(poly) < 3:
            continue
        r = float(rng.choice([0.0, 0.05, 0.25]))
        fast = cells_within(x0, y0, c, poly, r)
        for k in range(64):
            cell = np.array(
                [[x0[k], y0[k]], [x0[k] + c, y0[k]], [x0[k] + c, y0[k] + c], [x0[k], y0[k] + c]]
            )
            assert fast[k] == polygons_within(cell, poly, r), (k, r)


def test_sub_cells_of_a_tile_see_an_obstacle_placed_after_they_were_read():
    """The sub-cell bitfields live as long as the tile's raster: an obstacle placed (or
    moved) near the tile drops them with it, also when the refilled raster takes its old
    slot back (the planner reads a tile's cells before its sub-cells)."""

    def square(cx, cy, h):
        return np.array([[cx - h, cy - h], [cx + h, cy - h], [cx + h, cy + h], [cx - h, cy + h]])

    env = Environment(2.0, 8, 0.3)
    env.place(Obstacle("pillar", square(0.3, 0.3, 0.1)))
    before = env.sub_states((0, 0), 0.33)
    env.place(Obstacle("spot", square(1.4, 1.4, 0.2)))
    env.cell_states((0, 0))  # refills the raster first, as the search does
    after = env.sub_states((0, 0), 0.33)
    fresh = Environment(2.0, 8, 0.3)
    fresh.place(Obstacle("pillar", square(0.3, 0.3, 0.1)))
    fresh.place(Obstacle("spot", square(1.4, 1.4, 0.2)))
    want = fresh.sub_states((0, 0), 0.33)
    assert not np.array_equal(before[0], want[0])  # the spot takes sub-cells
    assert np.array_equal(after[0], want[0]) and np.array_equal(after[1], want[1])
    env.remove("spot")
    env.cell_states((0, 0))
    back = env.sub_states((0, 0), 0.33)
    assert np.array_equal(back[0], before[0]) and np.array_equal(back[1], before[1])
