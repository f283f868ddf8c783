# SPDX-License-Identifier: GPL-3.0-or-later
"""Layout checks as a studio's CI runs them: many .blend files and specs in one process with
one exit status, JUnit XML read back by a JUnit parser from PyPI (junitparser), the pairs
planned on a Dask worker with the same answers, and a second check of an unchanged scene
answered from what the first one built (dropped when a prop moves or its mesh changes)."""

import json
import sys

import bpy
import numpy as np
import pytest
from junitparser import Error, Failure, JUnitXml

from scene_helpers import empty, pillar, walker_from

CAGE = (3.0, -6.0)


@pytest.fixture
def cli(addon_module_name):
    return sys.modules[addon_module_name].cli


@pytest.fixture
def api(addon_module_name):
    return sys.modules[addon_module_name].api


def call(cli, capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def build(walk_blend, path, caged=False, shift=0.0):
    """A layout saved at ``path``: a walker, pillars on the way, a goal; with ``caged`` a
    second goal inside a ring of pillars."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    walker_from(bpy.context.scene.motion_patches.source_armature)
    for n, (x, y) in enumerate([(3.0, 1.0), (4.5, 3.0), (2.5, 4.0)]):
        pillar(f"Pillar{n}", x + shift, y)
    empty("Goal", 7.5, 5.0 + shift, 0.6)
    if caged:
        for n, a in enumerate(np.linspace(0, 2 * np.pi, 25)[:-1]):
            pillar(f"Ring{n:02d}", CAGE[0] + 1.6 * np.cos(a), CAGE[1] + 1.6 * np.sin(a), r=0.3)
        empty("CageGoal", CAGE[0], CAGE[1], 0.0)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


SPEC = {
    "radius": 0.25,
    "pairs": [
        {"name": "to the goal", "character": "Walker", "goal": "Goal"},
        {"name": "from the corner", "start": [0, 0, 90], "goal": "Goal", "max_seconds": 2},
    ],
}
CAGED_SPEC = {"pairs": [{"name": "into the cage", "character": "Walker", "goal": "CageGoal"}]}


@pytest.fixture(scope="module")
def files(walk_blend, tmp_path_factory):
    """Three layouts (one with a cage) and their specs: the shared one, and the caged file's
    own spec beside it (caged.layout.json)."""
    d = tmp_path_factory.mktemp("batch")
    a = build(walk_blend, d / "office.blend")
    b = build(walk_blend, d / "lobby.blend", shift=0.5)
    c = build(walk_blend, d / "caged.blend", caged=True)
    spec = d / "layout.json"
    spec.write_text(json.dumps(SPEC))
    (d / "caged.layout.json").write_text(json.dumps(CAGED_SPEC))
    return {"office": a, "lobby": b, "caged": c, "spec": spec, "dir": d}


def test_many_files_one_process_one_exit_status(cli, capsys, files):
    code, out, err = call(
        cli, capsys, "check", files["office"], files["lobby"], "--spec", files["spec"], "--json"
    )
    doc = json.loads(out)
    assert code == 1 and doc["exit_code"] == 1, err  # "from the corner" is too slow in each
    assert [c["blend"] for c in doc["checks"]] == [str(files["office"]), str(files["lobby"])]
    assert [(c["passed"], c["failed"]) for c in doc["checks"]] == [(1, 1), (1, 1)]
    assert len(doc["pairs"]) == 4 and doc["bad_input"] == 0
    lobby = [p for p in doc["pairs"] if p["blend"] == str(files["lobby"])]
    assert lobby[0]["goal"]["y"] == pytest.approx(5.5)  # its own file's goal, not the first's
    # without the too-tight limit every pair passes: 0
    loose = files["dir"] / "loose.json"
    loose.write_text(json.dumps({**SPEC, "pairs": SPEC["pairs"][:1]}))
    code, out, err = call(cli, capsys, "check", files["office"], files["lobby"], loose)
    assert code == 0, out + err
    assert "check: 2 check(s), 2 pair(s), 2 passed, 0 failed" in out


def test_a_blend_without_a_spec_uses_the_one_beside_it(cli, capsys, files):
    code, out, err = call(cli, capsys, "check", files["caged"], "--json")
    doc = json.loads(out)
    assert code == 1, err
    (pair,) = doc["pairs"]
    assert pair["name"] == "into the cage" and pair["spec"].endswith("caged.layout.json")
    assert pair["blocked_by"] and all(n.startswith("Ring") for n in pair["blocked_by"])


def test_bad_input_in_a_batch_exits_2_and_still_checks_the_others(cli, capsys, files, tmp_path):
    missing = tmp_path / "gone.blend"
    code, out, err = call(
        cli, capsys, "check", files["office"], missing, "--spec", files["spec"], "--json"
    )
    doc = json.loads(out)
    assert code == 2 and doc["bad_input"] == 1
    office, gone = doc["checks"]
    assert office["error"] is None and office["passed"] + office["failed"] == 2
    assert ".blend file not found" in gone["error"] and "gone.blend" in err


def test_junit_report_reads_back_with_junitparser(cli, capsys, files, tmp_path):
    report = tmp_path / "report.xml"
    bad_spec = tmp_path / "typo.json"
    bad_spec.write_text('{"pairs": [{"character": "Walker", "goal": "Nowhere"}]}')
    code, out, err = call(
        cli,
        capsys,
        "check",
        files["office"],
        files["caged"],
        "--spec",
        files["spec"],
        "--spec",
        files["dir"] / "caged.layout.json",
        "--spec",
        bad_spec,
        "--junit",
        report,
    )
    assert code == 2  # the typo spec is bad input; everything else was still checked
    xml = JUnitXml.fromfile(str(report))
    suites = {s.name: s for s in xml}
    # every .blend with every spec: office and caged x layout, caged.layout, typo
    assert set(suites) == {
        "office.layout",
        "office.caged.layout",
        "office.typo",
        "caged.layout",
        "caged.caged.layout",
        "caged.typo",
    }
    cases = {(c.classname, c.name): c for s in xml for c in s}
    assert ("office.layout", "to the goal") in cases
    assert cases[("office.layout", "to the goal")].is_passed
    slow = cases[("office.layout", "from the corner")]
    (failure,) = slow.result
    assert isinstance(failure, Failure) and failure.type == "limit"
    assert "exceeds max_seconds 2" in failure.message
    assert "reachable:" in failure.text and " m, " in failure.text and "cost" in failure.text
    cage = cases[("caged.caged.layout", "into the cage")]
    (failure,) = cage.result
    assert failure.type == "unreachable" and "blocked by Ring" in failure.message
    assert "blocking props (separated): Ring" in failure.text
    # the caged file has no cage goal in office.blend: bad input there, an error case
    (error,) = cases[("office.caged.layout", "layout spec")].result
    assert isinstance(error, Error) and "CageGoal" in error.message
    (error,) = cases[("caged.typo", "layout spec")].result
    assert isinstance(error, Error) and "Nowhere" in error.message
    assert xml.tests == sum(s.tests for s in xml) == 2 + 2 + 1 + 1 + 1 + 1
    assert suites["caged.caged.layout"].failures == 1
    assert suites["office.layout"].failures == 1 and suites["office.layout"].tests == 2
    assert suites["office.typo"].errors == 1


def test_a_single_bad_check_with_junit_still_writes_the_report(cli, capsys, files, tmp_path):
    report = tmp_path / "one.xml"
    bad = tmp_path / "bad.json"
    bad.write_text('{"pairs": []}')
    code, out, err = call(cli, capsys, "check", files["office"], bad, "--junit", report)
    assert code == 2 and out == "" and "non-empty list" in err
    (suite,) = JUnitXml.fromfile(str(report))
    assert suite.errors == 1


FIGURES = ("reachable", "seconds", "frames", "length_m", "cost", "pieces", "expansions")


def test_pairs_planned_on_a_dask_worker_match_in_process(api, files):
    from distributed import LocalCluster  # noqa: F401  (the test needs distributed)

    bpy.ops.wm.open_mainfile(filepath=str(files["caged"]))
    spec = {"pairs": SPEC["pairs"] + CAGED_SPEC["pairs"]}
    api.check_layout(bpy.context.scene, spec)  # warm: the in-process answers are kept
    here = api.check_layout(bpy.context.scene, spec)
    with api.cluster_executor(workers=1) as ex:
        there = api.check_layout(bpy.context.scene, spec, executor=ex)
    assert [r["reused"] for r in there] == [False] * 3  # planned afresh on the worker
    for a, b in zip(here, there):
        assert {k: a[k] for k in FIGURES} == {k: b[k] for k in FIGURES}
        assert (a["blocked_by"], a["failures"], a["goal"]) == (
            b["blocked_by"],
            b["failures"],
            b["goal"],
        )


def test_the_cli_takes_workers_for_a_batch(cli, capsys, files):
    code, out, err = call(
        cli, capsys, "check", files["office"], "--spec", files["spec"], "--workers", "1", "--json"
    )
    doc = json.loads(out)
    assert code == 1 and [p["passed"] for p in doc["pairs"]] == [True, False], err


def test_a_second_check_reuses_and_an_edit_is_seen(api, files):
    bpy.ops.wm.open_mainfile(filepath=str(files["office"]))
    scene = bpy.context.scene
    spec = {"pairs": [{"character": "Walker", "goal": "Goal"}]}
    (first,) = api.check_layout(scene, spec)
    (second,) = api.check_layout(scene, spec)
    assert second["reused"] and {**second, "reused": False} == {**first, "reused": False}
    # a crate put on the goal: a new world, planned, blocked by it
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(7.5, 5.0, 0.5))
    crate = bpy.context.object
    crate.name = "Crate"
    (blocked,) = api.check_layout(scene, spec)
    assert not blocked["reused"] and blocked["blocked_by"] == ["Crate"]
    # moved off the goal: reachable again
    crate.location = (7.5, 8.0, 0.5)
    (moved,) = api.check_layout(scene, spec)
    assert moved["reachable"] and not moved["reused"]
    # its mesh edited in place (same object, same matrix): the footprint follows the mesh
    for v in crate.data.vertices:
        v.co.y -= 3.0  # the box slid back onto the goal by its vertices alone
    crate.data.update()
    (edited,) = api.check_layout(scene, spec)
    assert not edited["reachable"] and edited["blocked_by"] == ["Crate"]


def test_each_pair_leaves_out_only_its_own_excludes(api, files):
    """The scene's footprints are read once for a check, and each pair leaves out its own
    excludes: in one check the pair excluding the cage's ring walks into it, the same pair
    without them is refused by the ring, and with half of them excluded only the other
    half can block it."""
    bpy.ops.wm.open_mainfile(filepath=str(files["caged"]))
    ring = sorted(o.name for o in bpy.data.objects if o.name.startswith("Ring"))
    into = {"character": "Walker", "goal": "CageGoal"}
    spec = {
        "pairs": [
            {**into, "name": "through the ring", "exclude": ring},
            {**into, "name": "round the ring"},
            {**into, "name": "through half of it", "exclude": ring[::2]},
        ]
    }
    through, round_, half = api.check_layout(bpy.context.scene, spec)
    assert through["reachable"] and not round_["reachable"]
    assert set(round_["blocked_by"]) <= set(ring) and round_["blocked_by"]
    assert set(half["blocked_by"]) <= set(ring[1::2])  # the half it still sees, if any


WRAPPER = """
import sys
sys.path.insert(0, {tools!r})
args = sys.argv[1:]
assert args[:3] == ["-b", "-c", "motion_patches"], args  # what the plugin runs Blender with
import blender_session
bpy, addon = blender_session.start()
sys.exit(addon.cli.main(args[3:]))
"""


def test_the_pytest_plugin_collects_the_specs_beside_blend_files(files, tmp_path):
    """tools/pytest-motion-patches: each pair of NAME.layout.* beside NAME.blend is a test
    (Blender started the way the plugin starts it: here bpy as a module behind a wrapper)."""
    import subprocess
    import tomllib
    from pathlib import Path

    from junitparser import JUnitXml

    repo = Path(__file__).resolve().parents[2]
    plugin = repo / "tools" / "pytest-motion-patches"
    meta = tomllib.loads((plugin / "pyproject.toml").read_text())
    assert meta["project"]["entry-points"]["pytest11"] == {
        "motion_patches_layout": "pytest_motion_patches"
    }
    (files["dir"] / "office.layout.toml").write_text(
        '[[pairs]]\nname = "walker to goal"\ncharacter = "Walker"\ngoal = "Goal"\n'
    )
    wrapper = tmp_path / "blender.py"
    wrapper.write_text(WRAPPER.format(tools=str(repo / "tools")))
    report = tmp_path / "pytest.xml"
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "-p",
            "pytest_motion_patches",
            "-p",
            "no:cacheprovider",
            "--rootdir",
            str(files["dir"]),
            "--motion-patches-blender",
            f"{sys.executable} {wrapper}",
            f"--junitxml={report}",
            str(files["dir"]),
        ],
        capture_output=True,
        text=True,
        cwd=files["dir"],
        env={**__import__("os").environ, "PYTHONPATH": str(plugin)},
    )
    assert run.returncode == 1, run.stdout + run.stderr  # the cage's pair fails
    cases = {c.name: c for s in JUnitXml.fromfile(str(report)) for c in s}
    assert set(cases) == {"walker to goal", "into the cage"}
    assert cases["walker to goal"].is_passed
    (failure,) = cases["into the cage"].result
    assert "blocked by Ring" in failure.message or "blocked by Ring" in (failure.text or "")
    assert "1 failed, 1 passed" in run.stdout


def test_a_start_inside_a_prop_is_said_in_the_scenes_coordinates(api, walk_blend):
    """A character 1.5 times the patch's size plans in the scene divided by 1.5; a start
    inside a prop is still reported where it is in the scene, with the scene's radius."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    walker = walker_from(bpy.context.scene.motion_patches.source_armature, location=(3.0, 2.0, 0))
    walker.scale = (1.5, 1.5, 1.5)
    pillar("Around", 3.0, 2.0, r=0.6)
    empty("Goal", 9.0, 2.0, 0.0)
    (r,) = api.check_layout(
        bpy.context.scene,
        {"radius": 0.3, "pairs": [{"character": "Walker", "goal": "Goal"}]},
    )
    assert not r["reachable"]
    assert "the start (3.00, 2.00) is inside or within 0.30 m" in r["error"], r["error"]
