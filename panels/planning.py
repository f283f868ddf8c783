"""Planning panel: the goal (the scene's, and the active character's own for crowds), the
cost weights α β γ, radius and stitching, and the Plan Path / Plan Crowd buttons."""

import bpy

from .sidebar import SidebarPanel


class MOTION_PATCHES_PT_planning(SidebarPanel, bpy.types.Panel):
    bl_label = "Planning"
    bl_idname = "MOTION_PATCHES_PT_planning"

    def draw(self, context):
        s = context.scene.motion_patches
        layout = self.layout
        layout.prop(s, "goal")
        ob = context.active_object
        if ob is not None and ob.type == 'ARMATURE':
            layout.prop(ob.motion_patches_character, "goal", text=f"{ob.name}'s Goal")
        col = layout.column(align=True)
        col.prop(s, "alpha")
        col.prop(s, "beta")
        col.prop(s, "gamma")
        layout.prop(s, "radius")
        layout.prop(s, "stitching")
        layout.prop(s, "foot_lock")
        layout.prop(s, "goal_facing")
        layout.operator("motion_patches.reset_planning", icon='LOOP_BACK')
        row = layout.row(align=True)
        row.operator("motion_patches.plan_path", icon='PLAY')
        row.operator("motion_patches.plan_crowd", icon='COMMUNITY')


classes = (MOTION_PATCHES_PT_planning,)
