# SPDX-License-Identifier: GPL-3.0-or-later
"""Gait cycles: detecting them in a clip and cutting one into a seamless loop.

A cycle runs from one left-foot strike to the next. The loop keeps the body relative to a
constant-curvature ground arc fitted to the cycle (a straight line for a straight walk), its
travelled distance per frame, and contacts; the small mismatch between the first and last
pose is spread linearly over the cycle so the loop repeats without a pop.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..kinematics import poses, quat
from ..kinematics.clip import Clip, sample
from ..kinematics.contacts import foot_contacts, strikes
from ..kinematics.inplace import facing_yaw, to_inplace
from .curves import arc_frame, arc_project


@dataclass
class Loop:
    """One gait cycle resampled to ``frames`` frames at the layer's frame rate."""

    name: str
    root_local: np.ndarray  # (N, 3) root relative to the ground arc
    rotations: np.ndarray  # (N, J, 4) in-place rotation channels
    distance: np.ndarray  # (N + 1,) travelled arc length at each frame, last = cycle distance
    contacts: np.ndarray  # (N, 4) planted flags [L ankle, L toe, R ankle, R toe]
    turn: float  # heading change over the cycle (radians, + = left)
    seam_deg: float  # largest joint mismatch spread over the cycle by the seam fix

    @property
    def frames(self) -> int:
        return self.rotations.shape[0]

    @property
    def cycle_distance(self) -> float:
        return float(self.distance[-1])

    @property
    def curvature(self) -> float:
        return self.turn / self.cycle_distance

    def pose_features(self) -> np.ndarray:
        """(N, D) :func:`~..kinematics.poses.pose_features` of every frame, kept on the loop
        (stitching and turns on the spot look poses up in it again and again)."""
        got = self.__dict__.get("_pose_features")
        if got is None:
            got = self.__dict__["_pose_features"] = poses.pose_features(
                self.root_local, self.rotations
            )
        return got

    def to_dict(self, prefix: str) -> dict[str, Any]:
        return {
            prefix + k: v
            for k, v in (
                ("root_local", self.root_local),
                ("rotations", self.rotations),
                ("distance", self.distance),
                ("contacts", self.contacts),
                ("scalars", np.array([self.turn, self.seam_deg])),
                ("name", np.array(self.name)),
            )
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], prefix: str) -> "Loop":
        turn, seam = d[prefix + "scalars"]
        return cls(
            str(d[prefix + "name"]),
            d[prefix + "root_local"],
            d[prefix + "rotations"],
            d[prefix + "distance"],
            np.asarray(d[prefix + "contacts"], bool),
            float(turn),
            float(seam),
        )


@dataclass
class CycleInfo:
    strikes: np.ndarray  # frames of left-foot strikes
    period: float  # seconds per cycle (median)
    distance: float  # metres travelled per cycle (median)
    speed: float  # m/s


def detect_cycles(clip: Clip) -> CycleInfo:
    """Left-foot strikes, cycle period and distance of a locomotion clip.

    Raises ValueError when fewer than two strikes are found (not a gait clip).
    """
    contacts, _, _ = foot_contacts(clip)
    left = contacts[:, 0] | contacts[:, 1]
    st = strikes(left, clip.fps)
    if st.size < 2:
        raise ValueError(
            f"clip '{clip.name}': found {st.size} left-foot strike(s); a locomotion "
            f"clip needs at least one full gait cycle"
        )
    periods = np.diff(st) / clip.fps
    dist = np.linalg.norm(np.diff(clip.root_pos[st, :2], axis=0), axis=1)
    return CycleInfo(
        st,
        float(np.median(periods)),
        float(np.median(dist)),
        float(np.median(dist) / np.median(periods)),
    )


def cycle_turns(clip: Clip, info: CycleInfo) -> np.ndarray:
    """Heading change (radians) over each detected cycle, from the root's facing."""
    yaw = facing_yaw(clip)
    return yaw[info.strikes[1:]] - yaw[info.strikes[:-1]]


def extract_loop(clip: Clip, start: int, end: int, frames: int, name: str | None = None) -> Loop:
    """Loop of the cycle between frames ``start`` and ``end`` resampled to ``frames`` frames."""
    times = (start + (end - start) * np.arange(frames + 1) / frames) / clip.fps
    pos, rot = sample(clip, times)
    cyc = Clip(clip.name, clip.skeleton, frames / ((end - start) / clip.fps), pos, rot)
    yaw = facing_yaw(cyc)
    turn = float(yaw[-1] - yaw[0])
    p0, p1 = pos[0, :2], pos[-1, :2]
    chord = p1 - p0
    c = float(np.linalg.norm(chord))
    half = 0.5 * turn
    length = c * (half / np.sin(half)) if abs(half) > 1e-6 else c
    h0 = float(np.arctan2(chord[1], chord[0]) - half)
    kappa = turn / length
    s = arc_project(p0, h0, kappa, pos[:, :2])
    s[0], s[-1] = 0.0, length
    gpos, gh = arc_frame(p0, h0, kappa, s)
    ground = np.column_stack((gpos, gh))
    root_local, rot_ip = to_inplace(cyc, ground)
    # Seam fix: spread the last-vs-first mismatch linearly so the loop closes exactly.
    ramp = np.arange(frames + 1) / frames
    delta = quat.log(quat.mul(rot_ip[0], quat.conj(rot_ip[-1])))
    seam_deg = float(np.degrees(np.linalg.norm(delta, axis=-1).max()))
    rot_fixed = quat.mul(quat.exp(delta[None] * ramp[:, None, None]), rot_ip)
    root_fixed = root_local + (root_local[0] - root_local[-1])[None] * ramp[:, None]
    if np.any(np.diff(s) <= 0):
        raise ValueError(
            f"clip '{clip.name}': the root does not advance monotonically over the "
            f"cycle {start}-{end}; not a locomotion cycle"
        )
    contacts, _, _ = foot_contacts(clip)
    src = np.clip(
        np.round(start + (end - start) * np.arange(frames) / frames).astype(int), 0, clip.frames - 1
    )
    return Loop(
        name or clip.name,
        root_fixed[:-1],
        quat.make_continuous(rot_fixed[:-1]),
        s,
        contacts[src],
        turn,
        seam_deg,
    )


def best_cycle(clip: Clip, info: CycleInfo, prefer: str = "seam") -> tuple[int, int]:
    """(start, end) frames of the cycle to loop: smallest pose seam, or largest turn."""
    pairs = list(zip(info.strikes[:-1], info.strikes[1:]))
    if prefer == "turn":
        turns = np.abs(cycle_turns(clip, info))
        return pairs[int(np.argmax(turns))]
    seams = [
        float(quat.angle_between(clip.rotations[a], clip.rotations[b]).max()) for a, b in pairs
    ]
    return pairs[int(np.argmin(seams))]
