# SPDX-License-Identifier: GPL-3.0-or-later
"""Give the selected characters a proxy body (capsules round their bones), or take it off."""

import bpy

from .. import api


def _chosen(context):
    """The characters among the selection and the active object, or [] (for polls)."""
    try:
        return api.chosen_characters([context.active_object, *context.selected_objects])
    except api.MotionPatchesError:
        return []


def _count(n, one, many):
    return f"{n} {one if n == 1 else many}"


class MOTION_PATCHES_OT_add_body(bpy.types.Operator):
    """Give the selected armatures a proxy body: a low-poly capsule round each bone,
    parented to it, in a colour per character (done again, it replaces the old body)"""

    bl_idname = "motion_patches.add_body"
    bl_label = "Add Body"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return bool(_chosen(context))

    def execute(self, context):
        try:
            res = api.add_bodies(_chosen(context))
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report(
            {"INFO"},
            f"{_count(len(res.characters), 'body', 'bodies')} made: "
            f"{_count(res.parts, 'capsule', 'capsules')} sharing "
            f"{_count(res.meshes, 'mesh', 'meshes')}",
        )
        return {"FINISHED"}


class MOTION_PATCHES_OT_remove_body(bpy.types.Operator):
    """Remove the proxy bodies of the selected armatures (only the capsules the add-on made)"""

    bl_idname = "motion_patches.remove_body"
    bl_label = "Remove Body"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):  # not whether each has a body: a pass over the file per character
        return bool(_chosen(context))

    def execute(self, context):
        n = api.remove_bodies(_chosen(context))
        self.report({"INFO"}, f"{_count(n, 'capsule', 'capsules')} removed")
        return {"FINISHED"}


classes = (MOTION_PATCHES_OT_add_body, MOTION_PATCHES_OT_remove_body)
