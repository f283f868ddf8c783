# SPDX-License-Identifier: GPL-3.0-or-later
"""Object patches inside Blender: tag low hurdles with the real CMU jump (16_06, a standing
broad jump, clears about 0.18 m over them), hurdle or walk around; a prop the jump does not
clear is walked around."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, prop_box, walker_from

HURDLE = (0.4, 0.44, 0.15)  # a chair's footprint, 15 cm high: what 16_06 clears


@pytest.fixture(scope="module")
def chairs_blend(addon_module, mocap_dir, tmp_path_factory):
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    cmu = mocap_dir / "cmu"
    arm, acts = api.import_mocap(
        [
            cmu / "16_15.bvh",
            cmu / "16_18.bvh",
            cmu / "16_06.bvh",
            cmu / "13_05.bvh",
            cmu / "13_05_standup.bvh",
        ],
        name="Source",
    )
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    for k, y in enumerate(np.linspace(-2.5, 2.5, 11)):
        ob = prop_box(f"Hurdle.{k:02d}", 5.0, y, size=HURDLE)
        bpy.context.view_layer.objects.active = ob
        assert bpy.ops.motion_patches.tag_object_patch(
            action="16_06", kind="TRAVERSAL", effort=8.0
        ) == {"FINISHED"}
    walker = walker_from(arm, location=(1.0, 0.3, 0))
    walker.rotation_euler = (0, 0, np.pi / 2)  # the rig's rest faces -Y: face +X
    scene.motion_patches.goal = empty("Goal", 9.0, 0.3, 0.0)
    path = tmp_path_factory.mktemp("chairs") / "chairs.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def plan(alpha, beta, gamma, stitching="DYNAMIC"):
    scene = bpy.context.scene
    s = scene.motion_patches
    s.alpha, s.beta, s.gamma, s.stitching = alpha, beta, gamma, stitching
    walker = bpy.data.objects["Walker"]
    bpy.context.view_layer.objects.active = walker
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    return walker


def strip_names(walker):
    return [s.name for s in walker.animation_data.nla_tracks["MP motion"].strips]


def test_hurried_character_hurdles_a_chair(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    walker = plan(4.0, 0.5, 0.1)
    names = strip_names(walker)
    assert any("16_06" in n for n in names), names
    f = addon_module.api.analyse(bpy.context, walker)
    assert f["traversals"] == 1
    assert f["frames_root_inside_obstacle"] == 0  # outside the jump, never inside a hurdle
    assert f["frames_body_inside_prop"] == 0  # and over it no bone sinks into it
    assert f["goal_root_position_error_cm"] < 10 and f["goal_heading_error_deg"] < 10
    assert f["root_from_plan_cm"]["max"] < 5


def test_a_jump_that_does_not_clear_its_prop_is_not_planned_over_it(
    chairs_blend, addon_module, capfd
):
    """A 1 x 3 x 0.5 m box tagged with 16_06: the tag warns naming both heights, and even a
    hurried walker (who hurdles the low ones) walks round it: no bone enters the box."""
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    for ob in [o for o in bpy.data.objects if o.name.startswith("Hurdle.")]:
        bpy.data.objects.remove(ob)
    box = prop_box("Box", 5.0, 0.3, size=(1.0, 3.0, 0.5))
    notes = []
    api.tag_object_patch(box, [(bpy.data.actions["16_06"], "TRAVERSAL", 8.0, 10.0)], notes=notes)
    assert len(notes) == 1 and "'Box', which is 0.50 m high" in notes[0], notes
    clears = float(notes[0].split(" clears ")[1].split(" m")[0])
    assert 0.0 < clears < 0.5
    capfd.readouterr()
    walker = plan(4.0, 0.5, 0.1)
    assert not any("16_06" in n for n in strip_names(walker))
    # Plan Path's report: the result first, and why it walked round (what the status bar shows)
    out = capfd.readouterr().out
    assert "Planned " in out and "(16_06 clears " in out and "'Box', which is 0.50 m high" in out
    rec = api.load_plan_record(walker)[0]
    f = api.analyse(bpy.context, walker)
    assert f["traversals"] == 0 and f["frames_body_inside_prop"] == 0
    res = api.plan_path(bpy.context.scene, walker, None, alpha=4.0, beta=0.5, gamma=0.1)
    assert any("16_06 clears" in n and "'Box'" in n for n in res.stats["traversals_too_low"])
    assert rec["frame_start"] == res.frame_start


def test_unhurried_character_walks_around(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    walker = plan(0.3, 0.1, 3.0)
    assert not any("16_06" in n for n in strip_names(walker))
    f = addon_module.api.analyse(bpy.context, walker)
    assert f["traversals"] == 0 and f["frames_root_inside_obstacle"] == 0


def test_static_stitching_finds_the_same_plan(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    dynamic = strip_names(plan(4.0, 0.5, 0.1, "DYNAMIC"))
    static = strip_names(plan(4.0, 0.5, 0.1, "STATIC"))
    assert dynamic == static


def user_notes_track(walker):
    """The animator's own animation on the walker: an action keying a custom property
    (so it does not move the rig) on an NLA track of their own, no active action."""
    walker["notes"] = 0.0
    walker.keyframe_insert('["notes"]', frame=1)
    walker["notes"] = 1.0
    walker.keyframe_insert('["notes"]', frame=40)
    ad = walker.animation_data
    action, slot = ad.action, ad.action_slot
    action.name = "My notes"
    track = ad.nla_tracks.new()
    track.name = "My notes track"
    strip = track.strips.new("My notes strip", 1, action)
    strip.action_slot = slot
    ad.action = None
    return action


def user_animation(walker):
    """Everything of the user's own tracks and actions an edit could change."""
    tracks = [
        (t.name, t.mute, [(s.name, s.frame_start, s.frame_end, s.action.name) for s in t.strips])
        for t in walker.animation_data.nla_tracks
        if not t.name.startswith("MP ")
    ]
    action = bpy.data.actions["My notes"]
    keys = [
        (fc.data_path, [tuple(k.co) for k in fc.keyframe_points])
        for fc in action.layers[0].strips[0].channelbags[0].fcurves
    ]
    return tracks, keys


def evaluated_root(api, walker):
    """(F, 3) world position of the hips over the last plan's frames, as Blender plays
    them (depsgraph-evaluated NLA)."""
    from importlib import import_module

    evaluate = import_module(api.__name__.rpartition(".")[0] + ".adapter.evaluate")
    meta, _ = api.load_plan_record(walker)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos, _, _, _ = evaluate.sample_armature(bpy.context, walker, frames, [meta["root_name"]])
    return pos[:, 0]


def crossing_y(root, x=5.0):
    """y of the hips where they first pass the chair line's x."""
    i = int(np.argmax(root[:, 0] >= x))
    assert root[i, 0] >= x, "the hips never reach the chair line"
    return float(root[i, 1])


def test_moving_chairs_and_re_planning_changes_the_path(chairs_blend, addon_module):
    """An animator sees the hurried walker hurdle a chair, slides that chair and its
    neighbours to the end of the row, re-plans: the walker now walks through the gap
    (no jump, another route, never inside a chair) and their own animation is intact."""
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    api = addon_module.api
    walker = bpy.data.objects["Walker"]
    user_notes_track(walker)
    users_before = user_animation(walker)
    plan(4.0, 0.5, 0.1)
    jump = [n for n in strip_names(walker) if "16_06" in n]
    assert len(jump) == 1, strip_names(walker)
    hurdled = next(
        ob for ob in bpy.data.objects if ob.name.startswith("Hurdle.") and ob.name in jump[0]
    )
    before = evaluated_root(api, walker)
    f = api.analyse(bpy.context, walker)
    assert f["traversals"] == 1 and f["frames_root_inside_obstacle"] == 0

    # Clear a passage around the walker's line: the chairs between y = 0 and 1.5 (the
    # hurdled one among them) go to the north end of the row.
    moved = [
        ob
        for ob in bpy.data.objects
        if ob.name.startswith("Hurdle.") and -0.1 < ob.location.y < 1.6
    ]
    assert hurdled in moved and len(moved) == 4
    for k, ob in enumerate(moved):
        ob.location = (5.0, 3.0 + 0.5 * k, ob.location.z)
    plan(4.0, 0.5, 0.1)
    after = evaluated_root(api, walker)
    assert not any("16_06" in n for n in strip_names(walker)), strip_names(walker)
    f = api.analyse(bpy.context, walker)
    assert f["traversals"] == 0
    assert f["frames_root_inside_obstacle"] == 0  # against the chairs where they are now
    assert f["goal_root_position_error_cm"] < 10 and f["root_from_plan_cm"]["max"] < 5
    meta, _ = api.load_plan_record(walker)
    for ob in moved:
        assert np.allclose(np.mean(meta["obstacles"][ob.name], axis=0), ob.location[:2], atol=0.01)

    # What an animator sees: the hips no longer rise into a jump, and the walker crosses
    # the row through the gap (between the remaining chairs at y = -0.5 and 2.0, grown
    # by the footprint and the radius), well away from where it jumped.
    assert after[:, 2].max() < before[:, 2].max() - 0.1  # the jump lifted the hips 0.24 m
    y0, y1 = crossing_y(before), crossing_y(after)
    assert -0.03 < y1 < 1.53 and abs(y1 - y0) > 0.3, (y0, y1)
    assert len(after) < len(before)  # no take-off and landing: a shorter walk

    # The user's own track and action are untouched; the add-on's tracks were replaced.
    assert user_animation(walker) == users_before
    names = [t.name for t in walker.animation_data.nla_tracks]
    assert names.count("MP motion") == 1 and names.count("MP root") == 1
    assert walker.animation_data.action is None


def test_tagging_bad_input_reports_and_changes_nothing(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    api = addon_module.api
    # A clip whose root never moves (only a rotation key) cannot be a traversal.
    still = bpy.data.actions.new("still")
    slot = still.slots.new(id_type="OBJECT", name="still")
    bag = still.layers.new("L").strips.new(type="KEYFRAME").channelbag(slot, ensure=True)
    fc = bag.fcurves.new('pose.bones["Hips"].location', index=0)
    fc.keyframe_points.insert(1, 0.0)
    fc.keyframe_points.insert(30, 0.0)
    target = prop_box("Extra", 12.0, 0.0)
    with pytest.raises(api.MotionPatchesError, match="root"):
        api.tag_object_patch(target, [(still, "TRAVERSAL", 8.0, 10.0)])
    assert not target.motion_patch.enabled and len(target.motion_patch.clips) == 0
    # A mesh without geometry has no footprint.
    me = bpy.data.meshes.new("nothing")
    hollow = bpy.data.objects.new("Hollow", me)
    bpy.context.scene.collection.objects.link(hollow)
    with pytest.raises(api.MotionPatchesError, match="footprint"):
        api.tag_object_patch(hollow, [(bpy.data.actions["16_06"], "TRAVERSAL", 8.0, 10.0)])
    assert not hollow.motion_patch.enabled


def test_import_retargets_another_subjects_clip(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    sit = bpy.data.actions["13_05"]
    assert "hip height" in sit["motion_patches_retargeted"]
    assert "13_05 (subject skeleton)" not in bpy.data.actions


def two_chairs(chairs_blend, api):
    """The chairs scene opened, with chair A (1, -4.5) tagged with the stand-up clip and
    chair B (9, -4), turned, with the sit-down clip: (A, B, the walker)."""
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    a, b = prop_box("Chair A", 1.0, -4.5), prop_box("Chair B", 9.0, -4.0)
    b.rotation_euler = (0, 0, 2.0)
    api.tag_object_patch(a, [(bpy.data.actions["13_05_standup"], "INTERACTION", 2.0, 0.0)])
    api.tag_object_patch(b, [(bpy.data.actions["13_05"], "INTERACTION", 2.0, 0.0)])
    return a, b, bpy.data.objects["Walker"]


def seated_on_a_then_b(api, walker, why=""):
    """The walker's evaluated hips seated on chair A on its plan's first frame and on chair
    B (:func:`two_chairs`) on its last."""
    meta, _ = api.load_plan_record(walker)
    for frame, (x, y) in ((meta["frame_start"], (1.0, -4.5)), (meta["frame_end"], (9.0, -4.0))):
        bpy.context.scene.frame_set(frame)
        hips = walker.matrix_world @ walker.pose.bones["Hips"].head
        assert hips.z < 0.75 and np.hypot(hips.x - x, hips.y - y) < 0.3, (why, frame, hips)


def test_stand_up_walk_and_sit_down(chairs_blend, addon_module):
    api = addon_module.api
    a, b, walker = two_chairs(chairs_blend, api)
    res = api.plan_path(bpy.context.scene, walker, b, start_prop=a, frame_start=1)
    names = [s.name for s in walker.animation_data.nla_tracks["MP motion"].strips]
    assert "13_05_standup" in names[0] and "13_05" in names[-1], names
    f = api.analyse(bpy.context, walker)
    assert f["frames_root_inside_obstacle"] == 0
    scene = bpy.context.scene
    scene.frame_set(res.frame_end)
    hips = walker.matrix_world @ walker.pose.bones["Hips"].head
    assert hips.z < 0.75 and np.hypot(hips.x - 9.0, hips.y + 4.0) < 0.3  # seated on chair B
    scene.frame_set(res.frame_start)
    hips = walker.matrix_world @ walker.pose.bones["Hips"].head
    assert hips.z < 0.75 and np.hypot(hips.x - 1.0, hips.y + 4.5) < 0.3  # seated on chair A


def test_the_button_reads_the_characters_start_prop_and_own_goal(chairs_blend, addon_module):
    """The Plan Path button with the walker's Start Prop and Own Goal set in the Planning
    panel (no goal given to it, the scene's elsewhere): it stands up from chair A and sits
    down on chair B, on every version (from Blender 5.0 a character's settings are no
    longer among its custom properties, where they used to be looked for)."""
    api = addon_module.api
    a, b, walker = two_chairs(chairs_blend, api)
    walker.motion_patches_character.start_prop = a
    walker.motion_patches_character.goal = b
    for ob in bpy.context.scene.objects:
        ob.select_set(ob == walker)
    bpy.context.view_layer.objects.active = walker
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    seated_on_a_then_b(api, walker)


@pytest.mark.parametrize("door", ["plan cli", "crowd button", "crowd cli", "crowd api"])
def test_every_door_starts_a_character_on_its_start_prop(chairs_blend, mp, capsys, door):
    """The walker's Start Prop and Own Goal set in the Planning panel, nothing else given:
    the ``plan`` command, the Plan Crowd button, the ``crowd`` command and
    ``api.plan_crowd(scene, api.crowd_members(...))`` all stand it up from chair A and sit it
    down on chair B, as Plan Path does (read from the evaluated hips)."""
    api = mp.api
    a, b, walker = two_chairs(chairs_blend, api)
    walker.motion_patches_character.start_prop = a
    walker.motion_patches_character.goal = b
    scene = bpy.context.scene
    if door == "plan cli":
        assert mp.cli.main(["plan", "--character", "Walker", "--json"]) == 0
    elif door == "crowd button":
        for ob in scene.objects:
            ob.select_set(ob == walker)
        bpy.context.view_layer.objects.active = walker
        assert bpy.ops.motion_patches.plan_crowd() == {"FINISHED"}
    elif door == "crowd cli":
        assert mp.cli.main(["crowd", "--character", "Walker", "--json"]) == 0
    else:
        assert api.crowd_members(scene, [walker]) == [(walker, b, {"start_prop": a})]
        assert not api.plan_crowd(scene, api.crowd_members(scene, [walker])).failed
    capsys.readouterr()
    seated_on_a_then_b(api, walker, door)


def test_a_goal_prop_without_a_sit_clip_is_refused(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    api = addon_module.api
    walker = bpy.data.objects["Walker"]
    tracks = [t.name for t in walker.animation_data.nla_tracks] if walker.animation_data else []
    with pytest.raises(api.MotionPatchesError, match="sit-down"):
        api.plan_path(bpy.context.scene, walker, bpy.data.objects["Hurdle.03"])
    # A goal position inside the chair (not the chair itself): refused the same way, as
    # bad input, not as "no path".
    x, y = bpy.data.objects["Hurdle.03"].matrix_world.translation[:2]
    with pytest.raises(
        api.MotionPatchesError,
        match="inside the object patch 'Hurdle.03', which has no interaction",
    ) as err:
        api.plan_path(bpy.context.scene, walker, (x, y, 0.0))
    assert not isinstance(err.value, api.PathNotFound)
    now = [t.name for t in walker.animation_data.nla_tracks] if walker.animation_data else []
    assert now == tracks


def test_layout_check_sees_traversals_and_can_forbid_them(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    check = addon_module.api.check_layout
    spec = {
        "alpha": 4.0,
        "beta": 0.5,
        "gamma": 0.1,
        "pairs": [
            {"character": "Walker", "goal": "Goal"},
            {"character": "Walker", "goal": "Goal", "allow_traversal": False},
        ],
    }
    hurdle, around = check(bpy.context.scene, spec)
    assert hurdle["reachable"] and hurdle["traversals"] == 1 and hurdle["passed"]
    assert around["reachable"] and around["traversals"] == 0 and around["passed"]
    assert around["length_m"] > hurdle["length_m"]
    ad = bpy.data.objects["Walker"].animation_data  # a check writes nothing
    assert ad is None or "MP motion" not in [t.name for t in ad.nla_tracks]


def test_overlay_buffers_and_handler_lifecycle(chairs_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(chairs_blend))
    overlay = addon_module.panels.overlay
    walker = plan(4.0, 0.5, 0.1)
    buf = overlay.buffers(bpy.context.scene)
    lines, colours = buf["lines"]
    assert lines.shape[1] == 3 and colours.shape == (lines.shape[0], 4) and len(lines) % 2 == 0
    red = np.all(np.isclose(colours, overlay.COLOURS["traversal"][0]), axis=1)
    assert red.any()  # the hurdle is drawn in the traversal colour
    strips = walker.animation_data.nla_tracks["MP motion"].strips
    pieces = [st for st in strips if addon_module.adapter.nla.PART not in st.name]
    assert len(buf["points"][0]) == len(pieces)  # one stitch point per piece's start
    assert len(buf["tris"][0]) > 0 and len(buf["tris"][0]) % 6 == 0  # occluded cells
    s = bpy.context.scene.motion_patches
    s.show_overlay = True
    assert overlay.is_enabled()
    s.show_overlay = False
    assert not overlay.is_enabled()
    s.show_overlay = True
    addon_utils = __import__("addon_utils")
    name = addon_module.__name__
    addon_utils.disable(name, default_set=True)
    try:
        assert not overlay.is_enabled()  # unregister removed the handler
    finally:
        addon_utils.enable(name, default_set=True)


def test_a_plan_and_the_overlay_leave_untagged_props_as_they_were(walk_blend, mp):
    """Planning round an untagged box, a crowd of one, and the overlay's drawing ask whether
    each mesh is an object patch, and whether the rig has a bone map, without adding those
    settings to it (reading them used to store an empty set on every mesh and rig looked at:
    on Blender 4.5 among its custom properties, which the FBX and glTF exporters write
    out)."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    src = scene.motion_patches.source_armature
    walker = walker_from(src, "Walker", (0.0, 0.0, 0.0))
    box = prop_box("Box", 3.0, 0.0, (1.0, 1.0, 1.0))
    goal = empty("Goal", 6.0, 0.0, 0.0)
    keys, rig_keys = list(box.keys()), list(walker.data.keys())
    had_map = walker.data.is_property_set("motion_patches_rig")
    walker.motion_patches_character.goal = goal
    mp.api.plan_path(scene, walker, None, frame_start=1)
    mp.api.plan_crowd(scene, mp.api.crowd_members(scene, [walker]))
    overlay = mp.panels.overlay
    overlay.buffers(scene, bpy.context.evaluated_depsgraph_get())
    overlay.plan_buffers(scene)
    overlay._markers_key(scene)
    assert not box.is_property_set("motion_patch")
    assert list(box.keys()) == keys
    # nor a bone map on the walker's rig, which plays the patch as it is
    assert walker.data.is_property_set("motion_patches_rig") == had_map
    assert list(walker.data.keys()) == rig_keys


def test_a_crowd_member_whose_start_prop_cannot_seat_it_is_named(chairs_blend, mp):
    """A crowd where one walker's Start Prop has no stand-up clip: refused before anything
    is written, naming the walker and the prop (a crowd has many Start Props)."""
    api = mp.api
    a, b, walker = two_chairs(chairs_blend, api)
    walker.motion_patches_character.start_prop = b  # chair B only sits down
    walker.motion_patches_character.goal = empty("Goal W", 5.0, 2.0, 0.0)
    with pytest.raises(api.MotionPatchesError) as err:
        api.plan_crowd(bpy.context.scene, api.crowd_members(bpy.context.scene, [walker]))
    assert str(err.value) == "'Walker': 'Chair B' has no stand-up interaction clip"
    assert walker.animation_data is None
