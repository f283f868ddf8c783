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


START_X, GOAL_X = -4.0, 14.0


@pytest.fixture(scope="module")
def layers_blend(addon_module, mocap_dir, tmp_path_factory):
    """Walk (16_15 + 16_18) and run (16_35 + 16_53) patches on the armature 'Source'; a
    line of 21 chairs (boxes) across the way at x = 5 m (10 m long), each carrying the
    16_06 jump declared as a run-layer clip only (16_06 is a standing forward jump, the
    one jump subject 16 recorded: it stands in for a hurdle, and is declared run-only so
    the walk has to go round); a walker at (-4, 0.3) facing +X; the goal 'Goal', an empty
    facing -Y turned to +X, at (14, 0.3)."""
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
        ob = prop_box(f"Chair.{k:02d}", LINE_X, y, size=(0.4, 0.44, 0.15))  # 16_06 clears it
        api.tag_object_patch(ob, [(acts[2], "TRAVERSAL", 8.0, 10.0)], patch_name="walk")
        for c in ob.motion_patch.clips:
            c.layer_in = c.layer_out = "run"
    walker = walker_from(arm, location=(START_X, 0.3, 0))
    walker.rotation_euler = (0, 0, np.pi / 2)  # the rig's rest faces -Y: face +X
    scene.motion_patches.goal = empty("Goal", GOAL_X, 0.3, 0.0)
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


def strip_layer(name):
    """The layer a motion strip plays in, from its name ("03 run seg0012", "01 walk ->
    run", "04 Chair.10 16_06 0deg"): walk, run, transition or clip."""
    label = name.split(" ", 1)[1]
    if "->" in label:
        return "transition"
    first = label.split(" ", 1)[0]
    return first if first in ("walk", "run") else "clip"


def source_skate(addon_module, mocap_dir, layer):
    """Foot skate (cm/s) of the clip a layer's straight cycles come from: 16_15 for the
    walk, 16_35 (retargeted onto the walk's skeleton, as baked) for the run."""
    from importlib import import_module
    from types import SimpleNamespace

    mp = SimpleNamespace(
        **{
            n: import_module(f"{addon_module.__name__}.motion_patches.{sub}.{n}")
            for n, sub in (
                ("bvh", "kinematics"),
                ("contacts", "kinematics"),
                ("metrics", "quality"),
                ("retarget", "kinematics"),
            )
        }
    )
    walk = mp.bvh.read(mocap_dir / "cmu" / "16_15.bvh")
    src = walk
    if layer == "run":
        run = mp.bvh.read(mocap_dir / "cmu16max" / "16_35.bvh")
        src = mp.retarget.rig_map(run.skeleton, walk.skeleton, label="clip").clip(run)
    planted, _, _ = mp.contacts.foot_contacts(src)
    fj = mp.contacts.foot_joints(src.skeleton)
    return mp.metrics.foot_skate(src.joint_positions()[:, fj], src.fps, planted)["mean_cm_per_s"]


def test_auto_walks_runs_hurdles_and_walks_back_to_a_walking_goal(
    layers_blend, addon_module, mocap_dir
):
    """Issue 19's Must show: walking round the chair line is long, the run-layer hurdle
    short; with gait "auto" the plan walks, blends into a run, hurdles, blends back to a
    walk and walks to the goal. Evaluated through the depsgraph: no hips step over 1.5x
    the per-frame speed of the strip's gait, no pop at a transition (largest joint step
    at its joins below the 99th percentile of steps inside strips), foot skate of each
    layer (foot lock on, as planned by default) within 1.25x its source clip's."""
    api = addon_module.api
    nla = addon_module.adapter.nla
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    walker = bpy.data.objects["Walker"]
    walk = plan(api, "walk")
    assert walk.stats["traversals_used"] == 0  # the jump is a run clip only
    walk_hips = evaluated(api, walker)
    i = int(np.argmax(walk_hips[:, 0] >= LINE_X))
    assert abs(walk_hips[i, 1]) > 5.0  # round the end of the line
    assert "foot_skate_by_layer" not in api.analyse(bpy.context, walker)  # one layer
    res = plan(api, "auto")
    costs = res.stats["layers"]
    print("auto:", costs, res.pieces)
    assert res.stats["layer"] == "walk+run"
    assert costs["walk+run"] < costs["walk"] and costs["walk+run"] < costs["run"]
    assert costs["walk"] == pytest.approx(walk.stats["cost_shortened"], abs=1e-3)
    assert res.stats["traversals_used"] == 1
    # One motion track: walk strips, a blend, run strips with the jump, a blend, walk.
    track = walker.animation_data.nla_tracks[nla.TRACK_MOTION]
    every = sorted(track.strips, key=lambda st: st.frame_start)
    strips = [st for st in every if nla.PART not in st.name]  # a piece's first strip
    assert [st.name for st in strips] == [s["name"] for s in res.strips]
    seq = [strip_layer(st.name) for st in strips]
    collapsed = [x for k, x in enumerate(seq) if k == 0 or x != seq[k - 1]]
    assert collapsed == ["walk", "transition", "run", "clip", "run", "transition", "walk"]
    assert [st.name.split(" ", 1)[1] for st in strips if "->" in st.name] == [
        "walk -> run",
        "run -> walk",
    ]
    for a, b in zip(every[:-1], every[1:]):
        assert b.frame_start == pytest.approx(a.frame_end)  # end to end, no gap
    for st, layer in zip(strips, seq):
        if layer in ("walk", "run") and "seg" in st.name and "[" not in st.name:
            # that layer's shared action (a straight segment's: its straight loop's)
            assert st.action.name.startswith((f"MP {layer} seg", f"MP {layer} loop"))
    assert any("16_06" in st.name for st in strips)
    f = api.analyse(bpy.context, walker)
    assert f["frames_root_inside_obstacle"] == 0
    assert f["goal_root_position_error_cm"] < 10
    # Through the depsgraph, every frame.
    meta, arrays = api.load_plan_record(walker)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    bones = [meta["root_name"], *meta["foot_names"]]
    evaluate = addon_module.adapter.evaluate
    pos, ground, rot, _ = evaluate.sample_armature(bpy.context, walker, frames, bones)
    hips, feet = pos[:, 0, :2], pos[:, 1:]
    gaits = {
        n: addon_module.adapter.storage.load_patch(bpy.context.scene, n).gait
        for n in ("walk", "run")
    }
    per_frame = {n: api.layers.speed(g) / 30.0 for n, g in gaits.items()}
    # each piece's frames (a piece played by the loop action too spans several strips)
    span = [(int(s["start"]) - frames[0], int(s["end"]) - frames[0]) for s in res.strips]
    step = np.linalg.norm(np.diff(hips, axis=0), axis=1)  # step k: frame k -> k + 1
    worst = {}
    for (a, b), layer in zip(span, seq):
        gait = "walk" if layer == "walk" else "run"
        s = step[a:b].max()
        worst[gait] = max(worst.get(gait, 0.0), s / per_frame[gait])
        assert s < 1.5 * per_frame[gait], (layer, a, b, s)
    # The object's root track (one action for the whole plan) runs on across the joins.
    ground_step = np.linalg.norm(np.diff(ground[:, :2], axis=0), axis=1)
    assert ground_step.max() < 1.5 * per_frame["run"]
    q = rot / np.linalg.norm(rot, axis=-1, keepdims=True)
    dots = np.abs((q[1:] * q[:-1]).sum(axis=-1)).clip(0, 1)
    jstep = np.degrees(2 * np.arccos(dots)).max(axis=1)  # largest joint step per frame step
    joins = [a for a, _ in span[1:]]
    near_join = np.zeros(jstep.size, bool)
    for j in joins:
        near_join[max(j - 1, 0) : j + 1] = True
    p99 = np.percentile(jstep[~near_join], 99)
    at_transitions = [
        jstep[max(j - 1, 0) : j + 1].max()
        for k, j in enumerate(joins, start=1)
        if seq[k] == "transition" or seq[k - 1] == "transition"
    ]
    assert len(at_transitions) == 4
    # Foot skate per layer (its strips' frames; blends and the jump counted in neither).
    planted = np.asarray(arrays["contacts"], bool)
    skate = {}
    for layer in ("walk", "run"):
        mine = np.zeros(frames.size, bool)
        for (a, b), lay in zip(span, seq):
            if lay == layer:
                mine[a : b + 1] = True
        got = api.metrics.foot_skate(feet, 30.0, planted & mine[:, None])
        skate[layer] = (got["mean_cm_per_s"], source_skate(addon_module, mocap_dir, layer))
        assert got["planted_steps"] > 20
        # Analyse reports the same, from the plan record's layer of each strip.
        assert f["foot_skate_by_layer"][layer]["mean_cm_per_s"] == pytest.approx(
            got["mean_cm_per_s"], abs=1e-9
        )
    assert set(f["foot_skate_by_layer"]) == {"walk", "run"}
    print(
        f"hips step / gait pace per frame: worst walk {worst['walk']:.2f}, run "
        f"{worst['run']:.2f}; joint step at the transitions "
        f"{', '.join(f'{v:.1f}' for v in at_transitions)} deg, p99 inside strips {p99:.1f} "
        f"deg; foot skate (cm/s, planned vs source clip): "
        + ", ".join(f"{k} {v[0]:.1f} vs {v[1]:.1f}" for k, v in skate.items())
    )
    assert max(at_transitions) < p99
    for layer, (planned, source) in skate.items():
        assert planned <= 1.25 * source, layer
    assert res.frame_end - res.frame_start < walk.frame_end - walk.frame_start


def test_on_open_ground_auto_walks(layers_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    bpy.data.objects["Goal"].location = (1.0, -9.0, 0.0)  # away from the chairs
    bpy.data.objects["Goal"].rotation_euler = (0, 0, 0)  # facing -Y
    res = plan(api, "auto")
    assert res.stats["layer"] == "walk"
    assert res.stats["layers"]["walk"] < res.stats["layers"]["run"]
    # Nothing to run for: no plan that changes gait is offered, and the plan says why.
    assert "walk+run" not in res.stats["layers"]
    assert "takes no traversal" in res.stats["gait_change"]
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
    assert code == 0 and doc["layer"] == "walk+run"
    assert set(doc["layer_costs"]) == {"walk", "run", "walk+run"}
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    code = cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--gait", "swim"])
    err = capsys.readouterr().err
    assert code != 0 and "no locomotion patch of layer 'swim'" in err
    assert "motion_patches_plan" not in bpy.data.objects["Walker"]


def test_with_props_that_move_auto_keeps_one_layer_and_says_why(layers_blend, addon_module):
    """Props that move are avoided after planning, leg by leg of one layer's plan (issue
    17); a plan that changes gait is not offered then, and the plan says so."""
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(12.0, -8.0, 0.5))
    cart = bpy.context.object
    cart.name = "Cart"
    for f, y in ((1, -8.0), (200, -7.0)):  # creeping along far from the way
        cart.location = (12.0, y, 0.5)
        cart.keyframe_insert("location", frame=f)
    res = plan(api, "auto")
    assert res.stats["layer"] in ("walk", "run")
    assert "walk+run" not in res.stats["layers"]
    assert res.stats["gait_change"] == "not offered with props that move"


def test_the_scene_gait_choice_is_the_plans_unless_one_is_given(layers_blend, addon_module):
    """The Planning panel's Gait: Run plans in the run layer, Automatic picks the gait
    change on the chair line, Active Patch the active patch; ``gait=`` given beats it."""
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(layers_blend))
    scene = bpy.context.scene
    assert scene.motion_patches.gait == "ACTIVE"
    active = plan(api, None)
    assert "layers" not in active.stats  # one patch, no layers compared
    scene.motion_patches.gait = "RUN"
    assert plan(api, None).stats["layer"] == "run"
    assert plan(api, "walk").stats["layer"] == "walk"  # given beats the scene's
    scene.motion_patches.gait = "AUTO"
    auto = plan(api, None)
    assert "walk+run" in auto.stats["layers"]
