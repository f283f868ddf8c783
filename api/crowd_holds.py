# SPDX-License-Identifier: GPL-3.0-or-later
"""Idle holds: a crowd character standing still mid-walk while another passes."""

from __future__ import annotations

import dataclasses

from ..motion_patches.crowd import held_motion, members
from ..motion_patches.kinematics import retime
from .errors import MotionPatchesError

CROWD_HOLD_RAMP_SECONDS = members.HOLD_RAMP_SECONDS
_CLIPS = members.CLIPS


def _piece_holding(plan, bounds, at, ramp):
    """Index of the walking piece whose scene frames ``bounds[i]..bounds[i+1]`` hold frame
    ``at`` with half a ``ramp`` to spare on both sides, or None."""
    half = ramp // 2
    for i, p in enumerate(plan.pieces):
        if p.kind not in _CLIPS and bounds[i] + half <= at <= bounds[i + 1] - half:
            return i
    return None


def _holdable(plan, placed, ramp):
    """Bool per scene frame of a placed plan (:func:`_placed`): frames a crowd may hold on
    (:func:`motion_patches.crowd.members.holdable`)."""
    return members.holdable(plan, placed[1], placed[2], ramp)


def _with_hold(plan, raw, bounds, at, hold, ramp, rate=1.0):
    """(plan, raw piece motions) with an idle hold of ``hold`` frames on scene frame ``at``
    (``bounds``: the pieces' scene frames, ``rate`` scene frames per patch frame): the piece
    it falls in is time-warped (:func:`motion_patches.kinematics.retime.held`; at another rate
    :func:`motion_patches.crowd.held_motion.held_piece`) and becomes a piece of kind "hold",
    so it is written as its own action, not the shared segment action."""
    i = _piece_holding(plan, bounds, at, ramp)
    if i is None:
        raise MotionPatchesError(f"internal: frame {at} is in no walking piece to hold in")
    raw = list(raw)
    if abs(rate - 1.0) < 1e-9:
        raw[i] = retime.held(raw[i], at - bounds[i], hold, ramp)
    else:
        span = int(bounds[i + 1] - bounds[i])
        raw[i] = held_motion.held_piece(raw[i], at - bounds[i], hold, ramp, span, rate)
    pieces = list(plan.pieces)
    p = pieces[i]
    pieces[i] = dataclasses.replace(
        p,
        kind="hold",
        held_from=p.held_from if p.kind == "hold" else p.label,
        holds=(*p.holds, (int(at - bounds[i]), int(hold))),
    )
    return dataclasses.replace(plan, pieces=pieces), raw


def _root_track(placed):
    """(frames, 2) ground position of the root joint of a placed motion (:func:`_placed`)."""
    return members.root_track(placed[2])
