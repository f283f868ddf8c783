# SPDX-License-Identifier: GPL-3.0-or-later
"""Actions <-> core arrays: reading an armature action into a Clip, writing keyed channels.

Reading takes every key of the rotation and root location curves (keys may sit on
fractional frames when the importer scaled a 120 fps clip to the scene rate), so the
clip keeps the source sampling; writing uses ``keyframe_points.add`` + ``foreach_set``.

Rotation modes: a pose bone plays only the channel of its own ``rotation_mode``; the
channels of every mode, and which keys store a pose, are worked out in the core
(:mod:`motion_patches.kinematics.channels`, :mod:`motion_patches.kinematics.pose_keys`, whose
names are also this module's) so a crowd can fit them where there is no Blender.
"""

import re

import numpy as np

from ..motion_patches.kinematics import keys as key_plan
from ..motion_patches.kinematics import quat
from ..motion_patches.kinematics.channels import (  # noqa: F401 (the adapter's names for them)
    EULER_ORDERS,
    axis_angle_to_quat,
    channels_to_quat,
    closest_channels,
    euler_to_quat,
    matching_channels,
    rest_channels,
    rotation_channels,
    rotation_path,
)
from ..motion_patches.kinematics.clip import Clip
from ..motion_patches.kinematics.pose_keys import (  # noqa: F401
    Tolerance,
    fit_curves,
    pose_curves,
    rest_values,
    whole_frames,
)
from ..motion_patches.kinematics.skeleton import Skeleton, root_location_to_position
from . import compat

_PATH = re.compile(
    r'^pose\.bones\["(.+)"\]\.'
    r"(rotation_quaternion|rotation_euler|rotation_axis_angle|location)$"
)


def skeleton_of(armature_obj):
    """Skeleton (names parent-first, rest matrices) of an armature object."""
    bones = armature_obj.data.bones
    order, seen = [], set()

    def visit(b):
        if b.name in seen:
            return
        if b.parent:
            visit(b.parent)
        seen.add(b.name)
        order.append(b)

    for b in bones:
        visit(b)
    names = [b.name for b in order]
    index = {n: i for i, n in enumerate(names)}
    parents = np.array([index[b.parent.name] if b.parent else -1 for b in order])
    # Every bone's matrix at once, in Blender's own type (a matrix at a time through
    # mathutils costs 100x more); Blender stores a matrix column by column.
    flat = np.empty(len(bones) * 16, np.float32)
    bones.foreach_get("matrix_local", flat)
    stored = {b.name: i for i, b in enumerate(bones)}
    local = flat.reshape(-1, 4, 4).transpose(0, 2, 1).astype(float)
    rest = local[[stored[n] for n in names]]
    if np.sum(parents < 0) != 1:
        raise ValueError(
            f"armature '{armature_obj.name}' has {np.sum(parents < 0)} root bones; one is needed"
        )
    return Skeleton(names, parents, rest)


def _curves(action):
    out = {}
    for fc in compat.fcurves(action):
        m = _PATH.match(fc.data_path)
        if m:
            n = len(fc.keyframe_points)
            co = np.empty(2 * n)
            fc.keyframe_points.foreach_get("co", co)
            out[(m.group(1), m.group(2), fc.array_index)] = co.reshape(n, 2)
    return out


def clip_from_action(action, armature_obj, scene_fps, skeleton=None):
    """Clip of an action on an armature (or on a stored ``skeleton``, all bones in
    quaternion mode); ValueError with a readable message if unusable."""
    skel = skeleton or skeleton_of(armature_obj)
    curves = _curves(action)
    if not curves:
        raise ValueError(f"action '{action.name}' has no pose bone curves")
    root = skel.names[skel.root]
    key_frames = None
    for (bone, prop, _), co in curves.items():
        if bone == root and prop == "location":
            key_frames = co[:, 0]
            break
    if key_frames is None:
        raise ValueError(
            f"action '{action.name}' does not move the root bone '{root}' "
            f"(no location keys): it has no root motion"
        )
    frames = key_frames
    step = np.median(np.diff(frames)) if frames.size > 1 else 1.0
    fps = scene_fps / step

    def sample(bone, prop, index, default):
        co = curves.get((bone, prop, index))
        if co is None:
            return np.full(frames.size, default)
        return np.interp(frames, co[:, 0], co[:, 1])

    loc = np.column_stack([sample(root, "location", i, 0.0) for i in range(3)])
    rot = np.empty((frames.size, len(skel.names), 4))
    modes = {pb.name: pb.rotation_mode for pb in armature_obj.pose.bones} if armature_obj else {}
    for j, name in enumerate(skel.names):
        mode = _keyed_mode(action, name, modes.get(name), curves)
        n = 3 if mode in EULER_ORDERS else 4
        rest = rest_channels(mode)
        v = np.column_stack([sample(name, rotation_path(mode), i, rest[i]) for i in range(n)])
        rot[:, j] = channels_to_quat(v, mode)
    pos = root_location_to_position(skel, loc)
    clip = Clip(action.name, skel, float(fps), pos, quat.make_continuous(rot, axis=0))
    return clip.validate()


def _keyed_mode(action, bone, mode, curves):
    """The rotation mode to read a bone's keys in: the bone's own ``mode`` when the action
    keys that channel (what Blender plays), else the channel the action does key. Euler
    keys are read only in the bone's own Euler order: an F-curve does not record it."""
    keyed = {p for (b, p, _) in curves if b == bone and p != "location"}
    if mode is not None and rotation_path(mode) in keyed:
        return mode
    if "rotation_quaternion" in keyed:
        return "QUATERNION"
    if "rotation_axis_angle" in keyed:
        return "AXIS_ANGLE"
    if "rotation_euler" in keyed:
        why = (
            f"the bone's rotation mode is {mode}"
            if mode is not None
            else "no armature gives its Euler order"
        )
        raise ValueError(
            f"action '{action.name}' keys bone '{bone}' in Euler angles but {why}: "
            f"read it on the armature it was imported on (bones in the Euler "
            f"order of the keys)"
        )
    return "QUATERNION"  # not keyed: the rest pose


LINEAR = 1  # Keyframe.interpolation enum value of 'LINEAR' (4.5 to 5.2)
BEZIER = 2  # ... of 'BEZIER'
FREE = 0  # Keyframe.handle_left_type / handle_right_type enum value of 'FREE'


LINEAR_TOL = 1e-5  # linear keys' tolerance (metres, radians, quaternion components)
CUBIC = Tolerance()  # cubic keys within 0.5 degrees and 1 mm (bench/bench_files.py)
# What every action of a plan is stored within: a number for linear keys, a Tolerance for
# cubic keys, None for a key on every frame. Cubic keys: every bone within 0.5 degrees of
# the plan, the hips within a millimetre and planted feet within one of where linear keys
# put them (a character's own pieces keyed on the scene's frames with the feet locked, the
# foot lock and the root keyed finer: adapter/nla.py), a sixth smaller than linear keys.
COMPACT = CUBIC
# How near its ``left_out`` value a curve of key_curves is left out at (a quaternion
# component: the rotation turns by at most twice this, radians; 1e-4 degrees): a bone that
# does not turn about an axis (a knee's hinge) holds it there to rounding, not exactly.
LEFT_OUT = 1e-6


def key_curves(
    action,
    slot,
    frames,
    curves,
    tol=None,
    stored=None,
    values=None,
    rotations=(),
    between=True,
    fitted=None,
    left_out=None,
    blend="REPLACE",
):
    """Create the F-curves ``curves`` = [(data_path, index, group, values (F,))], all keyed
    at ``frames``, each in one bulk write (``keyframe_points.add`` + ``foreach_set`` of
    float32 arrays, the type Blender stores, so nothing is converted value by value).

    ``tol`` a :class:`Tolerance`: cubic keys (:func:`motion_patches.kinematics.keys.cubic_keys`,
    all curves in one vectorised pass; ``rotations``: the
    :class:`~motion_patches.kinematics.keys.Rotations` among the curves, judged by the angle
    they play): Bezier keys whose handles sit a third of the way to the next key, so Blender
    plays the Hermite cubic the fit checked, a few keys a second; a constant curve is one
    key; a curve whose keys would cost more than one sample per frame is sampled
    (``convert_to_samples``, 16 bytes a frame). ``tol`` a number: the older linear keys
    within it (:func:`motion_patches.kinematics.keys.plan_columns`; ``stored``: those
    choices made already). None: a linear key on every frame.
    ``values``: the curves' values as one (F, C) array already (their ``curves`` entries
    are then not read). ``between``: the keys are also played between ``frames`` (a strip
    scaled to another rate) and held to the plan there too; False: only on them.
    ``fitted``: :func:`fit_curves` of these arguments, made already. ``left_out``: (C,)
    the value each curve is not made at when it holds it on every frame (within
    :data:`LEFT_OUT`; NaN: always made), stored compactly (``tol`` not None): the value
    the channel plays without it in the strips' ``blend`` (:func:`_made`; an F-curve costs
    a few hundred bytes even with one key)."""
    frames = np.asarray(frames, float)
    if values is None and curves:
        values = np.column_stack([np.asarray(c[3], float) for c in curves])
    whole = whole_frames(frames)
    cubic = fitted
    if cubic is None:
        cubic = fit_curves(frames, curves, tol, values, rotations, between)
    if cubic is not None:
        stored = [("cubic", None)] * len(curves)
    if stored is None:
        stored = (
            key_plan.plan_columns(values, tol)
            if tol is not None and curves
            else [("all", None)] * len(curves)
        )
    step = float(frames[1] - frames[0]) if frames.size > 1 else 1.0
    # every curve's (frame, value) pairs, float32, built at once; a curve takes its row
    rows = np.empty((len(curves), 2 * frames.size), np.float32)
    rows[:, 0::2] = frames
    if curves:
        rows[:, 1::2] = values.T
    linear = np.full(frames.size, LINEAR, np.int32)
    keys = _CubicKeys(frames, cubic, step) if cubic is not None else None
    bag = compat.channelbag(action, slot, create=True)
    groups, out = {}, []
    made = np.ones(len(curves), bool)
    if left_out is not None and tol is not None and curves:  # (every curve on every frame)
        off = np.abs(values - np.asarray(left_out, float)).max(axis=0)  # NaN: never
        made = _made(curves, ~(off <= LEFT_OUT), blend)
    for c, ((data_path, index, group, _), (how, kept)) in enumerate(zip(curves, stored)):
        if not made[c]:
            continue
        fc = bag.fcurves.new(data_path, index=index)
        if group:
            grp = groups.get(group)
            if grp is None:
                grp = groups[group] = bag.groups.get(group) or bag.groups.new(group)
            fc.group = grp
        if how == "cubic":
            if cubic["constant"][c]:
                how, co = "constant", np.array([frames[0], cubic["value"][c]], np.float32)
            else:
                lo, hi = keys.start[c], keys.start[c + 1]
                if whole and (
                    cubic["gave_up"][c]
                    or (hi - lo) * key_plan.KEY_BYTES >= frames.size * key_plan.SAMPLE_BYTES
                ):
                    how = "samples"
                else:
                    keys.write(fc, lo, hi)
                    out.append(fc)
                    continue
        if how == "samples" and not whole:
            how = "all"
        if how == "constant":
            co = rows[c, :2] if cubic is None else co
        elif how == "keys":
            co = rows[c].reshape(-1, 2)[kept].ravel()
        elif how != "constant":
            co = rows[c]
        n = co.size // 2
        fc.keyframe_points.add(n)
        fc.keyframe_points.foreach_set("co", co)
        if how == "samples":
            fc.convert_to_samples(int(frames[0]), int(frames[-1]) + 1)
        else:
            fc.keyframe_points.foreach_set("interpolation", linear[:n])
            fc.update()
        out.append(fc)
    return out


def _made(curves, changing, blend):
    """(C,) which ``curves`` to make, of those ``changing`` (the others hold the value
    :func:`key_curves` may leave them out at), as Blender's NLA plays a strip of ``blend``.
    It blends a quaternion whole (any other channel component by component): a strip
    keying some of a quaternion's components plays the others at their defaults, one
    keying none leaves the bone to the strips below. So an Add strip (adding zero where it
    keys nothing) leaves out a bone's quaternion only whole; a Replace strip leaves out the
    components at their defaults (the caller's values) while it keys one of them, and no
    other channel (the strips below would play there)."""
    made = changing.copy()
    quats = {}
    for c, (path, *_) in enumerate(curves):
        if path.endswith("rotation_quaternion"):
            quats.setdefault(path, []).append(c)
        elif blend != "ADD":
            made[c] = True
    for cs in quats.values():
        if blend == "ADD":
            made[cs] = made[cs].any()
        elif not made[cs].any():
            made[cs[0]] = True  # a Replace strip keeps the bone (its w, held at 1)
    return made


class _CubicKeys:
    """Every curve's Bezier keys of one :func:`fit_curves` answer, made at once (one numpy
    pass for the action, not one per curve: a crowd of 1,000 writes ~130,000 curves): on
    its kept frames, each key's value and its handles' slopes (per frame), free handles a
    third of the way to the neighbouring keys, so that Blender plays the Hermite cubic
    between keys (:func:`motion_patches.kinematics.keys.hermite`). Curve ``c``'s keys are
    rows ``start[c]:start[c + 1]``."""

    def __init__(self, frames, cubic, step):
        col, row = np.nonzero(np.asarray(cubic["keep"]).T)  # by curve, frames in order
        self.start = np.searchsorted(col, np.arange(cubic["keep"].shape[1] + 1))
        x = frames[row]
        y = cubic["values"][row, col]
        m = cubic["slopes"][row, col] / step
        m_in = cubic["slopes_in"][row, col] / step
        # the gap to the key before (after); a curve's first (last) key takes its other
        # side's, a lone key 3 (a handle a frame long)
        gap = np.diff(x) if x.size else np.zeros(0)
        first = np.zeros(x.size, bool)
        first[self.start[:-1][self.start[:-1] < x.size]] = True
        last = np.roll(first, -1)
        last[-1:] = True
        before = np.concatenate((np.zeros(min(x.size, 1)), gap))
        after = np.concatenate((gap, np.zeros(min(x.size, 1))))
        alone = first & last
        before = np.where(first, after, before)
        after = np.where(last, before, after)
        before, after = np.where(alone, 3.0, before) / 3.0, np.where(alone, 3.0, after) / 3.0
        self.co = np.empty((x.size, 2), np.float32)
        self.co[:, 0], self.co[:, 1] = x, y
        self.left = np.empty((x.size, 2), np.float32)
        self.left[:, 0], self.left[:, 1] = x - before, y - m_in * before
        self.right = np.empty((x.size, 2), np.float32)
        self.right[:, 0], self.right[:, 1] = x + after, y + m * after
        self.bezier = np.full(x.size, BEZIER, np.int32)
        self.free = np.full(x.size, FREE, np.int32)

    def write(self, fc, lo, hi):
        """Curve ``fc`` keyed with rows ``lo:hi``."""
        kp = fc.keyframe_points
        kp.add(hi - lo)
        kp.foreach_set("co", self.co[lo:hi].ravel())
        kp.foreach_set("interpolation", self.bezier[lo:hi])
        kp.foreach_set("handle_left_type", self.free[lo:hi])
        kp.foreach_set("handle_right_type", self.free[lo:hi])
        kp.foreach_set("handle_left", self.left[lo:hi].ravel())
        kp.foreach_set("handle_right", self.right[lo:hi].ravel())
        fc.update()


def curve_keys(fc):
    """(N, 4) frames, values, and the slopes (per frame) of the right and left handles
    (NaN where the segment a key starts is not Bezier) of an F-curve's keys, or its samples
    (linear) when it was converted to samples: what
    :func:`motion_patches.kinematics.keys.hermite` plays as Blender does for keys written by
    :func:`key_curves`."""
    kp = fc.keyframe_points
    if not len(kp):
        co = np.empty(2 * len(fc.sampled_points), np.float32)
        fc.sampled_points.foreach_get("co", co)
        co = co.reshape(-1, 2).astype(float)
        return np.column_stack((co, np.full((len(co), 2), np.nan)))
    n = len(kp)
    co, hl, hr = (np.empty(2 * n, np.float32) for _ in range(3))
    kp.foreach_get("co", co)
    kp.foreach_get("handle_left", hl)
    kp.foreach_get("handle_right", hr)
    ipo = np.empty(n, np.int32)
    kp.foreach_get("interpolation", ipo)
    co, hl, hr = (a.reshape(-1, 2).astype(float) for a in (co, hl, hr))
    dx = hr[:, 0] - co[:, 0]
    slope = np.where(dx > 0, (hr[:, 1] - co[:, 1]) / np.where(dx > 0, dx, 1.0), 0.0)
    dxl = co[:, 0] - hl[:, 0]
    slope_in = np.where(dxl > 0, (co[:, 1] - hl[:, 1]) / np.where(dxl > 0, dxl, 1.0), slope)
    bez = ipo == BEZIER
    return np.column_stack((co, np.where(bez, slope, np.nan), slope_in))


def curve_points(fc):
    """(N, 2) frames and values of an F-curve's keys, or of its samples when it was
    converted to samples (:func:`key_curves` with ``tol``)."""
    points = fc.keyframe_points if len(fc.keyframe_points) else fc.sampled_points
    co = np.empty(2 * len(points), np.float32)  # what Blender stores: read without conversion
    points.foreach_get("co", co)
    return co.reshape(-1, 2).astype(float)


def key_pose(
    action,
    slot,
    skel,
    frames,
    root_location,
    rotations,
    modes=None,
    tol=None,
    between=True,
    strip=False,
):
    """Key the root bone's location and every bone's rotation in the channel its rotation
    mode plays: ``modes`` is {bone name: rotation_mode}, quaternion for bones not in it.
    Quaternion channels are keyed as given (the caller makes them continuous); Euler and
    axis-angle ones are converted continuous over ``frames`` (:func:`rotation_channels`).
    ``tol``, ``between``: store the curves compactly (:func:`key_curves`); ``strip``: the
    action is only played by Replace strips, which play a quaternion component at rest
    without its curve (``key_curves``' ``left_out``)."""
    curves, values, tol, groups = pose_curves(skel, root_location, rotations, modes, tol, between)
    key_curves(
        action,
        slot,
        frames,
        curves,
        tol,
        values=values,
        rotations=groups,
        between=between,
        left_out=rest_values(curves) if strip else None,
    )


def read_channels(action, slot, bone, mode, frames, cache=None):
    """Values (F, 3 or 4) an action gives a bone's ``mode`` channel at (action) ``frames``,
    as Blender plays its keys (linear, samples, or the cubic keys of :func:`key_curves`),
    the rest value where the channel is not keyed.
    Only that channel's curves are read. ``cache``: a dict kept by the caller, so each
    curve is read once."""
    return read_bones(action, slot, [bone], mode, frames, cache)[:, 0]


def read_bones(action, slot, bones, mode, frames, cache=None):
    """:func:`read_channels` of several bones in one ``mode``: values (F, K, 3 or 4).

    Curves with a point on every whole frame of one span (samples, or keys on every
    frame: most curves of an action), read at whole ``frames``, are taken at once, not
    interpolated (what interpolating at the points gives, exactly); the others are
    interpolated one by one."""
    rest = rest_channels(mode)
    frames = np.asarray(frames, float)
    out = np.empty((len(frames), len(bones), rest.size))
    out[:] = rest
    whole = bool(frames.size) and np.array_equal(frames, np.round(frames))
    by_length = {}  # number of points -> [(bone, component, points)]
    for k, bone in enumerate(bones):
        for i, co in enumerate(_channel_points(action, slot, bone, mode, rest.size, cache)):
            if co is not None:
                by_length.setdefault(len(co), []).append((k, i, co))
    for n, curves in by_length.items():
        at = np.stack([co[:, 0] for _, _, co in curves])  # (M, n) the points' frames
        dense = whole and np.array_equal(at, np.broadcast_to(at[0, 0] + np.arange(n), at.shape))
        if dense:
            ks, cs = [k for k, _, _ in curves], [i for _, i, _ in curves]
            pick = np.clip(frames - at[0, 0], 0, n - 1).astype(int)
            values = np.stack([co[:, 1] for _, _, co in curves])  # (M, n)
            out[:, ks, cs] = values[:, pick].T
            continue
        for k, i, co in curves:
            out[:, k, i] = key_plan.hermite(co[:, 0], co[:, 1], co[:, 2], frames, co[:, 3])
    return out


def _channel_points(action, slot, bone, mode, size, cache=None):
    """[(N, 4) keys (:func:`curve_keys`) or None] of the curves of a bone's ``mode``
    channel in an action."""
    path = f'pose.bones["{bone}"].{rotation_path(mode)}'
    key = (action.name, slot.handle if slot is not None else None, path)
    points = cache.get(key) if cache is not None else None
    if points is None:
        slot = slot or compat.action_slot(action)
        bag = compat.channelbag(action, slot) if slot is not None else None
        found = [bag.fcurves.find(path, index=i) if bag else None for i in range(size)]
        points = [None if fc is None else curve_keys(fc) for fc in found]
        if cache is not None:
            cache[key] = points
    return points
