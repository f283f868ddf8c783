# SPDX-License-Identifier: GPL-3.0-or-later
"""UI: the Motion Patches tab of the 3D viewport's sidebar (one panel per concept, in the
order an animator works: locomotion patches, object patch, planning, analysis, overlay)
and the planner overlay's draw handler."""

import bpy

from . import analysis, file_import, locomotion, object_patch, overlay, planning

classes = (
    locomotion.classes
    + object_patch.classes
    + planning.classes
    + analysis.classes
    + overlay.classes
)

_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    file_import.register()
    overlay.register_handlers()  # the overlay follows the file's setting (load_post)


def unregister():
    overlay.unregister_handlers()
    file_import.unregister()
    _unregister()
