# SPDX-License-Identifier: GPL-3.0-or-later
"""Walls as a user models them block as they look (issue 20, item 1): a plane standing up is
a wall, and a room of four walls as one mesh is open inside, with its door the way out."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from


@pytest.fixture(scope="module")
def baked_blend(walk_blend):
    return walk_blend


def plane_wall(name, x, y, length, height=2.0, exact=True):
    """A wall of no thickness along X at ``y``: with ``exact`` a quad whose vertices lie
    exactly in the plane (as an imported or extruded wall has; its plan is a segment),
    else a plane added as a user does (Add > Mesh > Plane), stood up 90° about X and
    scaled (float32 rotation leaves it 1e-7 m thick)."""
    if exact:
        h = length / 2
        me = bpy.data.meshes.new(name)
        me.from_pydata(
            [(x - h, y, 0), (x + h, y, 0), (x + h, y, height), (x - h, y, height)],
            [],
            [(0, 1, 2, 3)],
        )
        ob = bpy.data.objects.new(name, me)
        bpy.context.scene.collection.objects.link(ob)
        return ob
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=(x, y, height / 2))
    ob = bpy.context.object
    ob.name = name
    ob.rotation_euler = (np.pi / 2, 0.0, 0.0)
    ob.scale = (length, height, 1.0)
    return ob


def room(name, x0, y0, x1, y1, door=(None, None), height=2.5):
    """Four plane walls of a room as ONE mesh (corners shared), the front wall (y = y0)
    split round a door from x = door[0] to door[1]."""
    corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    verts = [(x, y, z) for x, y in corners for z in (0.0, height)]
    faces = [(2, 4, 5, 3), (4, 6, 7, 5), (6, 0, 1, 7)]
    a, b = door
    verts += [(a, y0, 0.0), (a, y0, height), (b, y0, 0.0), (b, y0, height)]
    faces += [(0, 8, 9, 1), (10, 2, 3, 11)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def hips_and_record(addon_module, char):
    meta, arrays = addon_module.api.load_plan_record(char)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos = addon_module.adapter.evaluate.sample_armature(bpy.context, char, frames, ["Hips"])[0]
    return pos[:, 0, :2], arrays["ground"][:, :2]


def crossings(xy, y_line, x_lo, x_hi):
    """Frames where a trajectory crosses the line y = y_line between x_lo and x_hi."""
    s = np.sign(xy[:, 1] - y_line)
    k = np.flatnonzero(s[1:] != s[:-1])
    mid = (xy[k, 0] + xy[k + 1, 0]) / 2
    return k[(mid > x_lo) & (mid < x_hi)]


@pytest.mark.parametrize("exact", [True, False], ids=["exact plane", "rotated primitive"])
def test_a_plane_wall_two_metres_high_blocks(baked_blend, addon_module, exact):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    char.rotation_euler[2] = np.pi  # face +Y, towards the wall
    plane_wall("Wall", 0.0, 4.0, 6.0, exact=exact)  # from x = -3 to 3 at y = 4
    goal = empty("Goal", 0.0, 8.0, np.pi / 2)
    bpy.context.view_layer.update()
    addon_module.api.plan_path(scene, char, goal)
    hips, ground = hips_and_record(addon_module, char)
    # Neither the planned ground path nor the evaluated hips cross the wall: it goes round.
    assert crossings(ground, 4.0, -3.0, 3.0).size == 0
    assert crossings(hips, 4.0, -3.0, 3.0).size == 0
    assert np.abs(ground[:, 0]).max() > 3.0  # round one of its ends
    assert np.linalg.norm(hips[-1] - (0.0, 8.0)) < 0.3  # and on to the goal
    assert addon_module.api.analyse(bpy.context, char)["frames_root_inside_obstacle"] == 0


def test_a_start_inside_an_open_room_plans_out_through_its_door(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    room("Room", -4.0, -1.0, 4.0, 7.0, door=(0.5, 2.0))
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 3.0, 0.0))
    goal = empty("Goal", 1.0, -6.0, -np.pi / 2)
    bpy.context.view_layer.update()
    addon_module.api.plan_path(scene, char, goal)  # no longer "start inside 'Room'"
    hips, ground = hips_and_record(addon_module, char)
    for xy in (ground, hips):
        out = crossings(xy, -1.0, -4.5, 4.5)
        assert out.size == 1  # leaves the room once, through the front wall's line ...
        x = (xy[out[0], 0] + xy[out[0] + 1, 0]) / 2
        assert 0.5 < x < 2.0, x  # ... in the door
    assert np.linalg.norm(hips[-1] - (1.0, -6.0)) < 0.3


def test_a_room_without_a_door_boxes_the_start_in_naming_the_room(baked_blend, addon_module):
    bpy.ops.wm.open_mainfile(filepath=str(baked_blend))
    scene = bpy.context.scene
    room("Room", -4.0, -1.0, 4.0, 7.0, door=(1.0, 1.3))  # 0.3 m: narrower than the body
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 3.0, 0.0))
    goal = empty("Goal", 1.0, -6.0, -np.pi / 2)
    bpy.context.view_layer.update()
    with pytest.raises(addon_module.api.PathNotFound, match="Room"):
        addon_module.api.plan_path(scene, char, goal)
    assert char.animation_data is None or len(char.animation_data.nla_tracks) == 0
