# SPDX-License-Identifier: GPL-3.0-or-later
"""File > Import and File > Export entries: motion capture (BVH) as clips for a bake, and
a baked patch (.mpatch) read and written. They open the same operators as the sidebar's
buttons. The BVH entry sits beside Blender's own "Motion Capture (.bvh)": its label says
what it is for, its tooltip how it differs (one armature for every clip, in metres)."""

import bpy

IMPORTS = (
    ("motion_patches.import_mocap", "Motion Patches Clips to Bake (.bvh)"),
    ("motion_patches.import_patch", "Motion Patches Patch (.mpatch)"),
)
EXPORTS = (("motion_patches.export_patch", "Motion Patches Patch (.mpatch)"),)


def draw_entries(self, context):
    for idname, text in IMPORTS:
        self.layout.operator(idname, text=text)


def draw_exports(self, context):
    for idname, text in EXPORTS:
        self.layout.operator(idname, text=text)


def register():
    bpy.types.TOPBAR_MT_file_import.append(draw_entries)
    bpy.types.TOPBAR_MT_file_export.append(draw_exports)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(draw_exports)
    bpy.types.TOPBAR_MT_file_import.remove(draw_entries)
