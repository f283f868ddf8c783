# SPDX-License-Identifier: GPL-3.0-or-later
"""Tag a mesh as an object patch (a prop carrying clips), untag it, edit its clip list."""

import bpy
from bpy.props import EnumProperty, FloatProperty, StringProperty

from .. import api
from .common import list_operators


def _active_mesh(context):
    ob = context.active_object
    return ob if ob is not None and ob.type == "MESH" else None


class MOTION_PATCHES_OT_tag_object_patch(bpy.types.Operator):
    """Check the active mesh's clips and make it an object patch the planner can use"""

    bl_idname = "motion_patches.tag_object_patch"
    bl_label = "Tag Object Patch"
    bl_options = {"REGISTER", "UNDO"}

    action: StringProperty(
        name="Action",
        description="Clip to add (traversal or interaction); empty: tag "
        "with the clips already in the prop's list",
    )
    kind: EnumProperty(
        name="Kind", items=(("TRAVERSAL", "Traversal", ""), ("INTERACTION", "Interaction", ""))
    )
    effort: FloatProperty(name="Effort (T)", default=8.0, min=0.0)
    copy_step: FloatProperty(name="Copies Every (deg)", default=10.0, min=0.0, max=180.0)

    @classmethod
    def poll(cls, context):
        return _active_mesh(context) is not None

    def execute(self, context):
        ob = context.active_object
        act = None
        if self.action:
            act = bpy.data.actions.get(self.action)
            if act is None:
                self.report({"ERROR"}, f"no action named '{self.action}'")
                return {"CANCELLED"}
        clips = [
            (c.action, c.kind, c.effort, c.copy_step)
            for c in ob.motion_patch.clips
            if c.action is not None and c.action != act
        ]
        if act is not None:
            clips.append((act, self.kind, self.effort, self.copy_step))
        if not clips:
            self.report({"ERROR"}, f"'{ob.name}' has no clip: add one and choose its action")
            return {"CANCELLED"}
        notes: list[str] = []
        try:
            api.tag_object_patch(ob, clips, scene=context.scene, context=context, notes=notes)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"'{ob.name}' is an object patch with {len(clips)} clip(s)")
        for note in notes:
            self.report({"WARNING"}, note)
        return {"FINISHED"}


class MOTION_PATCHES_OT_untag_object_patch(bpy.types.Operator):
    """Stop using the active object as an object patch (its clip list is kept)"""

    bl_idname = "motion_patches.untag_object_patch"
    bl_label = "Untag Object Patch"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        ob = _active_mesh(context)
        return ob is not None and api.is_tagged(ob)

    def execute(self, context):
        context.active_object.motion_patch.enabled = False
        return {"FINISHED"}


# Choose the new clip's action in the list, then Tag to check it and use it.
clip_list = list_operators(
    "clip",
    "Clip",
    "the active prop's clips",
    lambda context: getattr(_active_mesh(context), "motion_patch", None),
    "clips",
    "active_clip_index",
)

classes = (MOTION_PATCHES_OT_tag_object_patch, MOTION_PATCHES_OT_untag_object_patch) + clip_list
