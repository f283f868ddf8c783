# SPDX-License-Identifier: GPL-3.0-or-later
"""Tagged props -> core object patches.

A tagged mesh object's footprint is the convex hull of its evaluated vertices in its own
ground coordinates (scale applied, Z rotation factored out; a flat prop grown to the least
thickness, :func:`motion_patches.props.footprint.outline`); its clips are read from their
actions on the patch's skeleton and placed relative to the prop.
"""

import numpy as np

from ..motion_patches.props import footprint as fp
from ..motion_patches.props import object_patch as op
from . import actions as act_io
from . import compat
from . import scene as scene_io

KINDS = {"TRAVERSAL": op.TRAVERSAL, "INTERACTION": op.INTERACTION}


def tag(obj, clips):
    """Make ``obj`` a tagged prop carrying ``clips`` [(action, kind, effort, copy_step)]
    (its clip list replaced)."""
    mp = obj.motion_patch
    mp.enabled = True
    mp.clips.clear()
    for action, kind, effort, step in clips:
        item = mp.clips.add()
        item.action, item.kind, item.effort, item.copy_step = action, kind, effort, step


def prop_pose(obj):
    m = np.array(obj.matrix_world)
    return (float(m[0, 3]), float(m[1, 3]), float(np.arctan2(m[1, 0], m[0, 0])))


def height(obj, depsgraph):
    """Top of the evaluated mesh above the floor (z = 0), metres."""
    world = scene_io.mesh_arrays(obj, depsgraph)[0]
    return float(world[:, 2].max()) if len(world) else 0.0


def footprint(obj, depsgraph):
    """Convex footprint in the prop's ground coordinates (the hull of its evaluated
    vertices, at least ``footprint.MIN_THICKNESS`` wide: :func:`motion_patches.props.footprint.
    outline`, the rule every footprint follows); ValueError if it has no vertices."""
    if obj.type != "MESH":
        raise ValueError(
            f"'{obj.name}' is not a mesh object: an object patch needs geometry for its footprint"
        )
    world = scene_io.mesh_arrays(obj, depsgraph)[0]
    if not len(world):
        raise ValueError(f"'{obj.name}' has no footprint: its mesh has no vertices")
    x, y, h = prop_pose(obj)
    c, s = np.cos(-h), np.sin(-h)
    d = world[:, :2] - (x, y)
    return fp.outline(np.column_stack((c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1])))


def object_patch(obj, depsgraph, skeleton, fps, gait_floor=None, scale=1.0):
    """The core ObjectPatch of a tagged object (clips read and copied around it); clips
    are put down on the walk's floor (``gait_floor``) when given. ``scale``: as
    :func:`adapter.scene.environment`'s, the prop placed in the world shrunk by it."""
    x, y, h = prop_pose(obj)
    patch = op.ObjectPatch(
        obj.name,
        footprint(obj, depsgraph) / scale,
        pose=(x / scale, y / scale, h),
        height=height(obj, depsgraph) / scale,
    )
    for item in obj.motion_patch.clips:
        if item.action is None:
            raise ValueError(f"object patch '{obj.name}' has a clip without an action")
        clip = act_io.clip_from_action(item.action, None, fps, skeleton=skeleton)
        pc = op.patch_clip_from(
            clip, KINDS[item.kind], fps, effort=item.effort, name=item.action.name, floor=gait_floor
        )
        pc.layer_in, pc.layer_out = item.layer_in, item.layer_out
        if pc.kind == op.TRAVERSAL and item.copy_step > 0:
            if patch.add_traversal_copies(pc, item.copy_step) == 0:
                raise ValueError(
                    f"every copy of '{item.action.name}' around '{obj.name}' "
                    f"takes off or lands on the prop: the prop is too large for it"
                )
        else:
            patch.clips.append(pc)
    patch.keep_clearing(skeleton, 0.0 if gait_floor is None else gait_floor)
    return patch


def is_tagged(ob):
    """Whether ``ob`` is a tagged object patch (a mesh with its Object Patch enabled), asked
    without adding the settings to a mesh that has none (:func:`compat.stored_settings`)."""
    settings = compat.stored_settings(ob, "motion_patch") if ob.type == "MESH" else None
    return settings is not None and settings.enabled


def tagged(scene):
    return [o for o in scene.objects if is_tagged(o) and o.visible_get()]


def interaction_clip(patch, sitting):
    """Index of the patch's interaction clip that ends seated (``sitting``) or standing."""
    for i, c in enumerate(patch.clips):
        if c.kind == op.INTERACTION:
            lower = c.motion.root_local[-1, 2] < c.motion.root_local[0, 2] - 0.2
            if lower == sitting:
                return i
    return None
