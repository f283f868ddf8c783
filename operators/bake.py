# SPDX-License-Identifier: GPL-3.0-or-later
"""Bake a locomotion patch from the scene's chosen clips, and edit the list of turn clips."""

import bpy
from bpy.props import StringProperty

from .. import api, props
from .common import LongWork, list_operators


class MOTION_PATCHES_OT_bake_locomotion_patch(LongWork, bpy.types.Operator):
    """Bake a tilable locomotion patch from a straight clip and turn clips (Esc cancels,
    leaving the scene as it was)"""

    bl_idname = "motion_patches.bake_locomotion_patch"
    bl_label = "Bake Locomotion Patch"
    bl_options = {"REGISTER", "UNDO"}
    progress_label = "Baking"

    layer: StringProperty(name="Layer", default="walk", description="Gait name of the patch")
    straight: StringProperty(
        name="Straight Action", description="Straight clip (default: the scene's bake setting)"
    )
    turns: StringProperty(
        name="Turn Actions", description="Comma-separated turn clips (default: the scene's list)"
    )
    # Not remembered between calls: unless given, they start from the add-on preferences.
    cells: props.BAKE["cells"](options={"SKIP_SAVE"})
    nodes: props.BAKE["nodes"](options={"SKIP_SAVE"})

    def _size_from_preferences(self, context):
        """Cells and nodes the caller did not give come from the preferences. Done in
        prepare, which execute and invoke both run: a button, a script and the redo panel
        all get it (bpy.ops calls from scripts, EXEC by default, and headless Blender never
        run invoke)."""
        prefs = props.preferences(context)
        for name in props.BAKE:
            if prefs is not None and not self.properties.is_property_set(name):
                setattr(self, name, getattr(prefs, name))

    def prepare(self, context):
        self._size_from_preferences(context)
        settings = context.scene.motion_patches
        # Action names or the scene's bake settings; the API checks them and remembers them.
        straight = self.straight or settings.straight_action
        turns = (
            [n.strip() for n in self.turns.split(",") if n.strip()]
            if self.turns
            else [r.action for r in settings.turn_actions if r.action]
        )
        scene, armature = context.scene, settings.source_armature or context.active_object
        layer, cells, nodes = self.layer, self.cells, self.nodes
        return lambda update, cancelled: api.bake_locomotion_patch(
            scene,
            armature,
            straight,
            turns,
            layer=layer,
            cells=cells,
            nodes=nodes,
            progress=update,
            cancelled=cancelled,
        )

    def finish(self, context, res):
        st = res.stats
        self.report(
            {"INFO"},
            f"Baked '{res.name}': {st['kept']} segments kept, {st['culled']} "
            f"culled ({res.seconds:.1f} s)",
        )
        for warning in res.warnings:
            self.report({"WARNING"}, warning)
        return {"FINISHED"}


turn_list = list_operators(
    "turn",
    "Turn Clip",
    "the clips the patch is baked from",
    lambda context: context.scene.motion_patches,
    "turn_actions",
    "active_turn_index",
)

classes = (MOTION_PATCHES_OT_bake_locomotion_patch,) + turn_list
