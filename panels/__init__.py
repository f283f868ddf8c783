"""UI: the Motion Patches tab of the 3D viewport's sidebar."""

import bpy

from . import main, overlay

classes = main.classes

_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()


def unregister():
    overlay.disable()  # never leave a draw handler behind
    _unregister()
