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

from ..kinematics.skeleton import Skeleton, forward_kinematics
from . import curves
from .gait import Gait
from .locomotion_patch import (
    DIRECTIONS,
    EDGES,
    SEGMENT_ARRAYS,
    LocomotionPatch,
    cell_mask,
    node_position,
    split_node_id,
)

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
    gait.floor()  # derived here, once, when the file is older than the stored floor
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
MAX_EXTENT = 100.0  # metres: a rest bone or a loop's root further out is not a character
MIN_CYCLE = 0.01  # metres a locomotion cycle travels at least
MAX_SPEED = 15.0  # m/s: faster than any sprint; a loop moving faster has a wrong rate
MAX_EFFORT_RATE = 1000.0  # effort per second of motion
UNIT_TOL = 1e-3  # rotations must be unit quaternions, rest rotations orthonormal
MAX_FLOOR_GAP = 0.25  # metres: a loop's lowest joint stays this near the floor (z = 0)
MATCH_TOL = 0.02  # a stored segment length or turn may differ this much from its curve's


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
    try:
        finite = bool(np.isfinite(float(v)))
    except OverflowError:  # a whole number past any float
        finite = False
    if (
        not finite
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
            f"locomotion patch format version {version} is newer than this add-on "
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
    _skeleton_sense(d, parents)
    skel = Skeleton.from_dict({k[5:]: d[k] for k in d if k.startswith("skel_")})
    fps = float(d["gait_fps"])
    frames, lows = [], []
    for i in range(loops):
        p = f"loop{i}_"
        n = _array(d, p + "root_local", "f", (None, 3), finite=True).shape[0]
        if n < 2:
            _fail(f"array '{p}root_local' has {n} frames, fewer than 2")
        frames.append(n)
        _array(d, p + "root_local", "f", (n, 3), lo=-MAX_EXTENT, hi=MAX_EXTENT)
        q = _array(d, p + "rotations", "f", (n, j, 4), finite=True)
        with np.errstate(over="ignore"):
            off = float(np.abs(np.linalg.norm(q, axis=-1) - 1.0).max())
        if off > UNIT_TOL:
            _fail(f"array '{p}rotations' holds quaternions of length {1.0 + off:.4g}, not 1")
        dist = _array(d, p + "distance", "f", (n + 1,), finite=True, lo=0.0)
        if (np.diff(dist) < -1e-9).any():
            _fail(f"array '{p}distance' goes backwards (it is the distance travelled)")
        if dist[-1] < MIN_CYCLE:
            _fail(f"array '{p}distance' travels {dist[-1]:.3g} m a cycle, under {MIN_CYCLE:g} m")
        speed = float(dist[-1]) * fps / n
        if speed > MAX_SPEED:
            _fail(
                f"array '{p}distance' with 'gait_fps' {fps:g} moves {speed:.3g} m/s, "
                f"faster than {MAX_SPEED:g} m/s"
            )
        if not _array(d, p + "contacts", "b", (n, 4)).any():
            _fail(f"array '{p}contacts' never puts a foot down")
        low = _lowest_joint(skel, d, p)
        lows.append(low)
        if abs(low) > MAX_FLOOR_GAP:
            _fail(
                f"array '{p}root_local' with 'skel_rest' and '{p}rotations' puts the feet "
                f"{low:+.3g} m from the floor, not within {MAX_FLOOR_GAP:g} m"
            )
        turn, seam = _array(d, p + "scalars", "f", (2,), finite=True)
        if abs(turn) > 4 * np.pi or not 0.0 <= seam <= 180.0:
            _fail(f"array '{p}scalars' (turn {turn:.3g} rad, seam {seam:.3g} deg) is out of range")
        _array(d, p + "name", "U", ())
    _array(d, "gait_turn_range", "f", (2,), lo=-4 * np.pi, hi=4 * np.pi)
    if "gait_floor" in d:  # optional: files written before it was stored derive it on load
        # The floor is a low percentile of the lowest foot joint: not below the lowest
        # joint of any loop, and not far above the highest of those.
        _array(d, "gait_floor", "f", (), finite=True, lo=min(lows) - 1e-6)
        _array(d, "gait_floor", "f", (), hi=max(lows) + MAX_FLOOR_GAP)
    _array(d, "pose_centres", "f", (k, None), lo=-1e3, hi=1e3)
    _segment_sense(d, header, fps, frames)
    return header


def _skeleton_sense(d, parents):
    """Rest matrices that are rigid placements within reach, and parents that lead to a root."""
    rest = d["skel_rest"]
    rot = rest[:, :3, :3]
    with np.errstate(over="ignore", invalid="ignore"):
        ortho = np.abs(rot @ rot.transpose(0, 2, 1) - np.eye(3)).max()
    if ortho > UNIT_TOL or (np.linalg.det(rot) < 0).any():
        _fail("array 'skel_rest' holds matrices that are not rotations (scaled or mirrored)")
    if np.abs(rest[:, 3] - (0.0, 0.0, 0.0, 1.0)).max() > UNIT_TOL:
        _fail("array 'skel_rest' holds matrices whose last row is not (0, 0, 0, 1)")
    reach = np.linalg.norm(rest[:, :3, 3], axis=1)
    if reach.max() > MAX_EXTENT:
        _fail(f"array 'skel_rest' places a bone {reach.max():.3g} m out, over {MAX_EXTENT:g} m")
    if np.ptp(rest[:, :3, 3], axis=0).max() < 1e-3:
        _fail("array 'skel_rest' puts every bone at one point (no bone has a length)")
    up = parents.copy()
    for _ in range(parents.size):  # after j steps up every bone must have reached a root
        up = np.where(up >= 0, parents[np.maximum(up, 0)], -1)
    if (up >= 0).any():
        _fail("array 'skel_parents' has a loop (a bone is its own ancestor)")
    top = np.arange(parents.size)
    for _ in range(parents.size):
        top = np.where(parents[top] >= 0, parents[top], top)
    if np.unique(top).size != 1:
        _fail("array 'skel_parents' has several roots (bones the walking root would not carry)")


def _lowest_joint(skel, d, prefix):
    """Height of the lowest joint over a loop, by forward kinematics of its frames."""
    local = d[prefix + "root_local"]
    root = np.column_stack((np.zeros((local.shape[0], 2)), local[:, 2]))
    with np.errstate(all="ignore"):
        return float(forward_kinematics(skel, root, d[prefix + "rotations"])[..., 2, 3].min())


# How far a segment's curve may land from where its bake put it, relative to the patch's
# side: the curve is summed in another order where numpy's BLAS runs on another CPU or
# with another thread count (OPENBLAS_NUM_THREADS=1, as Dask's workers and many farm nodes
# set it), and a curve that runs along a cell's side then lands a hair into the next cell.
HAIR = 1e-9


def _cells_crossed(points, side, cells):
    """uint64 bitmask (S,) of the cells every curve (S, M, 2) crosses however its points are
    nudged by a hair (:data:`HAIR`): a cell a point enters only by a hair is not counted,
    so a patch baked on one machine loads on another."""
    hair = HAIR * side
    crossed = np.full(points.shape[0], ~np.uint64(0))
    for nudge in ((-hair, -hair), (-hair, hair), (hair, -hair), (hair, hair)):
        crossed &= cell_mask(points + np.array(nudge), side, cells)
    return crossed


def _segment_sense(d, header, fps, frames):
    """Each segment's stored length, turn, cells and effort are what its curve gives."""
    side, nodes = float(header["side"]), int(header["nodes"])
    e0, k0, h0 = split_node_id(d["seg_entry"], nodes)
    e1, k1, h1 = split_node_id(d["seg_exit"], nodes)
    p0, p1 = node_position(e0, k0, side, nodes), node_position(e1, k1, side, nodes)
    scale = d["seg_scale"]
    if scale.max() > 100.0:
        _fail(f"array 'seg_scale' holds {scale.max():.3g}, above 100")
    pos, vel, _ = curves.hermite(
        p0,
        curves.unit(h0 * np.pi / 4),
        p1,
        curves.unit(h1 * np.pi / 4),
        scale,
        np.linspace(0.0, 1.0, 257),
    )
    length = curves.arc_lengths(pos)[:, -1]
    heading = np.unwrap(np.arctan2(vel[..., 1], vel[..., 0]), axis=1)
    turn = np.abs(np.diff(heading, axis=1)).sum(axis=1)
    for key, stored, want, slack in (
        ("seg_length", d["seg_length"], length, 1e-6),
        ("seg_turn", d["seg_turn"], turn, 0.05),
    ):
        bad = np.abs(stored - want) > MATCH_TOL * want + slack
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            _fail(
                f"array '{key}' says {stored[i]:.4g} for segment {i}, whose curve (header "
                f"'side' {side:g}, 'seg_entry', 'seg_exit', 'seg_scale') gives {want[i]:.4g}"
            )
    visited = _cells_crossed(pos[:, ::8], side, int(header["cells"]))
    if ((visited & d["seg_mask"]) != visited).any():
        _fail("array 'seg_mask' leaves out cells its segments' curves cross")
    rate = float(header["effort_rate"])
    if rate > MAX_EFFORT_RATE:
        _fail(f"header field 'effort_rate' is {rate:g}, above {MAX_EFFORT_RATE:g}")
    per_cycle = np.array([min(frames), max(frames)]) / fps * rate
    effort, cycles = d["seg_effort"], d["seg_cycles"]
    low = effort < cycles * per_cycle[0] * (1 - MATCH_TOL) - 1e-9
    high = effort > cycles * per_cycle[1] * (1 + MATCH_TOL) + 1e-9
    if (low | high).any():
        i = int(np.flatnonzero(low | high)[0])
        _fail(
            f"array 'seg_effort' says {effort[i]:.4g} for segment {i}: {cycles[i]} cycles at "
            f"'effort_rate' {rate:g} take {cycles[i] * per_cycle[0]:.4g}-"
            f"{cycles[i] * per_cycle[1]:.4g}"
        )
