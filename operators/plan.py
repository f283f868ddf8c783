# SPDX-License-Identifier: GPL-3.0-or-later
"""Plan one character (the active armature) or a crowd (every selected armature), and
reset the scene's planning settings to the animator's defaults from the preferences."""

import bpy
from bpy.props import BoolProperty, StringProperty

from .. import api, props
from .common import LongWork, report_conflicts


class MOTION_PATCHES_OT_plan_path(bpy.types.Operator):
    """Plan the active armature's walk to its own goal (or the scene's), written as NLA strips"""

    bl_idname = "motion_patches.plan_path"
    bl_label = "Plan Path"
    bl_options = {"REGISTER", "UNDO"}

    patch: StringProperty(name="Patch", description="Locomotion patch (default: the active one)")
    from_here: BoolProperty(
        name="From Current Frame",
        description="Start where the character is at the current frame (continue from here) "
        "instead of where it stood before it was planned",
        default=False,
    )

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == "ARMATURE"

    def execute(self, context):
        try:  # the planning settings are the scene's (api.planning_settings)
            res = api.plan_path(
                context.scene,
                context.active_object,
                None,  # its Own Goal, else the scene's (api.own_goal)
                patch_name=self.patch or None,
                context=context,
                start_prop=api.character_start_prop(context.active_object),
                from_here=self.from_here,
            )
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        n = len(res.pieces)
        text = (
            f"Planned {n} piece{'' if n == 1 else 's'}, frames {res.frame_start}-"
            f"{res.frame_end}, cost {res.cost:.2f} in {res.seconds * 1000:.0f} ms"
        )
        notes = list(res.stats.get("traversals_too_low", []))
        if res.stashed_action_track:
            notes.insert(
                0, f"the active action was moved to the muted track '{res.stashed_action_track}'"
            )
        for note in notes[1:]:  # the Info log has them all
            self.report({"INFO"}, note)
        # The result last and first in its line: the status bar shows the last report.
        self.report({"WARNING"} if notes else {"INFO"}, text + (f" ({notes[0]})" if notes else ""))
        return {"FINISHED"}


class MOTION_PATCHES_OT_plan_crowd(LongWork, bpy.types.Operator):
    """Plan every selected armature to its own goal (or the scene's), starting them apart
    (Esc cancels, leaving the scene as it was)"""

    bl_idname = "motion_patches.plan_crowd"
    bl_label = "Plan Crowd"
    bl_options = {"REGISTER", "UNDO"}
    progress_label = "Planning the crowd"

    patch: StringProperty(name="Patch", description="Locomotion patch (default: the active one)")

    @classmethod
    def poll(cls, context):
        return any(ob.type == "ARMATURE" for ob in context.selected_objects)

    def prepare(self, context):
        scene, patch = context.scene, self.patch or None
        self._count = len(pairs := api.crowd_members(scene, context.selected_objects))
        return lambda update, cancelled: api.plan_crowd(
            scene, pairs, patch_name=patch, context=context, progress=update, cancelled=cancelled
        )

    def finish(self, context, res):
        for name, why in res.failed:
            self.report({"WARNING"}, why if name in why else f"{name}: {why}")
        if not res.plans:
            self.report({"ERROR"}, "No character found a path; nothing was written")
            return {"CANCELLED"}
        report_conflicts(self, res)
        waits = [f"{n} {d} frames" for n, d in res.delays.items() if d]
        self.report(
            {"INFO"},
            f"Planned {len(res.plans)} of {self._count} characters in "
            f"{res.seconds:.1f} s" + (f"; waiting: {', '.join(waits)}" if waits else ""),
        )
        return {"FINISHED"}


class MOTION_PATCHES_OT_reset_planning(bpy.types.Operator):
    """Set this scene's planning settings (α, β, γ, radius, stitching, foot lock, goal
    facing) to the defaults in the preferences"""

    bl_idname = "motion_patches.reset_planning"
    bl_label = "Reset to Preferences"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        prefs = props.preferences(context)
        if prefs is None:
            self.report(
                {"ERROR"}, "The add-on preferences are not available (is the add-on enabled?)"
            )
            return {"CANCELLED"}
        s = context.scene.motion_patches
        for name in props.PLANNING:
            setattr(s, name, getattr(prefs, name))
        return {"FINISHED"}


def _armature(context):
    ob = context.active_object
    return ob if ob is not None and ob.type == "ARMATURE" else None


class MOTION_PATCHES_OT_bone_map_fill(bpy.types.Operator):
    """List every bone of the patch skeleton in the active armature's bone map with the
    armature bone its name pairs it with, ready to be corrected"""

    bl_idname = "motion_patches.bone_map_fill"
    bl_label = "Fill From Names"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _armature(context) is not None

    def execute(self, context):
        try:
            mapping = api.fill_bone_map(context.scene, _armature(context))
        except api.MotionPatchesError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        left = [p for p, r in mapping.items() if not r]
        self.report(
            {"INFO"},
            f"{len(mapping) - len(left)} of {len(mapping)} patch bones "
            f"paired" + (f"; none for {', '.join(left[:6])}" if left else ""),
        )
        return {"FINISHED"}


class MOTION_PATCHES_OT_bone_map_clear(bpy.types.Operator):
    """Clear the active armature's bone map: bones are paired by their names again"""

    bl_idname = "motion_patches.bone_map_clear"
    bl_label = "Clear Bone Map"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        ob = _armature(context)
        return ob is not None and len(ob.data.motion_patches_rig.bone_map) > 0

    def execute(self, context):
        api.set_bone_map(_armature(context), {})
        return {"FINISHED"}


classes = (
    MOTION_PATCHES_OT_plan_path,
    MOTION_PATCHES_OT_plan_crowd,
    MOTION_PATCHES_OT_reset_planning,
    MOTION_PATCHES_OT_bone_map_fill,
    MOTION_PATCHES_OT_bone_map_clear,
)
