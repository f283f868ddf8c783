# SPDX-License-Identifier: GPL-3.0-or-later
"""Duplicate the active armature into a crowd scattered over a region and plan it; select
the characters of a crowd that still come too close."""

import bpy
from bpy.props import BoolProperty, FloatVectorProperty, IntProperty, StringProperty

from .. import api
from .common import LongWork, report_conflicts


class MOTION_PATCHES_OT_duplicate_crowd(LongWork, bpy.types.Operator):
    """Copy the active armature (sharing its armature data) into a crowd scattered over a
    region, send each copy to a goal scattered over another region, and plan the crowd
    (Esc cancels, leaving the scene as it was)"""

    bl_idname = "motion_patches.duplicate_crowd"
    bl_label = "Duplicate Crowd"
    bl_options = {"REGISTER", "UNDO"}
    progress_label = "Planning the crowd"

    count: IntProperty(name="Characters", default=10, min=1, soft_max=200)
    region_min: FloatVectorProperty(
        name="Region From", size=2, default=(-5.0, -5.0), subtype="XYZ", unit="LENGTH"
    )
    region_max: FloatVectorProperty(
        name="Region To", size=2, default=(-1.0, 5.0), subtype="XYZ", unit="LENGTH"
    )
    goal_min: FloatVectorProperty(
        name="Goals From", size=2, default=(1.0, -5.0), subtype="XYZ", unit="LENGTH"
    )
    goal_max: FloatVectorProperty(
        name="Goals To", size=2, default=(5.0, 5.0), subtype="XYZ", unit="LENGTH"
    )
    seed: IntProperty(name="Seed", default=0, min=0)
    patch: StringProperty(name="Patch", description="Locomotion patch (default: the active one)")
    # Set by invoke: the dialog's OK runs execute, which then plans a step at a time.
    stepped: BoolProperty(options={"HIDDEN", "SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "ARMATURE"

    def invoke(self, context, event):
        self.stepped = not bpy.app.background and context.window is not None
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        if self.stepped:  # from the dialog (not the redo panel: it runs in one go)
            self.stepped = False
            return self.start(context)
        return LongWork.execute(self, context)

    def prepare(self, context):
        self._pairs = []
        w = api.planning_settings(context.scene)
        scene, patch = context.scene, self.patch or None
        self._pairs = pairs = api.duplicate_crowd(
            scene,
            context.active_object,
            self.count,
            (self.region_min, self.region_max),
            (self.goal_min, self.goal_max),
            seed=self.seed,
            radius=w["radius"],
            patch_name=patch,
            context=context,
        )
        return lambda update, cancelled: api.plan_crowd(
            scene, pairs, patch_name=patch, context=context, progress=update, cancelled=cancelled
        )

    def undo(self, context):
        api.remove_crowd(getattr(self, "_pairs", []))  # nothing made is left behind

    def finish(self, context, res):
        for name, why in res.failed:
            self.report({"WARNING"}, f"unreachable: {why}")
        report_conflicts(self, res)
        holds = sum(len(h) for h in getattr(res, "holds", {}).values())
        waits = sum(1 for d in res.delays.values() if d)
        self.report(
            {"INFO"},
            f"Crowd of {len(self._pairs)}: {len(res.plans)} planned, "
            f"{len(res.failed)} unreachable, {len(res.conflicts)} conflicts, "
            f"{holds} idle holds, {waits} waits, {len(res.rerouted)} re-routed, "
            f"in {res.seconds:.1f} s",
        )
        return {"FINISHED"}


class MOTION_PATCHES_OT_select_crowd_conflicts(bpy.types.Operator):
    """Select the characters that still come too close in the crowds planned here (and the
    moving props they meet), and go to the first frame where it happens"""

    bl_idname = "motion_patches.select_crowd_conflicts"
    bl_label = "Select Conflicts"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return api.has_crowd_conflicts(context.scene)

    def execute(self, context):
        try:
            conflicts = api.select_crowd_conflicts(context.scene, context.view_layer)
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        self.report(
            {"INFO"},
            f"{len(context.selected_objects)} selected, {len(conflicts)} conflict(s); "
            f"the first at frame {conflicts[0]['frame']}",
        )
        return {"FINISHED"}


classes = (MOTION_PATCHES_OT_duplicate_crowd, MOTION_PATCHES_OT_select_crowd_conflicts)
