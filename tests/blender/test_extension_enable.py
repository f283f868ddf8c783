# SPDX-License-Identifier: GPL-3.0-or-later
"""The working tree loads as a Blender extension and survives being switched off and on."""

import sys
from pathlib import Path

import addon_utils
import bpy

from conftest import BLENDER_HOME, EXTENSION_ID, REPO_ROOT, TEST_REPO_MODULE, raise_error


def test_addon_is_enabled_under_its_extension_module_name(addon_module_name):
    assert addon_module_name == f"bl_ext.{TEST_REPO_MODULE}.{EXTENSION_ID}"
    assert addon_module_name in bpy.context.preferences.addons
    assert addon_utils.check(addon_module_name) == (True, True)


def test_addon_module_is_this_working_tree(addon_module):
    assert addon_module.__name__.startswith("bl_ext.")
    assert hasattr(addon_module, "register") and hasattr(addon_module, "unregister")
    # The repository is symlinked into the extension repository: resolve to compare.
    assert Path(addon_module.__file__).resolve() == REPO_ROOT / "__init__.py"


def test_register_and_unregister_cycle_twice_without_errors(addon_module_name):
    for _ in range(2):
        addon_utils.disable(addon_module_name, default_set=True, handle_error=raise_error)
        assert addon_utils.check(addon_module_name) == (False, False)
        assert addon_module_name not in bpy.context.preferences.addons

        mod = addon_utils.enable(addon_module_name, default_set=True, handle_error=raise_error)
        assert mod is not None
        assert addon_utils.check(addon_module_name) == (True, True)
        assert addon_module_name in bpy.context.preferences.addons
        assert addon_module_name in sys.modules


def test_clean_scene_is_empty_and_keeps_the_addon(clean_scene, addon_module_name):
    assert clean_scene == bpy.context.scene
    assert len(clean_scene.objects) == 0
    assert addon_module_name in bpy.context.preferences.addons


def test_blender_user_directories_are_the_session_temp_dir():
    for resource in ("CONFIG", "SCRIPTS", "DATAFILES", "EXTENSIONS"):
        path = Path(bpy.utils.user_resource(resource)).resolve()
        assert path.is_relative_to(BLENDER_HOME.resolve()), f"{resource}: {path}"
