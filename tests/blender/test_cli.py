# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``blender -c motion_patches ...`` command: its handler called with argv, as Blender does.

There is no Blender binary here, so the handler registered with
``bpy.utils.register_cli_command`` is called directly with the extension enabled. The patch
is baked once per module through the CLI itself (real CMU mocap) and saved; a layout is
built on it and saved; each test reopens a file.
"""

import contextlib
import io
import json
import sys

import addon_utils
import bpy
import numpy as np
import pytest

from conftest import enable_addon, raise_error
from scene_helpers import empty, pillar, prop_box, walker_from


@pytest.fixture
def cli(addon_module_name):
    # Looked up per test: switching the add-on off and on may reload its modules.
    return sys.modules[addon_module_name].cli


def call(cli, capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def call_json(cli, capsys, *argv):
    code, out, err = call(cli, capsys, *argv, "--json")
    doc = json.loads(out)  # the whole of stdout is one JSON document
    assert doc["exit_code"] == code
    return code, doc, err


def one_line(err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def scene_state(name="Walker"):
    ob = bpy.data.objects.get(name)
    ad = ob.animation_data if ob else None
    return (
        sorted(o.name for o in bpy.data.objects),
        sorted(a.name for a in bpy.data.actions),
        [t.name for t in ad.nla_tracks] if ad else None,
        ad.action.name if ad and ad.action else None,
    )


CAGE = (3.0, -6.0)


@pytest.fixture(scope="module")
def baked(addon_module_name, mocap_dir, tmp_path_factory):
    """(path, exit code, JSON) of a bake run through the CLI on an empty scene."""
    cli = sys.modules[addon_module_name].cli
    bpy.ops.wm.read_homefile(use_empty=True)
    path = tmp_path_factory.mktemp("cli") / "baked.blend"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = cli.main(
            [
                "bake",
                "--import-bvh",
                str(mocap_dir / "cmu" / "16_15.bvh"),
                "--import-bvh",
                str(mocap_dir / "cmu" / "16_18.bvh"),
                "--armature",
                "Source",
                "--straight",
                "16_15",
                "--turn",
                "16_18",
                "--fps",
                "30",
                "--save",
                str(path),
                "--json",
            ]
        )
    return path, code, json.loads(out.getvalue())


@pytest.fixture(scope="module")
def layout(baked, tmp_path_factory):
    """The baked file plus a walker, pillars, a goal, and a goal caged in a ring of pillars."""
    bpy.ops.wm.open_mainfile(filepath=str(baked[0]))
    scene = bpy.context.scene
    walker_from(scene.motion_patches.source_armature)
    for n, (x, y) in enumerate([(3.0, 1.0), (4.5, 3.0), (2.5, 4.0), (6.0, 1.5)]):
        pillar(f"Pillar{n}", x, y)
    for n, a in enumerate(np.linspace(0, 2 * np.pi, 25)[:-1]):
        pillar(f"Ring{n:02d}", CAGE[0] + 1.6 * np.cos(a), CAGE[1] + 1.6 * np.sin(a), r=0.3)
    empty("Goal", 7.5, 5.0, 0.6)
    empty("CageGoal", CAGE[0], CAGE[1], 0.0)
    empty("Near", 4.0, -1.0, 0.0)
    path = tmp_path_factory.mktemp("cli") / "layout.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def open_blend(path):
    bpy.ops.wm.open_mainfile(filepath=str(path))
    return bpy.context.scene


# --- registration, help, usage ----------------------------------------------------------------


def test_command_is_registered_and_released_with_the_addon(addon_module_name, capfd):
    assert sys.modules[addon_module_name].cli._handle is not None
    addon_utils.disable(addon_module_name, default_set=True, handle_error=raise_error)
    try:
        assert sys.modules[addon_module_name].cli._handle is None
        capfd.readouterr()
        # The id is free again: registering it does not warn about a duplicate.
        h = bpy.utils.register_cli_command("motion_patches", lambda argv: 0)
        bpy.utils.unregister_cli_command(h)
        assert "duplicate" not in capfd.readouterr().err
    finally:
        enable_addon(addon_module_name)
    assert sys.modules[addon_module_name].cli._handle is not None


@pytest.mark.parametrize(
    "command", [None, "bake", "plan", "crowd", "analyse", "check", "export", "import"]
)
def test_help_exits_0(cli, capsys, command):
    code, out, err = call(cli, capsys, *([command] if command else []), "--help")
    assert code == 0
    assert out.startswith("usage: blender -c motion_patches")
    assert "exit codes" in out


@pytest.mark.parametrize(
    "argv, needle",
    [
        ([], "required"),
        (["frobnicate"], "invalid choice"),
        (["plan", "--goal", "Goal"], "--character"),
        (["plan", "--character", "W", "--alpha", "fast"], "invalid float"),
        (
            ["bake", "--armature", "A", "--straight", "s", "--cells", "12"],
            "cells must be a whole number from 2 to 8, not 12",
        ),
    ],
)
def test_usage_errors_exit_2_with_one_line(cli, capsys, argv, needle):
    code, out, err = call(cli, capsys, *argv)
    assert code == 2 and out == ""
    assert needle in one_line(err)


def test_usage_error_with_json_still_prints_one_document(cli, capsys):
    code, doc, err = call_json(cli, capsys, "plan")
    assert code == 2 and doc["ok"] is False and "--character" in doc["error"]
    one_line(err)


# --- bake -----------------------------------------------------------------------------------


def test_bake_imports_bakes_and_saves(baked):
    path, code, doc = baked
    assert code == 0 and doc["ok"] and doc["command"] == "bake"
    assert doc["patch"] == "walk" and doc["armature"] == "Source"
    assert doc["imported"] == ["16_15", "16_18"] and doc["fps"] == 30
    assert doc["stats"]["kept"] > 300
    assert doc["stats"]["kept"] + doc["stats"]["culled"] == doc["stats"]["candidates"]
    assert doc["saved"] == str(path) and path.is_file()
    scene = open_blend(path)
    assert scene.motion_patches.patches["walk"].fps == 30
    assert scene.motion_patches.source_armature.name == "Source"
    assert scene.motion_patches.straight_action.name == "16_15"


def test_bake_bad_input_exits_2_and_writes_nothing(cli, capsys, clean_scene, mocap_dir, tmp_path):
    out = tmp_path / "out.blend"
    walk = mocap_dir / "cmu" / "16_15.bvh"
    cases = [
        (
            ["--import-bvh", tmp_path / "missing.bvh", "--armature", "A", "--straight", "missing"],
            "BVH file not found",
        ),
        (["--armature", "Nobody", "--straight", "16_15"], "no armature object named 'Nobody'"),
        (
            ["--import-bvh", walk, "--armature", "A", "--straight", "16_99"],
            "no action named '16_99'",
        ),
        (
            ["--import-bvh", walk, "--armature", "A", "--straight", "16_15", "--turn", "nope"],
            "no action named 'nope'",
        ),
        (
            [
                "--import-bvh",
                walk,
                "--armature",
                "A",
                "--straight",
                "16_15",
                "--save",
                tmp_path / "no" / "such" / "dir.blend",
            ],
            "does not exist",
        ),
    ]
    for argv, needle in cases:
        if "--save" not in argv:
            argv = argv + ["--save", out]
        code, stdout, err = call(cli, capsys, "bake", *argv)
        assert code == 2, (argv, err)
        assert needle in one_line(err) and stdout == ""
        assert not out.exists()
        assert len(bpy.data.objects) == 0 and len(bpy.data.actions) == 0
        assert len(clean_scene.motion_patches.patches) == 0


def test_failed_bake_rolls_back_the_import(
    cli, capsys, clean_scene, mocap_dir, tmp_path, monkeypatch
):
    def refuse(*a, **k):  # the core bake, after the import: the API puts the import back
        raise ValueError("every candidate segment was culled")

    monkeypatch.setattr(cli.api.baking, "bake", refuse)
    fps = clean_scene.render.fps
    out = tmp_path / "out.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "bake",
        "--import-bvh",
        mocap_dir / "cmu" / "16_15.bvh",
        "--armature",
        "A",
        "--straight",
        "16_15",
        "--fps",
        "30",
        "--save",
        out,
    )
    assert code == 2 and doc["ok"] is False and "culled" in one_line(err)
    assert not out.exists()
    assert len(bpy.data.objects) == 0 and len(bpy.data.actions) == 0
    assert len(bpy.data.armatures) == 0 and clean_scene.render.fps == fps


def test_progress_bar_on_a_terminal_and_plain_lines_otherwise(cli):
    class Stream(io.StringIO):
        def __init__(self, tty):
            super().__init__()
            self.tty = tty

        def isatty(self):
            return self.tty

    tty, plain, quiet = Stream(True), Stream(False), Stream(True)
    for stream, enabled in ((tty, True), (plain, True), (quiet, False)):
        p = cli.Progress("bake", stream=stream, enabled=enabled)
        for f in np.linspace(0, 1, 101):
            p(f)
        p.close()
    assert tty.getvalue().startswith("\rbake [") and tty.getvalue().endswith("100%\n")
    assert plain.getvalue().splitlines() == [f"bake: {p}%" for p in range(0, 101, 10)]
    assert quiet.getvalue() == ""


# --- plan and analyse -----------------------------------------------------------------------


def test_plan_saves_nla_and_analyse_reports_figures(cli, capsys, layout, tmp_path):
    out = tmp_path / "planned.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "plan",
        "--blend",
        layout,
        "--character",
        "Walker",
        "--goal",
        "Goal",
        "--frame-start",
        "1",
        "--save",
        out,
    )
    assert code == 0 and doc["ok"], err
    assert doc["character"] == "Walker" and doc["goal"]["object"] == "Goal"
    assert doc["goal"]["x"] == pytest.approx(7.5) and doc["goal"]["heading_deg"] == pytest.approx(
        np.degrees(0.6)
    )
    assert doc["frame_start"] == 1 and doc["frames"] == doc["frame_end"]
    # The found path may be shortened down to one goal piece (one followed curve); the
    # walker faces 124 degrees away from the goal, so it first turns on the spot.
    assert doc["pieces"][-1] == "goal" and doc["pieces"][0] in (
        "start",
        "goal",
        "turn +124deg in place (derived)",
    )
    assert doc["length_m"] > np.hypot(7.1, 4.7) and doc["seconds_of_motion"] > 5
    assert doc["saved"] == str(out) and out.is_file()
    assert out.read_bytes()[:4] == b"\x28\xb5\x2f\xfd"  # saved compressed (zstd), 4.5 too

    # analyse on the plan in memory, and the saved file holds the same NLA
    code, doc, err = call_json(cli, capsys, "analyse", "--character", "Walker")
    assert code == 0, err
    f = doc["figures"]
    assert f["goal_position_error_cm"] < 10 and f["frames_root_inside_obstacle"] == 0
    open_blend(out)
    tracks = [t.name for t in bpy.data.objects["Walker"].animation_data.nla_tracks]
    assert tracks == ["MP motion", "MP root", "MP foot lock"]


def test_plan_to_coordinates_prints_a_summary(cli, capsys, layout):
    code, out, err = call(
        cli,
        capsys,
        "plan",
        "--blend",
        layout,
        "--character",
        "Walker",
        "--goal-xyh",
        "4",
        "-1",
        "0",
        "--alpha",
        "1",
        "--gamma",
        "0.1",
    )
    assert code == 0, err
    assert out.startswith("planned 'Walker':") and "cost" in out
    assert bpy.data.filepath == str(layout)  # nothing saved: the file is as it was
    assert "Traceback" not in err


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["--character", "Nobody", "--goal", "Goal"], "no armature object named 'Nobody'"),
        (["--character", "Pillar0", "--goal", "Goal"], "'Pillar0' is a mesh"),
        (["--character", "Walker", "--goal", "Nowhere"], "no object named 'Nowhere'"),
        (
            ["--character", "Walker", "--goal", "Goal", "--patch", "run"],
            "no locomotion patch named",
        ),
        (
            ["--character", "Walker", "--goal", "Goal", "--radius", "-1"],
            "radius must be a number of metres from 0.05 to 2",
        ),
        (
            ["--character", "Walker", "--goal-xyh", "3", "1", "0"],
            "the goal of 'Walker' is inside or within 0.25 m of 'Pillar0'",
        ),
        (["--character", "Walker", "--goal", "Walker"], "the goal cannot be the character itself"),
    ],
)
def test_plan_bad_input_exits_2_and_changes_nothing(cli, capsys, layout, tmp_path, argv, needle):
    out = tmp_path / "out.blend"
    open_blend(layout)
    before = scene_state()
    code, stdout, err = call(cli, capsys, "plan", *argv, "--save", out)
    assert code == 2 and stdout == ""
    assert needle in one_line(err)
    assert not out.exists() and scene_state() == before


def test_plan_without_a_baked_patch_exits_2(cli, capsys, clean_scene, tmp_path):
    arm = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    clean_scene.collection.objects.link(arm)
    empty("Goal", 3, 0, 0)
    out = tmp_path / "out.blend"
    code, doc, err = call_json(
        cli, capsys, "plan", "--character", "Rig", "--goal", "Goal", "--save", out
    )
    assert code == 2 and "no locomotion patch is baked" in one_line(err)
    assert doc["ok"] is False and not out.exists()


def test_analyse_without_a_plan_exits_2(cli, capsys, layout):
    code, out, err = call(cli, capsys, "analyse", "--blend", layout, "--character", "Walker")
    assert code == 2 and "no planned motion" in one_line(err)


def test_unreachable_plan_exits_1_and_changes_nothing(cli, capsys, layout, tmp_path):
    open_blend(layout)
    before = scene_state()
    out = tmp_path / "out.blend"
    code, doc, err = call_json(
        cli, capsys, "plan", "--character", "Walker", "--goal", "CageGoal", "--save", out
    )
    assert code == 1 and doc["ok"] is False
    assert "no path for 'Walker'" in one_line(err)
    assert not out.exists() and scene_state() == before


def test_json_stdout_is_only_the_document_at_the_fd_level(cli, capfd, layout, tmp_path):
    """Blender prints reports (file saved, ...) to stdout itself; they must not mix in."""
    out = tmp_path / "planned.blend"
    code = cli.main(
        [
            "plan",
            "--blend",
            str(layout),
            "--character",
            "Walker",
            "--goal",
            "Goal",
            "--save",
            str(out),
            "--json",
        ]
    )
    stdout, _ = capfd.readouterr()
    assert code == 0 and json.loads(stdout)["saved"] == str(out)


# --- check ----------------------------------------------------------------------------------


def test_check_spec_reports_every_pair_and_writes_nothing(cli, capsys, layout, tmp_path):
    spec = tmp_path / "layout.json"
    spec.write_text(
        json.dumps(
            {
                "radius": 0.25,
                "limits": {"max_seconds": 60},
                "pairs": [
                    {"name": "walker to goal", "character": "Walker", "goal": "Goal"},
                    {"start": [0, 0, 90], "goal": "Near", "max_length": 50},
                ],
            }
        )
    )
    open_blend(layout)
    before = scene_state()
    code, doc, err = call_json(cli, capsys, "check", "--spec", spec)
    assert code == 0 and doc["ok"] and doc["passed"] == 2, err
    a, b = doc["pairs"]
    assert a["name"] == "walker to goal" and a["reachable"] and a["passed"]
    assert a["start"]["object"] == "Walker" and a["goal"]["object"] == "Goal"
    assert a["length_m"] > np.hypot(7.1, 4.7) and 5 < a["seconds"] < 60 and a["cost"] > 0
    assert a["blocked_by"] == [] and a["limits"]["max_seconds"] == 60
    assert b["name"] == "(0, 0, 90 deg) -> Near" and b["reachable"]
    assert b["limits"]["max_length"] == 50 and b["limits"]["max_seconds"] == 60
    assert scene_state() == before  # no NLA, no actions, no objects: nothing written
    assert bpy.data.objects["Walker"].animation_data is None


def test_failing_check_exits_1_and_names_the_blocking_props(cli, capsys, layout, tmp_path):
    spec = tmp_path / "layout.toml"
    spec.write_text(
        '[[pairs]]\nname = "into the cage"\ncharacter = "Walker"\ngoal = "CageGoal"\n\n'
        '[[pairs]]\nname = "too slow"\ncharacter = "Walker"\ngoal = "Goal"\nmax_seconds = 2\n\n'
        '[[pairs]]\nname = "optional"\nstart = [0.0, -3.0, 0.0]\ngoal = "CageGoal"\n'
        "must_reach = false\n"
    )
    code, doc, err = call_json(cli, capsys, "check", "--blend", layout, "--spec", spec)
    assert code == 1 and doc["ok"] is False and doc["failed"] == 2
    cage, slow, optional = doc["pairs"]
    assert cage["reachable"] is False and cage["passed"] is False
    assert cage["blocked_reason"] == "separated"
    assert cage["blocked_by"] and all(n.startswith("Ring") for n in cage["blocked_by"])
    assert len(cage["blocked_by"]) >= 12  # the ring, not the pillars on the other path
    assert "blocked by Ring" in cage["failures"][0]
    assert slow["reachable"] and not slow["passed"] and "max_seconds 2" in slow["failures"][0]
    assert optional["reachable"] is False and optional["passed"] is True

    code, out, err = call(cli, capsys, "check", "--spec", spec)  # the human summary
    assert code == 1
    assert "FAIL  into the cage: UNREACHABLE, blocked by Ring" in out
    assert "max_seconds 2" in out and "PASS  optional" in out


def test_check_without_spec_rechecks_planned_characters(cli, capsys, layout, tmp_path):
    open_blend(layout)
    assert call(cli, capsys, "plan", "--character", "Walker", "--goal", "Goal")[0] == 0
    code, doc, err = call_json(cli, capsys, "check")
    assert code == 0, err
    (pair,) = doc["pairs"]
    assert pair["name"] == "Walker" and pair["reachable"]
    assert pair["goal"]["x"] == pytest.approx(7.5) and pair["goal"]["y"] == pytest.approx(5.0)
    # A crate dropped on the goal after planning: the check catches it and names it.
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(7.5, 5.0, 0.5))
    bpy.context.object.name = "Crate"
    code, doc, err = call_json(cli, capsys, "check", "--max-seconds", "60")
    assert code == 1
    (pair,) = doc["pairs"]
    assert pair["blocked_by"] == ["Crate"] and pair["blocked_reason"] == "goal"
    # explicit pairs; the character's own body mesh (a child) is not an obstacle
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(0.4, 0.3, 1.0))
    body = bpy.context.object
    body.name = "WalkerBody"
    body.parent = bpy.data.objects["Walker"]
    body.matrix_parent_inverse = bpy.data.objects["Walker"].matrix_world.inverted()
    code, doc, err = call_json(cli, capsys, "check", "--character", "Walker", "--goal", "Near")
    assert code == 0 and doc["pairs"][0]["goal"]["object"] == "Near", err
    # a spec can say which props are not obstacles (the crate will be moved)
    spec = tmp_path / "spec.json"
    spec.write_text(
        json.dumps(
            {
                "exclude": ["Crate"],
                "pairs": [{"start": [0.4, 0.3, -90], "goal": "Goal", "exclude": ["WalkerBody"]}],
            }
        )
    )
    code, doc, err = call_json(cli, capsys, "check", "--spec", spec)
    assert code == 0 and doc["pairs"][0]["reachable"], err


@pytest.mark.parametrize(
    "content, needle",
    [
        (None, "layout spec not found"),
        ("{not json", "cannot read layout spec"),
        ('{"pairs": [{"character": "Walker", "goal": "Nowhere"}]}', "no object named 'Nowhere'"),
        (
            '{"pairs": [{"character": "Walker", "goal": "Goal", "max_secs": 3}]}',
            "unknown key(s) max_secs",
        ),
        ('{"pairs": [{"start": [0, 0], "goal": "Goal"}]}', "[x, y, heading_deg]"),
        ('{"pairs": []}', "non-empty list"),
        (  # a goal no plan can reach is bad input, not a failed pair (exit 1)
            '{"pairs": [{"character": "Walker", "goal": [1e12, 0, 0]}]}',
            "lies 1e+12 m from the origin",
        ),
    ],
)
def test_check_bad_spec_exits_2(cli, capsys, layout, tmp_path, content, needle):
    spec = tmp_path / "spec.json"
    if content is not None:
        spec.write_text(content)
    code, out, err = call(cli, capsys, "check", "--blend", layout, "--spec", spec)
    assert code == 2 and out == ""
    assert needle in one_line(err)


def test_check_with_nothing_to_check_exits_2(cli, capsys, layout):
    code, out, err = call(cli, capsys, "check", "--blend", layout)
    assert code == 2 and "nothing to check" in one_line(err)


def test_missing_blend_exits_2(cli, capsys, tmp_path):
    code, out, err = call(cli, capsys, "check", "--blend", tmp_path / "nope.blend")
    assert code == 2 and ".blend file not found" in one_line(err)


# --- crowd ----------------------------------------------------------------------------------


def evaluated_roots(cli, names, frames):
    """(characters, frames, 2) ground positions of each armature's evaluated root bone."""
    sample = cli.api.evaluate.sample_armature
    return np.array(
        [
            sample(bpy.context, ob, frames, [ob.pose.bones[0].name])[0][:, 0, :2]
            for ob in (bpy.data.objects[n] for n in names)
        ]
    )


def facing(cli, walker, heading):
    """Turn ``walker`` about Z so that its rest facing points along ``heading``."""
    skel = cli.api.storage.load_patch(bpy.context.scene).gait.skeleton
    walker.rotation_euler = (0, 0, 0)
    bpy.context.view_layer.update()
    walker.rotation_euler = (0, 0, heading - cli.api.scene_io.character_state(walker, skel)[2])


@pytest.fixture
def crossing(cli, baked, layout, tmp_path, capsys):
    """Two walkers on an open floor whose straight ways cross at the same moment, plus
    the pillar layout (its caged goal) for the failure cases."""
    scene = open_blend(layout)
    src = scene.motion_patches.source_armature
    for ob in [o for o in scene.objects if o.type == "MESH"]:
        bpy.data.objects.remove(ob)
    facing(cli, walker_from(src, "East", (0.0, 0.0, 0.0)), 0.0)
    facing(cli, walker_from(src, "North", (4.0, -4.0, 0.0)), np.pi / 2)
    empty("EastGoal", 8.0, 0.0, 0.0)
    empty("NorthGoal", 4.0, 4.0, np.pi / 2)
    path = tmp_path / "crossing.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    capsys.readouterr()  # Blender's "Saved as" is not the tests' output
    return path


def test_crowd_plans_everyone_and_keeps_them_apart(cli, capsys, crossing, tmp_path):
    pairs = ["--pair", "East", "EastGoal", "--pair", "North", "NorthGoal"]
    # Walking at once they would come within a metre of each other; with no wait allowed
    # the second is re-routed round where the first walks at that time.
    rerouted = tmp_path / "rerouted.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "crowd",
        "--blend",
        crossing,
        *pairs,
        "--spacing",
        "1",
        "--max-wait",
        "0",
        "--frame-start",
        "1",
        "--save",
        rerouted,
    )
    assert code == 0 and doc["conflicts"] == [] and doc["rerouted"] == ["North"], err
    assert doc["delays_frames"] == {"East": 0, "North": 0}
    open_blend(rerouted)
    end = max(p["frame_end"] for p in doc["planned"])
    roots = evaluated_roots(cli, ["East", "North"], range(1, end + 1))
    gap = np.linalg.norm(roots[0] - roots[1], axis=1)
    assert gap.min() >= 1.0 - 0.05, f"closest approach {gap.min():.2f} m"
    assert np.linalg.norm(roots[1, -1] - (4.0, 4.0)) < 0.3
    out = tmp_path / "crowd.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "crowd",
        "--blend",
        crossing,
        *pairs,
        "--spacing",
        "1",
        "--frame-start",
        "1",
        "--save",
        out,
    )
    assert code == 0 and doc["ok"] and doc["conflicts"] == [] and doc["failed"] == [], err
    assert [p["character"] for p in doc["planned"]] == ["East", "North"]
    # North gives way by an idle hold mid-walk (preferred to a wait at its start)
    assert doc["delays_frames"] == {"East": 0, "North": 0}
    first, second = doc["planned"]
    assert first["frame_start"] == 1 and second["frame_start"] == 1
    # Evaluated through the depsgraph: both arrive, and they keep a metre apart throughout.
    open_blend(out)
    end = max(first["frame_end"], second["frame_end"])
    roots = evaluated_roots(cli, ["East", "North"], range(1, end + 1))
    gap = np.linalg.norm(roots[0] - roots[1], axis=1)
    assert gap.min() >= 1.0 - 0.05, f"closest approach {gap.min():.2f} m"
    assert np.linalg.norm(roots[0, -1] - (8.0, 0.0)) < 0.3
    assert np.linalg.norm(roots[1, -1] - (4.0, 4.0)) < 0.3
    # it stands still for a while between leaving its start and reaching its goal
    walk = roots[1, : second["frame_end"]]
    still = np.linalg.norm(np.diff(walk, axis=0), axis=1) < 1e-3
    moved = np.linalg.norm(walk - walk[0], axis=1) > 0.5
    far = np.linalg.norm(walk - (4.0, 4.0), axis=1) > 0.5
    assert (still & moved[1:] & far[1:]).sum() >= 6


def test_crowd_on_a_local_dask_cluster_plans_what_it_plans_in_process(
    cli, capsys, crossing, tmp_path
):
    """--workers 2: the members' paths are planned, and the characters' keys fitted, on a
    Dask LocalCluster of two worker processes (no Blender in them); the written crowd is
    the same as planned in process: the same strips, frames and costs, and through the
    depsgraph the same root motion and every bone's rotation (within its keys' tolerance)."""
    pairs = ["--pair", "East", "EastGoal", "--pair", "North", "NorthGoal"]
    names = ["East", "North"]
    docs, roots, bones = [], [], []
    for extra in ([], ["--workers", "2"]):
        out = tmp_path / f"crowd{len(docs)}.blend"
        code, doc, err = call_json(
            cli,
            capsys,
            "crowd",
            "--blend",
            crossing,
            *pairs,
            "--spacing",
            "1",
            "--frame-start",
            "1",
            "--save",
            out,
            *extra,
        )
        assert code == 0 and doc["conflicts"] == [] and doc["failed"] == [], err
        docs.append(doc)
        open_blend(out)
        end = max(p["frame_end"] for p in doc["planned"])
        roots.append(evaluated_roots(cli, ["East", "North"], range(1, end + 1)))
        sample = cli.api.evaluate.sample_armature
        bones.append(
            [sample(bpy.context, bpy.data.objects[n], range(1, end + 1), [])[2] for n in names]
        )
    assert docs[1]["workers"] == 2 and docs[0]["workers"] is None

    def plans(doc):
        keys = ("character", "frame_start", "frame_end", "length_m", "cost", "pieces", "strips")
        return [{k: p[k] for k in keys} for p in doc["planned"]]

    assert plans(docs[0]) == plans(docs[1])
    assert docs[0]["delays_frames"] == docs[1]["delays_frames"]
    assert np.array_equal(roots[0], roots[1])
    # every pose bone's rotation on every frame: the keys are fitted on the workers from the
    # same plan, each within the 0.5 degrees it is stored within (a float's last bits may
    # move a key between processes), so within 1 degree of the keys fitted in process
    for here, there in zip(*bones):
        dots = np.abs(np.einsum("fjc,fjc->fj", here, there))
        turn = np.degrees(2.0 * np.arccos(np.clip(dots, -1.0, 1.0)))
        assert here.shape[1] > 20 and turn.max() <= 1.0, turn.max()


def test_crowd_interrupted_exits_130_and_saves_nothing(
    cli, capsys, crossing, tmp_path, monkeypatch
):
    """Ctrl-C while the crowd is planned (raised from its progress): exit 130, the .blend
    to save is not written, the open file is unchanged on disk."""
    before = crossing.read_bytes()

    def interrupted(self, fraction):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli.crowd.Progress, "__call__", interrupted)
    out = tmp_path / "crowd.blend"
    code, _, err = call(
        cli,
        capsys,
        "crowd",
        "--blend",
        crossing,
        "--pair",
        "East",
        "EastGoal",
        "--frame-start",
        "1",
        "--save",
        out,
    )
    assert code == 130 and "interrupted: nothing was saved" in err
    assert not out.exists() and crossing.read_bytes() == before


def test_crowd_whose_cluster_is_lost_exits_69_and_saves_nothing(
    cli, capsys, crossing, tmp_path, monkeypatch
):
    """The Dask cluster dropping its tasks mid-run (the core's ClusterLost, which a lost
    scheduler raises: tests/core/test_cluster.py) is said as such, not as a bug: exit 69,
    the scheduler named, nothing saved, the open file unchanged."""
    before = crossing.read_bytes()
    where = "tcp://10.0.0.9:8786"

    def lost(c, progress):
        raise cli.api.crowd.cluster.ClusterLost(
            f"the Dask scheduler at {where} dropped the tasks before answering"
        )

    monkeypatch.setattr(cli.api.crowd, "_plan_each", lost)
    out = tmp_path / "crowd.blend"
    code, doc, err = call_json(
        cli, capsys, "crowd", "--blend", crossing, "--pair", "East", "EastGoal", "--save", out
    )
    assert code == 69 and where in doc["error"] and "nothing was written" in doc["error"], err
    assert "Traceback" not in err
    assert not out.exists() and crossing.read_bytes() == before


def test_crowd_with_no_worker_exits_2(cli, capsys, crossing):
    code, doc, err = call_json(
        cli, capsys, "crowd", "--blend", crossing, "--pair", "East", "EastGoal", "--workers", "0"
    )
    assert code == 2 and "workers must be a whole number of at least 1" in doc["error"], err


def test_crowd_with_an_unreachable_goal_exits_1_and_saves_nothing(cli, capsys, layout, tmp_path):
    scene = open_blend(layout)
    walker_from(scene.motion_patches.source_armature, "North", (1.0, -2.0, 0.0))
    out = tmp_path / "crowd.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "crowd",
        "--pair",
        "Walker",
        "Goal",
        "--pair",
        "North",
        "CageGoal",
        "--save",
        out,
    )
    assert code == 1 and not out.exists()
    assert [p["character"] for p in doc["planned"]] == ["Walker"]
    assert doc["failed"][0]["character"] == "North"
    assert "no path for 'North'" in doc["failed"][0]["error"]


def test_crowd_save_anyway_keeps_what_was_planned_and_still_exits_1(cli, capsys, layout, tmp_path):
    scene = open_blend(layout)
    walker_from(scene.motion_patches.source_armature, "North", (1.0, -2.0, 0.0))
    out = tmp_path / "crowd.blend"
    code, doc, err = call_json(
        cli,
        capsys,
        "crowd",
        "--pair",
        "Walker",
        "Goal",
        "--pair",
        "North",
        "CageGoal",
        "--save",
        out,
        "--save-anyway",
    )
    assert code == 1 and doc["saved"] == str(out.resolve()) and out.exists(), err
    assert [f["character"] for f in doc["failed"]] == ["North"]
    open_blend(out)
    walker = bpy.data.objects["Walker"]
    assert walker.animation_data and walker.animation_data.nla_tracks, "the planned walk is kept"


@pytest.mark.parametrize(
    "argv, needle",
    [
        ([], "no crowd: no armature in the scene has its own goal"),
        (["--pair", "East", "Goal", "--pair", "East", "NorthGoal"], "'East' appears twice"),
        (["--pair", "East", "Nowhere"], "no object named 'Nowhere'"),
        (["--pair", "East", "East"], "the character itself"),
        (["--pair", "Goal", "East"], "no armature object named 'Goal'"),
        (["--pair", "East", "Goal", "--max-wait", "-2"], "the longest wait must be numbers >= 0"),
        (["--pair", "East", "Goal", "--character", "North"], "either --pair or --character"),
    ],
)
def test_crowd_bad_input_exits_2_and_changes_nothing(cli, capsys, crossing, tmp_path, argv, needle):
    out = tmp_path / "out.blend"
    open_blend(crossing)
    before = scene_state("East"), scene_state("North")
    code, stdout, err = call(cli, capsys, "crowd", *argv, "--save", out)
    assert code == 2 and stdout == ""
    assert needle in one_line(err)
    assert not out.exists() and (scene_state("East"), scene_state("North")) == before


# --- patch files ----------------------------------------------------------------------------


def test_export_then_import_gives_the_same_plan(cli, capsys, layout, baked, tmp_path):
    patch_file = tmp_path / "walk.mpatch"
    code, doc, err = call_json(cli, capsys, "export", "--blend", baked[0], patch_file)
    assert code == 0 and patch_file.stat().st_size > 10_000, err
    open_blend(layout)
    code, doc, err = call_json(cli, capsys, "plan", "--character", "Walker", "--goal", "Goal")
    cost = doc["cost"]
    # A scene without the patch gets it from the file and plans the same path.
    scene = bpy.context.scene
    scene.motion_patches.patches.clear()
    code, doc, err = call_json(cli, capsys, "import", patch_file, "--name", "walk2")
    assert code == 0 and doc["patch"] == "walk2", err
    code, doc, err = call_json(cli, capsys, "plan", "--character", "Walker", "--goal", "Goal")
    assert code == 0 and doc["cost"] == pytest.approx(cost), err


def test_importing_a_file_that_is_not_a_patch_exits_2(cli, capsys, layout, tmp_path):
    junk = tmp_path / "junk.mpatch"
    junk.write_bytes(b"not a patch")
    open_blend(layout)
    before = len(bpy.context.scene.motion_patches.patches)
    code, out, err = call(cli, capsys, "import", junk)
    assert code == 2 and "not a stored locomotion patch" in one_line(err)
    assert len(bpy.context.scene.motion_patches.patches) == before
    code, out, err = call(cli, capsys, "import", tmp_path / "missing.mpatch")
    assert code == 2 and "patch file not found" in one_line(err)


def test_crowd_where_nobody_finds_a_path_exits_1(cli, capsys, layout, tmp_path):
    open_blend(layout)
    before = scene_state()
    code, doc, err = call_json(cli, capsys, "crowd", "--pair", "Walker", "CageGoal")
    assert code == 1 and doc["planned"] == [] and doc["failed"][0]["character"] == "Walker"
    assert "Traceback" not in err and scene_state() == before


def test_a_crowd_goal_object_blocks_everyone_but_its_own_character(cli, capsys, layout):
    """North walks to a pillar (its goal): for North it is no obstacle, for Walker it is."""
    scene = open_blend(layout)
    walker_from(scene.motion_patches.source_armature, "North", (1.0, -2.0, 0.0))
    code, doc, err = call_json(
        cli, capsys, "crowd", "--pair", "Walker", "Goal", "--pair", "North", "Pillar0"
    )
    assert not doc["failed"], err
    walker_obstacles = cli.api.load_plan_record(bpy.data.objects["Walker"])[0]["obstacles"]
    north_obstacles = cli.api.load_plan_record(bpy.data.objects["North"])[0]["obstacles"]
    assert "Pillar0" in walker_obstacles and "Pillar0" not in north_obstacles
    assert "Pillar1" in walker_obstacles and "Pillar1" in north_obstacles
    assert not any(n.startswith("\x00") for n in walker_obstacles)  # no standing spot left


def test_a_goal_facing_out_of_a_dead_end_is_reached_by_turning_on_the_spot(cli, capsys, layout):
    """A goal deep in a dead end facing its mouth: no walk can curve round in there, so the
    walker walks in and turns round on the spot (the derived turn in place), evaluated on
    the goal point and heading; --any-facing arrives facing the end wall instead."""
    open_blend(layout)
    for name, (x, y, sx, sy) in {
        "WallN": (9.8, 10.75, 3.6, 0.3),
        "WallS": (9.8, 9.25, 3.6, 0.3),
        "WallEnd": (11.45, 10.0, 0.3, 1.8),
    }.items():
        prop_box(name, x, y, (sx, sy, 2.0))
    empty("DeadEnd", 10.4, 10.0, np.pi)
    code, doc, err = call_json(cli, capsys, "plan", "--character", "Walker", "--goal", "DeadEnd")
    assert code == 0, err
    assert doc["pieces"][-1].startswith("turn") and "in place (derived)" in doc["pieces"][-1]
    code, doc, err = call_json(cli, capsys, "analyse", "--character", "Walker")
    f = doc["figures"]
    assert f["goal_root_position_error_cm"] < 10 and f["frames_root_inside_obstacle"] == 0
    assert f["goal_heading_error_deg"] < 5  # facing the way out, as the empty does
    code, doc, err = call_json(
        cli, capsys, "plan", "--character", "Walker", "--goal", "DeadEnd", "--any-facing"
    )
    assert code == 0, err
    assert abs(doc["goal"]["heading_deg"]) < 30  # facing the end wall, not the way out
    code, doc, err = call_json(cli, capsys, "analyse", "--character", "Walker")
    f = doc["figures"]
    assert f["goal_root_position_error_cm"] < 10 and f["frames_root_inside_obstacle"] == 0
    assert f["goal_heading_error_deg"] < 5  # against the facing it chose
    # The same pair as a layout check: both facings reachable.
    spec = {
        "pairs": [
            {"character": "Walker", "goal": "DeadEnd"},
            {"character": "Walker", "goal": "DeadEnd", "goal_facing": "any"},
        ]
    }
    exact, anyway = cli.api.check_layout(bpy.context.scene, spec)
    assert exact["reachable"] and anyway["reachable"] and anyway["goal_facing"] == "any"
    assert abs(anyway["goal"]["heading_deg"]) < 30
