# SPDX-License-Identifier: GPL-3.0-or-later
"""Measure the active character's evaluated motion; the API keeps the figures on it for
the Analysis panel."""

import bpy

from .. import api


class MOTION_PATCHES_OT_analyse_motion(bpy.types.Operator):
    """Measure the motion as Blender plays it: foot skate, goal error, props walked into, pops"""

    bl_idname = "motion_patches.analyse_motion"
    bl_label = "Analyse Motion"
    bl_options = {"REGISTER", "UNDO"}  # the figures are stored on the character

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "ARMATURE"

    def execute(self, context):
        ob = context.active_object
        try:
            figures = api.analyse(context, ob, keep=True)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        sk = figures["foot_skate"]
        self.report(
            {"INFO"},
            f"Foot skate {sk['mean_cm_per_frame']:.2f} cm/frame "
            f"({sk['mean_cm_per_s']:.1f} cm/s), goal error "
            f"{figures['goal_position_error_cm']:.1f} cm / "
            f"{figures['goal_heading_error_deg']:.1f} deg",
        )
        return {"FINISHED"}


classes = (MOTION_PATCHES_OT_analyse_motion,)
