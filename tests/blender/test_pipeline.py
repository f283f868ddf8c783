# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake -> save -> reload -> plan -> evaluate, on real CMU mocap inside Blender."""

import json

import bpy
import numpy as np
import pytest

from scene_helpers import empty, pillar, walker_from


@pytest.fixture(scope="module")
def baked_blend(addon_module, mocap_dir, tmp_path_factory):
    """A saved .blend with the walk patch baked from 16_15 + 16_18 through the operators."""
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap(
        [mocap_dir / "cmu" / "16_15.bvh", mocap_dir / "cmu" / "16_18.bvh"], name="Source"
    )
    s = scene.motion_patches
    s.source_armature = arm
    s.straight_action = acts[0]
    s.turn_actions.add().action = acts[1]
    assert bpy.ops.motion_patches.bake_locomotion_patch(layer="walk") == {"FINISHED"}
    path = tmp_path_factory.mktemp("blend") / "baked.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def test_import_puts_every_clip_on_one_armature(addon_module, mocap_dir, clean_scene):
    clean_scene.render.fps = 30
    arm, acts = addon_module.api.import_mocap(
        [mocap_dir / "cmu" / "16_15.bvh", mocap_dir / "cmu" / "16_18.bvh"]
    )
    assert [o.type for o in bpy.data.objects] == ["ARMATURE"]
    assert [a.name for a in acts] == ["16_15", "16_18"]
    clip = addon_module.adapter.actions.clip_from_action(acts[0], arm, 30.0)
    assert abs(clip.fps - 120) < 0.5 and clip.frames == 469


def test_bake_survives_save_and_reload(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    item = scene.motion_patches.patches["walk"]
    stats = json.loads(item.stats)
    patch = addon_module.adapter.storage.load_patch(scene, "walk")
    assert patch.segment_count == stats["kept"] > 300
    assert stats["kept"] + stats["culled"] == stats["candidates"]


def test_plan_writes_nla_and_evaluates_onto_the_goal(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature)
    for n, (x, y) in enumerate([(3.0, 1.0), (4.5, 3.0), (2.5, 4.0), (6.0, 1.5)]):
        pillar(f"Pillar{n}", x, y)
    scene.motion_patches.goal = empty("Goal", 7.5, 5.0, 0.6)
    bpy.context.view_layer.objects.active = char
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    tracks = [t.name for t in char.animation_data.nla_tracks]
    assert tracks == ["MP motion", "MP root", "MP foot lock"]
    strips = char.animation_data.nla_tracks["MP motion"].strips
    # Past four pillars the found path is shortened to one followed curve (one strip);
    # every strip, however many, has its action slot.
    assert len(strips) >= 1 and all(s.action_slot is not None for s in strips)

    figures = addon_module.api.analyse(bpy.context, char)
    meta, _ = addon_module.api.load_plan_record(char)
    # The plan aimed at where the goal and character really are (objects moved by script).
    assert np.allclose(meta["goal"][:2], (7.5, 5.0), atol=1e-6)
    assert np.isclose(meta["goal"][2], 0.6, atol=1e-6)
    scene.frame_set(meta["frame_start"])
    root = char.matrix_world @ char.pose.bones["Hips"].head
    assert np.hypot(root.x - 0.4, root.y - 0.3) < 0.1
    assert figures["goal_position_error_cm"] < 10
    assert figures["goal_root_position_error_cm"] < 10  # the hips, not only the root motion
    assert figures["goal_heading_error_deg"] < 10
    assert figures["frames_root_inside_obstacle"] == 0
    assert figures["root_from_plan_cm"]["max"] < 5
    assert figures["foot_skate"]["mean_cm_per_frame"] < 1.0
    pop = figures["boundary_pop"]
    assert pop["max_boundary_jump_deg"] <= max(pop["p99_step_deg"], 1.0) * 1.5


def boundary_step_over_its_neighbours(addon_module, character, around=3):
    """Degrees by which a bone's turn across a strip boundary exceeds its largest turn on
    the ``around`` frames either side (evaluated; the most over every bone and boundary):
    a pop stands out from the motion around it, a bone moving steadily through a
    boundary does not."""
    meta, _ = addon_module.api.load_plan_record(character)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    names = [pb.name for pb in character.pose.bones]
    rot = addon_module.adapter.evaluate.sample_armature(bpy.context, character, frames, names)[2]
    quat = addon_module.motion_patches.kinematics.quat
    steps = np.degrees(quat.angle_between(rot[1:], rot[:-1]))  # (F - 1, J)
    worst = -np.inf
    for b in meta["boundaries"]:
        i = b - meta["frame_start"] - 1  # the step onto the boundary's first frame
        near = np.concatenate((steps[max(i - around, 0) : i], steps[i + 1 : i + 1 + around]))
        worst = max(worst, float((steps[i] - near.max(axis=0)).max()))
    return worst


def test_foot_lock_pins_the_evaluated_feet(baked_blend, addon_module):
    """The Add track over the shared segment strips: the same plan, evaluated through
    the depsgraph with and without it; planted feet slide much less with it, nothing else
    about the path changes, and no pose pops: no bone turns across a strip boundary more
    than a degree beyond its turns on the frames around it. (The plan turns on the spot,
    then walks off: there the recorded swing passes 7 cm under the planted toe, and the
    lock lifts the foot, bending the knee 5-6 degrees a frame through the boundary.)"""
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    api = addon_module.api
    char = walker_from(scene.motion_patches.source_armature)
    goal = empty("Goal", 6.0, 4.0, -0.8)
    free = api.plan_path(scene, char, goal, frame_start=1, foot_lock=False)
    assert [t.name for t in char.animation_data.nla_tracks] == ["MP motion", "MP root"]
    before = api.analyse(bpy.context, char)
    locked = api.plan_path(scene, char, goal, frame_start=1)
    assert locked.pieces == free.pieces and locked.cost == free.cost
    lock_track = char.animation_data.nla_tracks["MP foot lock"]
    assert lock_track.strips[0].blend_type == "ADD"
    after = api.analyse(bpy.context, char)
    sk0, sk1 = before["foot_skate"], after["foot_skate"]
    assert sk1["mean_cm_per_s"] < 0.5 * sk0["mean_cm_per_s"], (sk0, sk1)
    assert sk1["p95_cm_per_s"] < sk0["p95_cm_per_s"]
    assert after["root_from_plan_cm"]["max"] < 0.5  # the hips are not touched
    assert after["goal_root_position_error_cm"] == pytest.approx(
        before["goal_root_position_error_cm"], abs=0.1
    )
    over = boundary_step_over_its_neighbours(addon_module, char)
    print(f"\nlocked: a boundary step at most {over:.2f} deg over the steps around it")
    assert locked.pieces[1:] and over <= 1.0
    # Re-planning without the lock removes its track (the add-on owns it), nothing else.
    api.plan_path(scene, char, goal, frame_start=1, foot_lock=False)
    assert [t.name for t in char.animation_data.nla_tracks] == ["MP motion", "MP root"]


def test_replanning_replaces_only_the_addon_tracks(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = scene.motion_patches.source_armature
    user_action = char.animation_data.action
    user_track = char.animation_data.nla_tracks.new()
    user_track.name = "My layout notes"
    scene.motion_patches.goal = empty("Goal", 5.0, 2.0, 0.0)
    bpy.context.view_layer.objects.active = char
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    scene.motion_patches.goal.location = (4.0, -3.0, 0)
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    names = [t.name for t in char.animation_data.nla_tracks]
    assert "My layout notes" in names
    assert names.count("MP motion") == 1 and names.count("MP root") == 1
    assert user_action.name in bpy.data.actions  # stashed, never deleted
    assert any(t.name.startswith("MP stash") and t.mute for t in char.animation_data.nla_tracks)


def test_unreachable_goal_reports_and_leaves_the_scene_untouched(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = scene.motion_patches.source_armature
    for n, a in enumerate(np.linspace(0, 2 * np.pi, 25)[:-1]):
        pillar(f"Ring{n}", 6 + 1.6 * np.cos(a), 6 + 1.6 * np.sin(a), r=0.3)
    scene.motion_patches.goal = empty("Goal", 6.0, 6.0, 0.0)
    bpy.context.view_layer.objects.active = char
    tracks_before = [t.name for t in char.animation_data.nla_tracks]
    actions_before = sorted(a.name for a in bpy.data.actions)
    with pytest.raises(RuntimeError, match="unreachable|no walkable way"):
        bpy.ops.motion_patches.plan_path()
    assert [t.name for t in char.animation_data.nla_tracks] == tracks_before
    assert sorted(a.name for a in bpy.data.actions) == actions_before
    assert char.animation_data.action is not None
