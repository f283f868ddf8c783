# SPDX-License-Identifier: GPL-3.0-or-later
"""Paths an animator keeps, judged through the depsgraph: straight on open ground, through a
narrow gap, starting and stopping from standing (issue: paths on any scene)."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from


@pytest.fixture(scope="module")
def baked_blend(walk_blend):
    """The session's walk patch (CMU 16_15 + 16_18, conftest.walk_blend)."""
    return walk_blend


def wall_box(name, x0, y0, x1, y1, height=2.0):
    """An axis-aligned box prop from (x0, y0) to (x1, y1), as a user scales a cube."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=((x0 + x1) / 2, (y0 + y1) / 2, height / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = (x1 - x0, y1 - y0, height)
    return ob


def evaluated_hips(addon_module, char):
    """World (x, y) of the hips at every planned frame, through the depsgraph, and fps."""
    meta, _ = addon_module.api.load_plan_record(char)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos, _, _, _ = addon_module.adapter.evaluate.sample_armature(
        bpy.context, char, frames, ["Hips"]
    )
    scene = bpy.context.scene
    return pos[:, 0, :2], scene.render.fps / scene.render.fps_base


def plan(addon_module, char, goal, **kw):
    bpy.context.view_layer.update()
    return addon_module.api.plan_path(bpy.context.scene, char, goal, **kw)


def test_open_ground_walk_goes_straight_and_starts_and_stops_standing(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.7, -0.4, 0.0))
    bpy.context.view_layer.update()
    start = addon_module.adapter.scene.character_state(
        char, addon_module.adapter.storage.load_patch(scene, "walk").gait.skeleton
    )
    d = np.array([np.cos(start[2]), np.sin(start[2])])
    goal = empty("Goal", *(start[:2] + 16.0 * d), start[2])  # 16 m straight ahead, same facing
    result = plan(addon_module, char, goal)
    hips, fps = evaluated_hips(addon_module, char)
    rel = hips - start[:2]
    lateral = rel @ np.array([-d[1], d[0]])
    along = rel @ d
    assert np.abs(lateral).max() < 0.05, np.abs(lateral).max()  # within 5 cm of the line
    assert along[-1] == pytest.approx(16.0, abs=0.1)
    assert result.length_m < 16.0 * 1.01
    speed = np.linalg.norm(np.diff(hips, axis=0), axis=1) * fps
    assert speed[0] < 0.2 and speed[-1] < 0.2, (speed[:3], speed[-3:])
    assert speed.max() > 1.0  # and it does walk at its pace in between


def test_a_gap_of_twice_the_radius_plus_0_3_m_is_used(baked_blend, addon_module):
    """A wall across the way with a 0.8 m gap (radius 0.25): the walk goes through it
    instead of round the wall's ends, and never comes within the radius of the wall."""
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    gap_lo, gap_hi = -0.17, 0.63  # 0.8 m, off the line start-goal and off any cell grid
    wall_box("WallA", -8.0, 4.9, gap_lo, 5.1)
    wall_box("WallB", gap_hi, 4.9, 8.0, 5.1)
    char.rotation_euler[2] = np.pi  # face +Y, towards the wall
    bpy.context.view_layer.update()
    start = addon_module.adapter.scene.character_state(
        char, addon_module.adapter.storage.load_patch(scene, "walk").gait.skeleton
    )
    goal = empty("Goal", start[0], 10.0, np.pi / 2)
    result = plan(addon_module, char, goal)
    figures = addon_module.api.analyse(bpy.context, char)
    assert figures["frames_root_inside_obstacle"] == 0
    meta, arrays = addon_module.api.load_plan_record(char)
    ground = arrays["ground"][:, :2]
    crossing = np.flatnonzero(np.diff(np.sign(ground[:, 1] - 5.0)) != 0)
    assert crossing.size == 1
    x = ground[crossing[0], 0]
    assert gap_lo + 0.25 <= x <= gap_hi - 0.25  # through the gap, clear of both ends
    straight = np.hypot(goal.location.x - start[0], goal.location.y - start[1])
    assert result.length_m < 1.25 * straight  # round a wall end would be over 1.6 x


def walker_facing_away(addon_module, baked_blend, distance=6.0):
    """(scene, walker, its start state, the ground point ``distance`` m behind it)."""
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.3, -0.2, 0.0))
    bpy.context.view_layer.update()
    skel = addon_module.adapter.storage.load_patch(scene, "walk").gait.skeleton
    start = addon_module.adapter.scene.character_state(char, skel)
    behind = start[:2] - distance * np.array([np.cos(start[2]), np.sin(start[2])])
    return scene, char, start, behind


def test_a_goal_behind_facing_minus_y_is_reached_by_turning_on_the_spot(baked_blend, addon_module):
    """The character faces away from a goal 6 m behind it, an unrotated empty (facing -Y as
    a user leaves it): it turns round where it stands (the turn in place derived from the
    walk's sharpest turn loop), walks straight there and turns to face -Y, instead of
    looping twice; evaluated hips path within 10 % of the straight line, feet planted,
    standing at both ends, the end facing -Y."""
    scene, char, start, behind = walker_facing_away(addon_module, baked_blend)
    goal = bpy.data.objects.new("Goal", None)  # an empty as added: no rotation, facing -Y
    scene.collection.objects.link(goal)
    goal.location = (behind[0], behind[1], 0.0)
    result = plan(addon_module, char, goal)
    assert any(p.startswith("turn") for p in result.pieces), result.pieces
    hips, fps = evaluated_hips(addon_module, char)
    length = np.sum(np.linalg.norm(np.diff(hips, axis=0), axis=1))
    assert length < 1.10 * 6.0, length
    assert result.length_m < 1.02 * 6.0
    speed = np.linalg.norm(np.diff(hips, axis=0), axis=1) * fps
    assert speed[0] < 0.2 and speed[-1] < 0.2, (speed[:3], speed[-3:])
    figures = addon_module.api.analyse(bpy.context, char)
    assert figures["goal_heading_error_deg"] < 5.0
    assert figures["goal_root_position_error_cm"] < 5.0
    assert figures["foot_skate"]["mean_cm_per_frame"] < 1.0
    pop = figures["boundary_pop"]  # no pop where the walk and the turns meet
    assert pop["max_boundary_jump_deg"] <= pop["p99_step_deg"], pop


def test_turning_on_the_spot_can_be_switched_off(baked_blend, addon_module):
    """The scene's Turn on the Spot off (or ``turn_in_place=False``): the same walker facing
    away from a goal behind it walks its loops instead, and says so in no strip."""
    scene, char, start, behind = walker_facing_away(addon_module, baked_blend)
    goal = empty("Goal", behind[0], behind[1], start[2])
    assert scene.motion_patches.turn_in_place  # on by default
    turned = plan(addon_module, char, goal)
    assert turned.pieces[0].startswith("turn")
    scene.motion_patches.turn_in_place = False
    looped = plan(addon_module, char, goal)
    assert not any(p.startswith("turn") for p in looped.pieces), looped.pieces
    assert looped.length_m > 1.2 * turned.length_m
    again = plan(addon_module, char, goal, turn_in_place=True)  # given beats the scene's
    assert again.pieces[0].startswith("turn")
    figures = addon_module.api.analyse(bpy.context, char)
    assert figures["goal_heading_error_deg"] < 5.0
