# SPDX-License-Identifier: GPL-3.0-or-later
"""Stretches of a character's own motion that a shared loop action plays
(:mod:`motion_patches.kinematics.loop_strips`), found on the real subject-16 walk."""

import numpy as np
import pytest

from motion_patches.kinematics import loop_strips, quat, retime
from motion_patches.kinematics.motion import Motion
from motion_patches.patch import curves, synthesis


def _walk(gait, kappa=0.0, cycles=5, eased=True):
    """The gait followed along a line (or an arc of curvature ``kappa``) for ``cycles``
    loops, started from and stopped at standing as a plan's single piece is."""
    s = np.linspace(0.0, cycles * gait.cycle_distance * 1.013, 600)  # a little longer
    pos, heading = curves.arc_frame(np.zeros(2), 0.0, kappa, s)
    m = synthesis.follow(gait, curves.Curve(s, pos, heading, np.full(s.size, kappa)), cycles=cycles)
    return retime.eased(m, True, True, gait.frames) if eased else m


def _played(loop, first, last, k0, pace):
    """What a loop strip plays on frames ``first`` .. ``last``: the loop's frames slerped
    at the phases the stretch names."""
    p = loop_strips.period(loop)
    u = (k0 + pace * np.arange(last - first + 1)) % p
    return retime.resample(loop, u)


def _largest_angle(a, b):
    dots = np.abs(np.einsum("fjc,fjc->fj", a, b))
    return np.degrees(2 * np.arccos(np.clip(dots, -1.0, 1.0))).max()


def test_a_straight_walk_plays_the_loop_between_its_ramps(walk_gait):
    m = _walk(walk_gait)
    loop = loop_strips.straight_loop(walk_gait)
    p = loop_strips.period(loop)
    assert loop.frames == 2 * p + 1 and p == walk_gait.frames
    found = loop_strips.runs(m, loop)
    assert len(found) == 1
    first, last, k0, pace = found[0]
    # the ramps (a cycle each) are not the loop; most of what lies between is
    assert first >= walk_gait.frames // 2 and last <= m.frames - 1 - walk_gait.frames // 2
    assert last - first + 1 >= 2 * p
    # the ramps' time warp plays the middle a little off the loop's own pace and frames
    assert 1e-4 < abs(pace - 1.0) < 0.05 and 1e-3 < k0 % 1.0 < 1.0 - 1e-3
    got = _played(loop, first, last, k0, pace)
    assert _largest_angle(got.rotations, m.rotations[first : last + 1]) < 1e-3
    assert np.abs(got.root_local - m.root_local[first : last + 1]).max() < 1e-6


def test_a_frame_changed_by_a_tenth_of_a_degree_is_left_to_the_body(walk_gait):
    m = _walk(walk_gait)
    loop = loop_strips.straight_loop(walk_gait)
    first, last, _, _ = loop_strips.runs(m, loop)[0]
    mid = (first + last) // 2
    rot = m.rotations.copy()
    bone = walk_gait.skeleton.names.index("LeftArm")
    rot[mid, bone] = quat.mul(rot[mid, bone], quat.about_z(np.radians([0.1]))[0])
    cut = Motion(m.ground, m.root_local, rot, m.contacts)
    found = loop_strips.runs(cut, loop)
    assert [(a, b) for a, b, *_ in found] == [(first, mid - 1), (mid + 1, last)]


def test_a_curved_walk_blends_other_loops_and_plays_none(walk_gait):
    m = _walk(walk_gait, kappa=0.3)
    assert loop_strips.runs(m, loop_strips.straight_loop(walk_gait)) == []


def test_loop_strips_play_the_stretch_on_the_scene_frames(walk_gait):
    m = _walk(walk_gait)
    loop = loop_strips.straight_loop(walk_gait)
    p = loop_strips.period(loop)
    found = loop_strips.runs(m, loop)
    lo, hi = 7, 7 + m.frames - 1
    parts = loop_strips.scene_parts(found, lo, hi, m.frames, p)
    # the parts cover the piece, each starting where the one before ends
    assert [x[0] for x in parts] == ["body", "loop", "body"]
    assert parts[0][1] == lo and parts[-1][2] == hi
    assert all(a[2] == b[1] for a, b in zip(parts[:-1], parts[1:]))
    _, a, b, first, scale = parts[1]
    assert b - a >= p * scale  # at least a cycle
    # on each scene frame of the strip, the loop frame it plays (Blender's fmod of a
    # repeating strip) shows the piece's pose there
    s = np.arange(a, b + 1)
    played = retime.resample(loop, first + np.fmod(s - a, p * scale) / scale)
    assert _largest_angle(played.rotations, m.rotations[s - lo]) < 1e-3
    assert np.abs(played.root_local - m.root_local[s - lo]).max() < 1e-6


@pytest.mark.parametrize("scene_fps", [24.0, 7.5])
def test_at_another_rate_the_plan_is_what_its_loop_strips_play(walk_patch, scene_fps):
    """On the scene's frames between the patch's the plan is the loop at the phase its
    strip plays there (not a slerp of two planned frames, each a slerp of two loop frames:
    a finger several tenths of a degree away); its body strips' frames are as before."""
    from motion_patches.kinematics import rig_keys, scene_rate
    from motion_patches.kinematics.pose_keys import Tolerance

    gait = walk_patch.gait
    m = _walk(gait)
    loop = loop_strips.straight_loop(gait)
    p = loop_strips.period(loop)
    motions, bounds, whole = scene_rate.placed(walk_patch, None, [m], scene_fps, [0])
    patch_bounds = np.array([0, m.frames - 1])
    slerped = scene_rate.at_scene_rate(m, patch_bounds, bounds)
    parts = loop_strips.played_parts(motions, bounds, [0], loop)[0]
    assert [x[0] for x in parts] == ["body", "loop", "body"]
    _, a, b, first, scale = parts[1]
    s = np.arange(a, b + 1)
    played = retime.resample(loop, first + np.fmod(s - a, p * scale) / scale)
    assert _largest_angle(played.rotations, whole.rotations[s]) < 1e-4
    assert np.abs(played.root_local - whole.root_local[s]).max() < 1e-9
    assert _largest_angle(played.rotations, slerped.rotations[s]) > 0.1
    body = np.r_[0:a, b + 1 : whole.frames]
    assert np.array_equal(whole.rotations[body], slerped.rotations[body])
    assert np.array_equal(whole.ground, slerped.ground)
    keys = rig_keys.body_keys(
        gait.skeleton, whole, None, bounds, [0], motions, {}, 1.0, Tolerance(), loop
    )
    assert [x[0] for x in keys["ranges"][0]] == ["body", "loop", "body"]
    assert keys["frames"].size == whole.frames - (b - a - 1)


def test_the_straight_segments_are_the_loop_and_no_other_is(walk_patch):
    """loop_strips.loop_segments: the segments of the real 16_15 patch whose motion is the
    straight loop's two cycles and a frame (so they play the shared loop action): at least
    one, each equal to the loop to 1e-9; every other segment of that length differs by more
    than a degree somewhere."""
    patch = walk_patch
    loop = loop_strips.straight_loop(patch.gait)
    found = loop_strips.loop_segments(patch)
    assert found
    assert loop_strips.loop_segments(patch) is found  # cached on the patch
    same_length = [s for s in range(patch.segment_count) if patch.seg_cycles[s] == 2]
    for s in same_length:
        m = patch.motion(s)
        if s in found:
            assert np.abs(m.rotations - loop.rotations).max() < 1e-9
            assert np.abs(m.root_local - loop.root_local).max() < 1e-9
        elif m.frames == loop.frames:
            assert _largest_angle(m.rotations, loop.rotations) > 1.0, s


def test_the_loop_action_keys_one_cycle_that_closes_on_itself(walk_gait):
    """What the shared loop action keys: the straight loop's first cycle and a frame, the
    last frame the first again (its curves repeat it), the second cycle the first."""
    n = walk_gait.straight.frames
    two, one = loop_strips.straight_loop(walk_gait), loop_strips.one_cycle(walk_gait)
    assert one.frames == n + 1 and two.frames == 2 * n + 1
    assert np.array_equal(one.rotations, two.rotations[: n + 1])
    assert np.array_equal(one.root_local, two.root_local[: n + 1])
    assert np.array_equal(one.rotations[-1], one.rotations[0])
    assert np.array_equal(one.root_local[-1], one.root_local[0])
    assert np.array_equal(two.rotations[n:], one.rotations)
