# SPDX-License-Identifier: GPL-3.0-or-later
"""The animator's side of the add-on: sidebar panels, lists, preferences, undo, crowd
planning from the selection, and the overlay's markers where props' clips start and end.

Blender runs here as a module without a window, so panels cannot be drawn on screen;
they are drawn into a recording layout that checks every property, operator, list and
icon they name exists. Undo is Blender's real memfile undo: ``ed.undo_push`` / ``ed.undo``
/ ``ed.redo`` work headless in bpy 4.5 and 5.0; an operator called from Python pushes its
own undo step only when called with ``undo=True`` (the second positional argument of
``bpy.ops`` calls), which then goes through the same ``bl_options`` check as a button.
"""

import json
from types import SimpleNamespace

import bpy
import numpy as np
import pytest

from scene_helpers import empty, prop_box, walker_from

ICONS = set(bpy.types.UILayout.bl_rna.functions["label"].parameters["icon"].enum_items.keys())


@pytest.fixture(scope="module")
def ui_blend(addon_module, mocap_dir, tmp_path_factory):
    """Walk patch baked through the scene settings (turn list filled with its operator),
    one box prop tagged with the real CMU jump 16_06 as a traversal, two walkers facing
    +X, the scene goal 8 m ahead of the first and an own goal for the second."""
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    cmu = mocap_dir / "cmu"
    arm, acts = api.import_mocap(
        [cmu / "16_15.bvh", cmu / "16_18.bvh", cmu / "16_06.bvh"], name="Source"
    )
    s = scene.motion_patches
    s.source_armature, s.straight_action = arm, acts[0]
    assert bpy.ops.motion_patches.turn_add() == {"FINISHED"}
    s.turn_actions[s.active_turn_index].action = acts[1]
    assert bpy.ops.motion_patches.bake_locomotion_patch(layer="walk") == {"FINISHED"}
    # A chair-sized footprint 15 cm high: the standing jump 16_06 clears it.
    bpy.context.view_layer.objects.active = prop_box("Chair", 4.0, 0.3, size=(0.4, 0.44, 0.15))
    assert bpy.ops.motion_patches.tag_object_patch(action="16_06", kind="TRAVERSAL") == {"FINISHED"}
    for name, y in (("Walker", 0.3), ("Walker.B", -2.5)):
        walker = walker_from(arm, name=name, location=(1.0, y, 0))
        walker.rotation_euler = (0, 0, np.pi / 2)  # the rig's rest faces -Y: face +X
    s.goal = empty("Goal", 8.0, 0.3, 0.0)
    bpy.data.objects["Walker.B"].motion_patches_character.goal = empty("Goal B", 7.0, -3.5, 0.0)
    path = tmp_path_factory.mktemp("ui") / "ui.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


@pytest.fixture
def scene(ui_blend):
    bpy.ops.wm.open_mainfile(filepath=str(ui_blend))
    return bpy.context.scene


def activate(*names):
    """Select the named objects, the first one active."""
    for ob in bpy.context.view_layer.objects:
        ob.select_set(ob.name in names)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]]


# --- panels ----------------------------------------------------------------------------------


class Layout:
    """A stand-in for ``UILayout`` that records what is drawn and fails on anything a real
    layout would reject or show as missing: unknown properties, operators, lists, icons."""

    def __init__(self, log):
        self.log = log

    def _icon(self, kw):
        assert kw.get("icon", "NONE") in ICONS, f"unknown icon {kw['icon']}"

    def row(self, *args, **kw):
        return Layout(self.log)

    column = box = split = row

    def label(self, text="", **kw):
        self._icon(kw)
        self.log.append(("label", text))

    def prop(self, data, name, **kw):
        self._icon(kw)
        assert name in data.bl_rna.properties, f"{data.bl_rna.identifier} has no '{name}'"
        self.log.append(("prop", name))

    def operator(self, idname, **kw):
        self._icon(kw)
        module, name = idname.split(".")
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # KeyError when unregistered
        self.log.append(("operator", idname))

    def template_list(self, listtype, list_id, data, items, active_data, active_prop, **kw):
        cls = getattr(bpy.types, listtype)  # AttributeError when the list is not registered
        assert items in data.bl_rna.properties and active_prop in active_data.bl_rna.properties
        for i, item in enumerate(getattr(data, items)):
            cls.draw_item(
                None, bpy.context, Layout(self.log), data, item, 0, active_data, active_prop, i
            )
        self.log.append(("list", listtype))


def draw_panels(addon_module):
    """{panel label: [what it drew]} of every sidebar panel whose poll passes."""
    out = {}
    for cls in addon_module.panels.classes:
        if not issubclass(cls, bpy.types.Panel):
            continue
        assert cls.bl_category == "Motion Patches" and cls.bl_space_type == "VIEW_3D"
        if hasattr(cls, "poll") and not cls.poll(bpy.context):
            continue
        log = []
        cls.draw(SimpleNamespace(layout=Layout(log)), bpy.context)
        out[cls.bl_label] = log
    return out


def test_sidebar_has_one_panel_per_concept(scene, addon_module):
    labels = [c.bl_label for c in addon_module.panels.classes if issubclass(c, bpy.types.Panel)]
    assert labels == ["Locomotion Patches", "Object Patch", "Planning", "Analysis", "Overlay"]
    activate("Walker")
    drawn = draw_panels(addon_module)
    assert "Object Patch" not in drawn  # only for a mesh
    loco = drawn["Locomotion Patches"]
    assert ("list", "MOTION_PATCHES_UL_actions") in loco
    assert ("list", "MOTION_PATCHES_UL_patches") in loco
    assert ("operator", "motion_patches.bake_locomotion_patch") in loco
    kept = json.loads(scene.motion_patches.patches["walk"].stats)["kept"]
    assert any(k == "label" and t.startswith(f"{kept} segments kept") for k, t in loco)
    plan = drawn["Planning"]
    for what in ("goal", "alpha", "beta", "gamma", "radius", "stitching"):
        assert ("prop", what) in plan
    for op in ("plan_path", "plan_crowd", "reset_planning"):
        assert ("operator", f"motion_patches.{op}") in plan
    assert plan.count(("prop", "goal")) == 2  # the scene's goal and the walker's own
    assert ("operator", "motion_patches.add_body") in plan  # the walker's proxy body
    assert ("prop", "show_overlay") in drawn["Overlay"]


def test_object_patch_panel_shows_clips_and_footprint(scene, addon_module):
    activate("Chair")
    drawn = draw_panels(addon_module)["Object Patch"]
    assert ("list", "MOTION_PATCHES_UL_clips") in drawn
    assert ("prop", "action") in drawn and ("prop", "kind") in drawn  # one row per clip
    # A 1 m cube scaled 0.4 x 0.44: 8 vertices, 0.176 m² on the ground.
    assert ("label", "8 vertices, footprint 0.18 m²") in drawn
    for op in ("tag_object_patch", "untag_object_patch", "clip_add", "clip_remove"):
        assert ("operator", f"motion_patches.{op}") in drawn


# --- lists, tagging --------------------------------------------------------------------------


def test_turn_list_add_and_remove(scene):
    s = scene.motion_patches
    assert len(s.turn_actions) == 1
    assert bpy.ops.motion_patches.turn_add() == {"FINISHED"}
    assert len(s.turn_actions) == 2 and s.active_turn_index == 1
    s.active_turn_index = 0
    assert bpy.ops.motion_patches.turn_remove() == {"FINISHED"}
    assert len(s.turn_actions) == 1 and s.turn_actions[0].action is None  # 16_18 row went
    assert bpy.ops.motion_patches.turn_remove() == {"FINISHED"}
    assert not bpy.ops.motion_patches.turn_remove.poll()  # nothing left to remove


def test_clip_list_then_tag_checks_and_keeps_the_clips(scene):
    box = prop_box("Crate", 12.0, 0.0)
    activate("Crate")
    assert bpy.ops.motion_patches.tag_object_patch.poll()
    with pytest.raises(RuntimeError, match="no clip"):
        bpy.ops.motion_patches.tag_object_patch()
    assert bpy.ops.motion_patches.clip_add() == {"FINISHED"}
    assert bpy.ops.motion_patches.clip_add() == {"FINISHED"}
    mp = box.motion_patch
    assert len(mp.clips) == 2 and mp.active_clip_index == 1
    assert bpy.ops.motion_patches.clip_remove() == {"FINISHED"}
    mp.clips[0].action, mp.clips[0].copy_step = bpy.data.actions["16_06"], 30.0
    assert bpy.ops.motion_patches.tag_object_patch() == {"FINISHED"}  # the list as it is
    assert mp.enabled and [(c.action.name, c.copy_step) for c in mp.clips] == [("16_06", 30.0)]
    assert bpy.ops.motion_patches.clip_add() == {"FINISHED"}  # a row left without an action
    assert bpy.ops.motion_patches.tag_object_patch() == {"FINISHED"}
    assert [c.action.name for c in mp.clips] == ["16_06"]  # is dropped by tagging
    assert bpy.ops.motion_patches.untag_object_patch() == {"FINISHED"} and not mp.enabled
    assert len(mp.clips) == 1  # untagging keeps the list


# --- preferences -----------------------------------------------------------------------------


@pytest.fixture
def prefs(addon_module_name):
    p = bpy.context.preferences.addons[addon_module_name].preferences
    keep = {
        n: getattr(p, n)
        for n in ("alpha", "beta", "gamma", "radius", "stitching", "cells", "nodes")
    }
    yield p
    for n, v in keep.items():
        setattr(p, n, v)


def test_reset_to_preferences_copies_the_defaults(scene, prefs):
    prefs.alpha, prefs.beta, prefs.gamma, prefs.radius = 2.5, 0.05, 3.0, 0.4
    prefs.stitching = "STATIC"
    s = scene.motion_patches
    assert (s.alpha, s.stitching) == (1.0, "DYNAMIC")
    assert bpy.ops.motion_patches.reset_planning() == {"FINISHED"}
    assert (s.alpha, s.beta, s.gamma, s.stitching) == pytest.approx((2.5, 0.05, 3.0, "STATIC"))
    assert s.radius == pytest.approx(0.4)


def test_bake_starts_from_the_preferred_patch_size(scene, prefs, addon_module):
    storage = addon_module.adapter.storage
    prefs.cells, prefs.nodes = 4, 4
    assert bpy.ops.motion_patches.bake_locomotion_patch(layer="small") == {"FINISHED"}
    patch = storage.load_patch(scene, "small")
    assert (patch.cells, patch.nodes) == (4, 4)
    # The new patch is the active row of the patch list, hence the one the planner uses;
    # selecting the walk row switches back.
    s = scene.motion_patches
    assert s.patches[s.active_patch_index].name == "small" and storage.load_patch(scene) is patch
    s.active_patch_index = s.patches.find("walk")
    assert storage.load_patch(scene).cells == 8
    # A size given by the caller wins over the preferences.
    assert bpy.ops.motion_patches.bake_locomotion_patch(layer="small", nodes=3) == {"FINISHED"}
    patch = addon_module.adapter.storage.load_patch(scene, "small")
    assert (patch.cells, patch.nodes) == (4, 3)


# --- undo ------------------------------------------------------------------------------------


def test_every_operator_is_undoable_and_registered(addon_module):
    for cls in addon_module.operators.classes:
        assert {"REGISTER", "UNDO"} <= cls.bl_options, cls.bl_idname
        assert cls.bl_idname.startswith("motion_patches.")


def nla_state(ob):
    """Everything of ``ob``'s animation a plan changes: tracks (mute, strips with frames
    and actions), the active action and its slot, and the plan record."""
    ad = ob.animation_data
    if ad is None:
        return None
    return {
        "action": ad.action and ad.action.name,
        "slot": ad.action_slot and ad.action_slot.identifier,
        "tracks": [
            (
                t.name,
                t.mute,
                [
                    (s.name, s.frame_start, s.frame_end, s.action and s.action.name)
                    for s in t.strips
                ],
            )
            for t in ad.nla_tracks
        ],
        "plan": ob.get("motion_patches_plan"),
    }


def evaluated_pose(name, frame, bones=None):
    """World head of every bone (or the named ones) of object ``name`` at ``frame``, as
    Blender plays it: the depsgraph-evaluated object and pose."""
    bpy.context.scene.frame_set(frame)
    ev = bpy.data.objects[name].evaluated_get(bpy.context.evaluated_depsgraph_get())
    mw = np.array(ev.matrix_world)
    pbs = ev.pose.bones if bones is None else [ev.pose.bones[b] for b in bones]
    return np.array([(mw @ np.append(pb.head, 1.0))[:3] for pb in pbs])


def test_undo_after_plan_restores_the_previous_nla_state(scene):
    """Plan through the operator as a button does (its own undo step), undo: the walker's
    tracks, active action and evaluated pose are as before; redo: the plan is back."""
    walker = bpy.data.objects["Walker"]
    ad = walker.animation_data_create()
    ad.action = bpy.data.actions["16_15"]  # the animator's own action, playing
    ad.action_slot = ad.action.slots[0]
    activate("Walker")
    scene.frame_set(1)
    before, pose_before = nla_state(walker), evaluated_pose("Walker", 40)
    scene.frame_set(1)
    bpy.ops.ed.undo_push(message="Before planning")
    assert bpy.ops.motion_patches.plan_path("EXEC_DEFAULT", True) == {"FINISHED"}
    planned, pose_planned = nla_state(bpy.data.objects["Walker"]), evaluated_pose("Walker", 40)
    assert planned["action"] is None and planned["plan"]
    assert [t[0] for t in planned["tracks"]][-3:] == ["MP motion", "MP root", "MP foot lock"]
    assert np.abs(pose_planned - pose_before).max() > 0.1  # the plan moves the rig

    assert bpy.ops.ed.undo() == {"FINISHED"}
    assert nla_state(bpy.data.objects["Walker"]) == before
    assert np.allclose(evaluated_pose("Walker", 40), pose_before, atol=1e-5)

    assert bpy.ops.ed.redo() == {"FINISHED"}  # the plan was its own undo step
    assert nla_state(bpy.data.objects["Walker"]) == planned
    assert np.allclose(evaluated_pose("Walker", 40), pose_planned, atol=1e-5)


# --- analysis --------------------------------------------------------------------------------


def test_analyse_keeps_the_figures_on_the_character(scene, addon_module):
    activate("Walker")
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    assert bpy.ops.motion_patches.analyse_motion() == {"FINISHED"}
    walker = bpy.data.objects["Walker"]
    figures = json.loads(walker["motion_patches_analysis"])
    assert figures["frames_root_inside_obstacle"] == 0
    assert figures["goal_root_position_error_cm"] < 10  # evaluated hips on the goal
    assert figures["foot_skate"]["mean_cm_per_frame"] < 1.0
    lines = [t for k, t in draw_panels(addon_module)["Analysis"] if k == "label"]
    sk = figures["foot_skate"]
    assert (
        f"Foot skate: {sk['mean_cm_per_frame']:.2f} cm/frame ({sk['mean_cm_per_s']:.1f} cm/s)"
    ) in lines
    assert "Frames inside props: root 0, body 0" in lines
    assert any(t.startswith("Boundary pop: ") for t in lines)
    activate("Walker.B")  # not analysed: the panel says what to do
    lines = [t for k, t in draw_panels(addon_module)["Analysis"] if k == "label"]
    assert lines == ["Select a planned character and analyse it"]


# --- crowd -----------------------------------------------------------------------------------


def test_plan_crowd_sends_each_selected_character_to_its_goal(scene, addon_module, monkeypatch):
    api = addon_module.api
    calls = []
    plan_crowd = api.plan_crowd

    def recording(scene, pairs, **kw):
        calls.append({"pairs": [(c.name, g.name) for c, g, _ in pairs], "progress": []})
        report = kw["progress"]
        kw["progress"] = lambda f: (calls[-1]["progress"].append(f), report(f))
        return plan_crowd(scene, pairs, **kw)

    monkeypatch.setattr(api, "plan_crowd", recording)
    activate("Walker.B", "Walker")
    assert bpy.ops.motion_patches.plan_crowd() == {"FINISHED"}
    assert calls[0]["pairs"] == [("Walker", "Goal"), ("Walker.B", "Goal B")]
    progress = calls[0]["progress"]
    assert progress[-1] == 1.0 and progress == sorted(progress)  # the progress bar moved on
    for name, goal in (("Walker", (8.0, 0.3)), ("Walker.B", (7.0, -3.5))):
        ob = bpy.data.objects[name]
        meta, _ = api.load_plan_record(ob)
        hips = evaluated_pose(name, meta["frame_end"], [meta["root_name"]])[0]
        assert np.hypot(hips[0] - goal[0], hips[1] - goal[1]) < 0.1, name
        assert api.analyse(bpy.context, ob)["frames_root_inside_obstacle"] == 0


def test_plan_crowd_names_a_character_without_a_goal(scene):
    scene.motion_patches.goal = None
    activate("Walker", "Walker.B")
    with pytest.raises(RuntimeError, match="'Walker' has no goal"):
        bpy.ops.motion_patches.plan_crowd()
    for name in ("Walker", "Walker.B"):
        assert bpy.data.objects[name].animation_data is None  # nothing was planned


# --- overlay ---------------------------------------------------------------------------------


def clip_ends(addon_module, scene):
    """(P, 3) world (x, y, heading) of the first and last ground frame of every clip of
    every tagged prop, entry then exit per clip, as the planner sees them."""
    api, storage = addon_module.api, addon_module.adapter.storage
    bpy.context.view_layer.update()
    props = api.object_patches(
        scene, bpy.context.evaluated_depsgraph_get(), storage.load_patch(scene)
    )
    return np.array(
        [
            g
            for p in props
            for c in p.clips
            for g in (p.world_clip(c).ground[0], p.world_clip(c).ground[-1])
        ]
    )


def markers(overlay, scene):
    bpy.context.view_layer.update()
    buf = overlay.buffers(scene, bpy.context.evaluated_depsgraph_get())
    return buf["markers"], buf["ticks"]


def test_overlay_marks_where_the_props_clips_start_and_end(scene, addon_module):
    overlay = addon_module.panels.overlay
    chair = bpy.data.objects["Chair"]
    (pos, col), (ticks, tcol) = markers(overlay, scene)
    ends = clip_ends(addon_module, scene)
    assert len(pos) == len(ends) >= 2 * 18  # copies every 10 degrees, some may be dropped
    assert np.allclose(pos[:, :2], ends[:, :2], atol=1e-4)
    assert np.allclose(col[0::2], overlay.ENTRY) and np.allclose(col[1::2], overlay.EXIT)
    # Each jump runs across the chair: entry and exit on opposite sides, its line passing
    # over the chair's centre, every end clear of the chair's 0.4 x 0.44 m top.
    c = np.array(chair.location[:2])
    entry, exit_ = pos[0::2, :2], pos[1::2, :2]
    for end in (entry, exit_):
        assert np.all(np.abs(end - c).max(axis=1) > 0.2)
    d = exit_ - entry
    t = np.einsum("ij,ij->i", c - entry, d) / np.einsum("ij,ij->i", d, d)
    assert np.all((t > 0.2) & (t < 0.8))
    v = c - entry
    miss = np.abs(d[:, 0] * v[:, 1] - d[:, 1] * v[:, 0]) / np.linalg.norm(d, axis=1)
    assert miss.max() < 0.3
    # A tick from every marker along the heading there.
    assert np.allclose(ticks[0::2], pos, atol=1e-6)
    step = ticks[1::2, :2] - ticks[0::2, :2]
    assert np.allclose(np.linalg.norm(step, axis=1), overlay.TICK, atol=1e-4)
    assert np.allclose(
        np.arctan2(step[:, 1], step[:, 0]),
        np.arctan2(np.sin(ends[:, 2]), np.cos(ends[:, 2])),
        atol=1e-3,
    )

    # Move and turn the chair: the markers go with it, rigidly.
    a = 0.7
    chair.location = (2.0, -3.0, chair.location.z)
    chair.rotation_euler.z += a
    (moved, _), _ = markers(overlay, scene)
    r = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    expect = (pos[:, :2] - c) @ r.T + (2.0, -3.0)
    assert np.allclose(moved[:, :2], expect, atol=1e-3)
    # Untagged, the chair has no markers.
    chair.motion_patch.enabled = False
    (none, _), _ = markers(overlay, scene)
    assert len(none) == 0


def test_overlay_draw_cache_follows_a_moved_prop(scene, addon_module):
    overlay = addon_module.panels.overlay
    chair = bpy.data.objects["Chair"]
    key = overlay._markers_key(scene)
    chair.location.x += 1.0
    bpy.context.view_layer.update()
    assert overlay._markers_key(scene) != key  # the drawn markers are rebuilt
    chair.motion_patch.clips[0].copy_step = 45.0
    assert overlay._markers_key(scene) != key


def test_export_and_import_patch_operators_carry_a_patch_to_another_scene(
    scene, addon_module, tmp_path
):
    api = addon_module.api
    path = tmp_path / "walk.mpatch"
    assert bpy.ops.motion_patches.export_patch(filepath=str(path)) == {"FINISHED"}
    activate("Walker")
    before = api.plan_path(scene, bpy.data.objects["Walker"], scene.motion_patches.goal)
    scene.motion_patches.patches.clear()
    assert not bpy.ops.motion_patches.export_patch.poll()  # nothing to export any more
    assert bpy.ops.motion_patches.import_patch(filepath=str(path)) == {"FINISHED"}
    assert [p.name for p in scene.motion_patches.patches] == ["walk"]
    after = api.plan_path(scene, bpy.data.objects["Walker"], scene.motion_patches.goal)
    assert after.cost == pytest.approx(before.cost) and after.pieces == before.pieces


def test_importing_a_file_that_is_not_a_patch_reports_and_changes_nothing(scene, tmp_path):
    junk = tmp_path / "junk.mpatch"
    junk.write_bytes(b"PK\x03\x04 not really")
    n = len(scene.motion_patches.patches)
    with pytest.raises(RuntimeError, match="not a stored locomotion patch"):
        bpy.ops.motion_patches.import_patch(filepath=str(junk))
    assert len(scene.motion_patches.patches) == n


def test_the_overlay_draws_paths_of_visible_characters_and_the_active_one_s_grid(
    scene, addon_module
):
    """A crowd's tile grids drawn on top of each other are unreadable: the grid, occluded
    cells and props walked round are the active character's (or, by the Overlay panel's
    toggle, every one's); a hidden character's path is not drawn."""
    overlay, api = addon_module.panels.overlay, addon_module.api
    for name in ("Walker", "Walker.B"):
        activate(name)
        assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    activate("Walker")

    def drawn():
        return {
            len(d.ground): bool(d.grid)
            for d in api.plan_drawings(scene, overlay._lattice_of(scene))
        }

    frames = {
        n: api.load_plan_record(bpy.data.objects[n])[1]["ground"].shape[0]
        for n in ("Walker", "Walker.B")
    }
    assert frames["Walker"] != frames["Walker.B"]
    assert drawn() == {frames["Walker"]: True, frames["Walker.B"]: False}
    scene.motion_patches.overlay_all_lattices = True
    assert drawn() == {frames["Walker"]: True, frames["Walker.B"]: True}
    key = overlay._plans_key(scene)
    bpy.data.objects["Walker.B"].hide_set(True)
    assert overlay._plans_key(scene) != key  # the overlay is rebuilt
    assert drawn() == {frames["Walker"]: True}
    assert "overlay_all_lattices" in [p for k, p in draw_panels(addon_module)["Overlay"]]


def test_the_overlay_reads_again_only_the_plans_that_changed(scene, addon_module):
    """Another character made active redraws the overlay from the drawings it made before
    (each plan record read once); a character planned again is read again; the buffers are
    the ones made from scratch."""
    overlay, api = addon_module.panels.overlay, addon_module.api
    for name in ("Walker", "Walker.B"):
        activate(name)
        assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    activate("Walker")
    first = {len(d.ground): d for d in api.plan_drawings(scene, overlay._lattice_of(scene))}
    again = {len(d.ground): d for d in api.plan_drawings(scene, overlay._lattice_of(scene))}
    assert all(again[n] is first[n] for n in first)  # nothing read again
    activate("Walker.B")
    swapped = {len(d.ground): d for d in api.plan_drawings(scene, overlay._lattice_of(scene))}
    assert all(swapped[n] is not first[n] for n in first)  # each one's grid came or went
    assert sorted(bool(d.grid) for d in swapped.values()) == [False, True]
    kept = overlay.plan_buffers(scene)
    api.overlay._drawn.clear()
    fresh = overlay.plan_buffers(scene)
    for k in fresh:
        for a, b in zip(kept[k], fresh[k]):
            np.testing.assert_array_equal(a, b)
    before = api.plan_drawings(scene, overlay._lattice_of(scene))
    walker_b = bpy.data.objects["Walker.B"]
    fp = api.storage.plan_fingerprint(walker_b)
    meta, _ = api.load_plan_record(walker_b)
    x, y, h = meta["goal"]
    api.plan_path(scene, walker_b, (x + 0.5, y, h))  # Walker.B planned again
    assert api.storage.plan_fingerprint(walker_b) != fp
    moved = api.plan_drawings(scene, overlay._lattice_of(scene))
    assert [any(d is old for old in before) for d in moved] == [
        ob.name == "Walker" for ob in scene.objects if ob.name in ("Walker", "Walker.B")
    ]  # Walker's kept, Walker.B's read again
