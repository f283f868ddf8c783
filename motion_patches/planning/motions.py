# SPDX-License-Identifier: GPL-3.0-or-later
"""The motions of a plan: each piece played in the world (segments, connectors and
shortcuts followed, clips placed, turns on the spot derived), eased across stitches and
from and to standing; and the interaction clips (stand up, sit down) around a plan."""

from collections.abc import Sequence

import numpy as np

from ..kinematics import retime, stand
from ..kinematics.motion import Motion, ease_to, sliced
from ..patch.gait import Gait
from ..patch.layers import has_flight
from ..patch.locomotion_patch import LocomotionPatch
from ..patch.synthesis import double_support, follow
from ..props.object_patch import ObjectPatch
from . import turn_in_place
from .pieces import Piece, Plan
from .plan_frame import IDENTITY
from .stitching import BLEND_FRAMES


def plan_motions(
    patch: LocomotionPatch, plan: Plan, standing: bool = True, poses: bool = True
) -> list[Motion]:
    """World-space motion of every piece, eased across stitches into and out of clips;
    with ``standing`` a plan that starts (ends) walking starts from (ends in) standing:
    its first (last) piece is time-warped (:mod:`.retime`), ramps one gait cycle long. A
    turn on the spot continues from the pose the walk before it stopped in; the walk
    slows to a stop at the goal and the turn eases in and out.

    ``poses`` False: the same frames, ground and root, without the body (no joint: nothing
    is slerped), for what only measures the motion (a layout check's seconds and metres).
    A turn still starts from the full pose before it, as it picks its phase by that pose:
    the last frame of the piece before is posed (that frame alone), and a turn's feet are
    pinned only when another turn starts from its last pose."""
    ms: list[Motion] = []
    full = None  # the last piece's motion with its body (poses False: for a turn after it)
    pieces = plan.pieces
    for i, p in enumerate(pieces):
        if p.kind == "turn":
            if not poses and ms and full is None:
                full = piece_motion(patch, pieces[i - 1], standing, last=True)
            pinned = poses or (i + 1 < len(pieces) and pieces[i + 1].kind == "turn")
            m = turn_motion(patch, p, (full if not poses else ms[-1]) if ms else None, pinned)
            full = m
        else:
            m = piece_motion(patch, p, standing, poses)
            full = None
        ms.append(m if poses else _bodiless(m))
    clips = ("traversal", "interaction")
    kinds = [p.kind for p in plan.pieces]
    if standing:
        ramp, n = patch.gait.frames, len(ms)
        for i, kind in enumerate(kinds):
            if kind in clips:
                continue
            ease_in = i == 0 or kind == "turn" or kinds[i - 1] == "turn"
            ease_out = i == n - 1 or kind == "turn" or kinds[i + 1] == "turn"
            ms[i] = retime.eased(ms[i], ease_in, ease_out, ramp)
            if poses and not has_flight(patch.gait):  # the body only: ground and frames kept
                ms[i] = stand.settled(
                    patch.gait.skeleton, ms[i], flat_feet(patch.gait), ease_in, ease_out, ramp // 2
                )
        if kinds[-1] not in clips and np.isfinite(np.asarray(plan.goal[:2], float)).all():
            ms[-1] = hips_to(ms[-1], plan.goal[:2], 2 * patch.gait.frames)
    for i, kind in enumerate(kinds):
        if kind in clips:
            continue
        if i + 1 < len(ms) and kinds[i + 1] in clips:
            ms[i] = ease_to(ms[i], ms[i + 1], BLEND_FRAMES, at_end=True)
        if i > 0 and (kinds[i - 1] in clips or "turn" in (kind, kinds[i - 1])):
            ms[i] = ease_to(ms[i], ms[i - 1], BLEND_FRAMES, at_end=False)
    return ms


def stand_note(patch: LocomotionPatch, plan: Plan) -> str | None:
    """What :func:`plan_motions` derives at the plan's ends, in words (None: nothing, the
    plan starts and ends in clips or its gait has no double support, as a run)."""
    if has_flight(patch.gait) or not plan.pieces:
        return None
    clips = ("traversal", "interaction")
    ends = [
        word
        for word, piece in (("start", plan.pieces[0]), ("stop", plan.pieces[-1]))
        if piece.kind not in clips
    ]
    if not ends:
        return None
    return (
        " and ".join(f"{e} (derived)" for e in ends)
        + ": a stand made from the walk's double-support frame, both feet put down flat"
        " (no start, stop or idle is recorded for the walking subject)"
    )


def flat_feet(gait: Gait) -> stand.FlatFeet:
    """The gait's feet standing flat (:func:`.stand.flat_feet` of its straight loop;
    cached on the loop)."""
    lp = gait.straight
    got = lp.__dict__.get("_flat_feet")
    if got is None:
        got = lp.__dict__["_flat_feet"] = stand.flat_feet(
            gait.skeleton, lp.root_local, lp.rotations, lp.contacts
        )
    return got


def turn_motion(
    patch: LocomotionPatch, piece: Piece, previous: Motion | None = None, pinned: bool = True
) -> Motion:
    """World-space motion of a turn on the spot (kind "turn"), continuing ``previous``
    (``pinned``: :func:`.turn_in_place.turn_motion`'s)."""
    assert piece.turn is not None, "a turn piece has its turn"
    x, y, heading, delta = piece.turn
    return turn_in_place.turn_motion(patch.gait, (x, y), heading, delta, previous, pinned)


def hips_to(motion: Motion, xy: Sequence[float] | np.ndarray, window: int) -> Motion:
    """The motion with its root (the hips) brought onto the ground point ``xy`` on its last
    frame: a walk stops wherever its stride ends, so the hips would stand a few centimetres
    beside the ground path's end. Over the last ``window`` frames (a smoothstep) the root's
    horizontal offset from the ground frame is blended from the stride's own sway to the
    offset that puts it on ``xy`` (none when the ground path ends there, as a plan's
    does): the body settles over the goal as a stopping walker does, never swaying farther
    from the path than the stride itself, and the ground path (the object) is unchanged.
    Planted feet move with the body by at most the sway; foot locking pins them."""
    n = motion.frames
    if n < 2:
        return motion
    g = motion.ground
    c, s = np.cos(g[-1, 2]), np.sin(g[-1, 2])
    d = np.asarray(xy, float) - g[-1, :2]
    target = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])  # in the last ground frame
    k = int(min(max(window, 2), n))
    t = np.linspace(0.0, 1.0, k)
    w = np.zeros(n)
    w[-k:] = t * t * (3.0 - 2.0 * t)
    root = motion.root_local.copy()
    root[:, :2] += w[:, None] * (target[None] - root[:, :2])
    return Motion(g, root, motion.rotations, motion.contacts)


def with_interactions(
    plan: Plan,
    start: tuple[ObjectPatch, int] | None = None,
    goal: tuple[ObjectPatch, int] | None = None,
) -> Plan:
    """The plan with an interaction clip before it (stand up) and/or after it (sit down):
    ``start`` / ``goal`` are (ObjectPatch, clip index); the plan must run from the start
    clip's last frame to the goal clip's first frame (see :func:`interaction_states`)."""

    def piece(ref):
        prop, ci = ref
        return Piece("interaction", prop=prop, clip_index=ci, cost=prop.clips[ci].effort)

    pieces = (
        ([piece(start)] if start is not None else [])
        + list(plan.pieces)
        + ([piece(goal)] if goal is not None else [])
    )
    return Plan(
        pieces,
        plan.cost,
        plan.expansions,
        plan.seconds,
        plan.start,
        plan.goal,
        dict(plan.stats, interactions=[p.label for p in pieces if p.kind == "interaction"]),
    )


def interaction_states(
    start: tuple[ObjectPatch, int] | None = None, goal: tuple[ObjectPatch, int] | None = None
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """World (x, y, heading) where walking must start after a stand-up clip and end before
    a sit-down clip: the clips' last and first ground frames."""
    s = g = None
    if start is not None:
        prop, ci = start
        s = prop.world_clip(prop.clips[ci]).ground[-1]
    if goal is not None:
        prop, ci = goal
        g = prop.world_clip(prop.clips[ci]).ground[0]
    return s, g


def _bodiless(m: Motion) -> Motion:
    """``m`` without its joints (:func:`plan_motions` without poses)."""
    if m.rotations.shape[1] == 0:
        return m
    return Motion(m.ground, m.root_local, m.rotations[:, :0], m.contacts)


def piece_motion(
    patch: LocomotionPatch,
    piece: Piece,
    standing: bool = False,
    poses: bool = True,
    last: bool = False,
) -> Motion:
    """World-space motion of one planned piece (not eased; see :func:`plan_motions`);
    with ``standing`` a start (goal) connector starts (ends) on a double-support phase
    (:func:`~..patch.synthesis.double_support`), where a stand is eased from (into);
    ``poses`` False: walking pieces without their body (:func:`..patch.synthesis.follow`);
    ``last``: its last frame alone (a walking piece posed on that frame only)."""
    if piece.kind == "turn":
        m = turn_motion(patch, piece)
        return sliced(m, m.frames - 1, m.frames - 1) if last else m
    phases = double_support(patch.gait) if standing else None
    m = _local_piece_motion(patch, piece, phases, poses, -1 if last else None)
    return m if piece.frame == IDENTITY else m.transformed(*piece.frame)


def _local_piece_motion(patch, piece, phases=None, poses=True, at=None):
    """The piece's motion in its plan frame; ``at`` -1: its last frame alone."""
    if piece.kind in ("segment", "part"):
        if piece.kind == "part":
            m = patch.motion(piece.segment, poses, piece.frames[1] if at == -1 else None)
            m = m if at == -1 else sliced(m, *piece.frames)
        else:
            m = patch.motion(piece.segment, poses, at)
        return m.transformed(piece.tile[0] * patch.side, piece.tile[1] * patch.side)
    if piece.kind in ("traversal", "interaction"):
        m = piece.prop.world_clip(piece.prop.clips[piece.clip_index])
        return m if at is None else sliced(m, m.frames - 1, m.frames - 1)
    if piece.kind == "start":
        return follow(patch.gait, piece.curve, "to node", phases=phases, poses=poses, at=at)
    if piece.kind == "shortcut":
        return follow(patch.gait, piece.curve, cycles=piece.cycles, poses=poses, at=at)
    return follow(
        patch.gait, piece.curve, None, eased=(True, False), phases=phases, poses=poses, at=at
    )
