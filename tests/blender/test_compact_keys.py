# SPDX-License-Identifier: GPL-3.0-or-later
"""Compact keys: a planned crowd's .blend grows less, and the evaluated rig still plays the
plan (every bone within 0.5 degrees of a write keyed on every frame, the hips within a
millimetre, planted feet where they were). Measured with bench/bench_files.py's code: the
same crowd planned from one saved scene, its actions stored each way, the file saved
before and after, every pose bone read through the depsgraph frame by frame."""

import sys
from pathlib import Path

import bpy
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import bench_files  # noqa: E402

CHARACTERS = 3
BOUND_KB = 25.0  # what a crowd's file may grow by per character-second (the bound)
CASES = [(30, 30), (30, 24), (30, 60), (120, 30)]  # patch fps, scene fps


@pytest.fixture(scope="module")
def measured(walk_blend, addon_module, mocap_dir, tmp_path_factory):
    """{(patch fps, scene fps): bench_files rows}, each case measured once for the module
    (the 30 fps patch is the session's; the 120 fps one is baked here)."""
    baked = {30: walk_blend}
    rows = {}

    def case(patch_fps, scene_fps):
        if (patch_fps, scene_fps) not in rows:
            if patch_fps not in baked:
                baked[patch_fps] = tmp_path_factory.mktemp(f"walk{patch_fps}") / "baked.blend"
                bench_files.bake(bpy, addon_module.api, mocap_dir, patch_fps, baked[patch_fps])
            tmp = tmp_path_factory.mktemp(f"files{patch_fps}-{scene_fps}")
            got = bench_files.measure_case(
                bpy, addon_module, baked[patch_fps], scene_fps, CHARACTERS, tmp
            )
            for how, r in got.items():
                print(
                    f"{patch_fps}/{scene_fps} fps {how}: {r['kb_per_char_s']:.1f} KB per "
                    f"character-second, bones {r['local_deg']:.3f} deg (world "
                    f"{r['world_deg']:.3f}), hips {r['hips_mm']:.2f} mm, planted feet "
                    f"{r['planted_mm']:.2f} mm, skate {r['skate_cm_s']:.2f} cm/s, frame_set "
                    f"{r['frame_set_ms']:.3f} ms per armature"
                )
            rows[patch_fps, scene_fps] = got
        return rows[patch_fps, scene_fps]

    return case


@pytest.mark.parametrize("patch_fps,scene_fps", CASES)
def test_compact_keys_shrink_the_file_and_play_the_plan(measured, patch_fps, scene_fps):
    rows = measured(patch_fps, scene_fps)
    every, linear, cubic = rows["every"], rows["linear"], rows["cubic"]
    assert every["char_s"] == linear["char_s"] == cubic["char_s"]  # the same plans
    assert linear["local_deg"] < 0.01  # linear keys within 1e-5 play the plan
    # every bone within 0.5 degrees of the plan relative to its parent (float32 keys aside)
    assert cubic["local_deg"] <= 0.5 + 0.01
    assert cubic["hips_mm"] <= 1.0
    # planted feet stay where the plan (keyed on every frame) puts them
    assert cubic["planted_mm"] <= 2.0
    assert cubic["skate_cm_s"] <= linear["skate_cm_s"] * 1.1 + 0.2
    assert cubic["kb_per_char_s"] < linear["kb_per_char_s"] < every["kb_per_char_s"]


# Blender 4.5 saves .blend files uncompressed by default (5.0 and 5.2 compress them, and
# meet the bound at every rate): there a few walkers' file meets it with a 30 fps patch at a
# scene of its rate or slower, not yet with a faster scene, nor with a 120 fps patch.
NOT_ON_45 = pytest.mark.xfail(
    bpy.app.version < (5, 0, 0),
    strict=True,
    reason="not reached on Blender 4.5 uncompressed: a character's own pieces (start, stop, "
    "connectors) are keyed per character, and captured motion bends on most frames "
    "(docs/benchmarks.md)",
)


@pytest.mark.parametrize(
    "patch_fps,scene_fps",
    [c if c in ((30, 30), (30, 24)) else pytest.param(*c, marks=NOT_ON_45) for c in CASES],
)
def test_a_crowd_file_grows_at_most_the_bound(measured, patch_fps, scene_fps):
    assert measured(patch_fps, scene_fps)["cubic"]["kb_per_char_s"] <= BOUND_KB
