# SPDX-License-Identifier: GPL-3.0-or-later
"""Props that move during a walk (paper Sec. 4.4): asleep / awake, repair of the pieces met."""

import numpy as np
import pytest

from motion_patches.kinematics.motion import concatenate
from motion_patches.planning import moving_props as mp
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment

CART = np.array([[-0.6, -0.4], [0.6, -0.4], [0.6, 0.4], [-0.6, 0.4]])  # 1.2 x 0.8 m


@pytest.fixture
def open_ground(walk_patch):
    return Environment(walk_patch.side, walk_patch.cells, radius=0.25)


def motions_of(patch):
    return lambda plan: plan_motions(patch, plan)


def when_at_x(patch, plan, x):
    """(seconds, ground x, y) when the planned walk passes ground x = ``x``."""
    m = concatenate(plan_motions(patch, plan))
    i = int(np.argmin(np.abs(m.ground[:, 0] - x)))
    return i / patch.gait.fps, m.ground[i, 0], m.ground[i, 1]


def clearance(patch, plan, track):
    m = concatenate(plan_motions(patch, plan))
    t = np.arange(m.frames) / patch.gait.fps
    return mp._distances(m.ground[:, :2], track.pose_at(t), track.polygon)


def test_a_track_is_asleep_before_and_after_its_keys_and_awake_between():
    tr = mp.PropTrack(
        "Cart", CART, [0.0, 2.0, 5.0, 9.0], [[0, 0, 0], [0, 0, 0], [3, 0, 0], [3, 0, 0]]
    )
    assert tr.awake_intervals() == [(2.0, 5.0)]
    assert not tr.awake_at(1.0) and tr.awake_at(3.0) and not tr.awake_at(6.0)
    assert np.allclose(tr.pose_at([-1.0, 3.5, 100.0])[:, 0], [0.0, 1.5, 3.0])
    swept = tr.swept(2.0, 5.0)
    pts = np.array([[-0.55, 0.0], [1.5, 0.35], [3.55, -0.35]])  # start, middle, end of the sweep
    assert all(any(o.within(p[None], 1e-6)[0] for o in swept) for p in pts)
    assert not any(o.within(np.array([[1.5, 0.6]]), 1e-6)[0] for o in swept)
    with pytest.raises(ValueError, match="increase"):
        mp.PropTrack("Bad", CART, [0.0, 0.0], [[0, 0, 0], [1, 0, 0]])


def test_a_cart_crossing_the_walk_has_only_the_pieces_it_meets_replanned(walk_patch, open_ground):
    planner = SegmentPlanner(walk_patch, open_ground)
    plan = planner.plan((0.0, 0.0, 0.0), (16.0, 0.0, 0.0), shorten=False)
    assert len(plan.pieces) >= 5
    t, x, y = when_at_x(walk_patch, plan, 8.0)
    # Across the walk at 1 m/s, in the middle of the path just as the character gets there.
    cart = mp.PropTrack(
        "Cart",
        CART,
        [0.0, t - 4, t + 4, t + 20],
        [[x, y - 4, 0], [x, y - 4, 0], [x, y + 4, 0], [x, y + 4, 0]],
    )
    assert clearance(walk_patch, plan, cart).min() < 0.25
    assert mp.conflicts(plan_motions(walk_patch, plan), [cart], 0.25, walk_patch.gait.fps)
    new, wait, repairs, left = mp.avoid(
        planner, walk_patch, plan, [cart], motions_of(walk_patch), longest_wait=0
    )
    assert left == [] and repairs and wait == 0
    assert clearance(walk_patch, new, cart).min() >= 0.25
    first = min(r["pieces"][0] for r in repairs)
    last = max(r["pieces"][1] for r in repairs)
    assert first > 0 and last < len(plan.pieces) - 1  # the start and the stop are kept...
    assert all(a is b for a, b in zip(new.pieces[:first], plan.pieces[:first]))
    tail = len(plan.pieces) - 1 - last
    assert all(a is b for a, b in zip(new.pieces[-tail:], plan.pieces[-tail:]))
    # ...and the walk is the same frame for frame until the repaired run begins.
    before = concatenate(plan_motions(walk_patch, plan))
    after = concatenate(plan_motions(walk_patch, new))
    k = sum(p.frames for p in plan_motions(walk_patch, plan)[:first]) - first
    assert np.allclose(before.ground[:k], after.ground[:k])
    assert np.allclose(after.ground[-1], before.ground[-1])


def test_a_cart_crossing_at_walking_pace_is_waited_for_when_a_detour_takes_longer(
    walk_patch, open_ground
):
    planner = SegmentPlanner(walk_patch, open_ground)
    plan = planner.plan((0.0, 0.0, 0.0), (14.0, 0.0, 0.0))
    t, x, y = when_at_x(walk_patch, plan, 7.0)
    cart = mp.PropTrack(
        "Cart",
        CART,
        [0.0, t - 3, t + 3, t + 20],
        [[x, y - 3, 0], [x, y - 3, 0], [x, y + 3, 0], [x, y + 3, 0]],
    )
    new, wait, repairs, left = mp.avoid(planner, walk_patch, plan, [cart], motions_of(walk_patch))
    assert left == [] and 0 < wait <= mp.MAX_DELAY_S
    assert new is plan  # the same walk, later
    assert (
        mp.conflicts(plan_motions(walk_patch, plan), [cart], 0.25, walk_patch.gait.fps, wait) == []
    )
    assert mp.conflicts(
        plan_motions(walk_patch, plan), [cart], 0.25, walk_patch.gait.fps, wait - mp.DELAY_STEP_S
    )  # and no shorter wait would do
    _, _, detours, _ = mp.avoid(
        planner, walk_patch, plan, [cart], motions_of(walk_patch), longest_wait=0
    )
    assert detours and detours[0]["seconds_longer"] >= wait


def test_a_cart_parked_across_the_way_is_walked_round(walk_patch, open_ground):
    planner = SegmentPlanner(walk_patch, open_ground)
    plan = planner.plan((0.0, 0.0, 0.0), (14.0, 0.0, 0.0))
    t, x, y = when_at_x(walk_patch, plan, 7.0)
    # Rolls in from the side well before the character gets there and stays (falls asleep).
    cart = mp.PropTrack("Cart", CART, [0.0, 1.0, 3.0], [[x, y - 3, 0], [x, y - 3, 0], [x, y, 0]])
    assert t > 3.0 and cart.awake_intervals() == [(1.0, 3.0)]
    new, wait, repairs, left = mp.avoid(planner, walk_patch, plan, [cart], motions_of(walk_patch))
    assert left == [] and repairs and wait == 0  # parked: waiting does not help
    assert clearance(walk_patch, new, cart).min() >= 0.25
    m = concatenate(plan_motions(walk_patch, new))
    assert np.allclose(m.ground[-1, :2], (14.0, 0.0), atol=1e-6)


def test_a_cart_that_parks_on_the_goal_is_reported_by_prop_and_frame(walk_patch, open_ground):
    planner = SegmentPlanner(walk_patch, open_ground)
    plan = planner.plan((0.0, 0.0, 0.0), (10.0, 0.0, 0.0))
    cart = mp.PropTrack(
        "Cart", CART, [0.0, 1.0, 4.0], [[10.0, -5.0, 0], [10.0, -5.0, 0], [10.0, 0.0, 0]]
    )
    new, wait, repairs, left = mp.avoid(planner, walk_patch, plan, [cart], motions_of(walk_patch))
    assert left and left[0].prop == "Cart"
    assert "'Cart' meets the walk at frame" in left[0].describe(walk_patch.gait.fps, 1)
