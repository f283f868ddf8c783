import json

import bpy


class MOTION_PATCHES_PT_main(bpy.types.Panel):
    bl_label = "Motion Patches"
    bl_idname = "MOTION_PATCHES_PT_main"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Motion Patches"

    def draw(self, context):
        s = context.scene.motion_patches
        layout = self.layout
        box = layout.box()
        box.label(text="Locomotion Patch", icon='MOD_ARRAY')
        box.operator("motion_patches.import_mocap", icon='IMPORT')
        box.prop(s, "source_armature")
        box.prop(s, "straight_action")
        box.operator("motion_patches.bake_locomotion_patch", icon='RENDER_ANIMATION')
        for item in s.patches:
            st = json.loads(item.stats or "{}")
            box.label(text=f"{item.name} ({item.layer}): {st.get('kept', '?')} segments, "
                           f"{item.fps:g} fps")
        ob = context.active_object
        if ob is not None and ob.type == 'MESH':
            box = layout.box()
            box.label(text=f"Object Patch: {ob.name}", icon='MESH_CUBE')
            mp = ob.motion_patch
            box.prop(mp, "enabled")
            for c in mp.clips:
                row = box.row()
                row.prop(c, "action", text="")
                row.prop(c, "kind", text="")
                row.prop(c, "effort")
                row.prop(c, "copy_step", text="Step")
            box.operator("motion_patches.tag_object_patch", icon='ADD')
        box = layout.box()
        box.label(text="Planning", icon='TRACKING')
        box.prop(s, "goal")
        col = box.column(align=True)
        col.prop(s, "alpha")
        col.prop(s, "beta")
        col.prop(s, "gamma")
        box.prop(s, "radius")
        box.prop(s, "stitching")
        box.operator("motion_patches.plan_path", icon='PLAY')
        box.operator("motion_patches.analyse_motion", icon='GRAPH')
        box.prop(s, "show_overlay")


classes = (MOTION_PATCHES_PT_main,)
