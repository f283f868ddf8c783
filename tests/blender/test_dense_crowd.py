# SPDX-License-Identifier: GPL-3.0-or-later
"""Dense crowds in a 24 fps scene from the 30 fps walk patch, planned with api.plan_crowd
and checked through the depsgraph on every frame (no two roots closer than two radii, none
inside a prop, everyone at its goal): a four-way crossing, 40 walkers entering a 21 m plaza
from its four sides (10 a side) and crossing to shuffled places on the far side between seven
pillars; and a counter-flow, 40 walkers through a 2 m doorway (20 each way), checked after
the file is saved and opened again."""

import time

import bpy
import numpy as np
import pytest

from scene_helpers import empty, pillar, prop_box, walker_from

RADIUS = 0.25
FPS = 24


def face(ob, heading):
    """Turn an armature whose rest faces -Y so that it faces ``heading``."""
    ob.rotation_euler = (0, 0, heading + np.pi / 2)


def build_fourway(src, per_side=10, half=10.5, seed=5):
    """The scene of tests/core/test_crowd_dense.py's four-way crossing, as objects."""
    rng = np.random.default_rng(seed)
    ring = [(3.5 * np.cos(a), 3.5 * np.sin(a)) for a in np.arange(6) * np.pi / 3 + 0.3]
    for k, (x, y) in enumerate([(0.0, 0.0)] + ring):
        pillar(f"Pillar.{k}", x, y, r=0.35)
    lane = np.linspace(-6.5, 6.5, per_side)
    pairs, edge = [], half - 1.0
    sides = (("W", (1, 0), 0.0), ("E", (-1, 0), np.pi), ("S", (0, 1), np.pi / 2))
    for name, d, h in sides + (("N", (0, -1), -np.pi / 2),):
        d = np.array(d, float)
        side = np.array([-d[1], d[0]])
        goals = rng.permutation(per_side)
        for k in range(per_side):
            s = -edge * d + lane[k] * side
            g = (edge - 1.0) * d + (lane[goals[k]] + 0.7) * side
            ob = walker_from(src, f"{name}{k:02d}", (s[0], s[1], 0.0))
            face(ob, h)
            pairs.append((ob, empty(f"Goal{name}{k:02d}", g[0], g[1], h)))
    return pairs


@pytest.fixture(scope="module")
def crossing(walk_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.render.fps = FPS
    pairs = build_fourway(scene.motion_patches.source_armature)
    t0 = time.perf_counter()
    res = api.plan_crowd(scene, pairs, frame_start=1, radius=RADIUS)
    seconds = time.perf_counter() - t0
    return scene, pairs, res, seconds, posed(scene, pairs, res)


def posed(scene, pairs, res, samples=9):
    """(characters, frames, bones, 3) where every bone's head is in the world, through the
    depsgraph, on ``samples`` frames spread over the crowd's."""
    last = max(p.frame_end for p in res.plans)
    out = []
    for f in np.linspace(1, last, samples).round().astype(int):
        scene.frame_set(int(f))
        dg = bpy.context.evaluated_depsgraph_get()
        frame = []
        for ob, _ in pairs:
            ev = ob.evaluated_get(dg)
            m = np.array(ev.matrix_world)
            heads = np.array([pb.head for pb in ev.pose.bones])
            frame.append(heads @ m[:3, :3].T + m[:3, 3])
        out.append(frame)
    return np.array(out).transpose(1, 0, 2, 3)


def build_doorway(src, per_side=20, gap=2.0, seed=5):
    """The scene of tests/core/test_crowd_dense.py's doorway, as objects: a wall 0.3 m thick
    with a ``gap`` m opening, walkers on a staggered grid on each side crossing to shuffled
    places on the other."""
    rng = np.random.default_rng(seed)
    for name, sign in (("Wall.S", -1), ("Wall.N", 1)):
        prop_box(name, 0.0, sign * (14.0 + gap / 2) / 2, size=(0.3, 14.0 - gap / 2, 2.0))
    grid = [
        (x, y + (1.5 if c % 2 else 0.0))
        for c, x in enumerate((3.0, 5.0, 7.0, 9.0))
        for y in np.linspace(-7.5, 4.5, per_side // 4)
    ]
    pairs = []
    for name, sign, h in (("E", 1, 0.0), ("W", -1, np.pi)):
        order = rng.permutation(len(grid))
        for k, (x, y) in enumerate(grid):
            gx, gy = grid[order[k]]
            ob = walker_from(src, f"{name}{k:02d}", (-sign * x, y, 0.0))
            face(ob, h)
            goal = empty(f"Goal{name}{k:02d}", sign * (gx + 1.0), gy + 0.75, h)
            pairs.append((ob, goal))
    return pairs


def planned_and_reopened(walk_blend, api, folder):
    """The doorway planned with plan_crowd, the file saved and opened again: (scene, pairs,
    result, seconds)."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.render.fps = FPS
    pairs = build_doorway(scene.motion_patches.source_armature)
    t0 = time.perf_counter()
    res = api.plan_crowd(scene, pairs, frame_start=1, radius=RADIUS, max_wait_seconds=15.0)
    seconds = time.perf_counter() - t0
    path = folder / "doorway.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    names = [(ob.name, g.name) for ob, g in pairs]
    bpy.ops.wm.open_mainfile(filepath=str(path))
    pairs = [(bpy.data.objects[ob], bpy.data.objects[g]) for ob, g in names]
    return bpy.context.scene, pairs, res, seconds


def roots_and_props(scene, res, api, props):
    """(roots (characters, frames, 2) through the depsgraph, the planned objects, an
    Environment of the ``props`` by name)."""
    from bl_ext.motion_patches_tests.motion_patches.motion_patches.props.environment import (
        Environment,
        Obstacle,
    )

    planned = [bpy.data.objects[p.character] for p in res.plans]
    frames = np.arange(1, max(p.frame_end for p in res.plans) + 1)
    roots = np.empty((len(planned), frames.size, 2))
    for i, f in enumerate(frames):
        scene.frame_set(int(f))
        dg = bpy.context.evaluated_depsgraph_get()
        for c, ob in enumerate(planned):
            ev = ob.evaluated_get(dg)
            root = api.load_plan_record(ob)[0]["root_name"]
            mw = np.array(ev.matrix_world)
            roots[c, i] = (mw @ np.array(ev.pose.bones[root].matrix)[:, 3])[:2]
    env = Environment(1.0, 8, 0.0)
    for name in props:
        ob = bpy.data.objects[name]
        pts = np.array([(ob.matrix_world @ v.co)[:2] for v in ob.data.vertices])
        env.place(Obstacle(ob.name, pts))
    return roots, planned, env


def check_apart(scene, pairs, res, api, props):
    """Everyone planned, no two roots closer than two radii on any frame, none inside a
    prop, everyone at its goal on the last frame."""
    assert len(res.plans) == 40 and not res.failed
    assert not res.conflicts, res.conflicts
    roots, planned, env = roots_and_props(scene, res, api, props)
    d = np.linalg.norm(roots[:, None] - roots[None], axis=-1)
    d[np.arange(len(planned)), np.arange(len(planned))] = np.inf
    print(f"closest roots {d.min():.3f} m")
    assert d.min() >= 2 * RADIUS - 0.01  # the depsgraph evaluates in float32
    for c, ob in enumerate(planned):
        assert not env.blocked(roots[c], radius=0.0).any(), ob.name
    goals = {ob.name: g for ob, g in pairs}
    for c, ob in enumerate(planned):
        at = np.array(goals[ob.name].matrix_world.translation[:2])
        assert np.linalg.norm(roots[c, -1] - at) < 0.35, (ob.name, roots[c, -1], at)


def summary(name, res, seconds):
    return (
        f"{name}: {len(res.plans)} planned, {len(res.conflicts)} conflicts, "
        f"{len(res.holds)} holding, {sum(1 for d in res.delays.values() if d)} waits, "
        f"{len(res.rerouted)} re-routed, {seconds:.1f} s"
    )


def test_a_four_way_crossing_of_forty_at_24_fps_keeps_everyone_apart(crossing, addon_module):
    scene, pairs, res, seconds, _ = crossing
    print(summary("four-way", res, seconds))
    assert res.holds  # holds are laid in at a scene rate other than the patch's
    check_apart(scene, pairs, res, addon_module.api, [f"Pillar.{k}" for k in range(7)])


def test_a_counter_flow_of_forty_through_a_doorway_keeps_everyone_apart(
    walk_blend, addon_module, tmp_path
):
    api = addon_module.api
    scene, pairs, res, seconds = planned_and_reopened(walk_blend, api, tmp_path)
    print(summary("doorway", res, seconds))
    assert res.holds  # walkers hold to let others through the doorway
    for p in res.plans:  # the plans came back with the file
        assert api.load_plan_record(bpy.data.objects[p.character])
    check_apart(scene, pairs, res, api, ["Wall.S", "Wall.N"])


def test_the_four_way_crossing_on_a_local_cluster_is_the_crowd_planned_in_process(
    crossing, walk_blend, addon_module, monkeypatch
):
    """Planned on a Dask LocalCluster of two workers (its members there, its re-plans
    worked out while the resolution places the next characters, the keys of those placed
    as planned fitted then): the same holds, waits, re-routes, strips, frames and costs as
    in process, and every bone where it was, through the depsgraph (within a tenth of a
    millimetre: keys fitted in another process may differ in their last bits)."""
    api = addon_module.api
    _, _, here, _, pose_here = crossing
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.render.fps = FPS
    pairs = build_fourway(scene.motion_patches.source_armature)
    keys = addon_module.api.crowd_keys.Keys
    writing, early = keys.writing, []

    def kept(self, planned):  # the keys fitted early that the writing takes
        writing(self, planned)
        early.append(len(self.asked))

    monkeypatch.setattr(keys, "writing", kept)
    with api.cluster_executor(workers=2) as ex:
        there = api.plan_crowd(scene, pairs, frame_start=1, radius=RADIUS, executor=ex)
    print(summary("four-way, 2 workers", there, 0.0), f"{early[0]} keys fitted early")
    assert 0 < early[0] < len(pairs)
    assert here.rerouted  # re-planned on the workers
    assert there.rerouted == here.rerouted
    assert there.delays == here.delays and there.holds == here.holds
    assert not there.conflicts

    def plans(res):
        return [(p.character, p.frame_start, p.frame_end, p.cost, p.strips) for p in res.plans]

    assert plans(there) == plans(here)
    pose_there = posed(scene, pairs, there)
    off = np.linalg.norm(pose_there - pose_here, axis=-1)
    print(f"bones on the cluster vs in process: {off.max() * 1000:.4f} mm at most")
    assert off.max() < 1e-4
