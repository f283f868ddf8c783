# SPDX-License-Identifier: GPL-3.0-or-later
"""Properties the add-on stores: baked patches and planning settings in the .blend, each
character's own goal, and the add-on preferences that hold an animator's defaults.

The planning settings are declared once (:data:`PLANNING`) and used twice: on the scene,
where the planner reads them, and in the preferences, from which "Reset to Preferences"
copies them (a property's default is fixed when the class registers, so new scenes cannot
read the preferences by themselves).
"""

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from .adapter.bodies import BODY_KEY
from .motion_patches.planning.settings import SETTINGS

# Called with the new value when Show Planner Overlay changes; the overlay (panels/overlay.py)
# sets it while registered, so the properties need not know the UI.
overlay_switch = None


def _overlay_toggle(on):
    if overlay_switch is not None:
        overlay_switch(on)


def _planning_property(setting):
    """The bpy property of a planning setting (:data:`SETTINGS`): its label, help, default
    and range, so the panel holds what the API and the CLI accept."""
    common = dict(name=setting.label, description=setting.help)
    if setting.kind is float:
        extra = dict(unit="LENGTH") if setting.unit == "m" else {}
        if setting.soft_maximum is not None:
            extra["soft_max"] = setting.soft_maximum
        return FloatProperty(
            default=setting.default, min=setting.minimum, max=setting.maximum, **common, **extra
        )
    if setting.kind is bool:
        return BoolProperty(default=setting.default, **common)
    items = tuple((v.upper(), label, tip) for v, label, tip in setting.choices)
    return EnumProperty(default=setting.default.upper(), items=items, **common)


PLANNING = {  # name -> factory of the bpy property (one fresh definition per class)
    **{s.name: (lambda s=s: _planning_property(s)) for s in SETTINGS},
    "fit_frame_range": lambda: BoolProperty(
        name="Fit Frame Range",
        default=True,
        description="After planning, set the scene's frame range to the planned motion "
        "(every planned character's); a range you set yourself is only extended, "
        "never shortened",
    ),
}
BAKE = {
    "cells": lambda **kw: IntProperty(
        name="Cells",
        default=8,
        min=2,
        max=8,
        description="Cells per side of the patch's square",
        **kw,
    ),
    "nodes": lambda **kw: IntProperty(
        name="Nodes per Edge",
        default=8,
        min=2,
        max=8,
        description="Entry/exit points along each side of the patch",
        **kw,
    ),
}


class MOTION_PATCHES_PG_patch(bpy.types.PropertyGroup):
    layer: StringProperty(name="Layer", description="Gait of this locomotion patch")
    payload: StringProperty(
        name="Payload", description="Baked patch (base64 npz)", options={"HIDDEN"}
    )
    stats: StringProperty(name="Statistics", description="Bake report (JSON)", options={"HIDDEN"})
    fps: FloatProperty(name="Frame Rate", description="Frame rate the patch was baked at")


class MOTION_PATCHES_PG_action_ref(bpy.types.PropertyGroup):
    action: PointerProperty(type=bpy.types.Action, name="Action")


class MOTION_PATCHES_PG_patch_clip(bpy.types.PropertyGroup):
    action: PointerProperty(
        type=bpy.types.Action, name="Action", description="Clip recorded on the patch's skeleton"
    )
    kind: EnumProperty(
        name="Kind",
        items=(
            ("TRAVERSAL", "Traversal", "Passes the prop (hurdle, vault): used by the planner"),
            ("INTERACTION", "Interaction", "Starts or ends a path at the prop (sit, stand)"),
        ),
    )
    effort: FloatProperty(
        name="Effort (T)",
        default=8.0,
        min=0.0,
        description="Effort of the whole clip, in walking seconds",
    )
    layer_in: StringProperty(
        name="Layer In",
        default="walk",
        description="Gait layer(s) the clip is entered from: a name, "
        "names separated by commas, or * for any",
    )
    layer_out: StringProperty(
        name="Layer Out",
        default="walk",
        description="Gait layer(s) the clip is left in: a name, names "
        "separated by commas, or * for any",
    )
    copy_step: FloatProperty(
        name="Copies Every (°)",
        default=10.0,
        min=0.0,
        max=180.0,
        description="Copy the clip around the prop every so many degrees (0: no copies)",
    )


class MOTION_PATCHES_PG_object(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Object Patch",
        default=False,
        description="This prop carries clips the planner may use",
    )
    clips: CollectionProperty(type=MOTION_PATCHES_PG_patch_clip)
    active_clip_index: IntProperty(default=0)


class MOTION_PATCHES_PG_bone_pair(bpy.types.PropertyGroup):
    """One row of a character's bone map: which of its bones plays a patch bone."""

    patch_bone: StringProperty(
        name="Patch Bone", description="Bone of the locomotion patch's skeleton"
    )
    rig_bone: StringProperty(
        name="Rig Bone",
        description="Bone of this armature that plays the patch bone "
        "(empty: the patch bone is left out)",
    )


# Objects a goal picker does not offer: a camera, a light or a sound is not a place to walk
# to, nor a capsule of a character's proxy body (a crowd has hundreds).
NOT_GOALS = {"CAMERA", "LIGHT", "LIGHT_PROBE", "SPEAKER"}


def _goal_poll(self, ob):
    return ob.type not in NOT_GOALS and BODY_KEY not in ob.keys()


def _prop_poll(self, ob):
    return ob.type == "MESH" and BODY_KEY not in ob.keys()


class MOTION_PATCHES_PG_character(bpy.types.PropertyGroup):
    goal: PointerProperty(
        type=bpy.types.Object,
        name="Own Goal",
        description="Where this character walks when it is planned, alone (Plan Path) or "
        "in a crowd (empty: the scene's goal; a character with neither is refused, named)",
        poll=_goal_poll,
    )
    start_prop: PointerProperty(
        type=bpy.types.Object,
        name="Start Prop",
        description="A prop tagged with a stand-up clip this character starts seated on "
        "when it is planned, alone (Plan Path) or in a crowd (empty: where it stands)",
        poll=_prop_poll,
    )


class MOTION_PATCHES_PG_rig(bpy.types.PropertyGroup):
    """Stored on the armature data (``Armature.motion_patches_rig``), so every character
    made from one rig shares it."""

    bone_map: CollectionProperty(
        type=MOTION_PATCHES_PG_bone_pair,
        name="Bone Map",
        description="Which bone of this armature plays each bone of the patch skeleton; "
        "patch bones not listed are paired by their names (naming conventions)",
    )
    active_bone_index: IntProperty(default=0)


class MOTION_PATCHES_PG_scene(bpy.types.PropertyGroup):
    patches: CollectionProperty(type=MOTION_PATCHES_PG_patch)
    active_patch_index: IntProperty(
        name="Active Patch", default=0, description="The patch the planner uses"
    )
    source_armature: PointerProperty(
        type=bpy.types.Object,
        name="Source Armature",
        description="Armature the mocap clips were imported on",
        poll=lambda self, ob: ob.type == "ARMATURE",
    )
    straight_action: PointerProperty(
        type=bpy.types.Action, name="Straight", description="Straight locomotion clip of the layer"
    )
    turn_actions: CollectionProperty(type=MOTION_PATCHES_PG_action_ref)
    active_turn_index: IntProperty(default=0)
    goal: PointerProperty(
        type=bpy.types.Object,
        name="Goal",
        description="Object whose location and facing (-Y) is the goal",
        poll=_goal_poll,
    )
    alpha: PLANNING["alpha"]()
    beta: PLANNING["beta"]()
    gamma: PLANNING["gamma"]()
    radius: PLANNING["radius"]()
    stitching: PLANNING["stitching"]()
    foot_lock: PLANNING["foot_lock"]()
    goal_facing: PLANNING["goal_facing"]()
    turn_in_place: PLANNING["turn_in_place"]()
    fit_frame_range: PLANNING["fit_frame_range"]()
    gait: EnumProperty(
        name="Gait",
        default="ACTIVE",
        items=(
            ("ACTIVE", "Active Patch", "Plan with the active locomotion patch"),
            ("WALK", "Walk", "Plan with the patch of the walk layer"),
            ("RUN", "Run", "Plan with the patch of the run layer"),
            (
                "AUTO",
                "Automatic",
                "Plan in every layer baked (and walk, run, walk where a run-layer hurdle "
                "pays) and keep the cheapest",
            ),
        ),
        description="Which gait layer Plan Path walks in",
    )
    show_overlay: BoolProperty(
        name="Show Planner Overlay",
        default=False,
        description="Draw the tile grid, occluded cells, planned paths, stitches and where "
        "the props' clips start and end",
        update=lambda self, context: _overlay_toggle(self.show_overlay),
    )
    overlay_all_lattices: BoolProperty(
        name="Every Character's Grid",
        default=False,
        description="Draw the tile grid, occluded cells and props walked round of every "
        "visible planned character, not only the active one's (a crowd's grids overlap)",
    )


class MOTION_PATCHES_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = __package__  # the root package: bl_ext.<repository>.motion_patches

    alpha: PLANNING["alpha"]()
    beta: PLANNING["beta"]()
    gamma: PLANNING["gamma"]()
    radius: PLANNING["radius"]()
    stitching: PLANNING["stitching"]()
    foot_lock: PLANNING["foot_lock"]()
    goal_facing: PLANNING["goal_facing"]()
    turn_in_place: PLANNING["turn_in_place"]()
    fit_frame_range: PLANNING["fit_frame_range"]()
    cells: BAKE["cells"]()
    nodes: BAKE["nodes"]()

    def draw(self, context):
        # One headed section each (a column's heading= would only label its first
        # checkbox, and show nothing before a number field).
        layout = self.layout
        for idname, title, names in (
            ("motion_patches_prefs_planning", "Planning Defaults", PLANNING),
            ("motion_patches_prefs_bake", "Bake Defaults", BAKE),
        ):
            body = _section(layout, idname, title)
            if body is None:  # collapsed
                continue
            body.use_property_split = True
            body.use_property_decorate = False
            for name in names:
                body.prop(self, name)
        layout.label(
            text="Planning > Reset to Preferences copies the planning defaults into a scene",
            icon="INFO",
        )


def _section(layout, idname, title):
    """A collapsible section with a header (a layout panel); its body, None when closed."""
    try:
        header, body = layout.panel(idname, default_closed=False)
    except (AttributeError, RuntimeError, TypeError):  # drawn outside a panel
        layout.label(text=title)
        return layout.column()
    header.label(text=title)
    return body


def preferences(context):
    """The add-on's preferences, or None (not enabled as an add-on, e.g. in some scripts)."""
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon is not None else None


classes = (
    MOTION_PATCHES_PG_patch,
    MOTION_PATCHES_PG_action_ref,
    MOTION_PATCHES_PG_patch_clip,
    MOTION_PATCHES_PG_object,
    MOTION_PATCHES_PG_bone_pair,
    MOTION_PATCHES_PG_rig,
    MOTION_PATCHES_PG_character,
    MOTION_PATCHES_PG_scene,
    MOTION_PATCHES_AP_preferences,
)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Scene.motion_patches = PointerProperty(type=MOTION_PATCHES_PG_scene)
    bpy.types.Object.motion_patch = PointerProperty(type=MOTION_PATCHES_PG_object)
    bpy.types.Object.motion_patches_character = PointerProperty(type=MOTION_PATCHES_PG_character)
    bpy.types.Armature.motion_patches_rig = PointerProperty(type=MOTION_PATCHES_PG_rig)


def unregister():
    del bpy.types.Armature.motion_patches_rig
    del bpy.types.Object.motion_patches_character
    del bpy.types.Object.motion_patch
    del bpy.types.Scene.motion_patches
    _unregister()
