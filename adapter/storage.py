# SPDX-License-Identifier: GPL-3.0-or-later
"""What the add-on keeps inside the .blend: baked patches (scene property group, base64
payload), the plan record of each planned character and the figures of its last analysis
(custom properties on the object). Every reader and writer of these goes through here.

Decoded patches are cached by content hash so planning does not re-decode them.
"""

import base64
import hashlib
import io
import json

import numpy as np

from ..motion_patches.patch import serialize
from ..motion_patches.props.environment import Environment, Obstacle

PLAN_KEY = "motion_patches_plan"  # custom property: the last plan written
# custom property beside it: the record's :func:`plan_fingerprint`, written with it, so the
# overlay's check for changed plans (every redraw) reads 16 characters, not every record
# (a crowd of 1,000: 11 KB each, 10 ms a redraw)
PLAN_ID_KEY = "motion_patches_plan_id"
ANALYSIS_KEY = "motion_patches_analysis"  # custom property: the last analysis figures

_cache = {}


def patch_items(scene):
    return scene.motion_patches.patches


def store_patch(scene, patch, name):
    """Save (or replace) patch ``name`` in the scene; returns the stored item."""
    data = serialize.patch_to_bytes(patch)
    items = patch_items(scene)
    item = items.get(name) or items.add()
    item.name = name
    item.layer = patch.layer
    item.payload = base64.b64encode(data).decode("ascii")
    item.stats = json.dumps(patch.stats)
    item.fps = patch.gait.fps
    _cache[hashlib.sha1(item.payload.encode()).hexdigest()] = patch
    return item


def remember_bake_clips(scene, armature, straight, turns):
    """Keep in the scene's bake settings the clips a patch came from (what the Locomotion
    Patches panel shows and bakes again)."""
    s = scene.motion_patches
    s.source_armature = armature
    s.straight_action = straight
    s.turn_actions.clear()
    for t in turns:
        s.turn_actions.add().action = t


def active_name(scene):
    """The patch used when none is named: the active one, else the first; None when none
    is baked. The one place that decides it."""
    items = patch_items(scene)
    if not len(items):
        return None
    i = scene.motion_patches.active_patch_index
    return (items[i] if 0 <= i < len(items) else items[0]).name


def make_active(scene, name):
    """Make the stored patch ``name`` the one planning uses."""
    scene.motion_patches.active_patch_index = patch_items(scene).find(name)


def _item(scene, name=None):
    items = patch_items(scene)
    if not len(items):
        raise ValueError("no locomotion patch is baked in this scene; bake one first")
    item = items.get(name or active_name(scene))
    if item is None:
        raise ValueError(
            f"no locomotion patch named '{name}' (have: {', '.join(i.name for i in items)})"
        )
    return item


def patch_key(scene, name=None):
    """Short content hash of a stored patch: names the shared segment actions it made."""
    return hashlib.sha1(_item(scene, name).payload.encode()).hexdigest()[:12]


def load_patch(scene, name=None):
    """The stored patch ``name`` (or the active/first one); ValueError when there is none."""
    item = _item(scene, name)
    key = hashlib.sha1(item.payload.encode()).hexdigest()
    if key not in _cache:
        _cache[key] = serialize.patch_from_bytes(base64.b64decode(item.payload))
    return _cache[key]


def export_patch(scene, name, path):
    patch = load_patch(scene, name)
    with open(path, "wb") as fh:
        fh.write(serialize.patch_to_bytes(patch))


def read_patch_file(path):
    """The patch in a .mpatch file, checked (ValueError naming what is wrong)."""
    with open(path, "rb") as fh:
        return serialize.patch_from_bytes(fh.read())


def free_patch_name(scene, base):
    """``base``, or Blender's way of naming a copy (``base.001``, ...) when it is taken."""
    items = patch_items(scene)
    if items.get(base) is None:
        return base
    n = 1
    while items.get(f"{base}.{n:03d}") is not None:
        n += 1
    return f"{base}.{n:03d}"


# --- plan records ---------------------------------------------------------------------------


# A plan record's tracks (metres, radians) are kept in steps of a hundred-thousandth: at
# 100 m from the origin single precision keeps about as much (7.6 micrometres).
TRACK_STEPS = 100_000  # per metre or radian
# a track kept in steps is two arrays of the npz: its name and these
_HEAD, _REST = "~d2head", "~d2rest"


def _stepped(v):
    """A track (F, C) as its whole steps' (:data:`TRACK_STEPS`) second differences down each
    column (a smooth track's are a few steps: they deflate to a third of single
    precision's bytes), column by column: {"head": the first two rows' steps (int64),
    "rest": the other rows' (int16 when they fit)}; None for what is not a finite track."""
    if v.ndim != 2 or v.shape[0] < 3 or not np.all(np.isfinite(v)):
        return None
    steps = np.round(v * TRACK_STEPS)
    if np.abs(steps).max() > 2.0**52:
        return None
    d2 = np.diff(steps.astype(np.int64), n=2, axis=0)
    rest = d2.T.astype(np.int16) if np.abs(d2).max() < 2**15 else d2.T
    return {"head": steps[:2].T.astype(np.int64), "rest": np.ascontiguousarray(rest)}


def _unstepped(head, rest):
    """The track :func:`_stepped` kept (F, C), in metres or radians (float64)."""
    d1 = np.cumsum(np.concatenate((head[:, 1:] - head[:, :1], rest.astype(np.int64)), 1), 1)
    steps = np.concatenate((head[:, :1], head[:, :1] + np.cumsum(d1, 1)), 1)
    return steps.T / TRACK_STEPS  # a value of whole steps comes back as it was written


def store_plan(obj, data):
    """Keep a plan record on ``obj``: numpy arrays as one npz (base64), every other value
    as JSON. Its tracks (metres, radians) are kept to :data:`TRACK_STEPS` as second
    differences of whole steps (:func:`_stepped`), anything else of double precision in
    single; :func:`load_plan` gives them back as float64. Deflated: a walk of 559 frames
    14.8 KB in deflated single precision, 5.7 KB so (under a millisecond); records of
    single precision tracks, deflated or not, load the same."""
    arrays = {}
    for k, v in data.items():
        if not isinstance(v, np.ndarray):
            continue
        kept = _stepped(v) if v.dtype == np.float64 else None
        if kept is not None:
            arrays[k + _HEAD], arrays[k + _REST] = kept["head"], kept["rest"]
        else:
            arrays[k] = v.astype(np.float32) if v.dtype == np.float64 else v
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    meta = {k: v for k, v in data.items() if not isinstance(v, np.ndarray)}
    record = {"meta": meta, "arrays": base64.b64encode(buf.getvalue()).decode()}
    if "frame_start" in meta and "frame_end" in meta:  # first, for plan_range
        record = {"range": [int(meta["frame_start"]), int(meta["frame_end"])], **record}
    raw = json.dumps(record)
    obj[PLAN_KEY] = raw
    obj[PLAN_ID_KEY] = _fingerprint_of(raw)


def has_plan(obj):
    return obj is not None and PLAN_KEY in obj


def stood(obj):
    """The 4x4 world matrix ``obj`` had where its plans start (kept in its plan record by
    every write), or None for a record without one."""
    try:
        m = plan_meta(obj).get("stood")
    except ValueError:
        return None
    return None if m is None else np.array(m, float).reshape(4, 4)


def plan_meta(obj):
    """The JSON part of ``obj``'s plan record (no arrays decoded); ValueError when none."""
    raw = obj.get(PLAN_KEY)
    if raw is None:
        raise ValueError(f"'{obj.name}' has no planned motion; plan a path first")
    return json.loads(raw)["meta"]


_RANGE_HEAD = '{"range": '
_DECODER = json.JSONDecoder()


def plan_range(obj):
    """(frame_start, frame_end) of ``obj``'s plan record, read from the record's head
    without decoding the rest (fitting the scene's frame range reads every character's;
    the obstacles and tracks of a record take far longer to decode). Records written
    before the range was put first are decoded whole. ValueError when there is none."""
    raw = obj.get(PLAN_KEY)
    if raw is None:
        raise ValueError(f"'{obj.name}' has no planned motion; plan a path first")
    if raw.startswith(_RANGE_HEAD):
        (start, end), _ = _DECODER.raw_decode(raw, len(_RANGE_HEAD))
        return int(start), int(end)
    meta = json.loads(raw)["meta"]
    return int(meta["frame_start"]), int(meta["frame_end"])


def load_plan(obj):
    """``obj``'s plan record: (meta dict, arrays dict); ValueError when it has none."""
    raw = obj.get(PLAN_KEY)
    if raw is None:
        raise ValueError(f"'{obj.name}' has no planned motion; plan a path first")
    d = json.loads(raw)
    arrays = {}
    with np.load(io.BytesIO(base64.b64decode(d["arrays"]))) as z:
        for k in z.files:
            if k.endswith(_HEAD):
                name = k[: -len(_HEAD)]
                arrays[name] = _unstepped(z[k], z[name + _REST])
            elif not k.endswith(_REST):
                arrays[k] = z[k].astype(float) if z[k].dtype == np.float32 else z[k]
    return d["meta"], arrays


def _fingerprint_of(raw):
    return hashlib.sha1(raw.encode()).hexdigest()[:16]


def plan_fingerprint(obj):
    """A short string that changes when ``obj``'s plan record does (for caches): the hash
    of the record, kept beside it when it was written (:data:`PLAN_ID_KEY`), else (a
    record of an older version of the add-on) made from it; "" for none."""
    if PLAN_KEY not in obj:
        return ""
    kept = obj.get(PLAN_ID_KEY)
    if isinstance(kept, str) and kept:
        return kept
    raw = obj.get(PLAN_KEY, "")
    return _fingerprint_of(raw) if raw else ""


def plan_environment(meta, side=1.0, cells=8, radius=0.0):
    """The props a plan walked around (its record's obstacle polygons, world metres) as an
    :class:`Environment` of tiles ``side`` metres, ``cells`` cells per side, grown by
    ``radius`` (0: the footprints themselves)."""
    env = Environment(side, cells, radius)
    for name, poly in meta["obstacles"].items():
        env.place(Obstacle(name, np.array(poly)))
    return env


# --- analysis figures -----------------------------------------------------------------------


def store_analysis(obj, figures):
    obj[ANALYSIS_KEY] = json.dumps(figures)


def forget_analysis(obj):
    """Drop ``obj``'s analysis figures: they measured a plan that is no longer there."""
    if ANALYSIS_KEY in obj:
        del obj[ANALYSIS_KEY]


def last_analysis(obj):
    """The figures of ``obj``'s last analysis (dict), or None."""
    raw = obj.get(ANALYSIS_KEY) if obj is not None else None
    return json.loads(raw) if raw else None
