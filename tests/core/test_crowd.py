# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowds: characters planned one by one are kept apart in space and time."""

import numpy as np
import pytest

from motion_patches.crowd import crowd, ways
from motion_patches.kinematics import contacts, retime
from motion_patches.kinematics.motion import concatenate
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment


def line(p0, p1, frames):
    return np.linspace(p0, p1, frames)


def lines_of(schedules):
    horizon = max(len(s.track) + s.delay for s in schedules) + 1
    return [crowd.timeline(s.track, s.delay, horizon) for s in schedules]


def min_gap(a, b):
    return np.linalg.norm(a - b, axis=1).min()


def brute_conflicts(lines, spacing):
    """{(a, b): frames closer than spacing} over whole timelines, every pair."""
    out = {}
    for i in range(len(lines)):
        for j in range(i):
            close = np.nonzero(np.linalg.norm(lines[i] - lines[j], axis=1) < spacing)[0]
            if close.size:
                out[(j, i)] = close
    return out


def test_the_reservation_table_finds_exactly_the_frames_too_close():
    """Against a brute-force comparison of whole timelines, on random walks with random
    starts (delays) in a small square, so that many come close, some stand on others'
    paths and some wait where others walk."""
    rng = np.random.default_rng(7)
    spacing = 0.5
    table = crowd.Reservations(spacing)
    placed = []
    for i in range(40):
        p0, p1 = rng.uniform(-4, 4, 2), rng.uniform(-4, 4, 2)
        n = int(rng.integers(20, 90))
        track = line(p0, p1, n) + rng.normal(0, 0.02, (n, 2))
        delay = int(rng.integers(0, 30))
        found = table.check(track, delay)
        horizon = max([len(t) + d for d, t in placed] + [n + delay]) + 1
        mine = crowd.timeline(track, delay, horizon)
        expect = {}
        for j, (d, t) in enumerate(placed):
            close = np.nonzero(
                np.linalg.norm(mine - crowd.timeline(t, d, horizon), axis=1) < spacing
            )[0]
            if close.size:
                expect[j] = close
        assert sorted(found) == sorted(expect), i
        for j, close in expect.items():
            frames, frame, dist = found[j]
            assert frames[0] == close[0] and set(frames) <= set(close)
            assert dist < spacing
        table.reserve(i, track, delay)
        placed.append((delay, track))
    assert sum(bool(v) for v in [table.check(t, d) for d, t in placed]) > 10  # many meet


def test_hold_phases_stop_on_the_frame_and_keep_the_pace_elsewhere():
    u = retime.hold_phases(60, 30, 12, 10)
    assert len(u) == 60 + 12 + 10 and u[0] == 0 and u[-1] == 59
    assert np.all(np.diff(u) >= -1e-12)
    assert np.sum(np.isclose(u, 30.0)) >= 12  # stands on frame 30
    assert np.allclose(u[:26], np.arange(26))  # full pace before the slow-down
    assert np.allclose(u[-25:], np.arange(35, 60))  # and after the speed-up
    assert np.diff(u).max() <= 1.0 + 1e-9  # never faster than recorded
    with pytest.raises(ValueError, match="ramp"):
        retime.hold_phases(60, 3, 12, 10)  # no room to slow down


def test_a_crossing_is_cleared_by_an_idle_hold_before_a_wait():
    a = line((-5.0, 0.0), (5.0, 0.0), 101)  # 10 m in 100 frames
    b = line((0.0, -5.0), (0.0, 5.0), 101)  # crosses a's path at the same moment
    holdable = [np.ones(101, bool), (np.arange(101) % 15) == 0]  # b: double support every 15
    assert min_gap(a, b) < 0.1
    sched, conflicts = crowd.resolve(
        [a, b], lambda i, d: None, 0.5, 0.25, 30.0, 60, 3, ramp=10, holdable=holdable
    )
    assert conflicts == []
    assert sched[0].delay == 0 and sched[0].holds == ()
    ((k, h),) = sched[1].holds
    assert sched[1].delay == 0 and holdable[1][k] and 0 < h <= 60
    la, lb = lines_of(sched)
    assert min_gap(la, lb) >= 0.5
    assert np.allclose(lb[-1], b[-1])  # still arrives
    # without double-support frames to stand on, it waits at its start instead
    sched, conflicts = crowd.resolve([a, b], lambda i, d: None, 0.5, 0.25, 30.0, 60, 3)
    assert conflicts == [] and sched[1].holds == () and sched[1].delay > 0
    d = sched[1].delay
    assert min_gap(*lines_of(sched)) >= 0.5
    shorter = crowd.Reservations(0.5)
    shorter.reserve(0, a)
    assert shorter.check(b, d - 3)  # and no shorter wait would do


def test_a_goal_on_someone_elses_path_is_reported_by_pair_and_frame():
    a = line((-5.0, 0.0), (5.0, 0.0), 101)
    b = line((0.0, -2.0), (0.0, 0.0), 21)  # b ends standing on a's path
    sched, conflicts = crowd.resolve([a, b], lambda i, d: None, 0.5, 0.25, 30.0, 30, 3)
    assert len(conflicts) == 1
    c = conflicts[0]
    assert (c["a"], c["b"]) == (0, 1) and c["distance_m"] < 0.5
    assert abs(c["frame"] - 50) <= 3 and c["frames"] > 0  # where a walks past b standing
    brute = brute_conflicts(lines_of(sched), 0.5)
    assert list(brute) == [(0, 1)] and len(brute[(0, 1)]) == c["frames"]


def test_a_restart_in_a_large_crowd_places_again_only_the_neighbours_of_those_left(monkeypatch):
    """a and b stay too close whatever the order (b ends standing on a's path, no wait
    long enough); ten others walk on their own far away. Each restart places again only
    a, b and those whose paths come near theirs (none), the rest kept as they were, and
    ends where restarting the whole crowd ends."""
    a = line((-5.0, 0.0), (5.0, 0.0), 101)
    b = line((0.0, -2.0), (0.0, 0.0), 21)
    far = [line((20.0 + 3 * k, 10.0), (20.0 + 3 * k, 18.0), 80) for k in range(10)]
    tracks = [*far[:5], a, *far[5:], b]
    placed = []
    once = crowd._resolve_once

    def spy(order, *args):
        placed.append(sorted(order))
        return once(order, *args)

    monkeypatch.setattr(crowd, "_resolve_once", spy)
    sched, left = crowd.resolve(tracks, lambda i, d: None, 0.5, 0.25, 30.0, 30, 3)
    assert placed[0] == list(range(12)) and len(placed) == 5  # the first pass, 4 restarts
    assert all(order == [5, 11] for order in placed[1:])
    assert [(c["a"], c["b"]) for c in left] in ([(5, 11)], [(11, 5)])
    assert all((s.delay, s.holds) == (0, ()) for k, s in enumerate(sched) if k not in (5, 11))
    assert sorted(s.rank for s in sched) == list(range(12))
    placed.clear()
    monkeypatch.setattr(crowd, "LOCAL_SHARE", 0.0)  # every restart places the whole crowd
    whole, whole_left = crowd.resolve(tracks, lambda i, d: None, 0.5, 0.25, 30.0, 30, 3)
    assert all(order == list(range(12)) for order in placed)
    assert [(c["a"], c["b"], c["frames"]) for c in whole_left] == [
        (c["a"], c["b"], c["frames"]) for c in left
    ]
    assert [(s.delay, s.holds) for s in whole] == [(s.delay, s.holds) for s in sched]


def test_each_character_placed_is_told_as_it_is_placed_in_every_pass():
    """``settled`` hears of each character as it is placed, with the schedule it was
    placed with, in the first pass and again in each restart that places it: a crowd with
    a re-route and held characters, and the restart crowd above. What a character comes
    out with is what it was last placed with, except where a repair moved it."""
    t = np.linspace(0.0, 1.0, 121)[:, None]
    a = np.array([0.0, 0.0]) + t * np.array([10.0, 0.0])
    b = np.array([10.0, 0.3]) + t * np.array([-10.0, 0.0])
    told = []

    def settled(i, s):
        told.append((i, s, (s.delay, s.holds, s.version, s.track.tobytes())))

    sched, conflicts = crowd.resolve(
        [a, b],
        lambda i, discs: (b + np.array([0.0, 2.0]), None),
        1.0,
        0.25,
        30.0,
        12,
        6,
        holdable=[None, np.ones(121, bool)],
        settled=settled,
    )
    assert not conflicts and sched[1].rerouted
    assert [i for i, _, _ in told] == [0, 1]
    for i, s, seen in told:  # each as it was placed, and as it came out
        assert s is sched[i] and seen == (s.delay, s.holds, s.version, s.track.tobytes())
    told.clear()
    crossing = [line((0.0, 0.0), (8.0, 0.0), 81), line((4.0, -4.0), (4.0, 4.0), 81)]
    held, _ = crowd.resolve(
        crossing,
        None,
        0.5,
        0.25,
        30.0,
        60,
        3,
        ramp=10,
        holdable=[np.ones(81, bool)] * 2,
        settled=settled,
    )
    assert held[1].holds or held[1].delay
    assert [(i, s) for i, s, _ in told] == [(0, held[0]), (1, held[1])]
    told.clear()
    a = line((-5.0, 0.0), (5.0, 0.0), 101)  # the restart crowd of the test above
    b = line((0.0, -2.0), (0.0, 0.0), 21)
    far = [line((20.0 + 3 * k, 10.0), (20.0 + 3 * k, 18.0), 80) for k in range(10)]
    sched, _ = crowd.resolve(
        [*far[:5], a, *far[5:], b], lambda i, d: None, 0.5, 0.25, 30.0, 30, 3, settled=settled
    )
    counts = np.bincount([i for i, _, _ in told], minlength=12)
    assert counts[5] == counts[11] == 5 and set(counts) == {1, 5}  # the first pass, 4 restarts
    last = {i: s for i, s, _ in told}
    assert all(last[k] is sched[k] for k in range(12) if k not in (5, 11))


def test_the_neighbourhood_of_a_restart_reaches_those_whose_paths_come_near():
    """Paths 0.4 m apart in a chain: one step out per ring, nobody further; a character
    re-routed meets those near the way it walks now as well as near its plan; a
    neighbourhood of more than half the crowd is the whole crowd (None)."""
    tracks = [line((0.0, 0.4 * k), (10.0, 0.4 * k), 101) for k in range(8)]
    sched = [crowd.Schedule(0, (), 0, t) for t in tracks]
    assert crowd._neighbourhood(tracks, sched, {0}, 0.5) == set(range(crowd.LOCAL_RINGS + 1))
    assert crowd._neighbourhood(tracks, sched, {0, 7}, 0.5) is None  # 6 of 8
    aside = line((0.0, -3.3), (10.0, -3.3), 101)  # near nobody's plan
    sched[7] = crowd.Schedule(0, (), 1, line((0.0, -3.0), (10.0, -3.0), 101))  # 7 re-routed
    away = line((0.0, 50.0), (10.0, 50.0), 101)
    more = [aside] * 4 + [away] * 4
    got = crowd._neighbourhood(
        tracks + more, sched + [crowd.Schedule(0, (), 0, t) for t in more], {7}, 0.5
    )
    assert got == {5, 6, 7, 8, 9, 10, 11}


def test_far_apart_characters_neither_wait_nor_hold():
    tracks = [line((x, 0.0), (x, 8.0), 80) for x in (0.0, 3.0, 6.0)]
    sched, conflicts = crowd.resolve(
        tracks, None, 0.5, 0.25, 30.0, 60, 6, holdable=[np.ones(80, bool)] * 3
    )
    assert [(s.delay, s.holds) for s in sched] == [(0, ())] * 3 and conflicts == []


def test_reroute_when_neither_hold_nor_wait_clears():
    """Head-on in the open: b would meet a or stand where a ends; re-planned round a's
    reserved stretch (discs on a's line near the meeting), it passes clear."""
    t = np.linspace(0.0, 1.0, 121)[:, None]
    a = np.array([0.0, 0.0]) + t * np.array([10.0, 0.0])  # west -> east
    b = np.array([10.0, 0.3]) + t * np.array([-10.0, 0.0])  # east -> west, 0.3 m aside
    calls = []

    def replan(index, discs):
        calls.append(index)
        centres = np.array([d.mean(axis=0) for d in discs])
        assert np.abs(centres[:, 1]).max() < 0.5  # the reserved stretch is on a's line
        return b + np.array([0.0, 2.0]), None  # the re-plan goes 2 m round it

    sched, conflicts = crowd.resolve(
        [a, b], replan, 1.0, 0.25, 30.0, 12, 6, holdable=[None, np.ones(121, bool)]
    )
    assert calls == [1] and conflicts == [] and sched[1].rerouted
    sched0, conflicts0 = crowd.resolve([a, b], lambda i, d: None, 1.0, 0.25, 30.0, 12, 6)
    assert conflicts0 and not sched0[1].rerouted  # without re-routing the conflict stays


def test_a_walker_held_up_does_not_stop_where_one_still_to_come_walks():
    """b holds before crossing a's path; c, placed after b, walks north a little before the
    crossing. Without c, b stops right before the crossing; with c to come, b stops before
    c's way instead, out of it (a hold there would block c until b walks on)."""
    a = line((5.0, -5.0), (5.0, 5.0), 101)
    b = line((0.0, 0.0), (10.0, 0.0), 101)  # meets a at (5, 0) on frame 50
    c = line((4.0, -5.0), (4.0, 5.0), 101)
    ones = np.ones(101, bool)
    sched, left = crowd.resolve([a, b], None, 0.5, 0.25, 30.0, 60, 3, ramp=10, holdable=[ones] * 2)
    ((k, _),) = sched[1].holds
    assert left == [] and abs(b[k][0] - 4.0) < 0.5  # where c would walk
    sched, left = crowd.resolve(
        [a, b, c], None, 0.5, 0.25, 30.0, 60, 3, ramp=10, holdable=[ones] * 3
    )
    ((k, _),) = sched[1].holds
    assert left == [] and 4.0 - b[k][0] >= 0.5 and b[k][0] < 4.5  # before c's way, out of it
    la, lb, lc = lines_of(sched)
    assert min(min_gap(la, lb), min_gap(la, lc), min_gap(lb, lc)) >= 0.5


def test_the_ways_of_those_to_come_are_found_within_the_spacing():
    """Every frame within the spacing of a waiting one's path is found, none further than
    the spacing and :data:`ways.BETWEEN_M` (paths are kept a point every few frames)."""
    tracks = [line((0.0, 0.0), (10.0, 0.0), 101), line((0.0, 3.0), (10.0, 3.0), 101)]
    paths = ways.Ways(tracks, 0.5)
    probe = line((5.0, -2.0), (5.0, 5.0), 71)  # 0.1 m a frame, across both
    gap = np.minimum(np.abs(probe[:, 1]), np.abs(probe[:, 1] - 3.0))
    found = paths.crossed(probe, np.array([True, True]))
    assert found[gap < 0.5].all() and (gap[found] < 0.5 + ways.BETWEEN_M).all()
    second = paths.crossed(probe, np.array([False, True]))  # the first already placed
    assert np.array_equal(second, found & (probe[:, 1] > 1.5))
    assert not paths.crossed(probe, np.zeros(2, bool)).any()


def test_a_pair_left_is_mended_by_placing_the_one_held_fast_first():
    """b cannot wait (c comes to stand by its start on frame 3) nor hold, and meets a where
    their paths cross: placed after a, it stays too close. Mended (no restart): b placed
    first and a re-timed round it, a waiting at its start."""
    a = line((5.0, -5.0), (5.0, 5.0), 101)
    c = line((10.0, -2.0), (10.0, -0.45), 4)
    b = line((10.0, 0.0), (0.0, 0.0), 101)
    sched, left = crowd.resolve([a, c, b], None, 0.5, 0.25, 30.0, 30, 3, restarts=0)
    assert left == []
    assert sched[2].rank == 0 and (sched[2].delay, sched[2].holds) == (0, ())
    assert sched[0].delay > 0
    assert min_gap(*lines_of([sched[0], sched[2]])) >= 0.5


def test_standing_spots_are_every_start_and_goal_else_those_passed_in_priority_order():
    ends = [((0, 0, 0), (10, 0, 0)), ((0, 3, 0), (10, 3, 0)), ((0, 6, 0), (10, 6, 0))]
    every = crowd.standing_spots(ends, 1, spacing=1.0, radius=0.25)
    assert [k for k, _ in every] == [0, 1, 4, 5]  # starts 2 m, goals 2 m + 1: of 0 and 2
    centres = [poly.mean(axis=0) for _, poly in every]
    assert np.allclose(centres, [(0, 0), (10, 0), (0, 6), (10, 6)])
    # fewer: the goal of the one before it, the start of the one after
    spots = crowd.standing_spots(ends, 1, spacing=1.0, radius=0.25, every=False)
    assert [k for k, _ in spots] == [1, 4]
    r = np.linalg.norm(spots[0][1] - (10, 0), axis=1)  # a polygon round the 0.75 m disc
    assert np.allclose(r, (0.75 + crowd.SPOT_MARGIN) / np.cos(np.pi / 12))  # and a margin
    ends[0] = ((0, 0, 0), (10, 3.5, 0))  # a goal by its own goal is left out
    assert [k for k, _ in crowd.standing_spots(ends, 1, 1.0, 0.25)] == [0, 4, 5]
    assert [k for k, _ in crowd.standing_spots(ends, 1, 1.0, 0.25, every=False)] == [4]
    assert crowd.standing_spots(ends, 0, spacing=0.0, radius=0.25) == []
    # a box: only the spots whose disc reaches into it (those at y = 6 barely do)
    box = (np.array([-1.0, -1.0]), np.array([11.0, 5.3]))
    assert [k for k, _ in crowd.standing_spots(ends, 1, 1.0, 0.25, box)] == [0, 4, 5]
    assert [k for k, _ in crowd.standing_spots(ends, 1, 1.0, 0.25, box, False)] == [4]
    box = (np.array([-1.0, -1.0]), np.array([11.0, 5.0]))
    assert [k for k, _ in crowd.standing_spots(ends, 1, 1.0, 0.25, box)] == [0]
    assert crowd.standing_spots(ends, 1, 1.0, 0.25, box, every=False) == []


def test_reservations_find_the_same_after_many_merges():
    """The table's runs merge as reservations come and go; what a check finds does not
    depend on how they lie: the same as a table of the remaining ones made afresh."""
    rng = np.random.default_rng(3)
    tracks = [
        np.cumsum(rng.normal(0, 0.05, (40, 2)), axis=0) + rng.uniform(0, 3, 2) for _ in range(60)
    ]
    table = crowd.Reservations(0.5)
    for i, t in enumerate(tracks):
        table.reserve(i, t, i % 7)
    for i in range(0, 60, 5):
        table.remove(i)
    fresh = crowd.Reservations(0.5)
    for i, t in enumerate(tracks):
        if i % 5:
            fresh.reserve(i, t, i % 7)
    probe = np.cumsum(rng.normal(0, 0.05, (50, 2)), axis=0) + 1.5
    got, want = table.check(probe, 3), fresh.check(probe, 3)
    assert got.keys() == want.keys() and len(got) > 3
    for j in got:
        assert np.array_equal(got[j][0], want[j][0]) and got[j][1:] == want[j][1:]
    assert np.array_equal(table.busy(probe, 60), fresh.busy(probe, 60))


def test_reservations_removed_and_placed_again_find_what_a_fresh_table_finds():
    """A removal marks its entries dead (passed over, left out of merges, swept once the
    dead outnumber the living); an index placed again after its removal is found at its new
    place only, whatever the runs hold."""
    rng = np.random.default_rng(7)

    def walk():
        return np.cumsum(rng.normal(0, 0.05, (40, 2)), axis=0) + rng.uniform(0, 3, 2)

    tracks = {i: walk() for i in range(60)}
    table = crowd.Reservations(0.5)
    for i, t in tracks.items():
        table.reserve(i, t, i % 7)
    probe = np.cumsum(rng.normal(0, 0.05, (50, 2)), axis=0) + 1.5
    for round_ in range(3):
        # the first round removes most (the dead outnumber the living: all runs swept)
        for i in rng.choice(sorted(tracks), 45 if round_ == 0 else 15, replace=False).tolist():
            table.remove(i)
            if (i + round_) % 3:  # placed again elsewhere, or left out
                tracks[i] = walk()
                table.reserve(i, tracks[i], i % 5)
            else:
                tracks.pop(i, None)
        fresh = crowd.Reservations(0.5)
        for i in sorted(tracks):
            fresh.reserve(i, tracks[i], table.placed[i][0])
        assert table.moving.size == fresh.moving.size == sum(len(t) for t in tracks.values())
        got, want = table.check(probe, 3), fresh.check(probe, 3)
        assert got.keys() == want.keys() and len(got) > 3
        for j in got:
            assert np.array_equal(got[j][0], want[j][0]) and got[j][1:] == want[j][1:]
        assert np.array_equal(table.busy(probe, 60), fresh.busy(probe, 60))


def test_an_empty_crowd_is_handled():
    assert crowd.resolve([], None, 0.5, 0.25, 30.0, 30, 3) == ([], [])


def test_a_hold_on_real_walking_keeps_the_feet_planted(walk_patch):
    """Two real planned walkers crossing: the later one holds on a double-support frame
    of its walk; on the held motion both feet stay planted and still while it stands."""
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    planner = SegmentPlanner(walk_patch, env)
    plans = [
        planner.plan((0.0, 0.0, 0.0), (8.0, 0.0, 0.0)),
        planner.plan((4.0, -4.0, np.pi / 2), (4.0, 4.0, np.pi / 2)),
    ]
    motions = [plan_motions(walk_patch, p) for p in plans]
    whole = [concatenate(m) for m in motions]
    tracks = [w.ground[:, :2] for w in whole]
    double = [w.contacts[:, :2].any(1) & w.contacts[:, 2:].any(1) for w in whole]
    ramp = 16
    sched, conflicts = crowd.resolve(
        tracks, None, 1.0, 0.5, walk_patch.gait.fps, 120, 6, ramp=ramp, holdable=double
    )
    assert conflicts == [] and len(sched[1].holds) == 1 and sched[1].delay == 0
    ((k, h),) = sched[1].holds
    motion = retime.held(whole[1], k, h, ramp)
    assert np.allclose(motion.ground[:, :2], sched[1].track)  # the track the crowd checked
    skel = walk_patch.gait.skeleton
    feet = motion.world_matrices(skel)[:, contacts.foot_joints(skel)][..., :3, 3]
    still = slice(k + ramp // 2, k + ramp // 2 + h)
    assert motion.contacts[still, :2].any(1).all() and motion.contacts[still, 2:].any(1).all()
    assert np.ptp(feet[still, :, :2], axis=0).max() < 1e-6
    assert min_gap(*lines_of(sched)) >= 1.0


def test_what_resolve_reports_is_exactly_what_is_left():
    """A dense random crowd: the pairs reported are exactly the pairs a brute-force
    comparison of the final timelines finds too close, with the same frame counts; every
    hold stands on a holdable frame of the track it was put in."""
    rng = np.random.default_rng(3)
    tracks, masks = [], []
    for i in range(25):
        p0 = rng.uniform(-4, 4, 2)
        p1 = p0 + rng.uniform(4, 7) * np.array([np.cos(a := rng.uniform(0, 2 * np.pi)), np.sin(a)])
        n = int(np.linalg.norm(p1 - p0) / 1.3 * 30)
        tracks.append(line(p0, p1, n))
        masks.append((np.arange(n) % 16) == 3)
    before = len(crowd.conflicts_of(tracks, [0] * 25, 0.5))
    sched, conflicts = crowd.resolve(tracks, None, 0.5, 0.25, 30.0, 120, 6, ramp=12, holdable=masks)
    brute = brute_conflicts(lines_of(sched), 0.5)
    # (two standing for good are counted to the end of the crowd as it was when placed)
    pair = lambda c: tuple(sorted((c["a"], c["b"])))  # noqa: E731 ("a" placed first)
    assert {pair(c): c["first_frame"] for c in conflicts} == {k: v[0] for k, v in brute.items()}
    horizon = max(len(s.track) + s.delay for s in sched)
    assert all(
        c["frames"] == len(brute[pair(c)]) for c in conflicts if brute[pair(c)][-1] < horizon - 1
    )
    assert all(sched[c["a"]].rank < sched[c["b"]].rank for c in conflicts)
    assert len(conflicts) < before, (len(conflicts), before)  # some are solved
    for s, track, mask in zip(sched, tracks, masks):
        t, m = track, mask
        for k, h in s.holds:
            assert m[k]
            t, m = crowd.held_track(t, k, h, 12, m)
        assert np.allclose(t, s.track)


def test_the_earliest_timing_is_clear_and_no_earlier_one_is():
    """path_timing.earliest on a crossing: without holds it is the shortest wait at the
    start that clears (one frame less does not); with holds it arrives no later than that
    and its holds, laid into the track, clear too."""
    from motion_patches.crowd import path_timing

    rng = np.random.default_rng(11)
    table = crowd.Reservations(0.5)
    for i in range(6):  # walkers streaming across b's way, one every 12 frames
        table.reserve(i, line((-5.0, 0.0), (5.0, 0.0), 101), delay=12 * i)
    b = line((0.0, -5.0), (0.0, 5.0), 101) + rng.normal(0, 0.005, (101, 2))
    assert table.check(b)
    busy = table.busy(b, 400)
    delay, holds = path_timing.earliest(b, busy, None, 10, 300, 300)
    assert holds == () and not table.check(b, delay) and table.check(b, delay - 1)
    mask = (np.arange(101) % 7) == 0
    delay2, holds2 = path_timing.earliest(b, busy, mask, 10, 300, 300, max_holds=2)
    track, m = b, mask
    for k, h in holds2:
        assert m[k]
        track, m = crowd.held_track(track, k, h, 10, m)
    assert not table.check(track, delay2)


def test_a_narrow_timing_later_than_it_may_arrive_is_not_searched(monkeypatch):
    """crowd._timed: when the earliest arrival of all (the widest search's) needs more
    extra time than a narrower search may take, that search finds nothing and is skipped:
    the same timing, one search fewer."""
    from motion_patches.crowd import path_timing

    table = crowd.Reservations(0.5)
    for i in range(14):  # walkers streaming across b's way, one every 8 frames
        table.reserve(i, line((-5.0, 0.0), (5.0, 0.0), 101), delay=8 * i)
    b = line((0.0, -5.0), (0.0, 5.0), 101)
    mask = (np.arange(101) % 5) == 0
    s = crowd.Schedule(0, (), 0, b, mask)
    found = table.check(b)
    calls = []
    earliest = path_timing.earliest
    monkeypatch.setattr(
        path_timing, "earliest", lambda *a, **k: calls.append(a[4:]) or earliest(*a, **k)
    )
    got, left = crowd._timed(table, s, 120, 30, 10, found)
    skipped = list(calls)
    calls.clear()
    monkeypatch.setattr(crowd, "_extra", lambda timing, ramp: 0)  # every search made
    want, _ = crowd._timed(table, s, 120, 30, 10, found)
    assert not left and (got.delay, got.holds) == (want.delay, want.holds)
    assert got.delay + sum(h + 10 for _, h in got.holds) > 30  # later than (0, 1) may
    assert len(calls) == len(skipped) + 1 and (0, 30, 1) in calls and (0, 30, 1) not in skipped


@pytest.mark.parametrize("seed", range(6))
def test_the_sliced_ramp_look_ups_give_the_point_by_point_timing(monkeypatch, seed):
    """path_timing._Looks: the slow-downs and speed-ups of a block of layers looked up as
    slices of the sheared busy table give the same earliest timing as each ramp's points
    looked up one by one (what it falls back to where a ramp's whole offsets differ), on
    random crossings, with holds, short and long searches."""
    from motion_patches.crowd import path_timing

    rng = np.random.default_rng(seed)
    n, ramp = int(rng.integers(40, 120)), int(rng.choice([4, 8, 12]))
    track = np.zeros((n, 2))
    busy = np.zeros((n, n + 200), bool)
    for _ in range(12):  # others crossing the track: a few frames of it busy a while
        k, t = int(rng.integers(5, n)), int(rng.integers(0, n + 120))
        busy[k - int(rng.integers(1, 4)) : k, t : t + int(rng.integers(4, 30))] = True
    busy[:, 0] = busy[n - 1, -1] = False
    holdable = rng.random(n) < 0.5
    tries = [(60, 120, 4), (0, 60, 1), (30, 150, 2)]
    sliced = [path_timing.earliest(track, busy, holdable, ramp, *t) for t in tries]
    ramp_of = path_timing._Looks._ramp
    monkeypatch.setattr(
        path_timing._Looks, "_ramp", lambda self, o, rows: (ramp_of(self, o, rows)[0], None)
    )
    assert sliced == [path_timing.earliest(track, busy, holdable, ramp, *t) for t in tries]
    if seed in (0, 1, 4, 5):  # these crossings are cleared by holds
        assert any(t is not None and t[1] for t in sliced), sliced


def test_a_path_placed_while_another_is_re_planned_keeps_clear_of_its_path_and_discs():
    """crowd._Clear: a path further than twice the margin from a re-planned walker's path
    and discs is clear of them; one within the margin of either is not."""
    path = np.column_stack((np.linspace(0.0, 10.0, 50), np.zeros(50)))
    disc = crowd.disc((12.0, 0.0), 0.5)
    clear = crowd._Clear([path, disc], 2.0)
    along = np.column_stack((np.linspace(-5.0, 20.0, 80), np.zeros(80)))
    assert clear.of(along + (0.0, 4.01))  # beyond twice the margin
    assert clear.of(along - (0.0, 4.01))
    assert not clear.of(along + (0.0, 1.9))  # within the margin of the path
    assert not clear.of(np.array([[12.0, 2.3], [30.0, 2.3]]))  # of the disc (0.5 + 1.8)
    assert clear.of(np.array([[16.1, 0.0], [40.0, 0.0]]))  # past the disc, beyond 2 margins
