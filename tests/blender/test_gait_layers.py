# SPDX-License-Identifier: GPL-3.0-or-later
"""Walk and run layers in one scene (issue 19): a run patch baked from CMU subject 16's
runs (16_35 straight, 16_53 turning right; 3ds Max naming, imported onto the walk's
armature, so retargeted) beside the walk patch of the same subject; plans per layer and
"auto", evaluated through the depsgraph."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, prop_box, walker_from

LINE_X = 5.0


@pytest.fixture(scope="module")
def layers_blend(addon_module, mocap_dir, tmp_path_factory):
    """Walk (16_15 + 16_18) and run (16_35 + 16_53) patches on the armature 'Source'; a
    line of 21 chairs across the way at x = 5 m (10 m long), each carrying the 16_06 jump
    declared as a run-layer clip; a walker at (1, 0.3) facing +X; the goal 'Goal' at
    (9, 0.3) facing +X."""
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap(
        [
            mocap_dir / "cmu" / "16_15.bvh",
            mocap_dir / "cmu" / "16_18.bvh",
            mocap_dir / "cmu" / "16_06.bvh",
        ],
        name="Source",
    )
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    _, runs = api.import_mocap(
        [mocap_dir / "cmu16max" / "16_35.bvh", mocap_dir / "cmu16max" / "16_53.bvh"], armature=arm
    )
    api.bake_locomotion_patch(scene, arm, runs[0], [runs[1]], layer="run")
    scene.motion_patches.source_armature = arm
    for k, y in enumerate(np.linspace(-5.0, 5.0, 21)):
        ob = prop_box(f"Chair.{k:02d}", LINE_X, y)
        api.tag_object_patch(ob, [(acts[2], "TRAVERSAL", 8.0, 10.0)], patch_name="walk")
        for c in ob.motion_patch.clips:
            c.layer_in = c.layer_out = "run"
    walker = walker_from(arm, location=(1.0, 0.3, 0))
    walker.rotation_euler = (0, 0, np.pi / 2)  # the rig's rest faces -Y: face +X
    scene.motion_patches.goal = empty("Goal", 9.0, 0.3, 0.0)
    path = tmp_path_factory.mktemp("layers") / "layers.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def evaluated(api, walker, bone="Hips"):
    """World (x, y) of ``bone`` at every planned frame, through the depsgraph."""
    from importlib import import_module

    evaluate = import_module(api.__name__.rsplit(".", 1)[0] + ".adapter.evaluate")
    meta, _ = api.load_plan_record(walker)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos, _, _, _ = evaluate.sample_armature(bpy.context, walker, frames, [bone])
    return pos[:, 0, :2]


def plan(api, gait, **kw):
    scene = bpy.context.scene
    bpy.context.view_layer.update()
    return api.plan_path(
        scene, bpy.data.objects["Walker"], bpy.data.objects["Goal"], gait=gait, **kw
    )


def test_auto_runs_and_hurdles_where_walking_round_the_chairs_is_long(layers_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    walk = plan(api, "walk")
    assert walk.stats["traversals_used"] == 0  # the jump is a run clip only
    walk_hips = evaluated(api, bpy.data.objects["Walker"])
    i = int(np.argmax(walk_hips[:, 0] >= LINE_X))
    assert abs(walk_hips[i, 1]) > 5.0  # round the end of the line
    res = plan(api, "auto")
    print("auto:", res.stats["layers"], res.pieces)
    assert res.stats["layer"] == "run"
    assert res.stats["layers"]["run"] < res.stats["layers"]["walk"]
    assert res.stats["layers"]["walk"] == pytest.approx(walk.cost, abs=1e-3)
    assert res.stats["traversals_used"] == 1
    assert any("16_06" in s["name"] for s in res.strips)
    hips = evaluated(api, bpy.data.objects["Walker"])
    assert res.frame_end - res.frame_start < walk.frame_end - walk.frame_start
    f = api.analyse(bpy.context, bpy.data.objects["Walker"])
    assert f["frames_root_inside_obstacle"] == 0
    assert f["goal_root_position_error_cm"] < 10
    # No root jump over 1.5x the run's per-frame speed.
    step = np.linalg.norm(np.diff(hips, axis=0), axis=1)
    run_gait = addon_module.adapter.storage.load_patch(bpy.context.scene, "run").gait
    per_frame = addon_module.api.layers.speed(run_gait) / run_gait.fps
    print(
        f"largest hips step {step.max() * 100:.1f} cm/frame, run pace {per_frame * 100:.1f} "
        f"cm/frame; foot skate (foot lock on) {f['foot_skate']['mean_cm_per_s']:.1f} cm/s"
    )
    assert step.max() < 1.5 * per_frame


def test_on_open_ground_auto_walks(layers_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    bpy.data.objects["Goal"].location = (1.0, -9.0, 0.0)  # away from the chairs
    bpy.data.objects["Goal"].rotation_euler = (0, 0, 0)  # facing -Y
    res = plan(api, "auto")
    assert res.stats["layer"] == "walk"
    assert res.stats["layers"]["walk"] < res.stats["layers"]["run"]
    run = plan(api, "run")
    assert run.stats["layer"] == "run"
    hips = evaluated(api, bpy.data.objects["Walker"])
    speed = np.linalg.norm(np.diff(hips, axis=0), axis=1) * 30.0
    assert speed.max() > 2.3  # it runs (the walk tops out near 1.3 m/s)
    assert run.frame_end - run.frame_start < 0.7 * (res.frame_end - res.frame_start)


def test_a_layer_not_baked_is_refused_and_nothing_written(layers_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    walker = bpy.data.objects["Walker"]
    with pytest.raises(
        api.MotionPatchesError,
        match="no locomotion patch of layer 'swim'.*'walk' \\(walk\\), 'run' \\(run\\)",
    ):
        plan(api, "swim")
    with pytest.raises(api.MotionPatchesError, match="'walk' is of layer 'walk', not 'run'"):
        plan(api, "run", patch_name="walk")
    assert walker.animation_data is None or not walker.animation_data.nla_tracks
    assert api.PLAN_KEY not in walker


def test_cli_plan_gait(layers_blend, addon_module_name, capsys):
    import json
    import sys

    cli = sys.modules[addon_module_name].cli
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    code = cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--gait", "auto", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["layer"] == "run"
    assert set(doc["layer_costs"]) == {"walk", "run"}
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    code = cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--gait", "swim"])
    err = capsys.readouterr().err
    assert code != 0 and "no locomotion patch of layer 'swim'" in err
    assert "motion_patches_plan" not in bpy.data.objects["Walker"]
