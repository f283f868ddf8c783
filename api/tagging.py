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
) -> bpy.types.Object:
    """Make ``obj`` an object patch carrying ``clips``: [(action, kind, effort, copy_step)]
    with kind 'TRAVERSAL' or 'INTERACTION'. Everything is validated first (footprint, root
    motion of each clip on the patch's skeleton); on error nothing is changed."""
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
        props_io.footprint(obj, depsgraph)
        for action, kind, effort, step in clips:
            if action is None:
                raise ValueError("a clip has no action")
            clip = act_io.clip_from_action(
                action, None, scene_fps(scene), skeleton=patch.gait.skeleton
            )
            object_patch.patch_clip_from(clip, props_io.KINDS[kind], scene_fps(scene), effort)
    except ValueError as exc:
        raise MotionPatchesError(f"cannot tag '{obj.name}': {exc}") from None
    props_io.tag(obj, clips)
    return obj
