# SPDX-License-Identifier: GPL-3.0-or-later
"""Tagging a mesh as an object patch: a prop carrying traversal and interaction clips."""

from __future__ import annotations

from collections.abc import Iterable

import bpy

from ..adapter import actions as act_io
from ..adapter import props_io, storage
from ..motion_patches.props import object_patch
from .common import scene_fps
from .errors import MotionPatchesError


def tag_object_patch(
    obj: bpy.types.Object,
    clips: Iterable[tuple],
    patch_name: str | None = None,
    scene: bpy.types.Scene | None = None,
    context: bpy.types.Context | None = None,
    notes: list[str] | None = None,
) -> bpy.types.Object:
    """Make ``obj`` an object patch carrying ``clips``: [(action, kind, effort, copy_step)]
    with kind 'TRAVERSAL' or 'INTERACTION'. Everything is validated first (footprint, root
    motion of each clip on the patch's skeleton); on error nothing is changed. A traversal
    clip whose body passes lower over the prop than its top is tagged but never planned
    over it (a jump must not sink its legs into the prop): ``notes`` (a list) gets a
    sentence naming both heights."""
    scene = scene or bpy.context.scene
    context = context or bpy.context
    try:
        patch = storage.load_patch(scene, patch_name)
    except ValueError as exc:
        raise MotionPatchesError(f"bake a locomotion patch before tagging props ({exc})") from None
    if obj is None:
        raise MotionPatchesError("choose a mesh object to tag")
    context.view_layer.update()
    depsgraph = context.evaluated_depsgraph_get()
    for action, kind, effort, step in clips:
        if kind not in props_io.KINDS:
            raise MotionPatchesError(f"clip kind must be TRAVERSAL or INTERACTION, not {kind}")
    try:
        prop = object_patch.ObjectPatch(
            obj.name, props_io.footprint(obj, depsgraph), height=props_io.height(obj, depsgraph)
        )
        floor = patch.gait.floor()
        for action, kind, effort, step in clips:
            if action is None:
                raise ValueError("a clip has no action")
            clip = act_io.clip_from_action(
                action, None, scene_fps(scene), skeleton=patch.gait.skeleton
            )
            pc = object_patch.patch_clip_from(
                clip, props_io.KINDS[kind], scene_fps(scene), effort, name=action.name, floor=floor
            )
            if pc.kind == object_patch.TRAVERSAL and step > 0:
                prop.add_traversal_copies(pc, step)
            else:
                prop.clips.append(pc)
    except ValueError as exc:
        raise MotionPatchesError(f"cannot tag '{obj.name}': {exc}") from None
    prop.keep_clearing(patch.gait.skeleton, floor)
    for name, clears, high in prop.too_low:
        if notes is not None:
            notes.append(
                f"{name} clears {clears:.2f} m over '{obj.name}', which is {high:.2f} m high: "
                f"planning will not jump it until the prop is lower or narrower (a traversal "
                f"clip must pass above its prop)"
            )
    props_io.tag(obj, clips)
    return obj


def is_tagged(ob: bpy.types.Object) -> bool:
    """Whether ``ob`` is a tagged object patch, asked without adding the Object Patch
    settings to an object that has none (the adapter's ``props_io.is_tagged``): the one test
    for the overlay, the buttons and the planner."""
    return props_io.is_tagged(ob)
