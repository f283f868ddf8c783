# SPDX-License-Identifier: GPL-3.0-or-later
"""File > Import entries: motion capture (BVH) as clips for a bake, and a baked patch
(.mpatch) written by Export Patch. They open the same operators as the sidebar's buttons."""

import bpy

ENTRIES = (
    ("motion_patches.import_mocap", "Motion Patches Mocap (.bvh)"),
    ("motion_patches.import_patch", "Motion Patches Patch (.mpatch)"),
)


def draw_entries(self, context):
    for idname, text in ENTRIES:
        self.layout.operator(idname, text=text)


def register():
    bpy.types.TOPBAR_MT_file_import.append(draw_entries)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(draw_entries)
