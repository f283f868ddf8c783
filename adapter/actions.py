"""Actions <-> core arrays: reading an armature action into a Clip, writing keyed channels.

Reading takes every key of the rotation and root location curves (keys may sit on
fractional frames when the importer scaled a 120 fps clip to the scene rate), so the
clip keeps the source sampling; writing uses ``keyframe_points.add`` + ``foreach_set``.
"""

import re

import numpy as np

from ..motion_patches import quat
from ..motion_patches.clip import Clip
from ..motion_patches.skeleton import Skeleton, root_location_to_position
from . import compat

_PATH = re.compile(r'^pose\.bones\["(.+)"\]\.(rotation_quaternion|rotation_euler|location)$')


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
    rest = np.array([np.array(b.matrix_local) for b in order])
    if np.sum(parents < 0) != 1:
        raise ValueError(f"armature '{armature_obj.name}' has {np.sum(parents < 0)} root bones; "
                         f"one is needed")
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
        raise ValueError(f"action '{action.name}' does not move the root bone '{root}' "
                         f"(no location keys): it has no root motion")
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
        mode = modes.get(name, "QUATERNION")
        if (name, "rotation_quaternion", 0) in curves or mode == "QUATERNION":
            q = np.column_stack([sample(name, "rotation_quaternion", i, 1.0 if i == 0 else 0.0)
                                 for i in range(4)])
            rot[:, j] = quat.normalize(q)
        elif mode in ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"):
            e = np.column_stack([sample(name, "rotation_euler", i, 0.0) for i in range(3)])
            rot[:, j] = euler_to_quat(e, mode)
        else:
            raise ValueError(f"bone '{name}' uses rotation mode {mode}; use quaternion or Euler")
    pos = root_location_to_position(skel, loc)
    clip = Clip(action.name, skel, float(fps), pos, quat.make_continuous(rot, axis=0))
    return clip.validate()


def euler_to_quat(e, order):
    """Quaternions of Blender Euler angles (F, 3) in rotation ``order`` (e.g. 'XYZ')."""
    axes = {"X": 0, "Y": 1, "Z": 2}
    q = np.tile([1.0, 0, 0, 0], (e.shape[0], 1))
    for ax in order:  # Blender's 'XYZ' applies X first: R = Rz Ry Rx
        i = axes[ax]
        half = e[:, i] * 0.5
        a = np.zeros((e.shape[0], 4))
        a[:, 0] = np.cos(half)
        a[:, 1 + i] = np.sin(half)
        q = quat.mul(a, q)
    return q


LINEAR = 1  # Keyframe.interpolation enum value of 'LINEAR' (4.5 and 5.0)


def key_curve(action, slot, data_path, index, frames, values, group=None):
    """Create one F-curve keyed at ``frames`` with ``values`` in one bulk write."""
    fc = compat.new_fcurve(action, slot, data_path, index, group)
    n = len(frames)
    fc.keyframe_points.add(n)
    co = np.empty(2 * n)
    co[0::2] = frames
    co[1::2] = values
    fc.keyframe_points.foreach_set("co", co)
    fc.keyframe_points.foreach_set("interpolation", np.full(n, LINEAR, dtype=np.int32))
    fc.update()
    return fc


def key_pose(action, slot, skel, frames, root_location, rotations):
    """Key the root bone's location and every bone's rotation quaternion."""
    root = skel.names[skel.root]
    for i in range(3):
        key_curve(action, slot, f'pose.bones["{root}"].location', i, frames,
                  root_location[:, i], group=root)
    for j, name in enumerate(skel.names):
        for i in range(4):
            key_curve(action, slot, f'pose.bones["{name}"].rotation_quaternion', i, frames,
                      rotations[:, j, i], group=name)
