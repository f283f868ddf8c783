"""Scene-building helpers shared by the Blender tests."""

import bpy
import numpy as np


def pillar(name, x, y, r=0.25, h=2.0):
    bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=h, location=(x, y, h / 2))
    bpy.context.object.name = name
    return bpy.context.object


def empty(name, x, y, heading):
    """An empty whose -Y axis (the add-on's facing convention) points along ``heading``."""
    ob = bpy.data.objects.new(name, None)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = (x, y, 0)
    ob.rotation_euler = (0, 0, heading + np.pi / 2)
    return ob


def walker_from(source, name="Walker", location=(0.4, 0.3, 0.0)):
    """A copy of the source armature with no animation, linked to the scene."""
    walker = source.copy()
    walker.name = name
    walker.animation_data_clear()
    bpy.context.scene.collection.objects.link(walker)
    walker.location = location
    return walker
