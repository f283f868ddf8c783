# SPDX-License-Identifier: GPL-3.0-or-later
"""Cubic keys: a planned crowd's .blend grows less, and the evaluated rig still plays the
plan (every bone within 0.5 degrees of a write keyed on every frame, the hips within a few
millimetres, planted feet held as before). Measured with bench/bench_files.py's code: the
same crowd planned from one saved scene, its actions stored each way, the file saved
before and after, every pose bone read through the depsgraph frame by frame."""

import sys
from pathlib import Path

import bpy
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import bench_files  # noqa: E402

CHARACTERS = 3


@pytest.fixture(scope="module")
def walk30(walk_blend):
    """The walk patch baked at 30 fps (the session's)."""
    return walk_blend


@pytest.mark.parametrize("scene_fps", [30, 24])
def test_cubic_keys_shrink_the_file_and_play_the_plan(walk30, addon_module, tmp_path, scene_fps):
    rows = bench_files.measure_case(bpy, addon_module, walk30, scene_fps, CHARACTERS, tmp_path)
    for how, r in rows.items():
        print(
            f"{scene_fps} fps {how}: {r['kb_per_char_s']:.1f} KB per character-second, "
            f"bones {r['local_deg']:.3f} deg (world {r['world_deg']:.3f}), hips "
            f"{r['hips_mm']:.2f} mm, skate {r['skate_cm_s']:.2f} cm/s, frame_set "
            f"{r['frame_set_ms']:.3f} ms per armature"
        )
    every, linear, cubic = rows["every"], rows["linear"], rows["cubic"]
    assert every["char_s"] == linear["char_s"] == cubic["char_s"]  # the same plans
    assert linear["local_deg"] < 0.01  # linear keys within 1e-5 play the plan
    # every bone within 0.5 degrees of the plan relative to its parent (float32 keys aside)
    assert cubic["local_deg"] <= 0.5 + 0.01
    assert cubic["hips_mm"] <= 3.0
    # planted feet hold: the skate measured on the evaluated toes hardly moves
    assert cubic["skate_cm_s"] <= linear["skate_cm_s"] * 1.1 + 0.2
    assert cubic["kb_per_char_s"] < linear["kb_per_char_s"]
