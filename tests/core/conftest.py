# SPDX-License-Identifier: GPL-3.0-or-later
"""Fixtures for the pure-numpy core: real CMU clips read without Blender."""

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from motion_patches import bvh, locomotion_patch  # noqa: E402
from motion_patches import gait as gait_mod

MOCAP = Path(os.environ.get("MOTION_PATCHES_MOCAP", REPO.parent / "shared" / "mocap"))


def cmu(name, folder="cmu"):
    """A clip of the shared mocap (``folder``: cmu, or cmu16max for the 3ds Max naming)."""
    path = MOCAP / folder / f"{name}.bvh"
    if not path.exists():
        pytest.fail(f"mocap clip missing: {path} (set MOTION_PATCHES_MOCAP)")
    return bvh.read(path)


@pytest.fixture(scope="session")
def walk16():
    return cmu("16_15")


@pytest.fixture(scope="session")
def turn16():
    return cmu("16_18")


@pytest.fixture(scope="session")
def walk_gait(walk16, turn16):
    return gait_mod.build_gait("walk", walk16, (turn16,))


@pytest.fixture(scope="session")
def walk_patch(walk_gait):
    return locomotion_patch.bake(walk_gait)
