# SPDX-License-Identifier: GPL-3.0-or-later
"""Feet that hold on the rig that plays them, judged through the depsgraph.

The session's walk patch (CMU subject 16: 16_15 + 16_18, 30 fps) is planned onto rigs it
was not baked from, both CMU subject 2 (a longer thigh over a shorter shin): Blender's own
BVH import of 02_01 at its defaults, and the same subject named as Mixamo names its bones
and left as Blender's FBX importer leaves a Mixamo character (centimetre bones, Y-up data
under a 90 degree X rotation, object scale 0.01). Each walks on open ground, through two
pillars and round a wall's end (a U-turn), the scenes set out from where the rig stands
and faces. The evaluated toes and ankles, by the label-free foot measure, must: stand on
the first and last frame (both ankles within 3 cm of their standing height), never jump
a planted toe more than 1 cm in one frame, swing every toe more than 0.5 cm above its
planted height, and skate (height-weighted) at most 1.25 times subject 2's own recording
(02_01 at the scene's rate) by the same measure. ``bench/bench_rigs.py`` prints the same
figures.
"""

import functools
from importlib import import_module

import bpy
import numpy as np
import pytest

from scene_helpers import empty, fbx_like_mixamo, native_rig, pillar

# obstacles and the goal in the rig's start frame (its hips over the origin, facing +X):
# pillars (x, y), walls ((x0, y0), (x1, y1)), goal (x, y, heading)
SCENES = {
    "open-ground": ([], [], (6.0, -1.5, -0.2)),
    "pillars": ([(2.6, 0.7), (4.1, 2.7)], [], (6.6, 3.7, 0.3)),
    "u-turn": ([], [((-3.5, -1.0), (2.5, -1.0))], (0.0, -2.0, np.pi)),
}
RIGS = ("bvh-import", "mixamo-cm")


def rig(mocap_dir, kind):
    if kind == "bvh-import":
        return native_rig(mocap_dir, "cmu/02_01.bvh", "Subject2")
    return fbx_like_mixamo(mocap_dir, "Subject2 Mixamo", rel="cmu/02_01.bvh")


def scene_from(addon_module, character, scene):
    """The props and the goal of ``scene`` set out from where ``character`` stands."""
    pillars, walls, (gx, gy, gh) = SCENES[scene]
    skel = addon_module.adapter.rig.skeleton_in_metres(character)
    x0, y0, h0 = addon_module.adapter.scene.character_state(character, skel)
    c, s = np.cos(h0), np.sin(h0)

    def at(x, y):
        return x0 + c * x - s * y, y0 + s * x + c * y

    for k, p in enumerate(pillars):
        pillar(f"Pillar{k}", *at(*p))
    for k, (p, q) in enumerate(walls):
        a, b = np.array(at(*p)), np.array(at(*q))
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=(*(a + b) / 2, 1.0))
        ob = bpy.context.object
        ob.name = f"Wall{k}"
        ob.scale = (float(np.linalg.norm(b - a)), 0.2, 2.0)
        ob.rotation_euler = (0.0, 0.0, float(np.arctan2(*(b - a)[::-1])))
    return empty("Goal", *at(gx, gy), h0 + gh)


@pytest.fixture(scope="module")
def recording(addon_module, mocap_dir):
    """fps -> the label-free figures of subject 2's own walk (02_01) at that rate."""
    core = addon_module.__name__ + ".motion_patches"
    clip = import_module(core + ".kinematics.bvh").read(mocap_dir / "cmu" / "02_01.bvh")
    resample = import_module(core + ".kinematics.clip").resample
    fm = import_module(core + ".quality.foot_measure")
    return functools.cache(lambda fps: fm.of_clip(resample(clip, fps)))


@pytest.mark.parametrize("scene", list(SCENES))
@pytest.mark.parametrize("kind", RIGS)
def test_retargeted_feet_hold_on_the_rig_that_plays_them(
    walk_blend, addon_module, mocap_dir, recording, kind, scene
):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    character = rig(mocap_dir, kind)
    goal = scene_from(addon_module, character, scene)
    res = api.plan_path(bpy.context.scene, character, goal, frame_start=1)
    assert "retargeted" in res.stats["retarget"]
    f = api.analyse(bpy.context, character)
    rec = recording(api.scene_fps(bpy.context.scene))
    feet, own = f["feet"], rec["weighted_skate"]["mean_cm_per_s"]
    summary = addon_module.motion_patches.quality.foot_measure.summary
    print(f"\n{kind}, {scene}: {summary(feet)}; subject 2's recording: {summary(rec)}")
    assert f["goal_position_error_cm"] < 10 and f["frames_root_inside_obstacle"] == 0
    ends = np.abs(
        np.array([feet["first_ankle_cm"], feet["last_ankle_cm"]])
        - np.array(feet["standing_ankle_cm"])
    )
    assert ends.max() <= 3.0  # both ankles stand on the first and last frame
    assert feet["pops"] == 0  # no planted toe jumps more than 1 cm in one frame
    assert feet["swings"] > 0 and feet["min_swing_clearance_cm"] > 0.5
    assert feet["weighted_skate"]["mean_cm_per_s"] <= 1.25 * own
