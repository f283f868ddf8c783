# SPDX-License-Identifier: GPL-3.0-or-later
"""Start bpy with throw-away user folders and this working tree enabled as an extension.

Used by the demo and other scripts run outside Blender's UI, so they exercise the add-on
exactly as an installed extension (module ``bl_ext.<repo>.motion_patches``) without
touching the user's own Blender preferences.
"""

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
REPO_MODULE = "motion_patches_local"


def start():
    """Import bpy isolated, enable the add-on, and return (bpy, add-on module)."""
    if "bpy" in sys.modules:
        raise RuntimeError("start() must run before anything imports bpy")
    home = Path(tempfile.mkdtemp(prefix="motion_patches-session-"))
    atexit.register(shutil.rmtree, home, ignore_errors=True)
    os.environ["BLENDER_USER_RESOURCES"] = str(home)
    for var, sub in (
        ("BLENDER_USER_CONFIG", "config"),
        ("BLENDER_USER_SCRIPTS", "scripts"),
        ("BLENDER_USER_DATAFILES", "datafiles"),
        ("BLENDER_USER_EXTENSIONS", "extensions"),
    ):
        os.environ[var] = str(home / sub)
    # isort: off
    import bpy
    import addon_utils  # ships with bpy: importable only once bpy is

    # isort: on
    repo_dir = home / "repo"
    repo_dir.mkdir()
    (repo_dir / "motion_patches").symlink_to(REPO_ROOT, target_is_directory=True)
    bpy.context.preferences.extensions.repos.new(
        name="Motion Patches (working tree)",
        module=REPO_MODULE,
        custom_directory=str(repo_dir),
        source="USER",
    )
    name = f"bl_ext.{REPO_MODULE}.motion_patches"

    def fail(exc):
        raise exc

    addon_utils.enable(name, default_set=True, handle_error=fail)
    return bpy, sys.modules[name]
