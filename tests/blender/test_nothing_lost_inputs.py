# SPDX-License-Identifier: GPL-3.0-or-later
"""Inputs that used to give wrong animation silently, freeze the window or speak unclearly
are refused naming the cause, the scene unchanged: weights all 0, a goal without a facing
(zero scale), a start that is not a number, a crowd too big for its region or for one
Duplicate Crowd."""

import bpy
import pytest

from scene_helpers import empty, walker_from


@pytest.fixture
def scene(walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    s = bpy.context.scene
    walker_from(s.motion_patches.source_armature)
    s.motion_patches.goal = empty("Goal", 6.0, 1.0, 0.0)
    bpy.context.view_layer.update()
    return s


def untouched(walker):
    return walker.animation_data is None or not walker.animation_data.nla_tracks


def test_weights_all_zero_are_refused_through_api_and_operator(mp, scene):
    walker = bpy.data.objects["Walker"]
    with pytest.raises(mp.api.MotionPatchesError, match="all 0"):
        mp.api.plan_path(scene, walker, None, alpha=0, beta=0, gamma=0)
    s = scene.motion_patches
    s.alpha = s.beta = s.gamma = 0.0
    bpy.context.view_layer.objects.active = walker
    with pytest.raises(RuntimeError, match="all 0"):
        bpy.ops.motion_patches.plan_path()
    assert untouched(walker)
    s.gamma = 0.1  # one positive weight is enough
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}


def test_a_goal_of_zero_scale_has_no_facing_and_is_refused(mp, scene):
    walker, goal = bpy.data.objects["Walker"], bpy.data.objects["Goal"]
    goal.scale = (0.0, 0.0, 0.0)
    bpy.context.view_layer.update()
    with pytest.raises(mp.api.MotionPatchesError, match="'Goal' has no facing"):
        mp.api.plan_path(scene, walker, goal)
    assert untouched(walker)
    res = mp.api.plan_path(scene, walker, goal, goal_facing="any")  # the facing is free
    assert res.frame_end > res.frame_start


def test_a_start_that_is_not_a_number_is_named_as_such(mp, scene):
    walker = bpy.data.objects["Walker"]
    walker.location = (float("nan"), 0.0, 0.0)
    bpy.context.view_layer.update()
    with pytest.raises(mp.api.MotionPatchesError, match="not a number") as err:
        mp.api.plan_path(scene, walker, None)
    assert "nan m" not in str(err.value)
    assert untouched(walker)


@pytest.mark.parametrize(
    "count, region, needle",
    [
        (10**9, ((0, 0), (10, 10)), "more than Duplicate Crowd makes at once"),
        (5_000, ((0, 0), (10, 10)), "cannot hold 5,000 characters"),
        (5, ((float("nan"), 0), (10, 10)), "corners must be numbers"),
    ],
)
def test_duplicate_crowd_refuses_at_once_what_it_cannot_place(mp, scene, count, region, needle):
    source = bpy.data.objects["Walker"]
    before = sorted(o.name for o in bpy.data.objects)
    with pytest.raises(mp.api.MotionPatchesError, match=needle):
        mp.api.duplicate_crowd(scene, source, count, region, ((20, 0), (30, 10)))
    assert sorted(o.name for o in bpy.data.objects) == before


def test_an_empty_or_damaged_bvh_names_the_importer_s_error(mp, clean_scene, mocap_dir, tmp_path):
    empty_file = tmp_path / "empty.bvh"
    empty_file.write_text("")
    with pytest.raises(mp.api.MotionPatchesError, match="empty.bvh is not a BVH file: it is empty"):
        mp.api.import_mocap([empty_file])
    cut = tmp_path / "cut.bvh"  # the hierarchy cut in the middle of a joint
    cut.write_text("\n".join((mocap_dir / "cmu" / "16_15.bvh").read_text().splitlines()[:30]))
    with pytest.raises(mp.api.MotionPatchesError) as err:
        mp.api.import_mocap([cut])
    assert "cut.bvh" in str(err.value) and "Location:" not in str(err.value)
    assert "ops.py" not in str(err.value)
    assert not bpy.data.objects  # nothing imported


@pytest.mark.parametrize("rate", [1e9, -1.0, float("nan"), True])
def test_an_absurd_effort_rate_is_refused_naming_it(mp, scene, rate):
    arm = scene.motion_patches.source_armature
    before = [p.name for p in scene.motion_patches.patches]
    with pytest.raises(mp.api.MotionPatchesError, match="effort rate"):
        mp.api.bake_locomotion_patch(scene, arm, "16_15", ["16_18"], effort_rate=rate)
    assert [p.name for p in scene.motion_patches.patches] == before
