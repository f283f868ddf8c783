# SPDX-License-Identifier: GPL-3.0-or-later
"""A straight clip alone bakes a patch that plans, and a failed plan names its cause
(issue 15, items 3 and 5), through the API on a rig from Blender's own BVH importer."""

import bpy
import numpy as np
import pytest

from scene_helpers import CMU_SCALE, empty, prop_box, walker_from


@pytest.fixture(scope="module")
def straight_blend(addon_module, mocap_dir, tmp_path_factory):
    """A saved .blend with a walk patch baked from CMU 16_15 alone (no turn clip)."""
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap([mocap_dir / "cmu" / "16_15.bvh"], name="Source")
    bake = api.bake_locomotion_patch(scene, arm, acts[0], [], layer="walk")
    scene.motion_patches.source_armature = arm
    path = tmp_path_factory.mktemp("straight") / "straight.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path, bake


def walker(addon_module, straight_blend, location=(0.0, 0.0, 0.0)):
    """The saved scene opened, a walker placed; returns it and its ground state."""
    bpy.ops.wm.open_mainfile(filepath=str(straight_blend[0]))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=location)
    bpy.context.view_layer.update()
    start = addon_module.adapter.scene.character_state(
        char, addon_module.adapter.storage.load_patch(scene, "walk").gait.skeleton
    )
    return char, start


def plan(addon_module, char, goal):
    bpy.context.view_layer.update()
    return addon_module.api.plan_path(bpy.context.scene, char, goal)


def evaluated_hips(addon_module, char):
    """World (x, y) of the hips at every planned frame, through the depsgraph."""
    meta, _ = addon_module.api.load_plan_record(char)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos, _, _, _ = addon_module.adapter.evaluate.sample_armature(
        bpy.context, char, frames, ["Hips"]
    )
    return pos[:, 0, :2]


def test_a_straight_clip_alone_bakes_a_patch_that_connects(straight_blend):
    _, bake = straight_blend
    assert bake.stats["curvature_limits"] == pytest.approx([-1.0, 1.0])
    assert bake.stats["entry_share"] >= 0.7
    assert bake.stats["kept"] > 100
    assert any("bends to 1.00 m" in n for n in bake.notes)


def test_it_walks_16_m_straight_within_5_cm_of_the_line(straight_blend, addon_module):
    char, start = walker(addon_module, straight_blend, location=(0.7, -0.4, 0.0))
    d = np.array([np.cos(start[2]), np.sin(start[2])])
    goal = empty("Goal", *(start[:2] + 16.0 * d), start[2])
    result = plan(addon_module, char, goal)
    rel = evaluated_hips(addon_module, char) - start[:2]
    lateral = rel @ np.array([-d[1], d[0]])
    assert np.abs(lateral).max() < 0.05, np.abs(lateral).max()
    assert (rel @ d)[-1] == pytest.approx(16.0, abs=0.1)
    assert result.length_m < 16.0 * 1.01


def test_it_turns_90_degrees_left(straight_blend, addon_module):
    char, start = walker(addon_module, straight_blend)
    d = np.array([np.cos(start[2]), np.sin(start[2])])
    left = np.array([-d[1], d[0]])
    target = start[:2] + 6.0 * d + 6.0 * left
    goal = empty("Goal", *target, start[2] + np.pi / 2)
    plan(addon_module, char, goal)
    figures = addon_module.api.analyse(bpy.context, char)
    assert figures["goal_position_error_cm"] < 5.0
    assert figures["goal_heading_error_deg"] < 1.0
    hips = evaluated_hips(addon_module, char)
    assert np.linalg.norm(hips[-1] - target) < 0.1


def walled_off(addon_module, straight_blend):
    """The walker with its goal 6 m ahead behind a wall 40 m long: (walker, goal, wall)."""
    char, start = walker(addon_module, straight_blend)
    d = np.array([np.cos(start[2]), np.sin(start[2])])
    across = np.round(np.abs(d[::-1]))  # the rig faces along an axis
    mid = start[:2] + 3.0 * d
    wall = prop_box("Garden wall", *mid, size=(*(40.0 * across + 0.3), 2.0))
    goal = empty("Goal", *(start[:2] + 6.0 * d), start[2])
    bpy.context.view_layer.update()
    return char, goal, wall


def test_a_wall_in_the_way_is_named_as_the_cause(straight_blend, addon_module):
    api = addon_module.api
    char, goal, wall = walled_off(addon_module, straight_blend)
    with pytest.raises(api.PathNotFound) as err:
        plan(addon_module, char, goal)
    assert "Cause: 'Garden wall' walls the goal off from the start" in str(err.value)
    assert (err.value.cause, err.value.props) == ("props", [wall.name])
    assert api.PLAN_KEY not in char  # nothing was written


def test_a_crowd_member_walled_off_is_reported_with_the_wall(straight_blend, addon_module):
    """Two walkers on the near side of the wall: the one whose goal is beyond it fails,
    naming the wall; the other walks 2 m ahead beside it."""
    char, goal, _ = walled_off(addon_module, straight_blend)
    loc = np.array(char.location)
    ahead = np.array(goal.location) - loc
    ahead /= np.linalg.norm(ahead)
    beside = np.array([-ahead[1], ahead[0], 0.0]) * 3.0
    other = walker_from(
        bpy.context.scene.motion_patches.source_armature, name="Other", location=tuple(loc + beside)
    )
    other_goal = empty(
        "Other goal", *(loc + beside + 2.0 * ahead)[:2], float(np.arctan2(ahead[1], ahead[0]))
    )
    bpy.context.view_layer.update()
    res = addon_module.api.plan_crowd(bpy.context.scene, [(char, goal), (other, other_goal)])
    assert [c for c, _ in res.failed] == [char.name]
    assert "Cause: 'Garden wall' walls the goal off" in res.failed[0][1]
    assert [p.character for p in res.plans] == ["Other"]


def test_the_cli_plan_exits_1_naming_the_wall(straight_blend, addon_module, tmp_path, capsys):
    walled_off(addon_module, straight_blend)
    path = tmp_path / "walled.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    capsys.readouterr()
    code = addon_module.cli.main(
        ["plan", "--blend", str(path), "--character", "Walker", "--goal", "Goal"]
    )
    err = capsys.readouterr().err
    assert code == 1
    assert "no path for 'Walker'" in err and "Cause: 'Garden wall'" in err


def test_a_bake_too_sparse_to_connect_is_refused_with_what_to_add(straight_blend, addon_module):
    """Two nodes per edge leave a straight clip alone too few ways on: refused, the patch
    list unchanged."""
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(straight_blend[0]))
    scene = bpy.context.scene
    arm = scene.motion_patches.source_armature
    action = next(a for a in bpy.data.actions if a.name.startswith("16_15"))
    with pytest.raises(
        api.MotionPatchesError,
        match=r"too sparse to plan with: only \d+% of entry states have a way on"
        r".*Add a turn clip",
    ) as err:
        api.bake_locomotion_patch(scene, arm, action, [], layer="sparse", nodes=2)
    assert "more nodes per edge" in str(err.value)
    assert [p.name for p in scene.motion_patches.patches] == ["walk"]


def test_clips_imported_at_another_rate_bake_with_a_warning(straight_blend, mocap_dir, mp, capfd):
    """16_15 (120 fps) and 16_18 (30 fps) through Blender's BVH importer at its defaults
    (Scale FPS off) into a 24 fps scene: each recorded frame becomes a scene frame, the walk
    five times slower. The bake goes ahead (a slow walk may be meant) and the button, the
    API and the CLI say so, with the cause; clips imported with Import Mocap Clips (the
    module's patch) bake without a word."""
    assert straight_blend[1].warnings == []
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 24
    for name in ("16_15", "16_18"):
        assert bpy.ops.import_anim.bvh(
            filepath=str(mocap_dir / "cmu" / f"{name}.bvh"),
            global_scale=CMU_SCALE,
            update_scene_fps=False,
        ) == {"FINISHED"}
    scene.motion_patches.source_armature = bpy.data.objects["16_15"]
    capfd.readouterr()
    assert bpy.ops.motion_patches.bake_locomotion_patch(
        layer="walk", straight="16_15", turns="16_18"
    ) == {"FINISHED"}
    said = capfd.readouterr().out
    assert "the straight clip '16_15' takes 5.8" in said and "Scale FPS" in said, said
    assert "the turn clip '16_18' takes 1.46 s" in said, said  # 30 fps read at 24
    res = mp.api.bake_locomotion_patch(
        scene, bpy.data.objects["16_15"], "16_15", ["16_18"], layer="walk"
    )
    assert [w.split(" takes ")[0] for w in res.warnings] == [
        "the straight clip '16_15'",
        "the turn clip '16_18'",
    ]
    capfd.readouterr()
    assert (
        mp.cli.main(["bake", "--armature", "16_15", "--straight", "16_15", "--turn", "16_18"]) == 0
    )
    assert "warning: the straight clip '16_15' takes 5.8" in capfd.readouterr().out
