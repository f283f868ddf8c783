# SPDX-License-Identifier: GPL-3.0-or-later
"""The glitch validator: it catches flips, backward steps and join jumps, passes clean walks."""

import numpy as np
import pytest

from motion_patches.kinematics.motion import Motion
from motion_patches.quality import validate


@pytest.fixture(scope="module")
def lim(walk_gait):
    return validate.limits(walk_gait)


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def track(steps, heading0=0.0, kappa=0.0, at=(0.0, 0.0)):
    """Ground track (len(steps) + 1, 3) taking per-frame ``steps`` along an arc of
    curvature ``kappa``, exactly on the arc (chords), headings wrapped to [-pi, pi)."""
    s = np.concatenate(([0.0], np.cumsum(steps)))
    h = heading0 + kappa * s
    mid = heading0 + kappa * 0.5 * (s[1:] + s[:-1])  # chord direction of each step
    chord = np.where(
        kappa == 0, steps, 2 * np.sin(kappa * np.asarray(steps) / 2) / (kappa if kappa else 1.0)
    )
    xy = np.concatenate(
        ([at], at + np.cumsum(chord[:, None] * np.stack((np.cos(mid), np.sin(mid)), 1), axis=0))
    )
    return np.column_stack((xy, wrap(h)))


def loop_steps(loop, cycles):
    return np.tile(np.diff(loop.distance), cycles)


def motion(ground):
    f = ground.shape[0]
    return Motion(
        ground, np.zeros((f, 3)), np.tile([1.0, 0, 0, 0], (f, 1, 1)), np.zeros((f, 4), bool)
    )


def test_limits_come_from_the_gait(walk_gait, lim):
    k = np.max(np.abs(walk_gait.kappa_limits))
    step = max(np.diff(lp.distance).max() for lp in walk_gait.loops)
    assert lim.step == pytest.approx(step * validate.MARGIN)
    assert lim.heading == pytest.approx(k * step * validate.MARGIN)
    # A walk turns a few degrees a frame: far from a flip, above what the sharp loop does.
    sharp = max(walk_gait.loops, key=lambda lp: abs(lp.curvature))
    assert abs(sharp.curvature) * np.diff(sharp.distance).max() < lim.heading < np.radians(10)


def test_a_clean_straight_walk_passes(walk_gait, lim):
    g = track(loop_steps(walk_gait.straight, 4), heading0=np.radians(-90))
    assert validate.ground_glitches(g, lim) == []


def test_a_clean_sharp_turn_round_and_round_passes(walk_gait, lim):
    # The sharpest loop's own steps on its own curvature, three cycles (more than a full
    # turn: the heading wraps past +-pi several times, which is not a flip).
    sharp = max(walk_gait.loops, key=lambda lp: abs(lp.curvature))
    g = track(loop_steps(sharp, 3), heading0=3.0 * np.sign(sharp.curvature), kappa=sharp.curvature)
    assert np.abs(np.diff(g[:, 2])).max() > np.pi  # wrapped
    assert validate.ground_glitches(g, lim) == []
    # The worst the limits allow for: the curvature range at the straight loop's steps.
    k = max(walk_gait.kappa_limits, key=abs)
    g = track(loop_steps(walk_gait.straight, 2), heading0=-3.0, kappa=k)
    assert validate.ground_glitches(g, lim) == []


def test_a_heading_flip_mid_strip_is_caught(walk_gait, lim):
    # Today's flipped segments: the tangent turns 180 degrees for two frames and back.
    g = track(loop_steps(walk_gait.straight, 2), heading0=np.radians(45))
    g[20:22, 2] = wrap(g[20:22, 2] + np.pi)
    recs = validate.ground_glitches(g, lim)
    spins = [r["frame"] for r in recs if r["kind"] == "spin"]
    assert spins == [20, 22]
    assert all(r["value"] == pytest.approx(np.pi) for r in recs if r["kind"] == "spin")
    assert any(r["kind"] == "backwards" for r in recs)
    # Among clean tracks, checked all at once (as a bake would check its candidates).
    clean = track(loop_steps(walk_gait.straight, 1))
    found = validate.track_glitches([clean, g, clean], lim)
    assert list(found) == [1] and found[1] == recs


def test_a_slow_spin_is_caught_where_it_exceeds_the_gait(walk_gait, lim):
    g = track(loop_steps(walk_gait.straight, 2))
    g[30:, 2] += np.radians(12)  # 12 degrees in one frame: twice the limit
    recs = validate.ground_glitches(g, lim)
    assert [(r["frame"], r["kind"]) for r in recs] == [(30, "spin")]


def test_a_backward_step_is_caught(walk_gait, lim):
    steps = loop_steps(walk_gait.straight, 2)
    steps[30] = -0.02  # one frame back along the heading, facing forward
    g = track(steps, heading0=1.0)
    recs = validate.ground_glitches(g, lim)
    assert [(r["frame"], r["kind"]) for r in recs] == [(31, "backwards")]
    assert recs[0]["value"] == pytest.approx(0.02)


def test_a_jump_at_a_join_is_caught(walk_gait, lim):
    a = track(loop_steps(walk_gait.straight, 1))
    b = track(loop_steps(walk_gait.straight, 1), at=a[-1, :2] + (0.0, 0.03))  # 3 cm aside
    joined = np.concatenate((a, b[1:]))
    j = a.shape[0] - 1
    # Continuous on both sides; the 3 cm offset is within one step's limit...
    assert validate.ground_glitches(a, lim) == validate.ground_glitches(b, lim) == []
    assert validate.ground_glitches(joined, lim) == []
    # ... but not at the join: the velocity changes there as no walk's does.
    recs = validate.ground_glitches(joined, lim, joins=[j])
    assert [(r["frame"], r["kind"]) for r in recs] == [(j, "jump")]
    # Given as pieces, the shared frame itself differs.
    recs = validate.motion_glitches([motion(a), motion(b)], ["segment", "goal"], lim)
    assert {(r["frame"], r["kind"], r["piece"]) for r in recs} == {(j, "jump", 1)}
    gap = [r for r in recs if r["where"] == "segment-goal join position"]
    assert len(gap) == 1 and gap[0]["value"] == pytest.approx(0.03)
    # A big jump is caught anywhere as an over-long step.
    b = track(loop_steps(walk_gait.straight, 1), at=a[-1, :2] + (0.3, 0.0))
    recs = validate.ground_glitches(np.concatenate((a, b[1:])), lim)
    assert [(r["frame"], r["kind"]) for r in recs] == [(j + 1, "jump")]


def test_a_heading_jump_at_a_join_is_caught(walk_gait, lim):
    a = track(loop_steps(walk_gait.straight, 1))
    b = track(loop_steps(walk_gait.straight, 1), heading0=np.radians(3), at=a[-1, :2])
    recs = validate.motion_glitches([motion(a), motion(b)], ["start", "segment"], lim)
    assert [(r["kind"], r["where"]) for r in recs] == [("jump", "start-segment join heading")]


def test_clips_are_checked_only_where_they_join(walk_gait, lim):
    a = track(loop_steps(walk_gait.straight, 1))
    # A "clip" that turns on the spot (as sitting down does) and moves fast: fine inside.
    clip = np.repeat(a[-1:], 20, axis=0)
    clip[:, 2] += np.linspace(0, np.pi, 20)
    clip[10:, 0] += 0.3
    b = track(loop_steps(walk_gait.straight, 1), heading0=clip[-1, 2], at=clip[-1, :2])
    kinds = ["segment", "interaction", "goal"]
    assert validate.motion_glitches([a, clip, b], kinds, lim) == []
    b[:, 1] += 0.1
    recs = validate.motion_glitches([a, clip, b], kinds, lim)
    assert [(r["frame"], r["piece"]) for r in recs] == [(a.shape[0] - 1 + 19, 2)]
    # The same clip as a locomotion piece is glitch upon glitch.
    assert validate.motion_glitches([a, clip], ["segment", "part"], lim)


def test_segments_it_names_are_the_ones_that_flip(walk_patch):
    # Every segment named has a heading change of more than 90 degrees in one frame, and
    # every segment with one is named; the others (the gait's own turns) pass.
    def ground(seg):
        g = walk_patch.ground(seg)
        return g[0] if isinstance(g, tuple) else g

    named = validate.segment_glitches(walk_patch)
    flips = [
        s
        for s in range(walk_patch.segment_count)
        if np.abs(wrap(np.diff(ground(s)[:, 2]))).max() > np.pi / 2
    ]
    assert named == flips
    # The synthesised motion has the flip too (the ground frames are the motion's).
    for s in named[:3]:
        assert np.allclose(walk_patch.motion(s).ground, ground(s))


def test_no_baked_segment_glitches(walk_patch):
    """The bake culls curves that fold back on themselves (a straight diagonal Hermite
    curve with a tangent scale over 3 x its chord runs backwards in the middle: the
    heading flips 180 degrees) and drops whatever the validator still finds."""
    assert validate.segment_glitches(walk_patch) == []
