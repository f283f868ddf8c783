# SPDX-License-Identifier: GPL-3.0-or-later
"""Fixtures for the pure-numpy core: real CMU clips read without Blender."""

import os
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from motion_patches.kinematics import bvh
from motion_patches.patch import gait as gait_mod
from motion_patches.patch import locomotion_patch

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


@pytest.fixture(scope="session")
def stand_walk_sit(walk_patch, walk_gait, walk16):
    """Standing up from chair A, walking and sitting down on chair B: CMU subject 13's
    stand-up and sit-down (13_05_standup, 13_05) retargeted onto subject 16 and put down on
    its floor. Returns (plan, environment, [sit source, stand source] retargeted)."""
    import numpy as np

    from motion_patches.kinematics import contacts
    from motion_patches.kinematics.retarget import retarget
    from motion_patches.planning.planner import (
        SegmentPlanner,
        interaction_states,
        with_interactions,
    )
    from motion_patches.props import object_patch as op
    from motion_patches.props.environment import Environment, Obstacle

    floor = contacts.floor_level(walk16)
    sources = [retarget(cmu(n), walk16.skeleton) for n in ("13_05", "13_05_standup")]
    sit, stand = (
        op.patch_clip_from(c, op.INTERACTION, walk_gait.fps, effort=2.0, floor=floor)
        for c in sources
    )
    chair = np.array([[-0.2, -0.22], [0.2, -0.22], [0.2, 0.22], [-0.2, 0.22]])
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    a = op.ObjectPatch("chair A", chair, [stand], pose=(1.0, 1.0, 0.0))
    b = op.ObjectPatch("chair B", chair, [sit], pose=(8.0, 3.0, 2.0))
    for o in (a, b):
        env.place(Obstacle(o.name, o.world_footprint()))
    s, g = interaction_states((a, 0), (b, 0))
    plan = with_interactions(SegmentPlanner(walk_patch, env).plan(s, g), (a, 0), (b, 0))
    return plan, env, sources
