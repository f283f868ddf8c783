# SPDX-License-Identifier: GPL-3.0-or-later
"""Duplicate Crowd (issue 17): a source armature copied into a linked crowd and planned,
and crowd requests that cannot be carried out refused with the scene unchanged."""

import json

import bpy
import numpy as np
import pytest

from scene_helpers import empty, pillar, prop_box, walker_from


def open_walk(walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    return scene, scene.motion_patches.source_armature


def snapshot():
    return (
        sorted(o.name for o in bpy.data.objects),
        sorted(c.name for c in bpy.data.collections),
        sorted(a.name for a in bpy.data.actions),
    )


def test_duplicate_crowd_makes_a_linked_crowd_and_plans_it(walk_blend, addon_module):
    api = addon_module.api
    scene, src = open_walk(walk_blend)
    prop_box("Crate", 0.0, 0.0, (1.0, 1.0, 1.0))  # in the way of some
    bpy.context.view_layer.objects.active = src
    before_src = src.animation_data.action if src.animation_data else None
    assert bpy.ops.motion_patches.duplicate_crowd(
        count=6,
        region_min=(-7.0, -3.0),
        region_max=(-4.0, 3.0),
        goal_min=(4.0, -3.0),
        goal_max=(7.0, 3.0),
        seed=3,
    ) == {"FINISHED"}
    crowd = [
        o
        for o in bpy.data.objects
        if o.name.startswith(f"{src.name}.crowd") and o.type == "ARMATURE"
    ]
    assert len(crowd) == 6
    assert all(o.data == src.data for o in crowd)  # linked armature data
    assert (src.animation_data.action if src.animation_data else None) == before_src
    end = max(api.load_plan_record(o)[0]["frame_end"] for o in crowd)
    roots = []
    for f in (end,):
        scene.frame_set(f)
        for o in crowd:
            goal = o.motion_patches_character.goal
            assert goal is not None and 4.0 <= goal.location.x <= 7.0
            roots.append(
                (
                    np.array(o.matrix_world.translation[:2]),
                    np.array(goal.matrix_world.translation[:2]),
                )
            )
    for at, goal in roots:
        assert np.linalg.norm(at - goal) < 0.3


@pytest.mark.parametrize(
    "kw, match",
    [
        (
            dict(count=40, region_min=(-5.0, -1.0), region_max=(-4.0, 0.0)),
            "cannot hold 40 characters",
        ),
        (dict(count=3, region_min=(-5.0, -1.0), region_max=(-6.0, 0.0)), "second corner"),
    ],
)
def test_duplicate_crowd_refuses_what_it_cannot_do_and_leaves_the_scene(
    walk_blend, kw, match, addon_module
):
    api = addon_module.api
    scene, src = open_walk(walk_blend)
    before = snapshot()
    with pytest.raises(api.MotionPatchesError, match=match):
        api.duplicate_crowd(
            scene, src, kw["count"], (kw["region_min"], kw["region_max"]), ((4.0, -3.0), (7.0, 3.0))
        )
    bpy.context.view_layer.objects.active = src
    with pytest.raises(RuntimeError, match=match):
        bpy.ops.motion_patches.duplicate_crowd(goal_min=(4.0, -3.0), goal_max=(7.0, 3.0), **kw)
    assert snapshot() == before


def test_a_character_the_patch_cannot_play_is_refused(walk_blend, addon_module):
    """A crowd member without a patch to play: an armature whose bones are not the patch's."""
    api = addon_module.api
    scene, src = open_walk(walk_blend)
    arm = bpy.data.armatures.new("Stick")
    stick = bpy.data.objects.new("Stick", arm)
    scene.collection.objects.link(stick)
    bpy.context.view_layer.objects.active = stick
    bpy.ops.object.mode_set(mode="EDIT")
    b = arm.edit_bones.new("Bone")
    b.head, b.tail = (0, 0, 0), (0, 0, 1)
    bpy.ops.object.mode_set(mode="OBJECT")
    walker = walker_from(src, "Walker", (-5.0, 0.0, 0.0))
    before = snapshot()
    with pytest.raises(api.MotionPatchesError, match="Stick"):
        api.plan_crowd(
            scene, [(walker, empty("G1", 5.0, 0.0, 0.0)), (stick, empty("G2", 5.0, 2.0, 0.0))]
        )
    with pytest.raises(RuntimeError, match="Stick"):
        bpy.ops.motion_patches.duplicate_crowd(count=2)
    assert snapshot()[1:] == before[1:]  # no collection, no action made
    assert walker.animation_data is None or not walker.animation_data.nla_tracks


def test_two_characters_to_one_seat_or_a_goal_never_free_are_refused(walk_blend, addon_module):
    api = addon_module.api
    scene, src = open_walk(walk_blend)
    a = walker_from(src, "A", (-5.0, 0.0, 0.0))
    b = walker_from(src, "B", (-5.0, 2.0, 0.0))
    goal = empty("Spot", 5.0, 0.0, 0.0)
    with pytest.raises(api.MotionPatchesError, match="'Spot' is the goal of both 'A' and 'B'"):
        api.plan_crowd(scene, [(a, goal), (b, goal)])
    near = empty("NearSpot", 5.2, 0.1, 0.0)
    with pytest.raises(api.MotionPatchesError, match="never find its goal free"):
        api.plan_crowd(scene, [(a, goal), (b, near)])
    for ob in (a, b):
        assert ob.animation_data is None or not ob.animation_data.nla_tracks


def test_a_plan_record_lists_the_props_near_its_path_not_every_prop(walk_blend, addon_module):
    """Two walkers cross a prop each; forty pillars stand 40 m away. Each record lists the
    prop it walked round (the overlay draws it, the analysis checks the root against it),
    none of the far pillars: a crowd's records do not grow with the scene's props. The
    analysis still finds no root inside a prop, and the overlay still draws the near one."""
    api = addon_module.api
    scene, src = open_walk(walk_blend)
    for k in range(40):
        pillar(f"Far{k}", 40.0 + (k % 8), 40.0 + (k // 8))
    prop_box("CrateA", 3.0, 0.0, (0.6, 0.6, 1.0))
    prop_box("CrateB", 3.0, 4.0, (0.6, 0.6, 1.0))
    a = walker_from(src, "A", (0.0, 0.0, 0.0))
    b = walker_from(src, "B", (0.0, 4.0, 0.0))
    res = api.plan_crowd(
        scene, [(a, empty("GA", 6.5, 0.0, 0.0)), (b, empty("GB", 6.5, 4.0, 0.0))], frame_start=1
    )
    assert len(res.plans) == 2 and not res.conflicts
    for ob, mine in ((a, "CrateA"), (b, "CrateB")):
        listed = api.load_plan_record(ob)[0]["obstacles"]
        assert mine in listed and not any(n.startswith("Far") for n in listed), sorted(listed)
        assert api.analyse(bpy.context, ob)["frames_root_inside_obstacle"] == 0
    drawn = api.overlay.plan_drawings(scene)
    assert len(drawn) == 2 and all(1 <= len(d.obstacles) <= 2 for d in drawn)
    assert all(d.occluded for d in drawn)  # the lattice cells the near crate covers


def test_a_crowds_own_meshes_are_no_obstacles_read_from_one_map(walk_blend, addon_module):
    """A character's body mesh (a child, with a grandchild) standing over its start and a
    marker mesh under each goal are no obstacle for the crowd, found from the file's
    children read once (_children_map) as children_recursive finds them; another prop still
    is one."""
    common = addon_module.api.common
    scene, src = open_walk(walk_blend)
    a = walker_from(src, "A", (0.0, 0.0, 0.0))
    b = walker_from(src, "B", (0.0, 4.0, 0.0))
    body = prop_box("BodyA", 0.0, 0.0, (0.5, 0.5, 1.6))
    body.parent = a
    badge = prop_box("BadgeA", 0.0, 0.1, (0.1, 0.1, 0.1))
    badge.parent = body
    goals = [empty("GA", 6.5, 0.0, 0.0), empty("GB", 6.5, 4.0, 0.0)]
    for g in goals:
        mark = prop_box(f"Mark{g.name}", 6.5, g.location[1], (0.4, 0.4, 0.05))
        mark.parent = g
    prop_box("CrateB", 3.0, 4.0, (0.6, 0.6, 1.0))
    objects = [a, b, *goals]
    kids = common._children_map()
    assert (
        {o.name for o in common._not_obstacles(objects, kids)}
        == {o.name for o in common._not_obstacles(objects)}
        == {"A", "B", "GA", "GB", "BodyA", "BadgeA", "MarkGA", "MarkGB"}
    )
    res = addon_module.api.plan_crowd(scene, list(zip((a, b), goals)), frame_start=1)
    assert len(res.plans) == 2 and not res.failed and not res.conflicts
    listed = addon_module.api.load_plan_record(b)[0]["obstacles"]
    assert "CrateB" in listed and "MarkGB" not in listed, sorted(listed)


def test_a_crowd_writes_each_foot_lock_on_top_and_a_re_plan_replaces_it(walk_blend, addon_module):
    """A crowd writes its characters' foot-lock strips after all of them (their keys fitted
    meanwhile): each on the top track, its action kept as the character's own, so planning
    the crowd again replaces it (one foot-lock action per character, none left over)."""
    api = addon_module.api
    nla = addon_module.adapter.nla
    scene, src = open_walk(walk_blend)
    a = walker_from(src, "A", (0.0, 0.0, 0.0))
    b = walker_from(src, "B", (0.0, 3.0, 0.0))
    pairs = [(a, empty("GA", 6.0, 0.5, 0.0)), (b, empty("GB", 6.0, 3.5, 0.0))]
    for _ in range(2):
        res = api.plan_crowd(scene, pairs, frame_start=1)
        assert len(res.plans) == 2
        for ob in (a, b):
            tracks = [t.name for t in ob.animation_data.nla_tracks]
            assert tracks[-1] == nla.TRACK_FOOT and nla.TRACK_MOTION in tracks
            lock = ob.animation_data.nla_tracks[nla.TRACK_FOOT].strips[0].action
            assert lock.name == f"MP {ob.name} foot lock"
            owned = json.loads(ob[nla.ACTIONS_KEY]).values()
            assert lock.name in owned and f"MP {ob.name} root" in owned
    names = [x.name for x in bpy.data.actions if "foot lock" in x.name]
    assert sorted(names) == ["MP A foot lock", "MP B foot lock"]


def test_an_objects_obstacles_are_found_by_name_with_its_parts(addon_module):
    """The obstacles of named objects are the object's own or its parts' ("name (part k)"),
    looked up by name: another object whose name starts the same is not one of them, and
    taking them out of the world and putting them back leaves it as it was."""
    solve = addon_module.api.solve
    environment = addon_module.motion_patches.props.environment
    env = environment.Environment(2.0, 8, 0.3)
    square = np.array([[0.0, 0.0], [0.4, 0.0], [0.4, 0.4], [0.0, 0.4]])
    names = ["Wall (part 1)", "Crate", "Wall (part 2)", "Wallpaper (part 1)", "Wall (part 3)"]
    for k, n in enumerate(names):
        env.place(environment.Obstacle(n, square + k))
    got = solve._obstacle_names(env, ["Wall", "Crate", "Door"])
    assert got == ["Wall (part 1)", "Wall (part 2)", "Wall (part 3)", "Crate"]
    with solve._without(env, ["Wall", "Crate"]):
        assert list(env.obstacles) == ["Wallpaper (part 1)"]
    assert sorted(env.obstacles) == sorted(names)
