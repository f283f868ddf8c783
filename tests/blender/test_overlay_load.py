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


def test_undo_and_redo_bring_the_overlay_back_in_step_with_its_checkbox(addon_module):
    """Undo puts Show Planner Overlay back without its update callback (the checkbox ticked,
    nothing drawn until the file was opened again): the add-on syncs after undo and redo."""
    overlay = addon_module.panels.overlay
    bpy.ops.wm.read_homefile(use_empty=True)
    s = bpy.context.scene.motion_patches
    s.show_overlay = False
    assert not overlay.is_enabled()
    for name in ("undo_post", "redo_post"):
        s["show_overlay"] = True  # what undo does: the stored value, no update callback
        assert not overlay.is_enabled()
        for handler in list(getattr(bpy.app.handlers, name)):
            handler(bpy.context.scene, None)
        assert overlay.is_enabled(), name
        s["show_overlay"] = False
        for handler in list(getattr(bpy.app.handlers, name)):
            handler(bpy.context.scene, None)
        assert not overlay.is_enabled(), name
