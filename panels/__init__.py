"""UI: the Motion Patches tab of the 3D viewport's sidebar."""

import bpy

from . import main

classes = main.classes

register, unregister = bpy.utils.register_classes_factory(classes)
