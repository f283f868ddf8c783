# SPDX-License-Identifier: GPL-3.0-or-later
"""Locomotion patches to and from bytes (compressed npz), for the .blend and for files.

Only arrays and a JSON header go in, so a stored patch never runs code when loaded. What is
read is checked field by field and array by array before a patch is built from it
(:func:`validate`): a damaged or crafted file is refused naming what is wrong, never stored
to fail later with NaN motion or a division by zero. ``VERSION`` is the schema version
written in the header; files of a newer schema are refused.
"""

import io
import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from .gait import Gait
from .locomotion_patch import DIRECTIONS, EDGES, SEGMENT_ARRAYS, LocomotionPatch

_KIND_NAMES = dict(f="float", i="integer", u="uint64", b="bool", U="text")  # dtype kinds

FORMAT = "motion_patches.locomotion_patch"
VERSION = 1
_ARRAYS = (*SEGMENT_ARRAYS, "pose_centres")


def patch_to_bytes(patch: LocomotionPatch) -> bytes:
    header = {
        "format": FORMAT,
        "version": VERSION,
        "layer": patch.layer,
        "side": patch.side,
        "cells": patch.cells,
        "nodes": patch.nodes,
        "effort_rate": patch.effort_rate,
        "stats": patch.stats,
    }
    arrays = {k: getattr(patch, k) for k in _ARRAYS}
    arrays.update(patch.gait.to_dict())
    arrays["header"] = np.array(json.dumps(header))
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    return buf.getvalue()


def patch_from_bytes(data: bytes) -> LocomotionPatch:
    """Inverse of :func:`patch_to_bytes`; ValueError naming the cause on anything that is
    not a patch this add-on can plan with: every header field and every array's dtype,
    shape and values are checked (:func:`validate`) before a patch is built."""
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as z:
            d = {k: z[k] for k in z.files}
    except Exception as exc:  # malformed bytes of any kind
        raise ValueError(f"not a stored locomotion patch ({exc})") from None
    header = validate(d)
    gait = Gait.from_dict(d)
    return LocomotionPatch(  # type: ignore[call-arg]  # (mypy cannot count the *arrays)
        header["layer"],
        gait,
        float(header["side"]),
        int(header["cells"]),
        int(header["nodes"]),
        float(header["effort_rate"]),
        *(d[k] for k in SEGMENT_ARRAYS),
        d["pose_centres"],
        header["stats"],
    )


MAX_CELLS = 8  # a segment's cell mask is one 64-bit word: cells x cells <= 64
MAX_NODES = 8  # local node ids: EDGES x nodes x DIRECTIONS <= 256 (node_keys.LOCAL)
MAX_LOOPS = 64


def _fail(what):
    raise ValueError(f"not a valid locomotion patch: {what}")


def _array(d, key, kind, shape, finite=False, lo=None, hi=None, hi_open=None):
    """d[key] checked: dtype kind ('f' float, 'i' integer, 'u' uint64, 'b' bool, 'U' text),
    shape (a tuple; None = any length there), finite values, lo <= values <= hi, values
    < hi_open; returns it."""
    if key not in d:
        _fail(f"array '{key}' is missing")
    a = d[key]
    ok = {
        "f": a.dtype.kind == "f",
        "i": a.dtype.kind in "iu",
        "u": a.dtype == np.uint64,
        "b": a.dtype.kind == "b",
        "U": a.dtype.kind == "U",
    }[kind]
    if not ok:
        _fail(f"array '{key}' has dtype {a.dtype}, not {_KIND_NAMES[kind]}")
    if a.ndim != len(shape) or any(n is not None and m != n for m, n in zip(a.shape, shape)):
        want = "(" + ", ".join("N" if n is None else str(n) for n in shape) + ")"
        _fail(f"array '{key}' has shape {a.shape}, not {want}")
    if finite and a.size and not np.isfinite(a).all():
        _fail(f"array '{key}' holds NaN or infinite values")
    if a.size and lo is not None and a.min() < lo:
        _fail(f"array '{key}' holds {a.min()}, below {lo}")
    if a.size and hi is not None and a.max() > hi:
        _fail(f"array '{key}' holds {a.max()}, above {hi}")
    if a.size and hi_open is not None and a.max() >= hi_open:
        _fail(f"array '{key}' holds {a.max()}, not below {hi_open}")
    return a


def _number(header, key, integer=False, lo=None, hi=None, above=None):
    v = header.get(key)
    if isinstance(v, bool) or not isinstance(v, int if integer else (int, float)):
        _fail(f"header field '{key}' is {v!r}, not {'a whole number' if integer else 'a number'}")
    if (
        not np.isfinite(v)
        or (lo is not None and v < lo)
        or (hi is not None and v > hi)
        or (above is not None and v <= above)
    ):
        rng = (f"> {above}" if above is not None else f">= {lo}") + (
            f" and <= {hi}" if hi is not None else ""
        )
        _fail(f"header field '{key}' is {v!r}, not {rng}")
    return v


def validate(d: Mapping[str, np.ndarray]) -> dict[str, Any]:
    """The header (dict) of the arrays ``d`` read from a patch file, after checking the
    header's fields (format tag, schema version, layer, side, cells, nodes, effort rate,
    stats) and every array the patch and its gait are built from; ValueError naming the
    first field or array that is wrong."""
    header_raw = _array(d, "header", "U", ())
    try:
        header = json.loads(str(header_raw))
    except ValueError:
        _fail("its header is not JSON")
    if not isinstance(header, dict):
        _fail(f"its header is a {type(header).__name__}, not a table of fields")
    if header.get("format") != FORMAT:
        raise ValueError("not a stored locomotion patch (wrong format tag)")
    version = header.get("version")
    if isinstance(version, int) and not isinstance(version, bool) and version > VERSION:
        raise ValueError(
            f"locomotion patch format {version} is newer than this add-on "
            f"reads ({VERSION}); update the add-on"
        )
    _number(header, "version", integer=True, lo=1)
    if not isinstance(header.get("layer"), str) or not header["layer"].strip():
        _fail(f"header field 'layer' is {header.get('layer')!r}, not a name")
    _number(header, "side", above=0.0, hi=1000.0)
    _number(header, "cells", integer=True, lo=1, hi=MAX_CELLS)
    nodes = _number(header, "nodes", integer=True, lo=1, hi=MAX_NODES)
    _number(header, "effort_rate", lo=0.0)
    if not isinstance(header.get("stats"), dict):
        _fail(f"header field 'stats' is {header.get('stats')!r}, not a table")
    s = _array(d, "seg_entry", "i", (None,), lo=0, hi_open=EDGES * nodes * DIRECTIONS).shape[0]
    if s == 0:
        _fail("it has no segments")
    _array(d, "seg_exit", "i", (s,), lo=0, hi_open=EDGES * nodes * DIRECTIONS)
    _array(d, "seg_scale", "f", (s,), finite=True, lo=1e-6)
    _array(d, "seg_cycles", "i", (s,), lo=1, hi=1000)
    _array(d, "seg_mask", "u", (s,))
    _array(d, "seg_length", "f", (s,), finite=True, lo=1e-6)
    _array(d, "seg_turn", "f", (s,), finite=True, lo=0.0)
    _array(d, "seg_effort", "f", (s,), finite=True, lo=0.0)
    k = _array(d, "pose_centres", "f", (None, None), finite=True).shape[0]
    if k == 0:
        _fail("array 'pose_centres' is empty")
    _array(d, "seg_pose", "i", (s, 2), lo=0, hi_open=k)
    _array(d, "gait_layer", "U", ())
    _array(d, "gait_fps", "f", (), finite=True, lo=1.0, hi=1000.0)
    _array(d, "gait_turn_range", "f", (2,), finite=True)
    loops = int(_array(d, "gait_count", "i", (), lo=1, hi=MAX_LOOPS))
    _array(d, "gait_notes", "U", (None,))
    j = _array(d, "skel_names", "U", (None,)).shape[0]
    if j == 0 or len(set(d["skel_names"].tolist())) != j:
        _fail("its skeleton's bone names are empty or repeated")
    parents = _array(d, "skel_parents", "i", (j,), lo=-1, hi_open=j)
    if (parents == np.arange(j)).any():
        _fail("array 'skel_parents' makes a bone its own parent")
    _array(d, "skel_rest", "f", (j, 4, 4), finite=True)
    for i in range(loops):
        p = f"loop{i}_"
        n = _array(d, p + "root_local", "f", (None, 3), finite=True).shape[0]
        if n < 2:
            _fail(f"array '{p}root_local' has {n} frames, fewer than 2")
        _array(d, p + "rotations", "f", (n, j, 4), finite=True)
        _array(d, p + "distance", "f", (n + 1,), finite=True)
        _array(d, p + "contacts", "b", (n, 4))
        _array(d, p + "scalars", "f", (2,), finite=True)
        _array(d, p + "name", "U", ())
    return header
