# SPDX-License-Identifier: GPL-3.0-or-later
"""The extension builds into a zip that Blender accepts, installs and enables.

Uses ``blender_ext.py``, the extension command line tool that ships inside the bpy wheel
(``bpy/<version>/scripts/addons_core/bl_pkg/cli/blender_ext.py``), so no Blender binary is
needed: ``validate [SOURCE_PATH]`` and ``build --source-dir DIR --output-dir DIR``.

The zip is installed in a separate Python process with its own Blender user directories: the
working tree is already enabled in this process as ``bl_ext.motion_patches_tests.motion_patches``
and two copies of one extension id in two repositories must not meet.
"""

import json
import os
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import bpy
import pytest

from conftest import EXTENSION_ID, REPO_ROOT, blender_user_env

# Top-level entries of the working tree that must never ship in the zip.
DEV_ONLY_DIRS = (
    "tests/",
    "bench/",
    "sample_blends/",
    "samples/",
    "tools/",
    "requirements/",
    "dist/",
    "examples/",
    "docs/",
    ".ci/",
    ".venv/",
    ".git/",
    ".pytest_cache/",
)
DEV_ONLY_FILES = ("dev", ".gitignore", "THIRD_PARTY_NOTICES.md")
CLI_TIMEOUT_S = 300


def bpy_package_dir():
    """The installed bpy wheel's directory (``site-packages/bpy``).

    Not ``bpy.__file__``: once imported, ``bpy`` is Blender's Python package inside
    ``bpy/<version>/scripts/modules``; the scripts directory is two levels below the wheel's.
    """
    return Path(bpy.utils.system_resource("SCRIPTS")).resolve().parents[1]


@pytest.fixture(scope="module")
def blender_ext_cli():
    """Path of the blender_ext.py shipped inside the installed bpy package."""
    bpy_dir = bpy_package_dir()
    found = sorted(bpy_dir.glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py")) or sorted(
        bpy_dir.glob("**/bl_pkg/cli/blender_ext.py")
    )
    if not found:
        pytest.fail(
            f"blender_ext.py not found under {bpy_dir} (looked for **/bl_pkg/cli/blender_ext.py): "
            "this bpy wheel does not ship the extension command line tool"
        )
    return found[0]


def run_cli(cli, *args):
    """Run blender_ext.py with this venv's Python; fail with its output if it fails."""
    cmd = [sys.executable, str(cli), *map(str, args)]
    result = subprocess.run(
        cmd, capture_output=True, text=True, timeout=CLI_TIMEOUT_S, stdin=subprocess.DEVNULL
    )
    if result.returncode != 0:
        pytest.fail(
            f"{' '.join(cmd)} exited {result.returncode}\n"
            f"--- stdout ---\n{result.stdout}\n--- stderr ---\n{result.stderr}"
        )
    return result.stdout


@pytest.fixture(scope="module")
def built_zip(blender_ext_cli, tmp_path_factory):
    out_dir = tmp_path_factory.mktemp("dist")  # build needs an existing output directory
    run_cli(blender_ext_cli, "build", "--source-dir", REPO_ROOT, "--output-dir", out_dir)
    zips = sorted(out_dir.glob("*.zip"))
    assert len(zips) == 1, f"expected one zip in {out_dir}, found {[z.name for z in zips]}"
    return zips[0]


def test_manifest_in_working_tree_validates(blender_ext_cli):
    run_cli(blender_ext_cli, "validate", REPO_ROOT)


def test_built_zip_is_named_after_id_and_version(built_zip):
    manifest = tomllib.loads((REPO_ROOT / "blender_manifest.toml").read_text(encoding="utf-8"))
    assert manifest["id"] == EXTENSION_ID
    assert built_zip.name == f"{EXTENSION_ID}-{manifest['version']}.zip"


def test_built_zip_validates(blender_ext_cli, built_zip):
    run_cli(blender_ext_cli, "validate", built_zip)


def test_built_zip_has_manifest_and_package_at_its_root(built_zip):
    names = set(zipfile.ZipFile(built_zip).namelist())
    assert "blender_manifest.toml" in names
    assert "__init__.py" in names


def test_built_zip_ships_no_development_files(built_zip):
    names = zipfile.ZipFile(built_zip).namelist()
    leaked = [
        n
        for n in names
        if n.startswith(DEV_ONLY_DIRS)
        or n in DEV_ONLY_FILES
        or "__pycache__/" in n
        or n.endswith((".md", ".pyc"))
    ]
    assert not leaked, f"development files in {built_zip.name}: {leaked}"


# Runs in a fresh interpreter: prints one JSON line (prefixed) describing what it saw.
INSTALL_SCRIPT = r"""
import json, os, sys, traceback
zip_path, repo_dir = sys.argv[1], sys.argv[2]
import bpy
import addon_utils

ext_id = "motion_patches"
repo_module = "zip_install_test"
module_name = f"bl_ext.{repo_module}.{ext_id}"
out = {"errors": []}

def raise_error(ex):
    raise ex

try:
    bpy.context.preferences.extensions.repos.new(
        name="Zip install test", module=repo_module, custom_directory=repo_dir, source='USER')
    # Some failures (e.g. an unreadable zip) are only reported (printed as "ERROR ...") while the
    # operator still returns {'FINISHED'}; others (register() raising) raise RuntimeError.
    out["operator_result"] = sorted(bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo=repo_module, enable_on_install=True))
    pkg_dir = os.path.join(repo_dir, ext_id)
    out["installed_files"] = sorted(os.listdir(pkg_dir)) if os.path.isdir(pkg_dir) else None
    out["check_after_install"] = list(addon_utils.check(module_name))
    if out["check_after_install"] != [True, True]:
        # Surface the add-on's own exception.
        addon_utils.enable(module_name, default_set=True, handle_error=raise_error)
    out["in_preferences"] = module_name in bpy.context.preferences.addons
    mod = sys.modules.get(module_name)
    out["module_file"] = getattr(mod, "__file__", None)

    # Operators: every class the add-on's operators package registers must be callable.
    operator_classes = getattr(getattr(mod, "operators", None), "classes", ())
    out["operator_idnames"] = [c.bl_idname for c in operator_classes if hasattr(c, "bl_idname")]
    out["ops_namespace"] = "motion_patches" in dir(bpy.ops)
    missing = []
    for idname in out["operator_idnames"]:
        space, _, op = idname.partition(".")
        if not hasattr(getattr(bpy.ops, space), op):
            missing.append(idname)
    out["missing_operators"] = missing
    out["has_bake_locomotion_patch"] = (
        out["ops_namespace"] and hasattr(bpy.ops.motion_patches, "bake_locomotion_patch"))

    # Cycle the installed copy off and on again, then leave it off.
    addon_utils.disable(module_name, default_set=True, handle_error=raise_error)
    out["check_after_disable"] = list(addon_utils.check(module_name))
    addon_utils.enable(module_name, default_set=True, handle_error=raise_error)
    out["check_after_reenable"] = list(addon_utils.check(module_name))
    addon_utils.disable(module_name, default_set=True, handle_error=raise_error)
except Exception:
    out["errors"].append(traceback.format_exc())
print("RESULT-JSON " + json.dumps(out), flush=True)
"""


@pytest.fixture(scope="module")
def install_report(built_zip, tmp_path_factory):
    """Install the zip into a fresh local repository of a fresh Blender (a subprocess)."""
    base = tmp_path_factory.mktemp("zip_install")
    user_dir, repo_dir = base / "blender_user", base / "repo"
    repo_dir.mkdir()
    env = {**os.environ, **blender_user_env(user_dir)}
    cmd = [sys.executable, "-c", INSTALL_SCRIPT, str(built_zip), str(repo_dir)]
    proc = subprocess.run(
        cmd,
        capture_output=True,
        text=True,
        env=env,
        timeout=CLI_TIMEOUT_S,
        stdin=subprocess.DEVNULL,
        cwd=base,
    )
    output = f"--- stdout ---\n{proc.stdout}\n--- stderr ---\n{proc.stderr}"
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("RESULT-JSON ")]
    if proc.returncode != 0 or not lines:
        pytest.fail(f"install subprocess exited {proc.returncode} without a result\n{output}")
    report = json.loads(lines[-1][len("RESULT-JSON ") :])
    if report["errors"]:
        pytest.fail("installing or enabling the zip raised:\n" + "".join(report["errors"]) + output)
    report["output"] = output
    report["repo_dir"] = repo_dir
    return report


def test_zip_installs_without_errors(install_report):
    r = install_report
    error_lines = [ln for ln in r["output"].splitlines() if ln.startswith("ERROR")]
    assert not error_lines, r["output"]
    assert r["operator_result"] == ["FINISHED"], r["output"]


def test_installed_package_has_manifest_and_init(install_report):
    files = install_report["installed_files"]
    assert files is not None, (
        f"nothing installed in {install_report['repo_dir']}\n{install_report['output']}"
    )
    assert "blender_manifest.toml" in files
    assert "__init__.py" in files
    assert "tests" not in files


def test_installed_addon_is_enabled_from_the_installed_copy(install_report):
    r = install_report
    assert r["check_after_install"] == [True, True], r["output"]
    assert r["in_preferences"], r["output"]
    assert r["module_file"] is not None
    assert Path(r["module_file"]).parent == r["repo_dir"] / EXTENSION_ID


def test_installed_addon_registers_its_operators(install_report):
    r = install_report
    assert r["missing_operators"] == [], r["output"]
    if r["operator_idnames"]:
        assert r["ops_namespace"], "operators declared but bpy.ops.motion_patches is missing"
    assert r["has_bake_locomotion_patch"], r["output"]
    assert {"motion_patches.plan_path", "motion_patches.bake_locomotion_patch"} <= set(
        r["operator_idnames"]
    )


def test_installed_addon_can_be_disabled_and_enabled_again(install_report):
    r = install_report
    assert r["check_after_disable"] == [False, False], r["output"]
    assert r["check_after_reenable"] == [True, True], r["output"]
