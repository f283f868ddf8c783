# SPDX-License-Identifier: GPL-3.0-or-later
"""Props keyframed across a walk (paper Sec. 4.4), judged through the depsgraph: a cart
crossing the path is walked round, a cart that leaves before the character gets there is no
obstacle, one that parks on the goal is reported by name and frame."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from

RADIUS = 0.25


def cart(name, keys, size=(1.2, 0.8, 1.0)):
    """A box as a user keys a cart: location keyframes [(frame, x, y)], linear."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(keys[0][1], keys[0][2], size[2] / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = size
    edit = bpy.context.preferences.edit
    kept = edit.keyframe_new_interpolation_type
    edit.keyframe_new_interpolation_type = "LINEAR"  # the same on every version's actions
    try:
        for f, x, y in keys:
            ob.location = (x, y, size[2] / 2)
            ob.keyframe_insert("location", frame=f)
    finally:
        edit.keyframe_new_interpolation_type = kept
    return ob


def footprint_distance(p, ob):
    """Distance from ground point p to the evaluated box's footprint (0 inside)."""
    dg = bpy.context.evaluated_depsgraph_get()
    m = np.array(ob.evaluated_get(dg).matrix_world)
    local = np.linalg.solve(m, np.array([p[0], p[1], m[2, 3], 1.0]))[:2]
    q = np.clip(local, -0.5, 0.5)  # the unit cube scaled: clamp in its own frame
    sx, sy = np.linalg.norm(m[:3, 0]), np.linalg.norm(m[:3, 1])
    return float(np.hypot((local[0] - q[0]) * sx, (local[1] - q[1]) * sy))


def setup(addon_module, walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.frame_set(1)
    char = walker_from(scene.motion_patches.source_armature, location=(0.0, 0.0, 0.0))
    bpy.context.view_layer.update()
    start = addon_module.adapter.scene.character_state(
        char, addon_module.adapter.storage.load_patch(scene, "walk").gait.skeleton
    )
    d = np.array([np.cos(start[2]), np.sin(start[2])])
    goal = empty("Goal", *(start[:2] + 14.0 * d), start[2])
    return scene, char, goal, start, d


def hips_track(addon_module, char):
    meta, _ = addon_module.api.load_plan_record(char)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    pos, _, _, _ = addon_module.adapter.evaluate.sample_armature(
        bpy.context, char, frames, ["Hips"]
    )
    return frames, pos[:, 0, :2]


def plan(addon_module, char, goal):
    bpy.context.view_layer.update()
    return addon_module.api.plan_path(bpy.context.scene, char, goal, radius=RADIUS, frame_start=1)


def crossing_frame(addon_module, char, goal, start, d, at):
    """Frame and hips point where a plan without any cart passes ``at`` m along the way."""
    plan(addon_module, char, goal)
    frames, hips = hips_track(addon_module, char)
    i = int(np.argmin(np.abs((hips - start[:2]) @ d - at)))
    return int(frames[i]), hips[i]


def clearances(addon_module, char, ob):
    """Hips track (frames, (F, 2)) and the hips' distance to the cart's footprint at every
    planned frame, both through the depsgraph."""
    scene = bpy.context.scene
    frames, hips = hips_track(addon_module, char)
    closest = []
    for fr, h in zip(frames, hips):
        scene.frame_set(int(fr))
        closest.append(footprint_distance(h, ob))
    return frames, hips, np.array(closest)


def check_walk(scene, goal, hips):
    fps = scene.render.fps / scene.render.fps_base
    assert np.linalg.norm(hips[-1] - np.array(goal.location[:2])) < 0.05
    speed = np.linalg.norm(np.diff(hips, axis=0), axis=1) * fps
    assert speed[0] < 0.2 and speed[-1] < 0.2
    assert speed.max() < 2.5  # no jump where a repaired run joins the kept pieces


def test_a_cart_crossing_at_walking_pace_is_waited_for(walk_blend, addon_module):
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    fps = scene.render.fps / scene.render.fps_base
    f, p = crossing_frame(addon_module, char, goal, start, d, 7.0)
    side = np.array([-d[1], d[0]])
    a, b = p - 4.0 * side, p + 4.0 * side  # across the way at 1 m/s, there when the walker is
    ob = cart("Cart", [(1, *a), (int(f - 4 * fps), *a), (int(f + 4 * fps), *b)])
    result = plan(addon_module, char, goal)
    info = result.stats["moving_props"]
    assert info["props"] == ["Cart"] and info["wait_s"] > 0, info
    assert result.frame_start == 1 + round(info["wait_s"] * fps)
    frames, hips, closest = clearances(addon_module, char, ob)
    assert closest.min() > RADIUS - 0.06, closest.min()  # the hips sway ~5 cm off the ground path
    check_walk(scene, goal, hips)
    assert result.length_m < 14.0 * 1.01  # the same straight walk, later
    # Before its first frame the character stands where it starts.
    scene.frame_set(1)
    pos, _, _, _ = addon_module.adapter.evaluate.sample_armature(bpy.context, char, [1], ["Hips"])
    assert np.linalg.norm(pos[0, 0, :2] - hips[0]) < 1e-3


def test_a_slow_cart_crossing_the_path_is_walked_round_keeping_the_other_pieces(
    walk_blend, addon_module
):
    """A long cart (2.4 m) crossing at a crawl (0.2 m/s) would keep the walker waiting longer
    than the longest wait offered: the pieces it meets are re-planned round it, the rest
    of the plan kept."""
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    fps = scene.render.fps / scene.render.fps_base
    f, p = crossing_frame(addon_module, char, goal, start, d, 11.0)
    side = np.array([-d[1], d[0]])
    a, b = p - 2.0 * side, p + 2.0 * side  # 4 m at 0.2 m/s, in the middle when the walker is
    half = 2.0 / 0.2
    assert f - half * fps > 1
    ob = cart(
        "Cart",
        [(1, *a), (int(f - half * fps), *a), (int(f + half * fps), *b)],
        size=(2.4, 2.4, 1.0),
    )
    result = plan(addon_module, char, goal)
    info = result.stats["moving_props"]
    assert info["wait_s"] == 0 and info["repairs"], info
    assert all(r["kept"] >= 1 for r in info["repairs"])  # not the whole plan searched again
    frames, hips, closest = clearances(addon_module, char, ob)
    assert closest.min() > RADIUS - 0.06, closest.min()
    assert np.all(closest > 0.0)
    check_walk(scene, goal, hips)


def test_a_cart_parked_across_the_path_is_walked_round(walk_blend, addon_module):
    """The cart rolls into the way and stays there (falls asleep) before the walker gets
    there: waiting does not help, the path is repaired round it."""
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    f, p = crossing_frame(addon_module, char, goal, start, d, 7.0)
    side = np.array([-d[1], d[0]])
    ob = cart("Cart", [(1, *(p - 4.0 * side)), (20, *(p - 4.0 * side)), (60, *p)])
    assert f > 60
    result = plan(addon_module, char, goal)
    info = result.stats["moving_props"]
    assert info["repairs"] and info["wait_s"] == 0, info
    frames, hips, closest = clearances(addon_module, char, ob)
    assert closest.min() > RADIUS - 0.06, closest.min()
    assert np.all(closest > 0.0)  # never inside the cart
    check_walk(scene, goal, hips)


def test_a_cart_gone_before_the_walker_arrives_changes_nothing(walk_blend, addon_module):
    """Awake at the first frame, the cart takes no part in the global plan (Sec. 4.4) and
    has left the way long before the walker gets there: a straight walk, no repair."""
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    p = start[:2] + 7.0 * d
    side = np.array([-d[1], d[0]])
    cart("Cart", [(1, *p), (40, *(p + 6.0 * side))])
    result = plan(addon_module, char, goal)
    assert result.stats["moving_props"]["awake_at_start"] == ["Cart"]
    assert result.stats["moving_props"]["repairs"] == []
    assert result.length_m < 14.0 * 1.01


def test_a_cart_parking_on_the_goal_is_reported_and_nothing_is_written(walk_blend, addon_module):
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    g = np.array(goal.location[:2])
    side = np.array([-d[1], d[0]])
    cart("Cart", [(1, *(g + 5.0 * side)), (60, *(g + 5.0 * side)), (120, *g)])
    before = char.animation_data.nla_tracks.keys() if char.animation_data else []
    with pytest.raises(
        addon_module.api.PathNotFound, match=r"'Cart' meets the walk at frame \d+"
    ) as e:
        plan(addon_module, char, goal)
    assert e.value.cause == "moving" and e.value.props == ["Cart"]
    after = char.animation_data.nla_tracks.keys() if char.animation_data else []
    assert list(after) == list(before)
    assert scene.frame_current == 1


def test_a_crowd_walks_round_a_cart_parked_across_its_way(walk_blend, addon_module):
    """Plan Crowd follows the props that move too: two walkers side by side, a long cart
    rolling into both their ways before they get there; each walk is repaired round it
    (through the depsgraph, the hips never come within the radius less the sway), and a
    third walker whose goal the cart parks on is reported, the others written."""
    scene, char, goal, start, d = setup(addon_module, walk_blend)
    side = np.array([-d[1], d[0]])
    f, p = crossing_frame(addon_module, char, goal, start, d, 7.0)
    assert f > 60
    other = walker_from(
        scene.motion_patches.source_armature, name="Other", location=(*(start[:2] + 1.5 * side), 0)
    )
    other_goal = empty("OtherGoal", *(start[:2] + 1.5 * side + 14.0 * d), start[2])
    third = walker_from(
        scene.motion_patches.source_armature, name="Third", location=(*(start[:2] - 3.0 * side), 0)
    )
    third_goal = empty("ThirdGoal", *(start[:2] - 3.0 * side + 10.0 * d), start[2])
    ob = cart(
        "Cart",
        [(1, *(p - 6.0 * side)), (20, *(p - 6.0 * side)), (60, *(p + 0.75 * side))],
        size=(1.6, 0.8, 1.0),
    )
    parked = np.array(third_goal.location[:2])
    cart("Blocker", [(1, *(parked - 5.0 * d)), (30, *(parked - 5.0 * d)), (90, *parked)])
    bpy.context.view_layer.update()
    res = addon_module.api.plan_crowd(
        scene,
        [(char, goal), (other, other_goal), (third, third_goal)],
        radius=RADIUS,
        frame_start=1,
    )
    assert [name for name, _ in res.failed] == ["Third"], res.failed
    assert "'Blocker' meets the walk" in res.failed[0][1]
    assert res.moving_conflicts == [], res.moving_conflicts
    for walker, g in ((char, goal), (other, other_goal)):
        frames, hips, closest = clearances(addon_module, walker, ob)
        assert closest.min() > RADIUS - 0.06, (walker.name, closest.min())
        assert np.linalg.norm(hips[-1] - np.array(g.location[:2])) < 0.05
