# SPDX-License-Identifier: GPL-3.0-or-later
"""The silent cases speak (issue 20, items 4 and 5): bad clips, files, characters, goals and
weights are refused up front with a message naming the cause, and a search that runs out of
nodes says so instead of blaming props."""

import math

import bpy
import numpy as np
import pytest

from scene_helpers import empty, pillar, walker_from


@pytest.fixture(scope="module")
def baked_blend(walk_blend):
    return walk_blend


@pytest.fixture
def walk(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    bpy.context.view_layer.update()
    return scene, char, addon_module.api


def test_a_turn_clip_that_does_not_turn_is_named_at_bake(walk):
    scene, _, api = walk
    arm = scene.motion_patches.source_armature
    straight = bpy.data.actions["16_15"]
    patches = [p.name for p in scene.motion_patches.patches]
    with pytest.raises(api.MotionPatchesError, match="turn clip '16_15' does not turn"):
        api.bake_locomotion_patch(scene, arm, straight, [straight], layer="walk2")
    assert [p.name for p in scene.motion_patches.patches] == patches


def test_a_turn_clip_with_other_bone_names_is_named_at_bake(walk):
    scene, _, api = walk
    arm = scene.motion_patches.source_armature
    other = bpy.data.actions["16_18"].copy()
    other.name = "renamed bones"
    for fc in api.compat.fcurves(other):
        fc.data_path = fc.data_path.replace('pose.bones["', 'pose.bones["mixamo:')
    with pytest.raises(api.MotionPatchesError, match="'renamed bones' animates bones .*mixamo:"):
        api.bake_locomotion_patch(scene, arm, bpy.data.actions["16_15"], [other], layer="walk2")


def test_a_truncated_bvh_is_one_line(walk, mocap_dir, tmp_path):
    _, _, api = walk
    text = (mocap_dir / "cmu" / "16_15.bvh").read_text()
    bad = tmp_path / "cut.bvh"
    bad.write_text(text[: len(text) // 50])  # cut inside the hierarchy
    objects = set(bpy.data.objects)
    with pytest.raises(api.MotionPatchesError) as info:
        api.import_mocap([bad])
    message = str(info.value)
    assert "cut.bvh" in message and "\n" not in message, message
    assert set(bpy.data.objects) == objects


def test_check_and_plan_refuse_a_mesh_as_character_alike(walk):
    scene, _, api = walk
    box = pillar("Box", 3.0, 3.0)
    goal = empty("Goal", 0.0, -5.0, -np.pi / 2)
    with pytest.raises(api.MotionPatchesError, match="must be an armature") as planned:
        api.plan_path(scene, box, goal)
    spec = {"pairs": [{"character": "Box", "goal": "Goal"}]}
    with pytest.raises(api.MotionPatchesError, match="must be an armature") as checked:
        api.check_layout(scene, spec)
    assert str(planned.value) == str(checked.value)


def test_a_goal_where_the_character_stands_is_refused(walk):
    scene, char, api = walk
    skel = api.storage.load_patch(scene, "walk").gait.skeleton
    x, y, h = api.scene_io.character_state(char, skel)
    goal = empty("Here", x, y, h)
    with pytest.raises(api.MotionPatchesError, match="nothing to plan"):
        api.plan_path(scene, char, goal)
    assert char.animation_data is None or not len(char.animation_data.nla_tracks)
    [r] = api.check_layout(scene, {"pairs": [{"character": char.name, "goal": "Here"}]})
    assert not r["reachable"] and "nothing to plan" in r["error"] and r["blocked_by"] == []
    # Turning round on the spot is a plan (a loop), not refused.
    empty("Behind", x, y, h + np.pi)
    [r] = api.check_layout(scene, {"pairs": [{"character": char.name, "goal": "Behind"}]})
    assert r["error"] is None or "nothing to plan" not in r["error"]


@pytest.mark.parametrize(
    "weights, cause",
    [
        (dict(alpha=1e308), "alpha must be a number from 0"),
        (dict(beta=-1.0), "beta must be a number"),
        (dict(gamma=float("nan")), "gamma must be a number"),
        (dict(radius=0.0), "radius must be a number of metres from 0.05 to 2"),
        (dict(radius=float("inf")), "radius must be"),
    ],
)
def test_absurd_weights_are_refused_up_front(walk, weights, cause):
    scene, char, api = walk
    goal = empty("Goal", 0.0, -5.0, -np.pi / 2)
    with pytest.raises(api.MotionPatchesError, match=cause):
        api.plan_path(scene, char, goal, **weights)
    with pytest.raises(api.MotionPatchesError, match=cause):
        api.plan_crowd(scene, [(char, goal)], **weights)
    spec = {"pairs": [{"character": char.name, "goal": "Goal"}], **weights}
    with pytest.raises(api.MotionPatchesError, match=cause):
        api.check_layout(scene, spec)


@pytest.mark.parametrize(
    "goal, cause",
    [
        ((1e12, 0.0, 0.0), "from the origin"),
        ((0.0, -3000.0, -math.pi / 2), "plan the walk in legs"),
    ],
)
def test_absurd_coordinates_are_refused_up_front(walk, goal, cause):
    scene, char, api = walk
    with pytest.raises(api.MotionPatchesError, match=cause):
        api.plan_path(scene, char, goal)
    assert char.animation_data is None or not len(char.animation_data.nla_tracks)


def test_a_400_m_diagonal_plans_or_reports_the_search_limit(walk):
    """Open ground, 400 m on the diagonal: a plan, or the search limit named as the cause
    with the node count (never props: there are none)."""
    scene, char, api = walk
    goal = (283.0, -283.0, -math.pi / 4)
    try:
        res = api.plan_path(scene, char, goal)
    except api.PathNotFound as exc:
        print("400 m diagonal:", exc)
        assert exc.cause == "search limit" and exc.props == []
        assert "search limit reached after" in str(exc) and "props close" not in str(exc)
    else:
        print(f"400 m diagonal: planned, {res.length_m:.1f} m, {res.expansions} nodes")
        assert res.length_m > 399.0
    [r] = api.check_layout(
        scene, {"pairs": [{"character": char.name, "goal": [283.0, -283.0, -45.0]}]}
    )
    print("check:", r["reachable"], r["error"])
    assert r["reachable"] or (
        r["blocked_reason"] == "search limit"
        and r["blocked_by"] == []
        and "search limit reached after" in r["error"]
    )


def test_a_search_limit_hit_is_reported_as_such_not_as_props(walk, addon_module, monkeypatch):
    """The node limit lowered to 20 (a 60 m walk past pillars needs more): plan and check
    name the search limit with its node count, and blame no prop."""
    scene, char, api = walk
    causes = addon_module.motion_patches.planning.causes
    planner_cls = addon_module.motion_patches.planning.planner.SegmentPlanner
    limit = 20
    plan = planner_cls.plan

    def limited(self, start, goal, *args, **kw):
        kw["max_expansions"] = min(kw.get("max_expansions", limit), limit)
        return plan(self, start, goal, *args, **kw)

    monkeypatch.setattr(planner_cls, "plan", limited)
    monkeypatch.setattr(causes, "SEARCH_LIMIT", limit)
    monkeypatch.setattr(causes.plan_explained, "__defaults__", (causes.MARGIN_TILES, limit))
    for k in range(6):
        pillar(f"Pillar{k}", 3.0 * (k % 3) - 3.0, -10.0 - 8.0 * (k // 3), r=0.4)
    goal = empty("Far", 0.0, -60.0, -np.pi / 2)
    with pytest.raises(
        api.PathNotFound, match=f"search limit reached after {limit:,} nodes"
    ) as info:
        api.plan_path(scene, char, goal)
    assert info.value.cause == "search limit" and info.value.props == []
    assert "Pillar" not in str(info.value)
    [r] = api.check_layout(scene, {"pairs": [{"character": char.name, "goal": "Far"}]})
    assert not r["reachable"] and r["blocked_reason"] == "search limit" and r["blocked_by"] == []
    assert f"search limit reached after {limit:,} nodes" in r["error"]


def test_a_yaml_spec_is_told_specs_are_json_or_toml(addon_module, tmp_path):
    cli = addon_module.cli
    spec = tmp_path / "layout.yaml"
    spec.write_text("pairs:\n  - character: Walker\n    goal: Goal\n")
    with pytest.raises(cli.CLIError, match="specs are JSON or TOML") as info:
        cli.load_spec(spec)
    assert info.value.code == cli.BAD_INPUT
    same = tmp_path / "layout.json"
    same.write_text(spec.read_text())
    with pytest.raises(cli.CLIError, match="as JSON \\(specs are JSON, or TOML"):
        cli.load_spec(same)
