# SPDX-License-Identifier: GPL-3.0-or-later
"""Lanes of a counter-flow (motion_patches.crowd.lanes): where walkers meet head-on, the
middle of the flow, the strips that keep each direction to its right, and the resolver
forming lanes where a pass leaves a head-on pair no timing clears."""

import numpy as np

from motion_patches.crowd import crowd, lanes


def line(a, b, frames):
    t = np.linspace(0.0, 1.0, frames)[:, None]
    return np.asarray(a, float) + t * (np.asarray(b, float) - np.asarray(a, float))


def test_head_on_walkers_meet_and_crossing_ones_do_not():
    east = line((-5.0, 0.0), (5.0, 0.0), 101)
    west = line((5.0, 0.1), (-5.0, 0.1), 101)
    north = line((0.0, -5.0), (0.0, 5.0), 101)
    mid, axis = lanes.meeting((0, east), (0, west), 50)
    assert np.allclose(mid, (0.0, 0.05), atol=0.06) and axis @ np.array([1.0, 0.0]) > 0.99
    assert lanes.meeting((0, east), (0, north), 50) is None
    # a walker standing in a hold is looked at where it walks before and after
    held, _ = crowd.held_track(west, 50, 30, 10)
    assert lanes.meeting((0, east), (0, held), 65) is not None


def test_the_two_strips_keep_each_direction_to_its_right_a_spacing_apart():
    spacing, radius = 0.55, 0.25
    mid, axis = np.array([0.0, 0.2]), np.array([1.0, 0.0])
    east, west = (
        lanes.strip(mid, axis, 1, spacing, radius),
        lanes.strip(mid, axis, -1, spacing, radius),
    )
    # the east-bound strip covers the north (its left), the west-bound one the south
    assert east[:, 1].max() > mid[1] + 0.9 and west[:, 1].min() < mid[1] - 0.9
    # walkers kept a radius off their strips pass at least a spacing apart
    lowest_west = west[:, 1].max() + radius
    highest_east = east[:, 1].min() - radius
    assert lowest_west - highest_east >= spacing


def test_the_middle_of_a_doorway_is_found_from_the_flow_not_the_pair():
    """Walkers through a 2 m doorway at x = 0 hug its corners; a pair met at y = 0.3, but
    the narrowest place of the flow is the doorway, and its middle is y = 0."""
    rng = np.random.default_rng(3)
    tracks = []
    for k in range(20):
        y = rng.uniform(-0.7, 0.7) if k > 1 else (-0.7, 0.7)[k]
        y0, y1 = rng.uniform(-6, 6, 2)
        a = line((-6.0, y0), (0.0, y), 60)
        b = line((0.0, y), (6.0, y1), 60)
        tracks.append(np.vstack((a, b[1:]))[:: 1 if k % 2 else -1])
    mid = lanes.centred(np.array([-0.6, 0.3]), np.array([1.0, 0.0]), tracks)
    assert abs(mid[0]) < 0.3 and abs(mid[1]) < 0.15


def test_a_head_on_pair_no_wait_clears_gets_lanes():
    """Two walkers head-on along one line and no time to wait: the resolver re-plans both
    round their strips (a re-plan here moves a track to the free side of its strips) and
    they pass on their own sides; without re-plans the pair is left."""
    a = line((-5.0, 0.0), (5.0, 0.0), 121)
    b = line((5.0, 0.0), (-5.0, 0.0), 121)
    calls = []

    def replan(i, polygons):
        strips = [p for p in polygons if len(p) == 4]
        if not strips:
            return None  # no way round the other's discs: only lanes help
        calls.append(i)
        track = (a, b)[i]
        ys = np.concatenate([p[:, 1] for p in strips])
        side = -1.0 if i == 0 else 1.0  # east-bound keeps south, west-bound north
        edge = ys.min() if side < 0 else ys.max()
        return track + np.array([0.0, edge + side * 0.25]), None

    sched, left = crowd.resolve([a, b], replan, 0.55, 0.25, 30.0, 0, 6)
    assert left == [] and sorted(calls) == [0, 1]
    assert sched[0].track[:, 1].max() < -0.25 and sched[1].track[:, 1].min() > 0.25
    assert all(s.version == 1 for s in sched)
    _, left = crowd.resolve([a, b], None, 0.55, 0.25, 30.0, 0, 6)
    assert left


def doorway_flow(seed=3, count=20, spread=0.7):
    """Walks through a doorway at x = 0 (crossing it within ``spread`` of y = 0) from and to
    places up to 6 m either side, every other one the other way."""
    rng = np.random.default_rng(seed)
    tracks = []
    for k in range(count):
        y = rng.uniform(-spread, spread)
        y0, y1 = rng.uniform(-6, 6, 2)
        a = line((-6.0, y0), (0.0, y), 60)
        b = line((0.0, y), (6.0, y1), 60)
        tracks.append(np.vstack((a, b[1:]))[:: 1 if k % 2 else -1])
    return tracks


def test_the_flow_through_a_doorway_goes_square_through_it_whatever_pair_met():
    tracks = doorway_flow()
    slant = np.array([1.0, 0.5]) / np.hypot(1.0, 0.5)  # a pair met at a slant
    axis = lanes.flow_axis(np.zeros(2), slant, tracks)
    assert abs(np.linalg.norm(axis) - 1.0) < 1e-9 and axis[0] > 0.97
    assert np.allclose(lanes.flow_axis(np.zeros(2), -slant, tracks), -axis)  # its way kept


def test_a_doorway_holds_its_flow_and_the_open_does_not():
    door, mid, axis = doorway_flow(), np.zeros(2), np.array([1.0, 0.0])
    assert lanes.confined(mid, axis, door)
    assert not lanes.confined(mid, axis, doorway_flow(spread=3.0))  # the same walks, no wall


def test_a_place_found_again_is_the_same_place():
    a = (np.array([0.0, 0.0]), np.array([1.0, 0.0]))
    assert lanes.same_place(a, (np.array([0.4, 0.3]), np.array([-0.98, 0.2])))
    assert not lanes.same_place(a, (np.array([1.5, 0.0]), np.array([1.0, 0.0])))
    assert not lanes.same_place(a, (np.array([0.2, 0.0]), np.array([0.0, 1.0])))


def test_lanes_stay_the_same_over_passes_and_narrow_ones_lose_the_sway():
    """Two head-on walkers give a place; a re-plan round the strips with the sway finds no
    path, one without it does. A second head-on pair at that place later makes no new place
    and re-plans no one."""
    a = line((-5.0, 0.0), (5.0, 0.0), 121)
    b = line((5.0, 0.0), (-5.0, 0.0), 121)
    tracks, widths, places = [a, b], [], []

    def replan(i, polygons):
        edge = min(np.abs(p[:, 1]).min() for p in polygons)  # the strip's edge past the middle
        widths.append(round(float(edge), 3))
        if edge > 0.05:
            return None  # too narrow with the sway
        return tracks[i] + np.array([0.0, 0.3 if i else -0.3]), None

    placed = {0: (0, a), 1: (0, b)}
    met = [{"a": 0, "b": 1, "frame": 60}]
    versions = [0, 0]
    out = lanes.form(placed, met, tracks, {}, replan, versions, 0.55, 0.25, places)
    assert sorted(out) == [0, 1] and len(places) == 1 and versions == [1, 1]
    assert widths == [0.075, 0.025, 0.075, 0.025]  # with the sway, then without
    assert out[0][1][:, 1].max() < 0 < out[1][1][:, 1].min()
    again = lanes.form(placed, met, tracks, {0: 1, 1: 1}, replan, versions, 0.55, 0.25, places)
    assert again == {} and len(places) == 1 and len(widths) == 4
