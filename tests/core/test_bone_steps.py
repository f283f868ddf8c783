# SPDX-License-Identifier: GPL-3.0-or-later
"""Per-frame bone steps of planned walks against their source clips': no bone turns
between two frames much faster than it ever does in the mocap (a "spin" a user sees).

The walk patch blends loops of different takes (16_15's straight walk, 16_18's turns
and their mirror images) by curvature; where the weights swap those takes within a frame
or two, a hand or the head held differently in each would snap round."""

import numpy as np
import pytest

from motion_patches.kinematics import foot_lock
from motion_patches.kinematics.motion import Motion, concatenate
from motion_patches.planning.planner import SegmentPlanner, plan_motions
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import metrics

LIMIT = 1.6  # largest step of any bone, as a multiple of that bone's largest in the source


def pillar(name, x, y, r):
    a = np.linspace(0, 2 * np.pi, 13)[:-1]
    return Obstacle(name, np.column_stack((x + r * np.cos(a), y + r * np.sin(a))))


@pytest.mark.parametrize("locked", [False, True], ids=["synthesised", "foot-locked"])
@pytest.mark.parametrize("seed", [3, 7, 11, 19])
def test_planned_walks_step_no_faster_than_their_source(walk_patch, walk16, turn16, seed, locked):
    """Pillar fields (12 m square, 14 pillars of 0.2-0.4 m) walked across with random start
    and goal headings: as synthesised and foot-locked as the API writes it, no bone's
    per-frame step exceeds ``LIMIT`` times its largest in 16_15 / 16_18 (sampled at the
    patch's 30 fps; a bone or its mirror image). Before the loop weights were averaged
    over frames (synthesis.held_weights) the neck stepped 3.7-5.9 times its largest here;
    before the feet the synthesis moves fast were left unplanted (foot_lock.still_contacts), a
    thigh 2.7 times at a turn on the spot's end."""
    rng = np.random.default_rng(seed)
    env = Environment(walk_patch.side, walk_patch.cells, radius=0.25)
    for n in range(14):
        env.place(pillar(f"p{n}", *rng.uniform(2.0, 10.0, 2), rng.uniform(0.2, 0.4)))
    start = np.array([0.5, rng.uniform(1.0, 11.0), rng.uniform(-np.pi, np.pi)])
    goal = np.array([11.5, rng.uniform(1.0, 11.0), rng.uniform(-np.pi, np.pi)])
    plan = SegmentPlanner(walk_patch, env).plan(start, goal)
    m = concatenate(plan_motions(walk_patch, plan))
    skel = walk_patch.gait.skeleton
    reference = metrics.source_bone_steps((walk16, turn16), walk_patch.gait.fps, skel.mirror_map())
    if locked:
        m = Motion(
            m.ground,
            m.root_local,
            m.rotations,
            foot_lock.still_contacts(skel, m, walk_patch.gait.fps),
        )
    rot = foot_lock.lock_feet(skel, m, fps=walk_patch.gait.fps) if locked else m.rotations
    ratio, worst = metrics.step_ratio(rot, reference, floor_deg=1e-3)
    print(
        f"seed {seed}{' locked' if locked else ''}: {[p.kind for p in plan.pieces]}, largest "
        f"step {ratio:.2f}x "
        f"the source's ({skel.names[worst]})"
    )
    assert ratio < LIMIT, skel.names[worst]


def test_easing_onto_another_subjects_clip_keeps_every_bone_to_its_pace(
    walk_patch, walk_gait, walk16, turn16, stand_walk_sit
):
    """Standing up from one chair (CMU 13_05, another subject, retargeted), walking and
    sitting down on another: easing the walk onto a clip of another take turns bones
    that take holds differently (the hips' tilt) over as many frames as keep them to
    the clips' pace; eased over the stitch's 4 frames the hips stepped 2.8 times their
    largest in any of the four clips. As synthesised and foot-locked; steps under 1 degree
    count as 1 (bones the takes barely move)."""
    plan, _, clips = stand_walk_sit
    m = concatenate(plan_motions(walk_patch, plan))
    skel = walk_gait.skeleton
    reference = metrics.source_bone_steps(
        [walk16, turn16, *clips], walk_gait.fps, skel.mirror_map()
    )
    still = Motion(
        m.ground, m.root_local, m.rotations, foot_lock.still_contacts(skel, m, walk_gait.fps)
    )
    locked = foot_lock.lock_feet(skel, still, fps=walk_gait.fps)
    ratio, worst = max(
        metrics.step_ratio(m.rotations, reference), metrics.step_ratio(locked, reference)
    )
    print(
        f"{[p.kind for p in plan.pieces]}: largest step {ratio:.2f}x the sources' "
        f"({skel.names[worst]})"
    )
    assert ratio < 1.8, skel.names[worst]
