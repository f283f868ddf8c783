# SPDX-License-Identifier: GPL-3.0-or-later
"""Foot contacts: which foot joints are planted on each frame.

On the source clip a joint counts as planted while it is near its typical planted height
and nearly still. Synthesised motion inherits these labels by phase and is never
re-labelled by speed, so the skate figures measure exactly the frames the recording had
planted. Heights are taken above the capture floor, fitted as a plane, because real
capture floors tilt (CMU subject 2: 4 cm over 3 m).
"""

import numpy as np

from .clip import Clip
from .skeleton import Skeleton

FOOT_NAMES = {
    "left": (("LeftFoot", "LeftAnkle", "foot.L"), ("LeftToeBase", "LeftToe", "toe.L")),
    "right": (("RightFoot", "RightAnkle", "foot.R"), ("RightToeBase", "RightToe", "toe.R")),
}
CONTACT_TOLERANCE = 0.025  # metres above the planted height
CONTACT_SPEED = 0.5  # m/s: faster than this a joint is moving, not planted


def foot_joints(skel: Skeleton) -> np.ndarray:
    """Indices [left ankle, left toe, right ankle, right toe]."""
    out = []
    for side in ("left", "right"):
        ankle, toe = FOOT_NAMES[side]
        out += [skel.find(*ankle), skel.find(*toe)]
    return np.array(out)


def planted_heights(heights: np.ndarray) -> np.ndarray:
    """Typical planted height per joint: a low percentile of its height over the clip."""
    return np.percentile(heights, 5, axis=0)


def detect(
    heights: np.ndarray,
    speeds: np.ndarray,
    planted: np.ndarray | None = None,
    tolerance: float = CONTACT_TOLERANCE,
    max_speed: float = CONTACT_SPEED,
) -> np.ndarray:
    """(F, K) bool contacts from foot joint heights (F, K) and horizontal speeds (F, K)."""
    heights = np.asarray(heights, float)
    if planted is None:
        planted = planted_heights(heights)
    return (heights < np.asarray(planted)[None] + tolerance) & (np.asarray(speeds) < max_speed)


def horizontal_speeds(pos: np.ndarray, fps: float) -> np.ndarray:
    """(F, K) horizontal speed (m/s) of positions (F, K, 3), central differences."""
    return np.linalg.norm(np.gradient(pos[..., :2], axis=0), axis=-1) * fps


def floor_plane(foot_pos: np.ndarray) -> np.ndarray:
    """Coefficients (a, b, c) of the floor z = a + b x + c y under foot positions (F, K, 3).

    Fitted to the lowest foot joint of each frame, twice dropping points above the fit (a
    lifted foot), so it follows the lower envelope. A clip that covers less than half a
    metre gets a level floor.
    """
    low = np.argmin(foot_pos[..., 2], axis=1)
    p = foot_pos[np.arange(foot_pos.shape[0]), low]
    extent = np.ptp(p[:, :2], axis=0).max()
    keep = np.ones(p.shape[0], bool)
    for _ in range(3):
        if extent < 0.5:
            coef = np.array([np.median(p[keep, 2]), 0.0, 0.0])
        else:
            a = np.column_stack((np.ones(keep.sum()), p[keep, 0], p[keep, 1]))
            coef = np.linalg.lstsq(a, p[keep, 2], rcond=None)[0]
        resid = p[:, 2] - (coef[0] + coef[1] * p[:, 0] + coef[2] * p[:, 1])
        keep = resid <= np.median(resid[keep])
    return coef


def heights_above_floor(foot_pos: np.ndarray, coef: np.ndarray) -> np.ndarray:
    return foot_pos[..., 2] - (coef[0] + coef[1] * foot_pos[..., 0] + coef[2] * foot_pos[..., 1])


def foot_contacts(
    clip: Clip, level_floor: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contacts (F, 4), planted heights (4,) above the fitted floor, and heights (F, 4).

    Positions are armature space; heights are above the clip's fitted capture floor (a
    level one with ``level_floor``, for clips that are not walking: a jump's few planted
    frames do not pin a tilt down).
    """
    pos = clip.joint_positions()[:, foot_joints(clip.skeleton)]
    coef = floor_plane(pos)
    if level_floor:
        coef = np.array([np.percentile(pos[..., 2].min(axis=1), 10), 0.0, 0.0])
    h = heights_above_floor(pos, coef)
    planted = planted_heights(h)
    return detect(h, horizontal_speeds(pos, clip.fps), planted), planted, h


def runs(c: np.ndarray, value: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) of the runs of ``value`` in a bool array, ends exclusive."""
    d = np.diff(np.concatenate(([not value], c == value, [not value])).astype(int))
    return np.flatnonzero(d == 1), np.flatnonzero(d == -1)


def debounce(contact: np.ndarray, min_frames: int) -> np.ndarray:
    """Contact flags with gaps and blips shorter than ``min_frames`` removed."""
    c = np.asarray(contact, bool).copy()
    for value in (False, True):  # close short gaps, then drop short contacts
        starts, ends = runs(c, value)
        for a, b in zip(starts, ends):
            if b - a < min_frames and a > 0 and b < c.size:
                c[a:b] = not value
    return c


def strikes(contact: np.ndarray, fps: float = 30.0, min_duration: float = 0.1) -> np.ndarray:
    """Frames where a (debounced) contact starts, ignoring one at frame 0."""
    c = debounce(contact, max(1, int(round(min_duration * fps))))
    return np.flatnonzero(c[1:] & ~c[:-1]) + 1


def floor_level(clip: Clip) -> float:
    """Height of the floor under a clip: a low percentile of its lowest foot joint."""
    pos = clip.joint_positions()[:, foot_joints(clip.skeleton)]
    return float(np.percentile(pos[..., 2].min(axis=1), 10))
