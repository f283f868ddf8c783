# SPDX-License-Identifier: GPL-3.0-or-later
"""The clearance rule for the body: the hips, not only the ground path, keep the radius.

The planner keeps the ground path (the character's ground frame, the root's smoothed
trajectory) the radius from every footprint. The hips sway a few centimetres round it as the
stride goes, so a path that grazes a prop at exactly the radius brings the hips nearer. A plan
whose hips come within the radius of a footprint (outside traversal and interaction clips,
which are meant to come close) is planned again with the radius grown by the gait's sway;
only those plans pay for it, the rest keep the shortest way.
"""

from collections.abc import Callable, Sequence

import numpy as np

from ..kinematics.inplace import to_world
from ..kinematics.motion import Motion
from ..patch.gait import Gait
from ..patch.locomotion_patch import LocomotionPatch
from ..props.environment import Environment
from .pieces import Piece, Plan, PlanError
from .planner import SegmentPlanner

CLIPS = ("traversal", "interaction")


def sway(gait: Gait, loops: Sequence | None = None) -> float:
    """Metres: how far the hips get from the ground path in any loop of the gait (or of
    ``loops``, some of them: a crowd's standing spots take the straight loop's)."""
    every = gait.loops if loops is None else loops
    return float(max(np.linalg.norm(lp.root_local[:, :2], axis=1).max() for lp in every))


def hips_too_close(
    patch: LocomotionPatch, pieces: list[Piece], motions: list[Motion], env: Environment
) -> list[int]:
    """Frames (indices into the joined motion) where the hips come within ``env``'s radius of
    a footprint, outside clips."""
    out, first = [], 0
    skel = patch.gait.skeleton
    for i, (piece, m) in enumerate(zip(pieces, motions)):
        if piece.kind not in CLIPS:
            hips = to_world(skel, m.ground, m.root_local, m.rotations)[0][:, :2]
            close = np.flatnonzero(env.blocked(hips))
            out += (first + close).tolist()
        first += m.frames - 1
    return sorted(set(out))


def grown(env: Environment, by: float) -> Environment:
    """A copy of ``env`` (the same footprints) keeping ``by`` metres more."""
    out = Environment(env.side, env.cells, env.radius + by)
    for ob in env.obstacles.values():
        out.place(ob)
    return out


def keep_clear(
    planner: SegmentPlanner,
    plan: Plan,
    motions: list[Motion],
    start: np.ndarray,
    goal: np.ndarray,
    motions_of: Callable[[Plan], list[Motion]],
    finish: Callable[[Plan], Plan] = lambda p: p,
) -> tuple[Plan, list[Motion]]:
    """(plan, its motions): ``plan`` when its hips keep the radius, else the plan of
    ``start`` -> ``goal`` found keeping the gait's :func:`sway` more, when that one's hips do
    (``stats["body_clearance"]`` says so); else ``plan`` with
    ``stats["hips_within_radius_frames"]``. ``motions_of(plan)``: the motions as played;
    ``finish(plan)``: what the caller adds to a fresh plan (interaction clips)."""
    patch, env = planner.patch, planner.world_env
    close = hips_too_close(patch, plan.pieces, motions, env)
    if not close:
        return plan, motions
    extra = sway(patch.gait)
    wider = SegmentPlanner(
        patch,
        grown(env, extra),
        planner.alpha,
        planner.beta,
        planner.gamma,
        props=planner.world_props,
        mode=planner.mode,
        turn_in_place=planner.turn_in_place,
    )
    try:
        again = finish(wider.plan(start, goal))
    except PlanError:
        again = None
    if again is not None:
        m = motions_of(again)
        if not hips_too_close(patch, again.pieces, m, env):
            again.stats["body_clearance"] = (
                f"planned again keeping {extra * 100:.0f} cm more: the hips came within the "
                f"radius of a prop on {len(close)} frames"
            )
            return again, m
    plan.stats["hips_within_radius_frames"] = len(close)
    return plan, motions
