# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene-building helpers shared by the Blender tests."""

import bpy
import numpy as np


def pillar(name, x, y, r=0.25, h=2.0):
    bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=h, location=(x, y, h / 2))
    bpy.context.object.name = name
    return bpy.context.object


def prop_box(name, x, y, size=(0.4, 0.44, 0.5)):
    """A box prop (a chair's bulk) standing on the ground at (x, y)."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, size[2] / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = size
    return ob


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
