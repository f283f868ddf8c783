# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowds: characters planned one by one are kept apart by waiting at their start."""

import numpy as np

from motion_patches import crowd
from motion_patches.environment import Environment
from motion_patches.motion import concatenate
from motion_patches.planner import SegmentPlanner, plan_motions


def line(p0, p1, frames):
    return np.linspace(p0, p1, frames)


def min_gap(a, b, da, db):
    horizon = max(len(a) + da, len(b) + db)
    return np.linalg.norm(crowd.timeline(a, da, horizon) - crowd.timeline(b, db, horizon),
                          axis=1).min()


def test_a_crossing_is_cleared_by_the_smallest_wait():
    a = line((-5.0, 0.0), (5.0, 0.0), 101)   # 10 m in 100 frames
    b = line((0.0, -5.0), (0.0, 5.0), 101)   # crosses a's path at the same moment
    assert min_gap(a, b, 0, 0) < 0.1
    delays, conflicts = crowd.stagger([a, b], clearance=0.5, max_delay=60, step=2)
    assert delays[0] == 0 and conflicts == []
    d = delays[1]
    assert min_gap(a, b, 0, d) >= 0.5
    assert min_gap(a, b, 0, d - 2) < 0.5       # and no shorter wait would do


def test_a_goal_on_someone_elses_path_is_reported_not_hidden():
    a = line((-5.0, 0.0), (5.0, 0.0), 101)
    b = line((0.0, -2.0), (0.0, 0.0), 21)      # b stands on a's path long before a comes
    delays, conflicts = crowd.stagger([a, b], clearance=0.5, max_delay=30, step=3)
    assert crowd.stagger([a, b], clearance=0.5, max_delay=60, step=3)[1] == []  # waiting longer lets a pass first
    assert len(conflicts) == 1
    c = conflicts[0]
    assert (c["a"], c["b"]) == (0, 1) and c["distance_m"] < 0.5
    assert abs(c["frame"] - 50) <= 3           # where a walks past b standing there


def test_far_apart_characters_do_not_wait():
    tracks = [line((x, 0.0), (x, 8.0), 80) for x in (0.0, 3.0, 6.0)]
    delays, conflicts = crowd.stagger(tracks, clearance=0.5, max_delay=60, step=6)
    assert delays == [0, 0, 0] and conflicts == []


def test_two_planned_walkers_crossing_in_the_open_are_staggered(walk_patch):
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    planner = SegmentPlanner(walk_patch, env)
    plans = [planner.plan((0.0, 0.0, 0.0), (8.0, 0.0, 0.0)),
             planner.plan((4.0, -4.0, np.pi / 2), (4.0, 4.0, np.pi / 2))]
    tracks = [concatenate(plan_motions(walk_patch, p)).ground[:, :2] for p in plans]
    clearance = 1.0  # two characters of 0.5 m radius
    assert min_gap(tracks[0], tracks[1], 0, 0) < clearance  # they would walk into each other
    delays, conflicts = crowd.stagger(tracks, clearance, max_delay=120, step=6)
    assert conflicts == [] and delays[0] == 0 and delays[1] > 0
    assert min_gap(tracks[0], tracks[1], 0, delays[1]) >= clearance


def test_standing_spots_are_earlier_goals_and_later_starts():
    ends = [((0, 0, 0), (10, 0, 0)), ((0, 3, 0), (10, 3, 0)), ((0, 6, 0), (10, 6, 0))]
    spots = crowd.standing_spots(ends, 1, spacing=1.0, radius=0.25)
    assert [m for m, _ in spots] == [0, 2]
    centres = [poly.mean(axis=0) for _, poly in spots]
    assert np.allclose(centres[0], (10, 0)) and np.allclose(centres[1], (0, 6))
    # grown by the planner's radius, a disc keeps the spacing between the two roots
    assert np.allclose(np.linalg.norm(spots[0][1] - (10, 0), axis=1), 0.75)
    # a spot on the character's own goal is left out: it could never arrive
    ends[0] = ((0, 0, 0), (10, 3.5, 0))
    assert [m for m, _ in crowd.standing_spots(ends, 1, 1.0, 0.25)] == [2]


def test_an_empty_crowd_and_no_spacing_are_handled():
    assert crowd.stagger([], clearance=0.5, max_delay=30, step=3) == ([], [])
    ends = [((0, 0, 0), (10, 0, 0)), ((0, 3, 0), (10, 3, 0))]
    assert crowd.standing_spots(ends, 0, spacing=0.0, radius=0.25) == []


def test_keep_apart_reroutes_the_later_walker_when_no_wait_clears_it():
    """Two walkers that cross head-on in a corridor-free plane: a wait cannot help the
    second one (the first stands at its goal where the second walks); re-planned round
    the first's reserved stretch, it passes clear."""
    from motion_patches import crowd
    t = np.linspace(0.0, 1.0, 121)[:, None]
    a = np.array([0.0, 0.0]) + t * np.array([10.0, 0.0])       # west -> east
    b = np.array([10.0, 0.3]) + t * np.array([-10.0, 0.0])     # east -> west, 0.3 m aside

    def replan(index, discs):
        assert index == 1 and discs
        centres = np.array([d.mean(axis=0) for d in discs])
        assert np.abs(centres[:, 1]).max() < 0.5   # the reserved stretch is on a's line
        return b + np.array([0.0, 2.0])            # the re-plan goes 2 m round it

    delays, conflicts, rerouted = crowd.keep_apart([a, b], replan, 1.0, 0.25, 30.0, 12, 6)
    assert rerouted == [1] and conflicts == []
    delays0, conflicts0 = crowd.stagger([a, b], 1.0, 12, 6)
    assert conflicts0  # without re-routing the conflict stays
