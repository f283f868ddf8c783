# SPDX-License-Identifier: GPL-3.0-or-later
"""The blend table: how a character changes layer, from each pose of one gait into another
(paper Sec. 6, "Transitions between layers").

For each pose cluster of a layer the table stores the motion of blending, going straight,
from that pose into the other layer's straight locomotion, and where it leaves the
character: the pose it ends in (the other layer's node pose) and the root's position and
heading relative to where the blend began. A transition is then placed by concatenating
the character's current position and heading with the stored relative transform.

The blend is phase-aligned (both loops start on a left-foot strike): at normalised phase
u of the blend, layer A plays its frame at phase u of its cycle and layer B its frame at
the same phase of its own, so the feet of the two gaits move together while the weight
of B rises by a smoothstep; the stride per frame is blended the same way. A blend from
A's cycle phase p runs to B's next cycle start (phase 0, B's node pose), taking between
half a cycle and one and a half: from a node pose (p = 0), one whole cycle. Feet stay
planted where both gaits plant them (flags of A before the middle, of B after).
"""

from dataclasses import dataclass

import numpy as np

from ..kinematics import poses, quat
from ..kinematics.motion import Motion
from .gait import Gait
from .locomotion_patch import LocomotionPatch


@dataclass
class Transition:
    """One entry of the blend table: layer ``source`` at pose cluster ``cluster`` (its
    straight loop's ``phase``) blended into layer ``target``."""

    source: str
    target: str
    cluster: int
    phase: int  # frame of the source's straight loop the blend starts on
    motion: Motion  # in place, ground from (0, 0, 0) going along +x
    offset: np.ndarray  # (3,) x, y, heading of the end relative to the start
    end_pose: int  # target pose cluster the blend ends in

    @property
    def frames(self) -> int:
        return self.motion.frames


def _at(loop, u):
    """Root (K, 3), rotations (K, J, 4), contacts (K, 4), stride per cycle share (K,) of a
    loop at normalised phases u (K,), interpolating between its frames."""
    n = loop.rotations.shape[0]
    x = (np.asarray(u, float) % 1.0) * n
    i0 = np.floor(x).astype(int) % n
    i1 = (i0 + 1) % n
    t = x - np.floor(x)
    root = loop.root_local[i0] * (1 - t)[:, None] + loop.root_local[i1] * t[:, None]
    rot = quat.slerp(
        loop.rotations[i0], loop.rotations[i1], np.repeat(t[:, None], loop.rotations.shape[1], 1)
    )
    con = np.where((t < 0.5)[:, None], loop.contacts[i0], loop.contacts[i1])
    return root, rot, con


def blend(gait_a: Gait, gait_b: Gait, phase: int = 0) -> Motion:
    """Motion blending ``gait_a``'s straight loop from its frame ``phase`` into
    ``gait_b``'s straight loop, ending on B's cycle start (its node pose); the ground goes
    straight along +x from the origin. Both gaits must share one skeleton."""
    if gait_a.skeleton.names != gait_b.skeleton.names:
        raise ValueError(
            f"layers '{gait_a.layer}' and '{gait_b.layer}' have different "
            f"skeletons: a blend between them needs one skeleton"
        )
    la, lb = gait_a.straight, gait_b.straight
    fa, fb = la.rotations.shape[0], lb.rotations.shape[0]
    u0 = (phase % fa) / fa
    span = 1.0 - u0 if u0 <= 0.5 else 2.0 - u0  # to B's next cycle start, >= half a cycle
    # Frames of the blend: the two cycles' frame counts weighted as the blend goes.
    n = max(2, int(round(span * 0.5 * (fa + fb))))
    s = np.linspace(0.0, 1.0, n + 1)
    u = u0 + span * s
    w = s * s * (3 - 2 * s)
    ra, qa, ca = _at(la, u)
    rb, qb, cb = _at(lb, u)
    root = ra * (1 - w)[:, None] + rb * w[:, None]
    q = quat.slerp(qa, qb, np.repeat(w[:, None], qa.shape[1], 1))
    con = np.where((w < 0.5)[:, None], ca, cb)
    # Stride: each gait's distance over the phase step, in its own metres per cycle.
    da = np.interp(u % 1.0 * fa, np.arange(fa + 1), la.distance) + np.floor(u) * la.cycle_distance
    db = np.interp(u % 1.0 * fb, np.arange(fb + 1), lb.distance) + np.floor(u) * lb.cycle_distance
    step = np.diff(da) * (1 - w[1:]) + np.diff(db) * w[1:]
    x = np.concatenate(([0.0], np.cumsum(step)))
    ground = np.column_stack((x, np.zeros_like(x), np.zeros_like(x)))
    # The last frame is B's cycle start itself: the node pose the blend lands on.
    return Motion(ground, root, quat.make_continuous(q), con)


def from_node(patch_a: LocomotionPatch, patch_b: LocomotionPatch) -> Transition:
    """The blend table's entry for the node pose of ``patch_a`` (every segment starts and
    ends on it: its straight loop's cycle start, phase 0) into ``patch_b``: a layer is
    changed where one of its segments ends, feet planted as both gaits plant them. The
    blend is computed from phase 0 itself (:func:`table` starts an entry on the loop frame
    nearest its cluster centre) and kept with the patch."""
    cache = patch_a.__dict__.setdefault("_node_transitions", {})
    key = (patch_b.layer, id(patch_b))
    got = cache.get(key)
    if got is None:
        m = blend(patch_a.gait, patch_b.gait, 0)
        end = poses.pose_features(m.root_local[-1:], m.rotations[-1:])
        got = cache[key] = Transition(
            patch_a.layer,
            patch_b.layer,
            int(patch_a.seg_pose[0, 0]),
            0,
            m,
            m.ground[-1].copy(),
            int(poses.nearest(patch_b.pose_centres, end)[0]),
        )
    return got


def table(patch_a: LocomotionPatch, patch_b: LocomotionPatch) -> list[Transition]:
    """The blend table from ``patch_a``'s layer into ``patch_b``'s: one
    :class:`Transition` per pose cluster of A, starting at the straight loop's frame
    nearest that cluster, ending in B's node pose."""
    la = patch_a.gait.straight
    feats = poses.pose_features(la.root_local, la.rotations)
    out = []
    for c in range(patch_a.pose_centres.shape[0]):
        phase = int(np.argmin(((feats - patch_a.pose_centres[c]) ** 2).sum(axis=1)))
        m = blend(patch_a.gait, patch_b.gait, phase)
        end = poses.pose_features(m.root_local[-1:], m.rotations[-1:])
        out.append(
            Transition(
                patch_a.layer,
                patch_b.layer,
                c,
                phase,
                m,
                m.ground[-1].copy(),
                int(poses.nearest(patch_b.pose_centres, end)[0]),
            )
        )
    return out
