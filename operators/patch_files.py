# SPDX-License-Identifier: GPL-3.0-or-later
"""Baked patches to and from files: bake once on the farm, use the patch in every shot."""

import bpy
from bpy.props import BoolProperty, StringProperty
from bpy_extras.io_utils import ExportHelper, ImportHelper

from .. import api

EXT = ".mpatch"


class MOTION_PATCHES_OT_export_patch(bpy.types.Operator, ExportHelper):
    """Write the active locomotion patch to a file other .blend files can import"""

    bl_idname = "motion_patches.export_patch"
    bl_label = "Export Patch"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = EXT
    filter_glob: StringProperty(default="*" + EXT, options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return len(context.scene.motion_patches.patches) > 0

    def execute(self, context):
        try:
            name = api.export_patch(context.scene, self.filepath)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Exported '{name}' to {self.filepath}")
        return {"FINISHED"}


class MOTION_PATCHES_OT_import_patch(bpy.types.Operator, ImportHelper):
    """Store a locomotion patch file in this .blend (a patch of the same name is kept: the
    import takes the next free name, walk.001, unless Replace is ticked)"""

    bl_idname = "motion_patches.import_patch"
    bl_label = "Import Patch"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = EXT
    filter_glob: StringProperty(default="*" + EXT, options={"HIDDEN"})

    replace: BoolProperty(
        name="Replace",
        description="Replace a patch of the same name instead of importing under a new name",
        default=False,
    )

    def execute(self, context):
        try:
            name = api.import_patch(context.scene, self.filepath, replace=self.replace)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        if name.kept:
            self.report({"WARNING"}, f"Imported as '{name}': the scene's '{name.kept}' is kept")
        else:
            self.report({"INFO"}, f"Imported '{name}'")
        return {"FINISHED"}


classes = (MOTION_PATCHES_OT_export_patch, MOTION_PATCHES_OT_import_patch)
