# SPDX-License-Identifier: GPL-3.0-or-later
"""The sample file saved by the oldest supported Blender opens and plans in this one."""

import bpy
import pytest

from conftest import REPO_ROOT

SAMPLE = REPO_ROOT / "sample_blends" / "demo_walk.blend"


def test_sample_blend_saved_by_blender_4_5_opens_and_replans(addon_module):
    if not SAMPLE.is_file():
        pytest.fail(
            f"{SAMPLE} is missing: ./dev test generates it with Blender 4.5 "
            f"(tools/demo.py) before the Blender suites"
        )
    bpy.ops.wm.open_mainfile(filepath=str(SAMPLE))
    assert tuple(bpy.data.version[:2]) == (4, 5)  # the version that saved the file
    api = addon_module.api
    scene = bpy.context.scene
    assert len(scene.motion_patches.patches) == 1
    walker, goal = bpy.data.objects["Walker"], bpy.data.objects["Goal"]
    goal.location.x -= 1.0
    res = api.plan_path(scene, walker, goal, frame_start=1)
    f = api.analyse(bpy.context, walker)
    assert len(res.pieces) >= 1 and res.pieces[-1] == "goal"
    assert f["goal_root_position_error_cm"] < 10 and f["goal_heading_error_deg"] < 10
    assert f["frames_root_inside_obstacle"] == 0
    hurried = bpy.data.objects["Hurried"]
    names = [s.name for s in hurried.animation_data.nla_tracks["MP motion"].strips]
    assert any("16_06" in n for n in names)  # the hurdle strip written by 4.5 survives


def test_the_documented_layout_spec_passes_on_the_sample(addon_module):
    """examples/demo_layout.toml (shown in the README) checks the sample scene."""
    import tomllib

    if not SAMPLE.is_file():
        pytest.fail(f"{SAMPLE} is missing: ./dev test generates it before the Blender suites")
    bpy.ops.wm.open_mainfile(filepath=str(SAMPLE))
    with open(REPO_ROOT / "examples" / "demo_layout.toml", "rb") as fh:
        spec = tomllib.load(fh)
    nla_before = [t.name for t in bpy.data.objects["Calm"].animation_data.nla_tracks]
    results = addon_module.api.check_layout(bpy.context.scene, spec)
    assert [r["passed"] for r in results] == [True, True, True], [r["failures"] for r in results]
    assert results[1]["traversals"] == 0 and results[1]["reachable"]
    assert [t.name for t in bpy.data.objects["Calm"].animation_data.nla_tracks] == nla_before
    # The same spec with a limit the walk cannot keep: the check fails and says which.
    spec["pairs"][0]["max_seconds"] = 1.0
    r = addon_module.api.check_layout(bpy.context.scene, spec)[0]
    assert not r["passed"] and "exceeds max_seconds" in r["failures"][0]
