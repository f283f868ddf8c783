# SPDX-License-Identifier: GPL-3.0-or-later
"""A bake says when its clips' timing looks wrong (motion_patches.patch.timing): real CMU
clips read at their own rate say nothing; read one scene frame per recorded frame, as
Blender's BVH importer does without Scale FPS, they are named with the likely cause."""

import dataclasses

import pytest

from motion_patches.patch.timing import timing_warnings

from conftest import cmu


@pytest.mark.parametrize(
    "straight, turns",
    [
        (("16_15", "cmu"), [("16_18", "cmu")]),  # a 120 fps walk and a 30 fps turn
        (("02_01", "cmu"), []),
        (("02_03", "cmu"), []),  # a run
        (("16_35", "cmu16max"), [("16_53", "cmu16max")]),  # a run and its turn
    ],
)
def test_clips_at_their_own_rate_say_nothing(straight, turns):
    assert timing_warnings(cmu(*straight), [cmu(*t) for t in turns]) == []


def test_a_120_fps_walk_played_at_24_fps_is_named_with_the_cause(walk16, turn16):
    slow = dataclasses.replace(walk16, fps=24.0)  # each recorded frame a scene frame
    warnings = timing_warnings(slow, [turn16])
    assert len(warnings) == 2, warnings
    assert warnings[0].startswith("the straight clip '16_15' takes 5.8")
    assert "0.22 m/s" in warnings[0] and "Scale FPS" in warnings[0]
    # ... and the turn clip, read at its own rate, strides five times faster than it
    assert warnings[1].startswith("the turn clip '16_18' takes 1.17 s a stride")


def test_a_clip_played_too_fast_is_named(turn16):
    fast = dataclasses.replace(turn16, fps=120.0)  # a 30 fps capture in a 120 fps scene
    (warning,) = timing_warnings(fast)
    assert warning.startswith("the straight clip '16_18' takes 0.29 s a stride")
    assert "far faster than people walk or run" in warning


def test_a_clip_without_cycles_is_left_to_the_bake(walk16):
    still = dataclasses.replace(
        walk16, root_pos=walk16.root_pos[:2], rotations=walk16.rotations[:2]
    )
    assert timing_warnings(still) == []
