# SPDX-License-Identifier: GPL-3.0-or-later
"""Shared set-up for the tests that run inside Blender (bpy from PyPI).

Why this file exists: bpy reads its user directories once, at import, and an add-on shipped as an
extension only gets its real module name (``bl_ext.<repo>.motion_patches``) when Blender loads it
from an extension repository. So this conftest

* points every Blender user directory at a throw-away session directory *before* anything
  imports bpy (the developer's own Blender preferences and add-ons are never touched or used);
* registers a temporary local extension repository whose ``motion_patches`` entry is a symlink
  to this working tree, and enables the add-on from there with errors raised, not swallowed.

Fixtures: ``addon_module_name`` / ``addon_module`` (session), ``clean_scene`` (function),
``mocap_dir`` (session), ``walk_blend`` (session: a .blend with the walk patch baked once).
``MOCAP_DIR`` and ``REPO_ROOT`` can also be imported from here.

Run these tests with ``./dev test``: one process per Blender version (bpy can be imported
only once per process). Keep ``tests/`` and ``tests/blender/`` without ``__init__.py``: pytest
would otherwise import the repository root (the add-on package, which imports bpy) first.
"""

import atexit
import os
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
EXTENSION_ID = "motion_patches"
# Module name of the temporary extension repository; the add-on becomes bl_ext.<this>.<id>.
TEST_REPO_MODULE = "motion_patches_tests"

# Motion capture data: $MOTION_PATCHES_MOCAP, else shared/mocap beside the repository
# (CI clones the repository with shared/ as a sibling).
MOCAP_DIR = Path(
    os.environ.get("MOTION_PATCHES_MOCAP") or (REPO_ROOT.parent / "shared" / "mocap")
).resolve()


# --- Blender user directories: must happen before the first `import bpy` ------------------

if "bpy" in sys.modules:
    raise RuntimeError(
        "bpy was imported before tests/blender/conftest.py could isolate Blender's user "
        "directories; do not import bpy from a parent conftest or plugin"
    )


def blender_user_env(base):
    """Environment variables that put all of Blender's user directories under ``base``.

    The specific variables win over BLENDER_USER_RESOURCES, so they are set too (a developer
    may have them in the environment).
    """
    base = Path(base)
    env = {"BLENDER_USER_RESOURCES": str(base)}
    for var, sub in (
        ("BLENDER_USER_CONFIG", "config"),
        ("BLENDER_USER_SCRIPTS", "scripts"),
        ("BLENDER_USER_DATAFILES", "datafiles"),
        ("BLENDER_USER_EXTENSIONS", "extensions"),
    ):
        env[var] = str(base / sub)
    return env


BLENDER_HOME = Path(tempfile.mkdtemp(prefix="motion_patches-blender-user-"))
os.environ.update(blender_user_env(BLENDER_HOME))
# Registered before bpy is imported, so it runs after bpy's own exit handlers.
atexit.register(shutil.rmtree, BLENDER_HOME, ignore_errors=True)

# isort: off
import bpy  # noqa: E402
import addon_utils  # noqa: E402  (ships with bpy; importable once bpy is)
# isort: on


def raise_error(ex):
    """``handle_error`` for addon_utils: fail loudly instead of printing and carrying on."""
    raise ex


def add_local_extension_repo(name, module, directory):
    """Register a local (no remote URL) extension repository at ``directory``.

    ``preferences.extensions.repos.new`` behaves the same in bpy 4.5 and 5.0 and, unlike the
    ``preferences.extension_repo_add`` operator, needs no UI context. It also registers
    ``bl_ext.<module>`` so add-ons in ``directory`` can be enabled at once.
    """
    repos = bpy.context.preferences.extensions.repos
    repo = repos.new(name=name, module=module, custom_directory=str(directory), source="USER")
    assert repo.module == module, f"extension repository module is {repo.module!r}, not {module!r}"
    return repo


def enable_addon(module_name):
    """Enable an add-on, raising the add-on's own exception if it fails to load or register."""
    mod = addon_utils.enable(module_name, default_set=True, handle_error=raise_error)
    if mod is None or addon_utils.check(module_name) != (True, True):
        raise RuntimeError(
            f"add-on {module_name} did not enable: "
            f"addon_utils.check -> {addon_utils.check(module_name)}"
        )
    return mod


def disable_addon(module_name):
    addon_utils.disable(module_name, default_set=True, handle_error=raise_error)


# --- fixtures ------------------------------------------------------------------------------


@pytest.fixture(scope="session")
def addon_module_name(tmp_path_factory):
    """``bl_ext.motion_patches_tests.motion_patches``: this working tree, enabled as an
    extension."""
    repo_dir = tmp_path_factory.mktemp("extension_repo")
    link = repo_dir / EXTENSION_ID
    try:
        link.symlink_to(REPO_ROOT, target_is_directory=True)
    except OSError:  # no symlinks (e.g. some Windows set-ups): copy the package instead
        shutil.copytree(
            REPO_ROOT,
            link,
            ignore=shutil.ignore_patterns(
                ".*", "tests", "bench", "sample_blends", "tools", "dist", "__pycache__"
            ),
        )
    repo = add_local_extension_repo("Motion Patches tests", TEST_REPO_MODULE, repo_dir)
    module_name = f"bl_ext.{repo.module}.{EXTENSION_ID}"
    enable_addon(module_name)
    yield module_name
    if addon_utils.check(module_name)[1]:
        disable_addon(module_name)
    bpy.context.preferences.extensions.repos.remove(repo)


@pytest.fixture(scope="session")
def addon_module(addon_module_name):
    """The enabled add-on's Python module (the package at the repository root)."""
    return sys.modules[addon_module_name]


@pytest.fixture
def mp(addon_module_name):
    """The add-on's module, looked up per test: switching the add-on off and on (some
    modules do) reloads it, and a session-wide reference would be the old one."""
    return sys.modules[addon_module_name]


@pytest.fixture
def clean_scene(addon_module_name):
    """An empty scene, freshly reset, with the add-on still enabled; yields
    ``bpy.context.scene``."""
    bpy.ops.wm.read_homefile(use_empty=True)
    # read_homefile(use_empty=True) keeps the preferences, hence the add-on, in bpy 4.5 and 5.0;
    # re-enable anyway should a future version reload them.
    if addon_utils.check(addon_module_name) != (True, True):
        enable_addon(addon_module_name)
    yield bpy.context.scene


@pytest.fixture(scope="session")
def mocap_dir():
    """``MOCAP_DIR``, failing (not skipping) when the motion capture data is not there."""
    if not MOCAP_DIR.is_dir():
        pytest.fail(
            f"motion capture data not found at {MOCAP_DIR}: set MOTION_PATCHES_MOCAP or "
            "place shared/mocap beside the repository"
        )
    return MOCAP_DIR


@pytest.fixture(scope="session")
def walk_blend(addon_module, mocap_dir, tmp_path_factory):
    """A saved .blend with the walk patch baked once per session through the API (CMU
    16_15 + 16_18 imported on the armature 'Source', the scene's source armature): modules
    that only plan open it instead of baking again."""
    api = addon_module.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap(
        [mocap_dir / "cmu" / "16_15.bvh", mocap_dir / "cmu" / "16_18.bvh"], name="Source"
    )
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    scene.motion_patches.source_armature = arm
    path = tmp_path_factory.mktemp("walk") / "baked.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path
