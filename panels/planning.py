# SPDX-License-Identifier: GPL-3.0-or-later
"""Planning panel: the goal (the scene's, and the active character's own, which it walks to), the
active character's proxy body and bone map (when it is another skeleton than the
patch's), the cost weights α β γ, radius and stitching, and the Plan Path / Plan Crowd
buttons."""

import bpy

from .. import api
from .sidebar import SidebarPanel, wrapped_label


class MOTION_PATCHES_PT_planning(SidebarPanel, bpy.types.Panel):
    bl_label = "Planning"
    bl_idname = "MOTION_PATCHES_PT_planning"

    def draw(self, context):
        s = context.scene.motion_patches
        layout = self.layout
        layout.use_property_split = True  # label | field, as Blender's own panels
        layout.use_property_decorate = False
        layout.prop(s, "goal")
        ob = context.active_object
        if ob is not None and ob.type == "ARMATURE":
            # The character's name over the field: beside it, "Walker's Goal" is cut.
            col = layout.column(align=True)
            col.use_property_split = False
            wrapped_label(col, context, f"{ob.name}'s Own Goal")
            col.prop(ob.motion_patches_character, "goal", text="")
            layout.prop(ob.motion_patches_character, "start_prop")
            draw_body(layout, ob)
            draw_bone_map(layout, context, ob)
        col = layout.column(align=True)
        col.prop(s, "alpha")
        col.prop(s, "beta")
        col.prop(s, "gamma")
        layout.prop(s, "radius", text="Radius")  # "Character Radius" is cut beside its field
        layout.prop(s, "stitching")
        layout.prop(s, "goal_facing", text="Facing")
        layout.prop(s, "gait")
        # Checkboxes with their labels beside them, the panel's whole width: in the label
        # column "Lock Planted Feet" would be cut.
        col = layout.column(align=True)
        col.use_property_split = False
        col.prop(s, "foot_lock")
        col.prop(s, "turn_in_place")
        col.prop(s, "fit_frame_range")
        layout.operator("motion_patches.reset_planning", icon="LOOP_BACK")
        row = layout.row(align=True)
        row.operator("motion_patches.plan_path", icon="PLAY")
        row.operator("motion_patches.plan_crowd", icon="COMMUNITY")
        layout.operator("motion_patches.duplicate_crowd", icon="DUPLICATE")
        if api.has_crowd_conflicts(context.scene):  # a crowd was written with close passes
            layout.operator("motion_patches.select_crowd_conflicts", icon="ERROR")


def draw_body(layout, ob):
    """Add Body (Replace Body once it has one) and Remove Body for the active character."""
    row = layout.row(align=True)
    has = api.has_body(ob)
    row.operator(
        "motion_patches.add_body", icon="MESH_CAPSULE", text="Replace Body" if has else "Add Body"
    )
    if has:
        row.operator("motion_patches.remove_body", icon="X", text="Remove")


class MOTION_PATCHES_UL_bone_map(bpy.types.UIList):
    """Bone map rows: the patch bone, and the armature bone that plays it (editable)."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname, index=0):
        layout.use_property_split = False  # a row's fields fill it (the panel splits)
        row = layout.row(align=True)
        row.label(text=item.patch_bone, icon="BONE_DATA")
        arm = context.active_object
        if arm is not None and arm.type == "ARMATURE":
            row.prop_search(item, "rig_bone", arm.data, "bones", text="")
        else:
            row.prop(item, "rig_bone", text="")


def draw_bone_map(layout, context, ob):
    """The active armature's bone map: whether it is the patch's own skeleton or is
    retargeted (or cannot be, naming the bones), and, unless it is the patch's own, the
    editable rows (patch bone -> armature bone) with Fill From Names / Clear."""
    from .. import api
    from ..adapter import nla, storage

    rig_props = ob.data.motion_patches_rig
    try:
        patch = storage.load_patch(context.scene)
        rig = nla.check_rig(ob, patch.gait.skeleton, patch.gait.floor())
        text, icon = (
            ("Bone map: the patch's own skeleton", "CHECKMARK")
            if rig is None
            else (
                f"Bone map: retargeted, {len(rig.pairs)} bones, root x{rig.scale:.3f}",
                "ARMATURE_DATA",
            )
        )
    except (ValueError, api.MotionPatchesError) as exc:
        rig, text, icon = False, str(exc), "ERROR"
    wrapped_label(layout, context, text, icon=icon)
    if rig is None and not len(rig_props.bone_map):
        return
    layout.template_list(
        "MOTION_PATCHES_UL_bone_map",
        "",
        rig_props,
        "bone_map",
        rig_props,
        "active_bone_index",
        rows=3,
    )
    row = layout.row(align=True)
    row.operator("motion_patches.bone_map_fill", icon="FILE_REFRESH")
    row.operator("motion_patches.bone_map_clear", icon="X", text="Clear")


classes = (MOTION_PATCHES_PT_planning, MOTION_PATCHES_UL_bone_map)
