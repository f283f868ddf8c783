# SPDX-License-Identifier: GPL-3.0-or-later
"""Object Patch panel: the active mesh as a prop carrying clips (traversals, interactions),
its clip list, its footprint and the tag / untag buttons."""

import bpy

from .. import api
from .sidebar import SidebarPanel, list_with_buttons


class MOTION_PATCHES_UL_clips(bpy.types.UIList):
    """A prop's clips: action and kind per row (effort and copies below the list)."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        layout.use_property_split = False  # a row's fields fill it (the panel splits)
        row = layout.row(align=True)
        row.prop(item, "action", text="", emboss=True)
        row.prop(item, "kind", text="")


class MOTION_PATCHES_PT_object_patch(SidebarPanel, bpy.types.Panel):
    bl_label = "Object Patch"
    bl_idname = "MOTION_PATCHES_PT_object_patch"

    @classmethod
    def poll(cls, context):
        ob = context.active_object
        return ob is not None and ob.type == "MESH"

    def draw(self, context):
        ob = context.active_object
        mp = ob.motion_patch
        layout = self.layout
        layout.use_property_split = True  # label | field, as Blender's own panels
        layout.use_property_decorate = False
        layout.label(text=ob.name, icon="MESH_CUBE")
        col = layout.column()
        col.use_property_split = False  # a checkbox with its label beside it
        col.prop(mp, "enabled")
        list_with_buttons(
            layout,
            "MOTION_PATCHES_UL_clips",
            mp,
            "clips",
            "active_clip_index",
            "motion_patches.clip_add",
            "motion_patches.clip_remove",
        )
        if 0 <= mp.active_clip_index < len(mp.clips):
            clip = mp.clips[mp.active_clip_index]
            col = layout.column(align=True)
            col.prop(clip, "effort")
            col.prop(clip, "copy_step", text="Copy Step (°)")  # "Copies Every (°)" is cut
            if clip.kind == "TRAVERSAL":  # which gait layers may take it (walk, run, *)
                col = layout.column(align=True)
                col.prop(clip, "layer_in")
                col.prop(clip, "layer_out")
        n, area = api.footprint_info(ob)
        layout.label(
            text=f"{n} vertices" + (f", footprint {area:.2f} m²" if area is not None else ""),
            icon="MESH_DATA",
        )
        row = layout.row(align=True)  # short texts: half the sidebar each
        row.operator("motion_patches.tag_object_patch", text="Tag", icon="CHECKMARK")
        row.operator("motion_patches.untag_object_patch", text="Untag", icon="X")


classes = (MOTION_PATCHES_UL_clips, MOTION_PATCHES_PT_object_patch)
