# SPDX-License-Identifier: GPL-3.0-or-later
"""A straight walk alone bakes a patch that plans (issue 15, item 3; paper Sec. 6): space-
curve following bends the straight stride into turns, up to the documented default radius
``gait.STRAIGHT_BEND_RADIUS``, and a bake too sparse to connect is refused."""

import numpy as np
import pytest

from motion_patches.kinematics import contacts
from motion_patches.kinematics.motion import concatenate
from motion_patches.patch import curves, locomotion_patch, synthesis
from motion_patches.patch import gait as gait_mod
from motion_patches.patch.locomotion_patch import SparsePatch
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle

from conftest import cmu

STRAIGHT_CLIPS = ("16_15", "02_01")  # subject 16 and subject 2, each a straight walk


@pytest.fixture(scope="module", params=STRAIGHT_CLIPS)
def straight_patch(request):
    """The patch of one straight clip, no turn clip (baked once per clip)."""
    gait = gait_mod.build_gait("walk", cmu(request.param), ())
    return locomotion_patch.bake(gait)


def pillar(name, x, y, r=0.25):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


def walked(patch, env, start, goal):
    """Ground track (F, 3) and root (hips) world positions (F, 3) of the planned walk."""
    plan = SegmentPlanner(patch, env).plan(np.array(start, float), np.array(goal, float))
    world = concatenate(plan_motions(patch, plan))
    root = world.world_matrices(patch.gait.skeleton)[:, patch.gait.skeleton.root, :3, 3]
    return world.ground, root


def open_ground(patch):
    return Environment(patch.side, patch.cells, radius=0.25)


def planted_drift_cm(gait, kappa, cycles=4):
    """Largest distance (cm) a planted foot joint (ankle or toe) strays, over one contact,
    from where it stands on average during it, the straight loop followed along an arc."""
    s = np.linspace(0.0, cycles * gait.cycle_distance, 400)
    pos, heading = curves.arc_frame(np.zeros(2), 0.0, kappa, s)
    motion = synthesis.follow(
        gait,
        curves.Curve(s, pos, heading, np.full(s.size, kappa)),
        cycles=cycles,
        eased=(False, False),
    )
    feet = contacts.foot_joints(gait.skeleton)
    fp = motion.world_matrices(gait.skeleton)[:, feet][..., :2, 3]
    drift = 0.0
    for j in range(feet.size):
        for a, b in zip(*contacts.runs(motion.contacts[:, j])):
            p = fp[a:b, j]
            drift = max(drift, float(np.linalg.norm(p - p.mean(axis=0), axis=1).max()))
    return 100.0 * drift


@pytest.mark.parametrize("name", STRAIGHT_CLIPS)
def test_the_default_bend_keeps_planted_feet_within_10_cm_and_is_the_tightest_that_does(name):
    gait = gait_mod.build_gait("walk", cmu(name), ())
    r = gait_mod.STRAIGHT_BEND_RADIUS
    assert gait.kappa_limits == pytest.approx((-1 / r, 1 / r))
    assert planted_drift_cm(gait, 0.0) < 6.0  # the recording's own
    assert planted_drift_cm(gait, 1 / r) < 10.0  # bent left and right to the default radius
    assert planted_drift_cm(gait, -1 / r) < 10.0
    assert planted_drift_cm(gait, 1 / (r - 0.2)) > 10.0  # 20 cm tighter strays further


def test_a_straight_clip_alone_bakes_a_patch_most_entry_states_leave(straight_patch):
    st = straight_patch.stats
    assert st["curvature_limits"] == pytest.approx([-1.0, 1.0])
    assert st["entry_share"] >= 0.7
    assert straight_patch.segment_count > 100


def test_a_straight_clip_alone_walks_16_m_straight_within_5_cm_of_the_line(straight_patch):
    ground, root = walked(straight_patch, open_ground(straight_patch), (0, 0, 0), (16, 0, 0))
    assert np.abs(ground[:, 1]).max() < 0.05
    assert np.abs(root[:, 1]).max() < 0.05  # the hips too
    assert ground[-1] == pytest.approx([16.0, 0.0, 0.0], abs=1e-6)
    assert np.linalg.norm(np.diff(ground[:, :2], axis=0), axis=1).sum() < 16.0 * 1.01


@pytest.mark.parametrize(
    "goal", [(6.0, 6.0, np.pi / 2), (5.0, -5.0, -np.pi / 2)], ids=["left", "right"]
)
def test_a_straight_clip_alone_turns_90_degrees(straight_patch, goal):
    ground, _ = walked(straight_patch, open_ground(straight_patch), (0, 0, 0), goal)
    assert ground[-1, :2] == pytest.approx(goal[:2], abs=1e-6)
    assert np.cos(ground[-1, 2] - goal[2]) > np.cos(np.radians(0.5))
    turn = np.abs(np.diff(ground[:, 2])).sum()
    assert turn < np.radians(135)  # one turn, no loop
    steps = np.linalg.norm(np.diff(ground[:, :2], axis=0), axis=1)
    assert steps.max() < 0.08  # continuous, no jump between pieces


def test_a_straight_clip_alone_crosses_a_pillar_field(straight_patch):
    env = open_ground(straight_patch)
    for n, (x, y) in enumerate(
        [(3, 0.6), (4.5, 1.5), (3.5, 2.8), (6, 0.2), (6.5, 2.5), (8, -0.8), (9.5, 1.0), (11, -0.2)]
    ):
        env.place(pillar(f"p{n}", x, y))
    ground, _ = walked(straight_patch, env, (0.5, 1.3, 0.0), (13.0, 1.3, 0.0))
    assert not env.blocked(ground[:, :2]).any()
    assert ground[-1, :2] == pytest.approx((13.0, 1.3), abs=1e-6)
    assert np.linalg.norm(np.diff(ground[:, :2], axis=0), axis=1).sum() < 12.5 * 1.3


def test_a_bake_too_sparse_to_connect_is_refused_saying_what_to_add():
    """Bent to 20 m at most (what a straight walk alone gave before it could bend) the
    patch keeps only segments that barely turn: refused, with the share and the remedy."""
    gait = gait_mod.build_gait("walk", cmu("16_15"), (), bend_radius=20.0)
    with pytest.raises(SparsePatch) as err:
        locomotion_patch.bake(gait, nodes=4)
    msg = str(err.value)
    share = int(msg.split("only ")[1].split("%")[0])
    assert share < 100 * locomotion_patch.MIN_ENTRY_SHARE
    assert "of entry states have a way on" in msg
    assert "radius 20.00 m" in msg
    assert "Add a turn clip" in msg
