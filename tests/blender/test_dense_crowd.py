# SPDX-License-Identifier: GPL-3.0-or-later
"""A dense four-way crossing: 40 walkers enter a 21 m plaza from its four sides (10 a side)
and cross to shuffled places on the far side between seven pillars, in a 24 fps scene from
the 30 fps walk patch; planned with api.plan_crowd and checked through the depsgraph on
every frame: no two roots closer than two radii, none inside a pillar."""

import time

import bpy
import numpy as np
import pytest

from scene_helpers import empty, pillar, walker_from

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
    return scene, pairs, res, time.perf_counter() - t0


def test_a_four_way_crossing_of_forty_at_24_fps_keeps_everyone_apart(crossing, addon_module):
    api = addon_module.api
    scene, pairs, res, seconds = crossing
    print(
        f"four-way: {len(res.plans)} planned, {len(res.conflicts)} conflicts, "
        f"{len(res.holds)} holding, {sum(1 for d in res.delays.values() if d)} waits, "
        f"{len(res.rerouted)} re-routed, {seconds:.1f} s"
    )
    assert len(res.plans) == 40 and not res.failed
    assert not res.conflicts, res.conflicts
    assert res.holds  # holds are laid in at a scene rate other than the patch's
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
    d = np.linalg.norm(roots[:, None] - roots[None], axis=-1)
    d[np.arange(len(planned)), np.arange(len(planned))] = np.inf
    print(f"closest roots {d.min():.3f} m")
    assert d.min() >= 2 * RADIUS - 0.01  # the depsgraph evaluates in float32
    from bl_ext.motion_patches_tests.motion_patches.motion_patches.props.environment import (
        Environment,
        Obstacle,
    )

    env = Environment(1.0, 8, 0.0)
    for k in range(7):
        ob = bpy.data.objects[f"Pillar.{k}"]
        pts = np.array([(ob.matrix_world @ v.co)[:2] for v in ob.data.vertices])
        env.place(Obstacle(ob.name, pts))
    for c, ob in enumerate(planned):
        assert not env.blocked(roots[c], radius=0.0).any(), ob.name
    goals = {ob.name: g for ob, g in pairs}
    for c, ob in enumerate(planned):
        at = np.array(goals[ob.name].matrix_world.translation[:2])
        assert np.linalg.norm(roots[c, -1] - at) < 0.35, (ob.name, roots[c, -1], at)
