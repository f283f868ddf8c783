import bpy
from bpy.props import StringProperty

from .. import api


class MOTION_PATCHES_OT_plan_path(bpy.types.Operator):
    """Plan the active armature's walk to the goal and write it as NLA strips"""
    bl_idname = "motion_patches.plan_path"
    bl_label = "Plan Path"
    bl_options = {'REGISTER', 'UNDO'}

    patch: StringProperty(name="Patch", description="Locomotion patch (default: the active one)")

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == 'ARMATURE'

    def execute(self, context):
        s = context.scene.motion_patches
        try:
            res = api.plan_path(context.scene, context.active_object, s.goal,
                                patch_name=self.patch or None, alpha=s.alpha, beta=s.beta,
                                gamma=s.gamma, radius=s.radius, context=context,
                                stitching=s.stitching.lower())
        except api.MotionPatchesError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        self.report({'INFO'}, f"Planned {len(res.pieces)} pieces, frames {res.frame_start}-"
                              f"{res.frame_end}, cost {res.cost:.2f} in {res.seconds * 1000:.0f} ms")
        if res.stashed_action_track:
            self.report({'WARNING'}, f"The active action was moved to the muted track "
                                     f"'{res.stashed_action_track}' so the plan can play")
        return {'FINISHED'}


classes = (MOTION_PATCHES_OT_plan_path,)
