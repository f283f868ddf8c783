# SPDX-License-Identifier: GPL-3.0-or-later
"""The committed sample scenes (samples/, built by tools/samples.py with Blender 4.5) open in
every supported Blender and plan as a newcomer would plan them: the walker across the
hurdles, the sitter from one chair to the other, the crowd; judged on the evaluated rig."""

from pathlib import Path

import bpy
import numpy as np
import pytest

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
MAX_BYTES = 5_000_000


def open_sample(name):
    path = SAMPLES / name
    assert path.is_file(), f"{path} is missing: run tools/samples.py"
    bpy.ops.wm.open_mainfile(filepath=str(path))
    return bpy.context.scene


@pytest.mark.parametrize("name", ["props.blend", "crowd.blend"])
def test_each_sample_is_small_and_saved_by_the_oldest_supported_blender(mp, name):
    assert (SAMPLES / name).stat().st_size < MAX_BYTES
    scene = open_sample(name)
    assert tuple(bpy.data.version[:2]) == (4, 5)  # so 4.5, 5.0 and 5.2 all open it
    assert len(scene.motion_patches.patches) == 1
    armatures = [o for o in scene.objects if o.type == "ARMATURE" and o.visible_get()]
    assert armatures and all(o.animation_data is None for o in armatures)  # nothing planned


def hips(walker, frame):
    bpy.context.scene.frame_set(frame)
    ev = walker.evaluated_get(bpy.context.evaluated_depsgraph_get())
    return np.array(ev.matrix_world @ ev.pose.bones["Hips"].head)


def test_the_walker_crosses_the_hurdles_to_its_goal(mp):
    scene = open_sample("props.blend")
    walker = bpy.data.objects["Walker"]
    bpy.context.view_layer.objects.active = walker
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    f = mp.api.analyse(bpy.context, walker)
    assert f["goal_root_position_error_cm"] < 10
    assert f["frames_root_inside_obstacle"] == 0 and f["frames_body_inside_prop"] == 0
    rec = mp.api.load_plan_record(walker)[0]
    goal = bpy.data.objects["Goal"].location
    end = hips(walker, rec["frame_end"])
    assert np.hypot(end[0] - goal.x, end[1] - goal.y) < 0.1
    assert scene.frame_end >= rec["frame_end"]


def test_the_sitter_stands_up_walks_and_sits_down(mp):
    scene = open_sample("props.blend")
    sitter, a, b = (bpy.data.objects[n] for n in ("Sitter", "Chair A", "Chair B"))
    assert sitter.motion_patches_character.start_prop == a
    scene.motion_patches.goal = b
    bpy.context.view_layer.objects.active = sitter
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    rec = mp.api.load_plan_record(sitter)[0]
    seated = hips(sitter, rec["frame_end"])
    assert seated[2] < 0.75 and np.hypot(seated[0] - b.location.x, seated[1] - b.location.y) < 0.3
    start = hips(sitter, rec["frame_start"])
    assert start[2] < 0.75 and np.hypot(start[0] - a.location.x, start[1] - a.location.y) < 0.3


def test_the_crowd_crosses_without_a_conflict(mp):
    scene = open_sample("crowd.blend")
    walkers = [o for o in scene.objects if o.name.startswith("Walker.")]
    pairs = mp.api.crowd_members(scene, walkers)
    assert len(pairs) == 12
    res = mp.api.plan_crowd(scene, pairs)
    assert not res.failed and not res.conflicts
    radius = scene.motion_patches.radius
    frames = range(scene.frame_start, scene.frame_end + 1, 2)
    tracks = []
    for f in frames:
        scene.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        tracks.append([np.array(w.evaluated_get(dg).matrix_world.translation[:2]) for w in walkers])
    pos = np.array(tracks)  # (F, N, 2) evaluated roots
    d = np.linalg.norm(pos[:, :, None] - pos[:, None], axis=-1)
    d[:, np.arange(len(walkers)), np.arange(len(walkers))] = np.inf
    assert d.min() >= 2 * radius - 0.02
