"""Properties the add-on stores in the .blend: baked patches and planning settings."""

import bpy
from bpy.props import (CollectionProperty, FloatProperty, IntProperty, PointerProperty,
                       StringProperty)


class MOTION_PATCHES_PG_patch(bpy.types.PropertyGroup):
    layer: StringProperty(name="Layer", description="Gait of this locomotion patch")
    payload: StringProperty(name="Payload", description="Baked patch (base64 npz)",
                            options={'HIDDEN'})
    stats: StringProperty(name="Statistics", description="Bake report (JSON)", options={'HIDDEN'})
    fps: FloatProperty(name="Frame Rate", description="Frame rate the patch was baked at")


class MOTION_PATCHES_PG_action_ref(bpy.types.PropertyGroup):
    action: PointerProperty(type=bpy.types.Action, name="Action")


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


classes = (MOTION_PATCHES_PG_patch, MOTION_PATCHES_PG_action_ref, MOTION_PATCHES_PG_scene)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Scene.motion_patches = PointerProperty(type=MOTION_PATCHES_PG_scene)


def unregister():
    del bpy.types.Scene.motion_patches
    _unregister()
