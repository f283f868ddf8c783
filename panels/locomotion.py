# SPDX-License-Identifier: GPL-3.0-or-later
"""Locomotion Patches panel: the clips a patch is baked from, the bake, and the baked
patches with the active one (the one the planner uses) and its bake figures."""

import json

import bpy

from .sidebar import SidebarPanel, list_with_buttons, wrapped_label


class MOTION_PATCHES_UL_actions(bpy.types.UIList):
    """Turn clips of the bake (each row picks an action)."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        layout.use_property_split = False  # a row's fields fill it (the panel splits)
        layout.prop(item, "action", text="", emboss=True)


class MOTION_PATCHES_UL_patches(bpy.types.UIList):
    """Baked locomotion patches; the active row is the patch the planner uses."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        layout.use_property_split = False  # a row's fields fill it (the panel splits)
        row = layout.row()
        row.label(text=item.name, icon="MOD_ARRAY")
        row.label(text=f"{item.layer}, {item.fps:g} fps")


# Why the bake culled candidate segments (the keys of its report's "culled_by"), as the
# panel says it: one line per reason, so no line is cut at the sidebar's width.
CULL_REASONS = {
    "curvature": "bend too tight or fold",
    "outside": "leave the patch",
    "no fit": "fit no whole cycle",
    "glitch": "spin, step back or jump",
}


def patch_summary(item):
    """Lines describing a baked patch for the panel: segments kept and culled, why, fps."""
    st = json.loads(item.stats or "{}")
    lines = [
        f"Layer '{item.layer}' at {item.fps:g} fps",
        f"{st.get('kept', '?')} segments kept, {st.get('culled', '?')} culled",
    ]
    by = st.get("culled_by") or {}
    if by:
        lines.append("Culled:")
        lines += [f"{n:,} {CULL_REASONS.get(why, why)}" for why, n in by.items()]
    return lines


class MOTION_PATCHES_PT_locomotion(SidebarPanel, bpy.types.Panel):
    bl_label = "Locomotion Patches"
    bl_idname = "MOTION_PATCHES_PT_locomotion"

    def draw(self, context):
        s = context.scene.motion_patches
        layout = self.layout
        layout.use_property_split = True  # label | field, as Blender's own panels
        layout.use_property_decorate = False
        layout.operator("motion_patches.import_mocap", icon="IMPORT")
        # Short labels: the label column is 40 % of the sidebar ("Source Armature" is cut).
        layout.prop(s, "source_armature", text="Armature")
        layout.prop(s, "straight_action", text="Straight Clip")
        layout.label(text="Turn Clips")
        list_with_buttons(
            layout,
            "MOTION_PATCHES_UL_actions",
            s,
            "turn_actions",
            "active_turn_index",
            "motion_patches.turn_add",
            "motion_patches.turn_remove",
        )
        layout.operator("motion_patches.bake_locomotion_patch", icon="RENDER_ANIMATION")
        row = layout.row(align=True)
        row.operator("motion_patches.import_patch", icon="IMPORT")
        row.operator("motion_patches.export_patch", icon="EXPORT")
        if not len(s.patches):
            layout.label(text="No patch baked yet", icon="INFO")
            return
        layout.label(text="Baked Patches")
        layout.template_list(
            "MOTION_PATCHES_UL_patches", "", s, "patches", s, "active_patch_index", rows=2
        )
        if 0 <= s.active_patch_index < len(s.patches):
            col = layout.column(align=True)
            for line in patch_summary(s.patches[s.active_patch_index]):
                wrapped_label(col, context, line)


classes = (MOTION_PATCHES_UL_actions, MOTION_PATCHES_UL_patches, MOTION_PATCHES_PT_locomotion)
