# SPDX-License-Identifier: GPL-3.0-or-later
"""Patch files are validated before anything is stored (issue 20, item 3): truncated or
damaged bytes and crafted headers and arrays are refused naming the cause."""

import io
import json

import numpy as np
import pytest

from motion_patches.patch import serialize


@pytest.fixture(scope="module")
def good(walk_patch):
    return serialize.patch_to_bytes(walk_patch)


def arrays_of(data):
    with np.load(io.BytesIO(data)) as z:
        return {k: z[k] for k in z.files}


def pack(d):
    buf = io.BytesIO()
    np.savez_compressed(buf, **d)
    return buf.getvalue()


def crafted(good, fields=None, **arrays):
    """The good file with header fields replaced (``fields``: dict of changes, None
    removing a field, or any JSON value for the whole header) and arrays replaced (None:
    removed)."""
    d = arrays_of(good)
    h = json.loads(str(d["header"]))
    if isinstance(fields, dict):
        for k, v in fields.items():
            if v is None:
                h.pop(k)
            else:
                h[k] = v
    elif fields is not None:
        h = fields
    d["header"] = np.array(json.dumps(h))
    for k, v in arrays.items():
        if v is None:
            d.pop(k)
        else:
            d[k] = v
    return pack(d)


def test_the_good_file_reads_back(good, walk_patch):
    p = serialize.patch_from_bytes(good)
    assert p.segment_count == walk_patch.segment_count
    assert np.array_equal(p.seg_mask, walk_patch.seg_mask)


def test_a_patch_loads_where_its_curves_land_a_hair_apart(good, monkeypatch):
    """numpy's BLAS sums in another order on another CPU or thread count (Dask's workers
    and many farm nodes set OPENBLAS_NUM_THREADS=1): a segment's curve that runs along a
    cell's side then lands a hair into the next cell. The patch still loads either way; a
    cell a curve crosses that the mask leaves out is still refused."""
    from motion_patches.patch.locomotion_patch import cell_mask

    hermite = serialize.curves.hermite
    d = arrays_of(good)
    header = json.loads(str(d["header"]))
    side, cells = float(header["side"]), int(header["cells"])
    left_out = []
    for nudge in (-1e-13, 1e-13):
        seen = []

        def nudged(*args, nudge=nudge, seen=seen):
            pos, vel, acc = hermite(*args)
            seen.append(pos + nudge)
            return seen[-1], vel, acc

        monkeypatch.setattr(serialize.curves, "hermite", nudged)
        serialize.patch_from_bytes(good)
        plain = cell_mask(seen[0][:, ::8], side, cells)
        left_out.append(bool(((plain & d["seg_mask"]) != plain).any()))
    assert any(left_out)  # counted plainly, one nudge leaves the stored mask short
    crossed = serialize._cells_crossed(seen[0][:, ::8], side, cells)
    mask = d["seg_mask"].copy()
    mask[0] &= ~(crossed[0] & (~crossed[0] + np.uint64(1)))  # a cell its curve crosses
    with pytest.raises(ValueError, match="seg_mask"):
        serialize.patch_from_bytes(crafted(good, seg_mask=mask))


@pytest.mark.parametrize("fraction", [0.0, 0.1, 0.5, 0.9, 0.999])
def test_truncated_files_are_refused(good, fraction):
    with pytest.raises(ValueError, match="not a stored locomotion patch"):
        serialize.patch_from_bytes(good[: int(len(good) * fraction)])


def test_flipped_bytes_are_refused_or_change_nothing(good, walk_patch):
    """300 single-byte flips at random places: each either refused, or (a flip in a field
    numpy does not read, e.g. a zip time stamp) a patch identical to the original."""
    rng = np.random.default_rng(20)
    refused = same = 0
    for pos in rng.integers(0, len(good), 300):
        bad = bytearray(good)
        bad[pos] ^= 0xFF
        try:
            p = serialize.patch_from_bytes(bytes(bad))
        except ValueError:
            refused += 1
            continue
        for k in serialize._ARRAYS[:-1]:
            assert np.array_equal(getattr(p, k), getattr(walk_patch, k)), (pos, k)
        same += 1
    assert refused + same == 300 and refused > 250


def _cases(d):
    """{case: (arrays to replace, cause the message names)} for the good file's arrays."""
    s = d["seg_entry"].shape[0]
    return {
        "NaN scales": (dict(seg_scale=np.full(s, np.nan)), "'seg_scale' holds NaN"),
        "short lengths": (dict(seg_length=d["seg_length"][:-5]), "'seg_length' has shape"),
        "float mask": (dict(seg_mask=d["seg_mask"].astype(float)), "'seg_mask' has dtype"),
        "no turn array": (dict(seg_turn=None), "'seg_turn' is missing"),
        "zero cycles": (dict(seg_cycles=np.zeros(s, np.int64)), "'seg_cycles' holds 0"),
        "node id too large": (dict(seg_exit=np.full(s, 10_000)), "'seg_exit' holds 10000"),
        "pose cluster out of range": (dict(seg_pose=np.full((s, 2), 7)), "'seg_pose' holds 7"),
        "no segments": ({k: d[k][:0] for k in serialize._ARRAYS[:-1]}, "no segments"),
        "inf rest pose": (
            dict(skel_rest=np.full_like(d["skel_rest"], np.inf)),
            "'skel_rest' holds NaN or infinite",
        ),
        "one loop missing": (dict(loop1_rotations=None), "'loop1_rotations' is missing"),
        "short rotations": (
            dict(loop0_rotations=d["loop0_rotations"][:, :3]),
            "'loop0_rotations' has shape",
        ),
        "NaN fps": (dict(gait_fps=np.array(np.nan)), "'gait_fps' holds NaN"),
        "bone its own parent": (dict(skel_parents=np.arange(d["skel_parents"].size)), "own parent"),
        "no header": (dict(header=None), "'header' is missing"),
    }


CASES = [
    "NaN scales",
    "short lengths",
    "float mask",
    "no turn array",
    "zero cycles",
    "node id too large",
    "pose cluster out of range",
    "no segments",
    "inf rest pose",
    "one loop missing",
    "short rotations",
    "NaN fps",
    "bone its own parent",
    "no header",
]


@pytest.mark.parametrize("case", CASES)
def test_crafted_arrays_are_refused_naming_the_array(good, case):
    arrays, cause = _cases(arrays_of(good))[case]
    with pytest.raises(ValueError, match=cause.replace("(", r"\(")):
        serialize.patch_from_bytes(crafted(good, **arrays))


@pytest.mark.parametrize(
    "header, cause",
    [
        ([1, 2, 3], "header is a list"),
        ("walk", "header is a str"),
        ({"side": -2.6}, "'side' is -2.6"),
        ({"side": "2.6"}, "'side' is '2.6', not a number"),
        ({"cells": 0}, "'cells' is 0"),
        ({"cells": 9}, "'cells' is 9"),
        ({"cells": 8.0}, "'cells' is 8.0, not a whole number"),
        ({"nodes": -1}, "'nodes' is -1"),
        ({"effort_rate": -1.0}, "'effort_rate' is -1.0"),
        ({"layer": ""}, "'layer' is ''"),
        ({"layer": None}, "'layer' is None"),
        ({"stats": None}, "'stats' is None"),
        ({"side": None}, "'side' is None"),
        ({"cells": None}, "'cells' is None"),
        ({"version": None}, "'version' is None"),
        ({"version": 0}, "'version' is 0"),
        ({"version": "1"}, "'version' is '1'"),
        ({"version": 99}, "format version 99 is newer"),
        ({"format": "something else"}, "wrong format tag"),
    ],
)
def test_crafted_headers_are_refused_naming_the_field(good, header, cause):
    with pytest.raises(ValueError, match=cause.replace("(", r"\(")):
        serialize.patch_from_bytes(crafted(good, header))


def test_the_schema_version_is_written(good):
    assert json.loads(str(arrays_of(good)["header"]))["version"] == serialize.VERSION
