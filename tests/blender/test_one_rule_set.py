# SPDX-License-Identifier: GPL-3.0-or-later
"""One rule set behind the three doors: the Plan Crowd button, the CLI ``crowd`` command
and :func:`api.crowd_members` give the same crowd (who, walking to which goal) and the
same refusals for the same scene; the CLI plans with the scene's settings unless a flag
overrides one; the patch a bake or an import stores is the active one whichever door it
came through.

The scene is built the way a user builds it: the walk patch baked from CMU BVH files, the
walkers copies of the imported armature, goals as empties facing -Y, a body mesh selected
with the walkers."""

import json

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from, world_bone_matrices

pytestmark = pytest.mark.usefixtures("addon_module")


@pytest.fixture(scope="module")
def crowd_blend(walk_blend, tmp_path_factory):
    """Walkers A (own goal 'Goal A') and B (none), a mesh 'Body' parented to B, the
    scene's goal 'Goal'."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    src = scene.motion_patches.source_armature
    a = walker_from(src, "A", (0.0, 0.0, 0.0))
    b = walker_from(src, "B", (0.0, -3.0, 0.0))
    a.motion_patches_character.goal = empty("Goal A", 6.0, 0.0, 0.0)
    scene.motion_patches.goal = empty("Goal", 6.0, -3.0, 0.0)
    bpy.ops.mesh.primitive_cube_add(size=0.3, location=(0.0, -3.0, 1.0))
    body = bpy.context.object
    body.name = "Body"
    body.parent = b
    path = tmp_path_factory.mktemp("doors") / "crowd.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


@pytest.fixture
def scene(crowd_blend):
    bpy.ops.wm.open_mainfile(filepath=str(crowd_blend))
    return bpy.context.scene


@pytest.fixture
def cli(mp):
    return mp.cli


def select(*names):
    for ob in bpy.context.scene.objects:
        ob.select_set(ob.name in names)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]]


class Recorded(Exception):
    pass


@pytest.fixture
def recorded(mp, monkeypatch):
    """Every door's call of api.plan_crowd recorded as [(character, goal)] names; the
    call then stops with a MotionPatchesError the door reports (nothing is planned: this
    is about who is in the crowd)."""
    api = mp.api
    calls = []

    def record(scene, pairs, **kw):
        calls.append([(c.name, g.name) for c, g, _ in pairs])
        raise api.MotionPatchesError("recorded")

    monkeypatch.setattr(api, "plan_crowd", record)
    return calls


def through_operator(names):
    """The Plan Crowd button with ``names`` selected: its error report, or None."""
    select(*names)
    try:
        bpy.ops.motion_patches.plan_crowd()
    except RuntimeError as exc:  # an operator's ERROR report, in background mode
        return str(exc).strip()
    return None


def through_cli(cli, capsys, names):
    capsys.readouterr()
    argv = ["crowd", "--json"] + [a for n in names for a in ("--character", n)]
    code = cli.main(argv)
    out = capsys.readouterr()
    return code, json.loads(out.out)["error"]


EXPECTED = [("A", "Goal A"), ("B", "Goal")]  # A's own goal; B has none: the scene's


def test_the_button_the_cli_and_the_api_make_the_same_crowd(scene, mp, cli, capsys, recorded):
    api = mp.api
    objects = [bpy.data.objects[n] for n in ("B", "Body", "A")]
    by_api = [(c.name, g.name) for c, g, _ in api.crowd_members(scene, objects)]
    assert by_api == EXPECTED  # the body mesh is no character; ordered by name

    assert through_operator(["B", "Body", "A"]) == "Error: recorded"
    assert recorded[-1] == EXPECTED

    code, error = through_cli(cli, capsys, ["B", "A"])
    assert code == 2 and error == "recorded"
    assert recorded[-1] == EXPECTED
    assert len(recorded) == 2

    # Nobody chosen (the CLI with neither --pair nor --character; a script passing None):
    # every armature with its own goal, i.e. A only; B would need the scene's goal.
    assert [(c.name, g.name) for c, g, _ in api.crowd_members(scene)] == [("A", "Goal A")]
    capsys.readouterr()
    assert cli.main(["crowd", "--json"]) == 2
    assert recorded[-1] == [("A", "Goal A")]


@pytest.mark.parametrize(
    "case, needle",
    [
        ("no goal", "'B' has no goal: give it its own goal or set the scene's goal"),
        ("own goal is itself", "the goal of 'B' is the character itself"),
    ],
)
def test_the_three_doors_refuse_the_same_crowd_with_the_same_words(
    scene, mp, cli, capsys, recorded, case, needle
):
    api = mp.api
    b = bpy.data.objects["B"]
    if case == "no goal":
        scene.motion_patches.goal = None
    else:
        b.motion_patches_character.goal = b
    with pytest.raises(api.MotionPatchesError) as by_api:
        api.crowd_members(scene, [bpy.data.objects["A"], b])
    by_operator = through_operator(["A", "B"])
    code, by_cli = through_cli(cli, capsys, ["A", "B"])
    assert str(by_api.value) == needle
    assert by_operator == f"Error: {needle}"  # as Blender reports an operator's error
    assert code == 2 and by_cli == needle
    assert recorded == []  # refused before planning
    assert all(bpy.data.objects[n].animation_data is None for n in ("A", "B"))


def test_bad_settings_are_refused_alike_by_the_api_and_the_cli(scene, mp, cli, capsys):
    """The operator reads the scene's settings, which Blender keeps in range (radius >= 0.05);
    a script and the CLI can ask for anything, and get the same refusal."""
    api = mp.api
    pairs = api.crowd_members(scene, [bpy.data.objects["A"]])
    for flag, value, needle in (
        ("radius", -1.0, "radius must be a number of metres from 0.05 to 2"),
        ("alpha", -0.5, "alpha must be a number from 0 to"),
        ("gamma", float("nan"), "gamma must be a number from 0 to"),
    ):
        with pytest.raises(api.MotionPatchesError) as by_api:
            api.plan_crowd(scene, pairs, **{flag: value})
        with pytest.raises(api.MotionPatchesError) as by_api_plan:
            api.plan_path(scene, pairs[0][0], pairs[0][1], **{flag: value})
        capsys.readouterr()
        code = cli.main(["crowd", "--json", "--character", "A", f"--{flag}", str(value)])
        by_cli = json.loads(capsys.readouterr().out)["error"]
        assert needle in str(by_api.value), str(by_api.value)
        assert str(by_api.value) == str(by_api_plan.value) == by_cli and code == 2
    assert bpy.data.objects["A"].animation_data is None


def test_the_cli_plans_with_the_scene_settings_and_its_flags_override_them(
    scene, mp, cli, capsys, tmp_path
):
    record = mp.api.load_plan_record
    s = scene.motion_patches
    s.stitching, s.foot_lock, s.goal_facing, s.radius = "STATIC", False, "ANY", 0.3
    s.turn_in_place = False
    path = tmp_path / "settings.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    capsys.readouterr()
    assert cli.main(["plan", "--json", "--blend", str(path), "--character", "A"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["weights"] == {
        "alpha": 1.0,
        "beta": 0.5,
        "gamma": pytest.approx(0.2),
        "radius": pytest.approx(0.3),
        "stitching": "static",
        "foot_lock": False,
        "goal_facing": "any",
        "turn_in_place": False,
    }
    assert doc["goal"]["object"] == "Goal A"  # no --goal: its Own Goal (else the scene's)
    meta = record(bpy.data.objects["A"])[0]
    assert meta["foot_lock"] is False and meta["radius"] == pytest.approx(0.3)
    assert (
        cli.main(
            [
                "plan",
                "--json",
                "--blend",
                str(path),
                "--character",
                "A",
                "--foot-lock",
                "--stitching",
                "dynamic",
                "--exact-facing",
                "--turn-in-place",
                "--radius",
                "0.25",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc["weights"]["stitching"] == "dynamic" and doc["weights"]["foot_lock"] is True
    assert doc["weights"]["goal_facing"] == "exact" and doc["weights"]["turn_in_place"] is True
    meta = record(bpy.data.objects["A"])[0]
    assert meta["foot_lock"] is True and meta["radius"] == pytest.approx(0.25)


def test_an_imported_patch_is_the_active_one_through_every_door(scene, mp, cli, capsys, tmp_path):
    api = mp.api
    s = scene.motion_patches
    patch_file = tmp_path / "walk.mpatch"
    assert api.export_patch(scene, patch_file) == "walk"
    assert api.import_patch(scene, patch_file, "by api") == "by api"
    assert api.active_patch_name(scene) == "by api" == s.patches[s.active_patch_index].name
    assert bpy.ops.motion_patches.import_patch(filepath=str(patch_file)) == {"FINISHED"}
    assert api.active_patch_name(scene) == "walk.001"  # the scene's 'walk' is kept
    path = tmp_path / "with two.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    out = tmp_path / "imported.blend"
    capsys.readouterr()
    assert (
        cli.main(
            [
                "import",
                "--blend",
                str(path),
                str(patch_file),
                "--name",
                "by cli",
                "--save",
                str(out),
            ]
        )
        == 0
    )
    bpy.ops.wm.open_mainfile(filepath=str(out))
    assert mp.api.active_patch_name(bpy.context.scene) == "by cli"


def test_file_menus_offer_mocap_and_patch_files_and_import_them(scene, mp, mocap_dir, tmp_path):
    """File > Import lists both entries, File > Export the patch (drawn into a recording
    layout), each an operator that exists; run in background mode the imports read CMU BVH
    files and a patch file."""
    entries = []
    for menu, draw in (
        (bpy.types.TOPBAR_MT_file_import, mp.panels.file_import.draw_entries),
        (bpy.types.TOPBAR_MT_file_export, mp.panels.file_import.draw_exports),
    ):
        assert draw in menu._dyn_ui_initialize()
        drawn = []
        layout = type(
            "Layout", (), {"operator": lambda self, idname, text="": drawn.append((idname, text))}
        )()
        draw(type("Menu", (), {"layout": layout})(), bpy.context)
        entries.append(drawn)
    assert [t for _, t in entries[0]] == [
        "Motion Patches Clips to Bake (.bvh)",  # beside Blender's own "Motion Capture (.bvh)"
        "Motion Patches Patch (.mpatch)",
    ]
    assert entries[1] == [("motion_patches.export_patch", "Motion Patches Patch (.mpatch)")]
    for idname, _ in entries[0] + entries[1]:
        module, name = idname.split(".")
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # raises when it does not exist
    tip = bpy.ops.motion_patches.import_mocap.get_rna_type().description
    assert "one armature" in tip and "Blender's own Motion Capture importer" in tip

    before = set(bpy.data.objects)
    cmu = mocap_dir / "cmu"
    files = [{"name": f} for f in ("16_06.bvh", "16_15.bvh", "16_18.bvh")]  # as the browser
    assert bpy.ops.motion_patches.import_mocap(directory=str(cmu), files=files) == {"FINISHED"}
    (arm,) = set(bpy.data.objects) - before
    s = scene.motion_patches
    assert arm.type == "ARMATURE" and s.source_armature == arm
    assert arm.name == "Subject 16"  # not the first file's "16_06"
    # The straight walk just imported, ready to bake (the file's own "16_15" is the bake's).
    assert s.straight_action.get("motion_patches_source") == "16_15.bvh"
    assert s.straight_action.name == "16_15.001"

    patch_file = tmp_path / "walk.mpatch"
    mp.api.export_patch(scene, patch_file)
    assert bpy.ops.motion_patches.import_patch(filepath=str(patch_file)) == {"FINISHED"}
    assert mp.api.active_patch_name(scene) == "walk.001"  # beside the scene's own 'walk'
    with pytest.raises(RuntimeError, match="patch file not found"):
        bpy.ops.motion_patches.import_patch(filepath=str(tmp_path / "missing.mpatch"))


def test_list_buttons_stay_out_of_f3_search(mp):
    """The + / - buttons beside the add-on's lists are INTERNAL, as Blender's own are."""
    buttons = [c for c in mp.operators.classes if c.bl_idname.endswith(("_add", "_remove"))]
    assert len(buttons) == 4  # turn clips and a prop's clips, add and remove each
    assert all("INTERNAL" in c.bl_options for c in buttons)


@pytest.mark.parametrize("door", ["button", "cli", "api"])
def test_plan_path_walks_a_character_to_its_own_goal(scene, mp, cli, capsys, door):
    """Plan Path with no goal given sends a character with an Own Goal there (A), one
    without to the scene's goal (B): the rule a crowd follows, through every door, read
    from where each walker's evaluated root ends."""
    api = mp.api
    for name in ("A", "B"):
        if door == "button":
            select(name)
            assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
        elif door == "cli":
            capsys.readouterr()
            assert cli.main(["plan", "--character", name, "--json"]) == 0
            doc = json.loads(capsys.readouterr().out)
            assert doc["goal"]["object"] == dict(EXPECTED)[name]
        else:
            api.plan_path(scene, bpy.data.objects[name], None)
    for name, goal in EXPECTED:
        walker = bpy.data.objects[name]
        meta, _ = api.load_plan_record(walker)
        at = bpy.data.objects[goal].matrix_world.translation
        end = world_bone_matrices([walker], [meta["frame_end"]], ["Hips"])[name][0, 0, :2, 3]
        assert np.hypot(*(end - np.array(at[:2]))) < 0.15, (name, goal, end)


def test_plan_path_without_any_goal_names_the_character(scene, mp):
    scene.motion_patches.goal = None
    b = bpy.data.objects["B"]
    with pytest.raises(mp.api.MotionPatchesError, match="no goal for 'B'"):
        mp.api.plan_path(scene, b, None)
    assert b.animation_data is None  # refused before anything was written
