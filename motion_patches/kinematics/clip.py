# SPDX-License-Identifier: GPL-3.0-or-later
"""Clip: one source animation reduced to arrays, and the operations on whole clips.

A clip holds the root's armature-space position and every bone's pose rotation per frame
(the channels an action keys), with the skeleton needed to pose it. Resampling to a
common frame rate and mirroring (for the missing right turns) work on clips as a whole.
"""

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import quat
from .skeleton import Skeleton, forward_kinematics, local_rotations_from_global


@dataclass
class Clip:
    name: str
    skeleton: Skeleton
    fps: float
    root_pos: np.ndarray  # (F, 3) root head, armature space, metres
    rotations: np.ndarray  # (F, J, 4) pose rotation channels
    tags: dict = field(default_factory=dict)

    @property
    def frames(self) -> int:
        return self.root_pos.shape[0]

    @property
    def duration(self) -> float:
        return (self.frames - 1) / self.fps

    def global_matrices(self) -> np.ndarray:
        return forward_kinematics(self.skeleton, self.root_pos, self.rotations)

    def joint_positions(self) -> np.ndarray:
        """(F, J, 3) armature-space head position of every bone."""
        return self.global_matrices()[..., :3, 3]

    def validate(self) -> "Clip":
        """Raise ValueError with a user-facing message when the arrays are unusable."""
        f = self.frames
        if f < 2:
            raise ValueError(f"clip '{self.name}' has {f} frame(s); at least 2 are needed")
        if self.rotations.shape != (f, len(self.skeleton.names), 4):
            raise ValueError(
                f"clip '{self.name}': rotation array has shape "
                f"{self.rotations.shape}, expected {(f, len(self.skeleton.names), 4)}"
            )
        if not (np.all(np.isfinite(self.root_pos)) and np.all(np.isfinite(self.rotations))):
            raise ValueError(f"clip '{self.name}' contains NaN or infinite values")
        if self.fps <= 0:
            raise ValueError(f"clip '{self.name}' has a frame rate of {self.fps}")
        return self


def sample(clip: Clip, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clip values at arbitrary times (seconds): positions lerped, rotations slerped."""
    t = np.clip(np.asarray(times, float) * clip.fps, 0, clip.frames - 1)
    i0 = np.floor(t).astype(int)
    i1 = np.minimum(i0 + 1, clip.frames - 1)
    a = t - i0
    pos = clip.root_pos[i0] * (1 - a)[:, None] + clip.root_pos[i1] * a[:, None]
    rot = quat.slerp(
        clip.rotations[i0], clip.rotations[i1], np.repeat(a[:, None], clip.rotations.shape[1], 1)
    )
    return pos, quat.make_continuous(rot, axis=0)


def resample(clip: Clip, fps: float) -> Clip:
    """The clip at another frame rate, same duration (rounded down to whole frames)."""
    n = int(np.floor(clip.duration * fps + 1e-6)) + 1
    pos, rot = sample(clip, np.arange(n) / fps)
    return Clip(clip.name, clip.skeleton, float(fps), pos, rot, dict(clip.tags))


STRAIGHT_DISTANCE = 2.0  # metres a straight walk covers at least, start to end
STRAIGHT_RATIO = 0.95  # its start-to-end distance over the length of its root's path


def straightest(clips: Sequence[Clip]) -> int | None:
    """Index of the clip that walks furthest in a straight line: the greatest start-to-end
    ground distance (root, x and y) among the clips covering ``STRAIGHT_DISTANCE`` at
    least with a path at most 1 / ``STRAIGHT_RATIO`` as long; None when none does (a turn
    curves, a standing jump or a sit-down goes too short a way). What a bake's straight
    clip is guessed from (CMU 16: 16_15 walks 4.3 m in a 4.3 m path; the turn 16_18 goes
    3.1 m in 3.9 m; the jump 16_06 1.3 m)."""
    best, far = None, 0.0
    for i, c in enumerate(clips):
        xy = np.asarray(c.root_pos, float)[:, :2]
        if len(xy) < 2:
            continue
        net = float(np.linalg.norm(xy[-1] - xy[0]))
        path = float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum())
        if net >= STRAIGHT_DISTANCE and net >= STRAIGHT_RATIO * path and net > far:
            best, far = i, net
    return best


def lateral_axis(skel: Skeleton) -> np.ndarray:
    """Unit horizontal axis pointing from the right hip to the left hip in the rest pose."""
    left = skel.find("LeftUpLeg", "LeftHip", "LeftThigh", "thigh.L", "LeftUpperLeg")
    right = skel.find("RightUpLeg", "RightHip", "RightThigh", "thigh.R", "RightUpperLeg")
    a = skel.rest[left, :3, 3] - skel.rest[right, :3, 3]
    a[2] = 0.0
    n = np.linalg.norm(a)
    if n < 1e-6:
        raise ValueError("cannot find the skeleton's left-right axis from its hips")
    return a / n


def mirror(clip: Clip, name: str | None = None) -> Clip:
    """Left/right mirror image of a clip (a left turn becomes a right turn).

    Each bone's armature-space rotation *relative to its rest orientation* is reflected in
    the skeleton's sagittal plane and given to its counterpart bone, so the result is exact
    for a symmetric rest pose whatever the bones' rolls.
    """
    skel = clip.skeleton
    a = lateral_axis(skel)
    s = np.eye(3) - 2.0 * np.outer(a, a)
    m = skel.mirror_map()
    g = clip.global_matrices()
    rest_rot = skel.rest[:, :3, :3]
    delta = g[..., :3, :3] @ np.swapaxes(rest_rot, -1, -2)[None]
    delta_m = s @ delta[:, m] @ s
    new_global = delta_m @ rest_rot[None]
    rot = local_rotations_from_global(skel, new_global)
    pos = clip.root_pos @ s.T
    tags = dict(clip.tags)
    tags["mirrored_from"] = clip.name
    return Clip(name or clip.name + "_mirror", skel, clip.fps, pos, rot, tags)
