# SPDX-License-Identifier: GPL-3.0-or-later
"""An idle hold laid into a piece of motion played at another rate than it was baked at.

The crowd times holds on the scene's frames (:func:`.crowd.held_track`); a piece's motion
lives on the patch's frames and is played scaled to the scene's rate
(:mod:`motion_patches.kinematics.scene_rate`). At the same rate the hold is laid in as it is
(:func:`motion_patches.kinematics.retime.held`); at another, the scene frames of the hold,
its slow-down and its speed-up are read back onto the patch's frames, so that the piece,
played at the scene's rate, stands where and when the crowd saw it stand.
"""

import numpy as np

from ..kinematics import retime
from ..kinematics.motion import Motion


def held_piece(
    motion: Motion, at: float, hold: int, ramp: int, scene_frames: int, ratio: float
) -> Motion:
    """``motion`` (a piece on the patch's frames, ``scene_frames`` + 1 scene frames long when
    played ``ratio`` scene frames per patch frame) with an idle hold of ``hold`` scene frames
    on its scene frame ``at``, slowing down and speeding up over ``ramp`` scene frames each
    (:func:`motion_patches.kinematics.retime.hold_phases` on the scene's frames): a motion on
    the patch's frames again, ``(scene_frames + hold + ramp) / ratio`` frames long, rounded."""
    s = int(scene_frames)
    u_scene = retime.hold_phases(s + 1, at, hold, ramp)  # old scene frame per new scene frame
    span = s + int(hold) + int(ramp)
    frames = max(int(round(span / float(ratio))), 1) + 1
    t = np.linspace(0.0, span, frames)  # new patch frames on the new scene's time
    u = np.interp(t, np.arange(span + 1), u_scene) * (motion.frames - 1) / max(s, 1)
    u[0], u[-1] = 0.0, motion.frames - 1.0
    return retime.resample(motion, u)
