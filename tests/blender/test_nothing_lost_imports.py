# SPDX-License-Identifier: GPL-3.0-or-later
"""Importing a patch file never overwrites a patch of the scene, and a file with absurd
values is refused naming the field, through the API, the operator and the CLI, leaving the
scene's patches as they were."""

import io
import json

import bpy
import numpy as np
import pytest


@pytest.fixture
def scene(walk_blend):
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    return bpy.context.scene


def patches(scene):
    return [(p.name, p.payload) for p in scene.motion_patches.patches]


def arrays_of(path):
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def write(path, d):
    buf = io.BytesIO()
    np.savez_compressed(buf, **d)
    path.write_bytes(buf.getvalue())
    return path


@pytest.fixture
def other_walk(mp, scene, tmp_path):
    """A file holding another patch named 'walk' (the scene's own, its notes changed)."""
    exported = tmp_path / "walk.mpatch"
    mp.api.export_patch(scene, exported)
    d = arrays_of(exported)
    header = json.loads(str(d["header"]))
    header["stats"] = {**header["stats"], "made_by": "another scene"}
    d["header"] = np.array(json.dumps(header))
    return write(tmp_path / "other walk.mpatch", d)


def test_the_api_imports_beside_a_patch_of_the_same_name(mp, scene, other_walk):
    before = patches(scene)
    name = mp.api.import_patch(scene, other_walk)
    assert name == "walk.001" and name.kept == "walk" and not name.replaced
    assert patches(scene)[: len(before)] == before  # the scene's 'walk' untouched
    assert mp.api.active_patch_name(scene) == "walk.001"


def test_a_taken_name_is_refused_unless_replace(mp, scene, other_walk):
    before = patches(scene)
    with pytest.raises(mp.api.MotionPatchesError, match="already has a patch 'walk'"):
        mp.api.import_patch(scene, other_walk, "walk")
    assert patches(scene) == before
    name = mp.api.import_patch(scene, other_walk, "walk", replace=True)
    assert name == "walk" and name.replaced
    assert [n for n, _ in patches(scene)] == ["walk"] and patches(scene) != before


def test_the_operator_imports_beside_and_says_so(mp, scene, other_walk):
    before = patches(scene)
    assert bpy.ops.motion_patches.import_patch(filepath=str(other_walk)) == {"FINISHED"}
    assert patches(scene)[0] == before[0] and patches(scene)[1][0] == "walk.001"
    assert bpy.ops.motion_patches.import_patch(filepath=str(other_walk), replace=True) == {
        "FINISHED"
    }
    assert [n for n, _ in patches(scene)] == ["walk", "walk.001"]
    assert patches(scene)[0] != before[0]  # asked for: replaced


def test_the_cli_keeps_the_scene_s_patch_and_says_so(mp, scene, other_walk, capsys):
    before = patches(scene)
    code = mp.cli.main(["import", str(other_walk)])
    out, err = capsys.readouterr()
    assert code == 0 and "imported 'walk.001'" in out and "'walk' is kept" in out, out + err
    assert patches(scene)[0] == before[0]
    code = mp.cli.main(["import", str(other_walk), "--name", "walk"])
    out, err = capsys.readouterr()
    assert code == 2 and "already has a patch 'walk'" in err
    code = mp.cli.main(["import", str(other_walk), "--name", "walk", "--replace", "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert code == 0 and doc["patch"] == "walk" and doc["replaced"] is True


def crafted(mp, scene, tmp_path, key, how):
    exported = tmp_path / "walk.mpatch"
    mp.api.export_patch(scene, exported)
    d = arrays_of(exported)
    d[key] = how(d[key])
    return write(tmp_path / f"absurd {key}.mpatch", d)


def cyclic(parents):
    parents = parents.copy()
    parents[0] = 5
    return parents


ABSURD = [
    ("loop0_root_local", lambda a: a * 1e30, "loop0_root_local"),
    ("loop0_rotations", lambda a: a * 1e200, "loop0_rotations"),
    ("loop0_rotations", lambda a: a * 0.0, "loop0_rotations"),
    ("gait_fps", lambda a: np.array(999.0), "gait_fps"),
    ("loop0_distance", lambda a: -a, "loop0_distance"),
    ("skel_rest", lambda a: a * 1e300, "skel_rest"),
    ("skel_parents", cyclic, "skel_parents"),
]


@pytest.mark.parametrize(
    "key,how,named", ABSURD, ids=[f"{k}-{i}" for i, (k, _, _) in enumerate(ABSURD)]
)
def test_absurd_values_are_refused_naming_the_field_at_every_door(
    mp, scene, tmp_path, capsys, key, how, named
):
    path = crafted(mp, scene, tmp_path, key, how)
    before = patches(scene)
    with pytest.raises(mp.api.MotionPatchesError, match=named):
        mp.api.import_patch(scene, path, "absurd")
    with pytest.raises(RuntimeError, match=named):
        bpy.ops.motion_patches.import_patch(filepath=str(path))
    code = mp.cli.main(["import", str(path)])
    out, err = capsys.readouterr()
    assert code == 2 and named in err and "Traceback" not in err
    assert patches(scene) == before
