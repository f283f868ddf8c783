# SPDX-License-Identifier: GPL-3.0-or-later
"""Well-formed but absurd patch files are refused naming the field: every numeric array
and header number of a real baked patch pushed to NaN, inf, 0, negative, huge and a wrong
shape (a root 1e30 m out, rotations that are not unit quaternions, a rate that walks 12 m in
12 frames, a 999 m tile, rest matrices x 1e300, a parent loop). Before these checks such
files were read and written as motion, or planning ran out of memory."""

import io
import json

import numpy as np
import pytest

from motion_patches.patch import serialize

PUSHES = ("nan", "inf", "zero", "negative", "huge", "shape")

# Pushes that give a valid patch, and why (each a value a real patch may hold).
VALID = {
    ("seg_pose", "zero"): "every segment in pose cluster 0 (the baked patch has that)",
    ("pose_centres", "zero"): "pose cluster centres are labels' features, any finite value",
    ("pose_centres", "negative"): "pose cluster centres are labels' features, any finite value",
    ("gait_turn_range", "zero"): "(0, 0) is how a gait without turns is stored",
    ("gait_turn_range", "negative"): "(-a, b) -> (a, -b): the range mirrored, still a range",
    ("loop0_scalars", "zero"): "a straight cycle with nothing spread over its seam",
}


@pytest.fixture(scope="module")
def good(walk_patch):
    with np.load(io.BytesIO(serialize.patch_to_bytes(walk_patch))) as z:
        return {k: z[k] for k in z.files}


def pack(d):
    buf = io.BytesIO()
    np.savez_compressed(buf, **d)
    return buf.getvalue()


def pushed(a, how):
    """``a`` with every value pushed ``how`` (dtype kept where the value fits it)."""
    if how == "shape":
        return a[..., None]
    if a.dtype.kind == "b":
        return {"nan": np.full(a.shape, np.nan), "inf": np.full(a.shape, np.inf)}.get(
            how, np.zeros(a.shape, bool) if how == "zero" else np.full(a.shape, -1)
        )
    value = {"nan": np.nan, "inf": np.inf, "zero": 0, "negative": None, "huge": 1e30}[how]
    if how == "negative":
        return -np.abs(a) - (1 if a.dtype.kind in "iu" else 0.5)
    return np.full(a.shape, value, dtype=float if how in ("nan", "inf", "huge") else a.dtype)


NUMERIC = (
    *serialize.SEGMENT_ARRAYS,
    "pose_centres",
    "gait_fps",
    "gait_turn_range",
    "gait_count",
    "skel_parents",
    "skel_rest",
    "loop0_root_local",
    "loop0_rotations",
    "loop0_distance",
    "loop0_contacts",
    "loop0_scalars",
)
HEADER = ("side", "cells", "nodes", "effort_rate", "version")


@pytest.mark.parametrize("how", PUSHES)
@pytest.mark.parametrize("key", NUMERIC)
def test_every_array_pushed_is_refused_naming_it(good, key, how):
    if (key, how) in VALID:
        serialize.patch_from_bytes(pack({**good, key: pushed(good[key], how)}))
        return
    with pytest.raises(ValueError) as err:
        serialize.patch_from_bytes(pack({**good, key: pushed(good[key], how)}))
    assert f"'{key}'" in str(err.value), str(err.value)


@pytest.mark.parametrize("how", PUSHES)
@pytest.mark.parametrize("field", HEADER)
def test_every_header_number_pushed_is_refused_naming_it(good, field, how):
    header = json.loads(str(good["header"]))
    v = header[field]
    header[field] = {
        "nan": float("nan"),
        "inf": float("inf"),
        "zero": 0,
        "negative": -abs(v) - 1,
        "huge": 10**30 if isinstance(v, int) else 1e30,
        "shape": [v],
    }[how]
    data = pack({**good, "header": np.array(json.dumps(header))})
    with pytest.raises(ValueError) as err:
        serialize.patch_from_bytes(data)
    assert field in str(err.value), str(err.value)


def test_the_issue_s_cases_name_their_cause(good):
    """The values a user's broken exporter wrote, each refused with its cause."""
    rot = good["loop0_rotations"]
    rest = good["skel_rest"]
    parents = good["skel_parents"].copy()
    parents[0] = 5  # the root under one of its own descendants
    cases = {
        "loop0_root_local": (good["loop0_root_local"] * 1e30, "'loop0_root_local'"),
        "loop0_rotations": (rot * 1e200, "not 1"),
        "gait_fps": (np.array(999.0), "m/s"),
        "skel_rest": (rest * 1e300, "'skel_rest'"),
        "skel_parents": (parents, "loop"),
    }
    for key, (value, says) in cases.items():
        with pytest.raises(ValueError, match=says):
            serialize.patch_from_bytes(pack({**good, key: value}))
    header = json.loads(str(good["header"]))
    header["side"] = 999.0
    with pytest.raises(ValueError, match="'side' 999"):
        serialize.patch_from_bytes(pack({**good, "header": np.array(json.dumps(header))}))
    distance = good["loop0_distance"].copy()
    distance[5:] -= 0.5
    with pytest.raises(ValueError, match="backwards|below"):
        serialize.patch_from_bytes(pack({**good, "loop0_distance": distance}))


def test_the_baked_patch_still_reads(good, walk_patch):
    p = serialize.patch_from_bytes(pack(good))
    assert p.segment_count == walk_patch.segment_count


def test_the_gait_floor_is_stored_and_older_files_derive_it(good, walk_patch):
    """The floor is written with the patch (no forward kinematics per plan or check); a file
    written before it was stored loads and derives the same value once."""
    assert float(good["gait_floor"]) == walk_patch.gait.floor()
    stored = serialize.patch_from_bytes(pack(good))
    assert stored.gait.floor_height == walk_patch.gait.floor()
    older = serialize.patch_from_bytes(pack({k: v for k, v in good.items() if k != "gait_floor"}))
    assert older.gait.floor_height == pytest.approx(walk_patch.gait.floor(), abs=1e-12)


@pytest.mark.parametrize(
    "value",
    [np.nan, np.inf, -0.5 + 0.0, 1e30, np.array([0.0]), np.array("0.0"), np.array(0)],
    ids=["nan", "inf", "below the feet", "huge", "shape", "text", "integer"],
)
def test_a_bad_gait_floor_is_refused_naming_it(good, value):
    floor = float(good["gait_floor"])
    value = np.array(floor - 0.5 if isinstance(value, float) and value == -0.5 else value)
    with pytest.raises(ValueError) as err:
        serialize.patch_from_bytes(pack({**good, "gait_floor": value}))
    assert "'gait_floor'" in str(err.value), str(err.value)
