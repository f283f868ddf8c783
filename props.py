"""Properties the add-on stores in the .blend: baked patches and planning settings."""

import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty,
                       IntProperty, PointerProperty, StringProperty)


def _overlay_toggle(on):
    from .panels import overlay
    overlay.enable() if on else overlay.disable()


class MOTION_PATCHES_PG_patch(bpy.types.PropertyGroup):
    layer: StringProperty(name="Layer", description="Gait of this locomotion patch")
    payload: StringProperty(name="Payload", description="Baked patch (base64 npz)",
                            options={'HIDDEN'})
    stats: StringProperty(name="Statistics", description="Bake report (JSON)", options={'HIDDEN'})
    fps: FloatProperty(name="Frame Rate", description="Frame rate the patch was baked at")


class MOTION_PATCHES_PG_action_ref(bpy.types.PropertyGroup):
    action: PointerProperty(type=bpy.types.Action, name="Action")


class MOTION_PATCHES_PG_patch_clip(bpy.types.PropertyGroup):
    action: PointerProperty(type=bpy.types.Action, name="Action",
                            description="Clip recorded on the patch's skeleton")
    kind: EnumProperty(name="Kind", items=(
        ('TRAVERSAL', "Traversal", "Passes the prop (hurdle, vault): used by the planner"),
        ('INTERACTION', "Interaction", "Starts or ends a path at the prop (sit, stand)")))
    effort: FloatProperty(name="Effort (T)", default=8.0, min=0.0,
                          description="Effort of the whole clip, in walking seconds")
    layer_in: StringProperty(name="Layer In", default="walk")
    layer_out: StringProperty(name="Layer Out", default="walk")
    copy_step: FloatProperty(name="Copies Every", default=10.0, min=0.0, max=180.0,
                             description="Copy the clip around the prop every so many "
                                         "degrees (0: no copies)")


class MOTION_PATCHES_PG_object(bpy.types.PropertyGroup):
    enabled: BoolProperty(name="Object Patch", default=False,
                          description="This prop carries clips the planner may use")
    clips: CollectionProperty(type=MOTION_PATCHES_PG_patch_clip)
    active_clip_index: IntProperty(default=0)


class MOTION_PATCHES_PG_scene(bpy.types.PropertyGroup):
    patches: CollectionProperty(type=MOTION_PATCHES_PG_patch)
    active_patch_index: IntProperty(default=0)
    source_armature: PointerProperty(
        type=bpy.types.Object, name="Source Armature",
        description="Armature the mocap clips were imported on",
        poll=lambda self, ob: ob.type == 'ARMATURE')
    straight_action: PointerProperty(type=bpy.types.Action, name="Straight",
                                     description="Straight locomotion clip of the layer")
    turn_actions: CollectionProperty(type=MOTION_PATCHES_PG_action_ref)
    goal: PointerProperty(type=bpy.types.Object, name="Goal",
                          description="Object whose location and facing (+Y) is the goal")
    alpha: FloatProperty(name="Distance (α)", default=1.0, min=0.0,
                         description="Cost per metre walked")
    beta: FloatProperty(name="Turning (β)", default=0.5, min=0.0,
                        description="Cost per radian turned")
    gamma: FloatProperty(name="Effort (γ)", default=0.2, min=0.0,
                         description="Cost per unit of effort")
    radius: FloatProperty(name="Character Radius", default=0.25, min=0.05, max=2.0,
                          unit='LENGTH', description="Clearance kept between the root and props")
    show_overlay: BoolProperty(
        name="Show Planner Overlay", default=False,
        description="Draw the tile grid, occluded cells, planned paths and stitches",
        update=lambda self, context: _overlay_toggle(self.show_overlay))
    stitching: EnumProperty(name="Stitching", default='DYNAMIC', items=(
        ('DYNAMIC', "Dynamic", "Stitch traversal clips lazily, when the search needs them"),
        ('STATIC', "Static", "Stitch every traversal clip before searching (Lee 2006 baseline)")))


classes = (MOTION_PATCHES_PG_patch, MOTION_PATCHES_PG_action_ref, MOTION_PATCHES_PG_patch_clip,
           MOTION_PATCHES_PG_object, MOTION_PATCHES_PG_scene)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Scene.motion_patches = PointerProperty(type=MOTION_PATCHES_PG_scene)
    bpy.types.Object.motion_patch = PointerProperty(type=MOTION_PATCHES_PG_object)


def unregister():
    del bpy.types.Object.motion_patch
    del bpy.types.Scene.motion_patches
    _unregister()
