# SPDX-License-Identifier: GPL-3.0-or-later
"""Feet on a rig the patch was not baked from: the subject-16 walk patch played on CMU
subject 2 (another thigh-to-shin ratio), under its own names and Mixamo's, through open
ground, a pillar field and a U-turn round a wall's end. Written as the API writes a plan
(retargeted, contacts kept where the feet are still as played on that rig, the lock solved
on that rig's legs with its frame rate) and judged by the label-free foot measure against
subject 2's own recording (02_01) by the same measure. The Blender suite checks the same
bounds on the evaluated rigs (tests/blender/test_retargeted_feet.py)."""

import numpy as np
import pytest

from motion_patches.kinematics import foot_lock
from motion_patches.kinematics.clip import resample
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.kinematics.retarget import rig_map
from motion_patches.kinematics.skeleton import Skeleton
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import foot_measure as fm

from conftest import cmu
from rig_names import MIXAMO

ORIGIN = np.array([5.0, 5.0, 0.0])


def wall(name, p, q, thickness=0.2):
    p, q = np.asarray(p, float), np.asarray(q, float)
    d = (q - p) / np.linalg.norm(q - p)
    n = np.array([-d[1], d[0]]) * thickness / 2
    return Obstacle(name, np.array([p - n, q - n, q + n, p + n]))


def pillar(name, x, y, r=0.25):
    a = np.linspace(0.0, 2.0 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


# obstacles and the goal (x, y, heading), the start at the origin facing +X
SCENES = {
    "open-ground": ([], (6.0, -1.5, -0.2)),
    "pillars": ([pillar("a", 2.6, 0.7), pillar("b", 4.1, 2.7)], (6.6, 3.7, 0.3)),
    "u-turn": ([wall("wall", (-3.5, -1.0), (2.5, -1.0))], (0.0, -2.0, np.pi)),
}


@pytest.fixture(scope="module")
def subject2():
    return cmu("02_01")


@pytest.fixture(scope="module")
def recording(subject2, walk_patch):
    """The label-free figures of subject 2's own walk at the patch's rate."""
    return fm.of_clip(resample(subject2, walk_patch.gait.fps))


def rig(subject2, naming):
    skel = subject2.skeleton
    if naming == "mixamo":
        return Skeleton([MIXAMO.get(n, n) for n in skel.names], skel.parents, skel.rest)
    return skel


def written(walk_patch, target, scene, lift=True):
    """The plan of ``scene`` on ``target`` as the API writes it: the label-free figures of
    its locked feet."""
    obstacles, goal = SCENES[scene]
    env = Environment(walk_patch.side, walk_patch.cells, 0.25)
    for o in obstacles:
        env.place(Obstacle(o.name, o.polygon + ORIGIN[:2]))
    plan = SegmentPlanner(walk_patch, env).plan(ORIGIN, ORIGIN + goal)
    rm = rig_map(walk_patch.gait.skeleton, target, floor=walk_patch.gait.floor())
    skel, fps = rm.target, walk_patch.gait.fps
    m = concatenate([rm.motion(p) for p in plan_motions(walk_patch, plan)])
    posed = foot_lock.pose_legs(skel, m)
    m = Motion(m.ground, m.root_local, m.rotations, foot_lock.still_contacts(skel, m, fps, posed))
    rot = foot_lock.lock_feet(skel, m, posed=posed, fps=fps if lift else None)
    w = Motion(m.ground, m.root_local, rot, m.contacts).world_matrices(skel)[..., :3, 3]
    ankles, toes = fm.foot_bones(skel)
    return fm.measure(w[:, toes], w[:, ankles], fps)


@pytest.mark.parametrize("scene", list(SCENES))
@pytest.mark.parametrize("naming", ["cmu", "mixamo"])
def test_retargeted_feet_hold_as_the_rigs_own_recording(
    walk_patch, subject2, recording, naming, scene
):
    f = written(walk_patch, rig(subject2, naming), scene)
    own = recording["weighted_skate"]["mean_cm_per_s"]
    print(f"\nsubject 2 ({naming}), {scene}: {fm.summary(f)}; recording {fm.summary(recording)}")
    assert f["max_end_ankle_off_cm"] <= 3.0  # first and last frame stand
    assert f["pops"] == 0  # no planted toe jumps over 1 cm in one frame
    assert f["swings"] > 0 and f["min_swing_clearance_cm"] > 0.5
    assert f["weighted_skate"]["mean_cm_per_s"] <= 1.25 * own


def test_without_the_swing_lift_the_retargeted_toes_scuff(walk_patch, subject2):
    """The same U-turn locked without the swing lift: a toe swings through the floor of
    its own plants (the other thigh-to-shin ratio drops a bent leg's foot)."""
    f = written(walk_patch, subject2.skeleton, "u-turn", lift=False)
    assert f["min_swing_clearance_cm"] < 0.5
