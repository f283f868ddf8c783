# SPDX-License-Identifier: GPL-3.0-or-later
"""The overlay follows the file: a .blend saved with it ticked draws it when opened again, and
after the add-on is disabled and enabled again; one saved without it draws nothing."""

import addon_utils
import bpy


def test_the_overlay_is_drawn_again_after_opening_a_file_and_reloading_the_addon(
    addon_module, tmp_path
):
    overlay = addon_module.panels.overlay
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.context.scene.motion_patches.show_overlay = True
    assert overlay.is_enabled()
    on = tmp_path / "overlay_on.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(on))
    bpy.context.scene.motion_patches.show_overlay = False
    off = tmp_path / "overlay_off.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(off))
    assert not overlay.is_enabled()

    bpy.ops.wm.open_mainfile(filepath=str(on))
    assert bpy.context.scene.motion_patches.show_overlay
    assert overlay.is_enabled()  # was: ticked, and nothing drawn

    bpy.ops.wm.open_mainfile(filepath=str(off))
    assert not overlay.is_enabled()

    bpy.ops.wm.open_mainfile(filepath=str(on))
    name = addon_module.__name__
    addon_utils.disable(name, default_set=True)
    try:
        assert not overlay.is_enabled()  # no handler left behind
        assert overlay._on_load not in bpy.app.handlers.load_post
    finally:
        addon_utils.enable(name, default_set=True)
    overlay = __import__(name, fromlist=["panels"]).panels.overlay
    assert overlay.is_enabled()  # enabled again with the file's overlay ticked
    bpy.context.scene.motion_patches.show_overlay = False
    assert not overlay.is_enabled()
