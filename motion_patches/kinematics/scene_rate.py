# SPDX-License-Identifier: GPL-3.0-or-later
"""Playing a plan at the scene's frame rate when the patch was baked at another.

A patch's motion lives on the patch's frames (its gait loops are sampled at the bake's
rate). In a scene at another rate the pieces of a plan are not re-keyed: each piece's
strip plays its patch-rate keys scaled in time, so the shared segment actions stay one
per segment whatever the scene's rate, and a 24 fps patch in a 120 fps scene writes no
more keys than in a 24 fps scene. Piece ``i`` starts on scene frame ``bounds[i]``, the
patch's frame count up to it times the rate ratio, rounded: every strip starts and ends
on a whole frame and its scale is within half a frame of the ratio. What is keyed per
character on the scene's frames (the root trajectory, the foot lock) is the same motion
read at the same fractional patch frames (:func:`at_scene_rate`), so body and root play
in step.
"""

from collections.abc import Sequence
from typing import Any

import numpy as np

from . import loop_strips
from .motion import Motion, concatenate
from .retarget import RigMap
from .retime import resample


def piece_bounds(frames: Sequence[int], ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """(patch bounds (P + 1,), scene bounds (P + 1,) ints) of pieces of ``frames`` frames
    each (joined end to start) played ``ratio`` scene frames per patch frame."""
    patch = np.concatenate(([0], np.cumsum([int(f) - 1 for f in frames])))
    scene = np.round(patch * float(ratio)).astype(int)
    for i in range(1, scene.size):  # a piece never shrinks to nothing
        scene[i] = max(scene[i], scene[i - 1] + 1)
    return patch, scene


def scene_positions(patch_bounds: np.ndarray, scene_bounds: np.ndarray) -> np.ndarray:
    """Fractional patch frame (K,) shown on each scene frame 0 .. scene_bounds[-1]."""
    return np.interp(np.arange(scene_bounds[-1] + 1), scene_bounds, patch_bounds)


def at_scene_rate(motion: Motion, patch_bounds: np.ndarray, scene_bounds: np.ndarray) -> Motion:
    """``motion`` (on the patch's frames) on the scene's frames: unchanged when they are
    the same, else resampled at :func:`scene_positions`."""
    if np.array_equal(patch_bounds, scene_bounds):
        return motion
    return resample(motion, scene_positions(patch_bounds, scene_bounds))


def placed(
    patch: Any,
    rig: RigMap | None,
    raw: list,
    scene_fps: float,
    own: Sequence[int] = (),
    loop: Motion | None = None,
) -> tuple:
    """(piece motions on the character's rig, scene bounds of the pieces, the whole motion on
    the scene's frames) of a plan's piece motions ``raw`` at the patch's rate. ``rig``: the
    character's rig map (None: the patch's skeleton). ``own``: the pieces only the
    character plays (:func:`~.rig_keys.own_pieces`): at another rate than the patch's, the
    stretches of them a shared loop action plays are that loop at the phase it plays there
    (:func:`~.loop_strips.on_loops`; ``loop``: its :func:`~.loop_strips.straight_loop`
    when made already)."""
    motions = [rig.motion(m) for m in raw] if rig is not None else list(raw)
    patch_bounds, bounds = piece_bounds([m.frames for m in motions], scene_fps / patch.gait.fps)
    whole = at_scene_rate(concatenate(motions), patch_bounds, bounds)
    if own and not np.array_equal(patch_bounds, bounds):
        if loop is None:
            loop = loop_strips.straight_loop(patch.gait, rig)
        parts = loop_strips.played_parts(motions, bounds, own, loop)
        whole = loop_strips.on_loops(whole, parts, loop)
    return motions, bounds, whole
