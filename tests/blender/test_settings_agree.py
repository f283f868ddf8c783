# SPDX-License-Identifier: GPL-3.0-or-later
"""Every planning setting has one default and one range behind every door: the panel's
properties (on the scene and in the add-on preferences), the CLI's flags and the API's
checks all hold what the settings table (``motion_patches/planning/settings.py``) says.
A property, a flag or a check written by hand again, with its own default or range, fails
here.

The CLI is driven as Blender drives it (its handler called with argv); for ``plan`` and
``crowd`` the planner is replaced by a recorder, since what matters is the value that
reaches it; ``check`` plans a short open-floor pair for real at each bound."""

import argparse
import json
import math

import bpy
import pytest

from scene_helpers import empty, walker_from

pytestmark = pytest.mark.usefixtures("addon_module")


@pytest.fixture(scope="module")
def walker_blend(walk_blend, tmp_path_factory):
    """Walker 'A' at the origin and the scene's goal 'Goal' 3 m ahead, on an open floor."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    walker_from(scene.motion_patches.source_armature, "A", (0.0, 0.0, 0.0))
    scene.motion_patches.goal = empty("Goal", 3.0, 0.0, 0.0)
    path = tmp_path_factory.mktemp("settings") / "walker.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


@pytest.fixture
def scene(walker_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walker_blend))
    return bpy.context.scene


# --- the three views of one setting ----------------------------------------------------------


def table(s):
    """(default, range) of a setting as the table gives it: (min, max), the choices, or
    both truth values."""
    if s.kind is float:
        return s.default, (s.minimum, s.maximum)
    if s.kind is bool:
        return s.default, (False, True)
    return s.default, s.values


def panel(prop):
    """(default, range) of a bpy property, worded as :func:`table` words them."""
    if prop.type == "FLOAT":
        return prop.default, (prop.hard_min, prop.hard_max)
    if prop.type == "BOOLEAN":
        return prop.default, (False, True)
    assert prop.type == "ENUM", prop.type
    return prop.default.lower(), tuple(i.identifier.lower() for i in prop.enum_items)


def cli_values(mp, command, s):
    """What the ``command``'s flags can set ``s`` to: ``float`` for a flag that takes a
    number, else the set of its choices and switch values; None when no flag reaches it."""
    parser = mp.cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    actions = [a for a in sub._actions if a.dest == s.name]
    if not actions:
        return None
    values = set()
    for a in actions:
        if isinstance(a, argparse.BooleanOptionalAction):
            values |= {True, False}
        elif a.choices:
            values |= set(a.choices)
        elif a.nargs == 0:  # a switch
            values.add(a.const)
        else:
            return float  # takes a number: which ones is tried by running the CLI
    return values


def bounds(s):
    """The values at the edges of the setting's range (all of them for a choice)."""
    if s.kind is float:
        return [s.minimum, s.maximum]
    if s.kind is bool:
        return [True, False]
    return list(s.values)


def just_outside(s):
    """Values just past the range's edges (a word that is no choice), none for a bool."""
    if s.kind is float:
        return [s.minimum - 1e-6 * max(1.0, abs(s.minimum)), s.maximum * (1 + 1e-6) + 1e-6]
    if s.kind is str:
        return ["sideways"]
    return []


def named(s, message):
    """Whether ``message`` names the setting (as the API words it, or as its flag)."""
    return s.name.replace("_", " ") in message.replace("-", " ")


def argv_for(s, value):
    """The flags that ask for ``value`` of ``s``, in the table's words."""
    for v, words, _ in s.switches:
        if v == value:
            return ["--" + words]
    if s.switches:
        return []  # a value no switch asks for: only the API can be given it
    words = "--" + (s.flag or s.name).replace("_", "-")
    if s.kind is bool:
        return [words if value else "--no-" + words[2:]]
    return [f"{words}={value!r}" if s.kind is float else f"{words}={value}"]


def same(a, b):
    """Equal, floats as Blender stores them (single precision)."""
    if isinstance(a, float) or isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-9)
    return a == b


# --- the panel -------------------------------------------------------------------------------


def test_the_panel_and_the_preferences_hold_the_tables_defaults_and_ranges(
    mp, addon_module_name, clean_scene
):
    prefs = bpy.context.preferences.addons[addon_module_name].preferences
    assert mp.api.SETTINGS
    for owner in (clean_scene.motion_patches, prefs):
        for s in mp.api.SETTINGS:
            prop = owner.bl_rna.properties[s.name]
            (d, r), (td, tr) = panel(prop), table(s)
            where = f"{owner.bl_rna.identifier}.{s.name}"
            assert same(d, td), f"{where}: default {d!r}, the table's {td!r}"
            assert len(r) == len(tr) and all(map(same, r, tr)), f"{where}: {r}, the table's {tr}"
            assert prop.name == s.label, where
    for s in mp.api.SETTINGS:  # a new scene starts from the defaults
        v = getattr(clean_scene.motion_patches, s.name)
        assert same(v.lower() if isinstance(v, str) else v, s.default), s.name


# --- the API ---------------------------------------------------------------------------------


def test_the_api_takes_the_bounds_and_refuses_just_past_them(mp, scene):
    api = mp.api
    given = api.planning_settings(scene)  # nothing given: the scene's, the table's defaults
    for s in api.SETTINGS:
        assert same(given[s.name], s.default), s.name
        for v in bounds(s):
            assert same(api.planning_settings(scene, **{s.name: v})[s.name], v), (s.name, v)
        for v in just_outside(s):
            with pytest.raises(api.MotionPatchesError) as refused:
                api.planning_settings(scene, **{s.name: v})
            assert named(s, str(refused.value)), str(refused.value)


# --- the CLI ---------------------------------------------------------------------------------


class Recorded(Exception):
    pass


@pytest.fixture
def recorded(mp, monkeypatch):
    """The planning settings each plan or crowd request hands the API's planner, which then
    stops (nothing is planned: this is about the values)."""
    api = mp.api
    calls = []

    def record(scene, *args, **kw):
        calls.append({s.name: kw[s.name] for s in api.SETTINGS})
        raise api.MotionPatchesError("recorded")

    monkeypatch.setattr(api, "plan_path", record)
    monkeypatch.setattr(api, "plan_crowd", record)
    return calls


def run(mp, capsys, argv):
    """(exit code, error) of the CLI run with ``argv`` and --json."""
    capsys.readouterr()
    code = mp.cli.main([*argv, "--json"])
    return code, json.loads(capsys.readouterr().out).get("error")


REQUESTS = {"plan": ["plan", "--character", "A"], "crowd": ["crowd", "--character", "A"]}


@pytest.mark.parametrize("command", sorted(REQUESTS))
def test_the_cli_flags_reach_the_tables_range_and_default_to_the_scenes(
    mp, scene, recorded, capsys, command
):
    request = REQUESTS[command]
    for s in mp.api.SETTINGS:
        reach = cli_values(mp, command, s)
        assert reach is not None, f"{command} has no flag for {s.name}"
        assert reach is float if s.kind is float else reach == set(bounds(s)), (s.name, reach)
        for v in bounds(s):
            recorded.clear()
            assert argv_for(s, v), (s.name, v)
            assert run(mp, capsys, request + argv_for(s, v)) == (2, "recorded"), (s.name, v)
            assert same(recorded[0][s.name], v), (s.name, v, recorded)
        # Switches cannot ask for a value past the range (their values are the range: above).
        for v in [v for v in just_outside(s) if argv_for(s, v)]:
            recorded.clear()
            code, error = run(mp, capsys, request + argv_for(s, v))
            assert code == 2 and named(s, error) and not recorded, (s.name, v, error)
    # No flag: the scene's setting, whatever it is (here the far end of each range).
    scene_values = {}
    for s in mp.api.SETTINGS:
        v = [b for b in bounds(s) if not same(b, s.default)][-1]
        setattr(scene.motion_patches, s.name, v.upper() if s.kind is str else v)
        scene_values[s.name] = v
    recorded.clear()
    assert run(mp, capsys, request) == (2, "recorded")
    assert all(same(recorded[0][k], v) for k, v in scene_values.items()), recorded


def test_the_check_command_plans_at_the_bounds_and_refuses_just_past_them(
    mp, scene, capsys, tmp_path
):
    """``check`` takes the float settings (a layout spec's own keys) and plans with them."""
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"pairs": [{"character": "A", "goal": "Goal"}]}))
    request = ["check", "--spec", str(spec)]
    weights = [s for s in mp.api.SETTINGS if s.kind is float]
    assert weights
    for s in mp.api.SETTINGS:
        assert cli_values(mp, "check", s) == (float if s.kind is float else None), s.name
    for s in weights:
        for v in bounds(s):
            code, error = run(mp, capsys, request + argv_for(s, v))
            assert code in (0, 1) and error is None, (s.name, v, error)
        for v in just_outside(s):
            code, error = run(mp, capsys, request + argv_for(s, v))
            assert code == 2 and named(s, error), (s.name, v, error)
