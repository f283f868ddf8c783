# SPDX-License-Identifier: GPL-3.0-or-later
import bpy
from bpy.props import CollectionProperty, FloatProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from .. import api


class MOTION_PATCHES_OT_import_mocap(bpy.types.Operator, ImportHelper):
    """Import BVH files as clips to bake a locomotion patch from: every file an action on
    one armature named after the subject, in metres, the straight walk picked as the
    Straight Clip (Blender's own Motion Capture importer makes an armature per file)"""

    bl_idname = "motion_patches.import_mocap"
    bl_label = "Import Mocap Clips"
    bl_options = {"REGISTER", "UNDO"}

    filter_glob: StringProperty(default="*.bvh", options={"HIDDEN"})
    files: CollectionProperty(
        type=bpy.types.OperatorFileListElement, options={"HIDDEN", "SKIP_SAVE"}
    )
    directory: StringProperty(subtype="DIR_PATH", options={"HIDDEN", "SKIP_SAVE"})
    scale: FloatProperty(
        name="Scale",
        default=0.056444,
        min=1e-6,
        precision=6,  # all of CMU's 0.056444, not 0.06
        description="File units to metres (CMU: 0.056444)",
    )

    def execute(self, context):
        import os

        paths = [os.path.join(self.directory, f.name) for f in self.files if f.name] or [
            self.filepath
        ]
        try:
            arm, acts = api.import_mocap(paths, self.scale, scene=context.scene)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        straight = context.scene.motion_patches.straight_action
        n = len(acts)
        self.report(
            {"INFO"},
            f"Imported {n} clip{'' if n == 1 else 's'} on '{arm.name}'"
            + (f"; straight clip: '{straight.name}'" if straight in acts else ""),
        )
        return {"FINISHED"}


classes = (MOTION_PATCHES_OT_import_mocap,)
