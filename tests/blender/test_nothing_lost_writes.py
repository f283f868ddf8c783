# SPDX-License-Identifier: GPL-3.0-or-later
"""A plan that cannot be written leaves the scene as it was (issue 20, item 2), compared
object by object: every object's NLA tracks, strips, active action and plan record, every
action (name, users, keys), the scene's frame range."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from


@pytest.fixture(scope="module")
def baked_blend(walk_blend):
    return walk_blend


def scene_state():
    """Everything planning may touch, as plain values."""
    objects = {}
    for ob in bpy.data.objects:
        ad = ob.animation_data
        anim = None
        if ad is not None:
            anim = {
                "action": ad.action and ad.action.name,
                "tweak": ad.use_tweak_mode,
                "tracks": [
                    (
                        t.name,
                        t.mute,
                        t.is_solo,
                        [
                            (
                                s.name,
                                s.action and s.action.name,
                                s.frame_start,
                                s.frame_end,
                                s.blend_type,
                                s.extrapolation,
                                round(s.scale, 6),
                                s.mute,
                            )
                            for s in t.strips
                        ],
                    )
                    for t in ad.nla_tracks
                ],
            }
        objects[ob.name] = {
            "anim": anim,
            "props": {k: str(ob[k]) for k in ob.keys()},
            # to a nanometre: the rig's evaluated place at the current frame, which cubic
            # keys give to within rounding (2e-16 m) of their value
            "location": tuple(round(v, 9) + 0.0 for v in ob.location),
        }
    actions = {
        a.name: (
            a.users,
            a.use_fake_user,
            sorted(a.keys()),
            sum(len(fc.keyframe_points) for fc in _fcurves(a)),
        )
        for a in bpy.data.actions
    }
    sc = bpy.context.scene
    return {
        "objects": objects,
        "actions": actions,
        "frames": (sc.frame_start, sc.frame_end, sc.frame_current),
        "scene_props": {k: str(sc[k]) for k in sc.keys() if k.startswith("motion_patches_")},
    }


def _fcurves(action):
    out = []
    for layer in action.layers:
        for strip in layer.strips:
            for bag in strip.channelbags:
                out += list(bag.fcurves)
    return out


def assert_same(before, after):
    assert after["frames"] == before["frames"]
    assert after["scene_props"] == before["scene_props"]
    assert sorted(after["objects"]) == sorted(before["objects"])
    for name in before["objects"]:
        assert after["objects"][name] == before["objects"][name], name
    assert after["actions"] == before["actions"]


@pytest.fixture
def planned(baked_blend, addon_module):
    """A walker planned once (its tracks, actions and plan record exist), with a user
    track of its own, and a goal to plan to again."""
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    goal = empty("Goal", 0.0, -6.0, -np.pi / 2)
    bpy.context.view_layer.update()
    addon_module.api.plan_path(scene, char, goal)
    mine = char.animation_data.nla_tracks.new()
    mine.name = "My layer"
    mine.strips.new("wave", 1, bpy.data.actions["16_18"])
    other = empty("Goal2", 3.0, -5.0, -np.pi / 2)
    return scene, char, other


def test_an_absurd_frame_start_is_refused_before_anything_changes(planned, addon_module):
    scene, char, goal = planned
    before = scene_state()
    for frame in (-(10**9), 10**9, float("nan")):
        with pytest.raises(addon_module.api.MotionPatchesError, match="frame"):
            addon_module.api.plan_path(scene, char, goal, frame_start=frame)
        assert_same(before, scene_state())


def test_a_frame_start_whose_end_is_out_of_range_is_refused(planned, addon_module):
    scene, char, goal = planned
    lo, hi = addon_module.adapter.transaction.frame_limits(bpy)
    before = scene_state()
    with pytest.raises(addon_module.api.MotionPatchesError, match="outside what Blender holds"):
        addon_module.api.plan_path(scene, char, goal, frame_start=hi - 10)
    assert_same(before, scene_state())


def test_tweak_mode_is_refused_and_the_scene_kept(planned, addon_module):
    scene, char, goal = planned
    ad = char.animation_data
    track = ad.nla_tracks["My layer"]
    ad.nla_tracks.active = track
    track.strips[0].select = True
    ad.use_tweak_mode = True
    assert ad.use_tweak_mode
    before = scene_state()
    with pytest.raises(addon_module.api.MotionPatchesError, match="tweak mode"):
        addon_module.api.plan_path(scene, char, goal)
    assert_same(before, scene_state())
    with pytest.raises(addon_module.api.MotionPatchesError, match="tweak mode"):
        addon_module.api.plan_crowd(scene, [(char, goal)])
    assert_same(before, scene_state())


def test_a_user_track_with_the_add_ons_name_is_not_deleted(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    ad = char.animation_data_create()
    tr = ad.nla_tracks.new()
    tr.name = "MP root"
    tr.strips.new("mine", 1, bpy.data.actions["16_18"])
    goal = empty("Goal", 0.0, -6.0, -np.pi / 2)
    before = scene_state()
    with pytest.raises(addon_module.api.MotionPatchesError, match="'MP root'"):
        addon_module.api.plan_path(scene, char, goal)
    assert_same(before, scene_state())


def test_a_user_strip_on_the_add_ons_track_is_not_deleted(planned, addon_module):
    scene, char, goal = planned
    motion = char.animation_data.nla_tracks["MP motion"]
    motion.strips.new("my extra", int(motion.strips[-1].frame_end) + 50, bpy.data.actions["16_18"])
    before = scene_state()
    with pytest.raises(addon_module.api.MotionPatchesError, match="my extra"):
        addon_module.api.plan_path(scene, char, goal)
    assert_same(before, scene_state())


def failing_foot_lock(*args, **kwargs):
    raise RuntimeError("simulated failure while writing")


@pytest.mark.parametrize("active_action", [False, True], ids=["NLA only", "active action"])
def test_a_write_that_fails_half_way_is_undone(planned, addon_module, monkeypatch, active_action):
    """Writing fails after the old tracks were removed, the active action stashed, new
    tracks and actions made: everything is put back, the old actions included."""
    scene, char, goal = planned
    if active_action:
        char.animation_data.action = bpy.data.actions["16_15"]
    before = scene_state()
    monkeypatch.setattr(addon_module.adapter.nla, "write_foot_lock", failing_foot_lock)
    with pytest.raises(RuntimeError, match="simulated"):
        addon_module.api.plan_path(scene, char, goal)
    assert_same(before, scene_state())
    with pytest.raises(RuntimeError, match="simulated"):
        addon_module.api.plan_crowd(scene, [(char, goal)])
    assert_same(before, scene_state())


def test_the_operator_reports_an_unexpected_failure_and_keeps_the_scene(
    planned, addon_module, monkeypatch
):
    scene, char, goal = planned
    scene.motion_patches.goal = goal
    for ob in bpy.context.view_layer.objects:
        ob.select_set(ob == char)
    bpy.context.view_layer.objects.active = char
    before = scene_state()
    monkeypatch.setattr(addon_module.adapter.nla, "write_foot_lock", failing_foot_lock)
    with pytest.raises(RuntimeError, match="Internal error.*simulated"):
        bpy.ops.motion_patches.plan_path()
    after = scene_state()
    assert_same(before, after)


def test_a_successful_re_plan_keeps_the_action_names_and_drops_the_old_ones(planned, addon_module):
    scene, char, goal = planned
    root = [a.name for a in bpy.data.actions if a.name.startswith(f"MP {char.name} root")]
    assert root == [f"MP {char.name} root"]
    addon_module.api.plan_path(scene, char, goal)
    root = [a.name for a in bpy.data.actions if a.name.startswith(f"MP {char.name} root")]
    assert root == [f"MP {char.name} root"]
    assert "My layer" in char.animation_data.nla_tracks  # the user's track is kept
    assert not any(a.use_fake_user for a in bpy.data.actions if a.name.startswith("MP "))
