import bpy
from bpy.props import EnumProperty, FloatProperty, StringProperty

from .. import api


class MOTION_PATCHES_OT_tag_object_patch(bpy.types.Operator):
    """Make the active mesh object an object patch carrying a clip"""
    bl_idname = "motion_patches.tag_object_patch"
    bl_label = "Tag Object Patch"
    bl_options = {'REGISTER', 'UNDO'}

    action: StringProperty(name="Action", description="Clip (traversal or interaction)")
    kind: EnumProperty(name="Kind", items=(('TRAVERSAL', "Traversal", ""),
                                           ('INTERACTION', "Interaction", "")))
    effort: FloatProperty(name="Effort (T)", default=8.0, min=0.0)
    copy_step: FloatProperty(name="Copies Every (deg)", default=10.0, min=0.0, max=180.0)

    @classmethod
    def poll(cls, context):
        return context.active_object is not None and context.active_object.type == 'MESH'

    def execute(self, context):
        ob = context.active_object
        act = bpy.data.actions.get(self.action)
        if act is None:
            self.report({'ERROR'}, f"no action named '{self.action}'")
            return {'CANCELLED'}
        clips = [(c.action, c.kind, c.effort, c.copy_step) for c in ob.motion_patch.clips
                 if c.action is not None and c.action != act]
        clips.append((act, self.kind, self.effort, self.copy_step))
        try:
            api.tag_object_patch(ob, clips, scene=context.scene, context=context)
        except api.MotionPatchesError as exc:
            self.report({'ERROR'}, str(exc))
            return {'CANCELLED'}
        self.report({'INFO'}, f"'{ob.name}' is an object patch with {len(clips)} clip(s)")
        return {'FINISHED'}


class MOTION_PATCHES_OT_untag_object_patch(bpy.types.Operator):
    """Stop using the active object as an object patch (its clip list is kept)"""
    bl_idname = "motion_patches.untag_object_patch"
    bl_label = "Untag Object Patch"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        ob = context.active_object
        return ob is not None and ob.type == 'MESH' and ob.motion_patch.enabled

    def execute(self, context):
        context.active_object.motion_patch.enabled = False
        return {'FINISHED'}


classes = (MOTION_PATCHES_OT_tag_object_patch, MOTION_PATCHES_OT_untag_object_patch)
