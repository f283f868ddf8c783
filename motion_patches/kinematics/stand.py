# SPDX-License-Identifier: GPL-3.0-or-later
"""Standing: a walk's double-support pose with both feet put down flat (DERIVED).

The shared mocap has no recorded idle, start or stop of the walking subject, and a walk
has no frame with both feet flat: at double support the trailing heel is already 3-5 cm
up and the leading toes are still coming down. A stand is derived from such a frame: each
foot is turned flat (to its own orientation in the middle of its flat stance in the
walk's straight loop, about the joint that is down: the toe of a heel that is up, the
heel of toes that are up) and put at its standing height (the walk's own planted heights),
the legs reach it by two-bone IK and the hips sink as far as a stretched leg needs.
The body above the hips and the hips' own turn are the recorded ones. A plan eases into
it over its last frames and out of it over its first (:func:`settled`), where the stop
(start) has slowed the walk almost to a standstill on that double-support frame.
"""

from dataclasses import dataclass

import numpy as np

from . import quat
from .foot_lock import STRETCH, leg_chains, two_bone_ik
from .motion import Motion
from .skeleton import Skeleton


@dataclass
class FlatFeet:
    """Per foot (left, right): standing heights of the ankle and the toe (2,) and the
    foot bone's world rotation on flat ground facing +X (2, 3, 3), from a walk loop."""

    ankle: np.ndarray  # (2,) metres above the floor
    toe: np.ndarray  # (2,)
    rotation: np.ndarray  # (2, 3, 3)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_stands", None)  # remembered stands (:func:`stand_of`): made where used
        return state


def _in_place(skel, root_local, rotations):
    """World matrices (F, J, 4, 4) of in-place poses (the ground frame at the origin)."""
    root_local = np.atleast_2d(root_local)
    rotations = np.asarray(rotations, float).reshape((root_local.shape[0],) + rotations.shape[-2:])
    n = root_local.shape[0]
    return Motion(np.zeros((n, 3)), root_local, rotations, np.zeros((n, 4), bool)).world_matrices(
        skel
    )


def flat_feet(
    skel: Skeleton, root_local: np.ndarray, rotations: np.ndarray, contacts: np.ndarray
) -> FlatFeet:
    """The flat feet of a walk loop (in place: root (F, 3), rotations (F, J, 4), contacts
    (F, 4)): per foot, the middle frame of the frames with its heel and toe both planted
    (the lowest-heeled frame if there are none) gives the rotation; the heights are the
    medians over those frames."""
    w = _in_place(skel, root_local, rotations)
    c = np.asarray(contacts, bool)
    ankle, toe, rot = np.zeros(2), np.zeros(2), np.zeros((2, 3, 3))
    for side, (_, _, a, t) in enumerate(leg_chains(skel)):
        flat = np.flatnonzero(c[:, 2 * side] & c[:, 2 * side + 1])
        if flat.size == 0:
            flat = np.array([int(np.argmin(w[:, a, 2, 3]))])
        ankle[side] = np.median(w[flat, a, 2, 3])
        toe[side] = np.median(w[flat, t, 2, 3])
        rot[side] = w[flat[flat.size // 2], a, :3, :3]
    return FlatFeet(ankle, toe, rot)


def _yaw(v):
    return np.arctan2(v[..., 1], v[..., 0])


def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def standing(
    skel: Skeleton, root_local: np.ndarray, rotations: np.ndarray, feet: FlatFeet
) -> tuple[np.ndarray, np.ndarray]:
    """(root_local (3,), rotations (J, 4)) of one in-place pose with both feet put down
    flat where they are (see the module): the foot turned flat about the joint nearer its
    standing height (the toe when the heel is up, the heel when the toes are), the legs by
    two-bone IK, the hips lowered as far as the straighter leg needs to reach."""
    root = np.array(root_local, float)
    rot = np.array(rotations, float)
    chains = leg_chains(skel)
    w = _in_place(skel, root, rot)[0]
    targets, foot_rot = [], []
    for side, (hip, knee, a, t) in enumerate(chains):
        A, T, G = w[a, :3, 3], w[t, :3, 3], w[a, :3, :3]
        ref = feet.rotation[side]
        # the reference foot turned to this foot's own yaw (ankle to toe, horizontally)
        r_ref = _yaw(ref @ (G.T @ (T - A)))
        R = _rz(_yaw(T - A) - r_ref) @ ref
        v = G.T @ (T - A)  # the toe in the foot's frame
        if A[2] - feet.ankle[side] > T[2] - feet.toe[side]:  # heel up: turn about the toe
            toe_at = np.array([T[0], T[1], feet.toe[side]])
            target = toe_at - R @ v
        else:  # toes up (or flat): turn about the heel
            target = np.array([A[0], A[1], feet.ankle[side]])
        targets.append(target)
        foot_rot.append(R)
    # Sink the hips where a leg could not reach its ankle otherwise.
    drop = 0.0
    for (hip, knee, a, _), target in zip(chains, targets):
        H, K, A = w[hip, :3, 3], w[knee, :3, 3], w[a, :3, 3]
        reach = STRETCH * (np.linalg.norm(K - H) + np.linalg.norm(A - K)) - 1e-3
        h = np.linalg.norm((target - H)[:2])
        if h < reach:
            drop = max(drop, (H[2] - target[2]) - np.sqrt(reach * reach - h * h))
    if drop > 0.0:
        root[2] -= drop
        w = _in_place(skel, root, rot)[0]
    glob = w[:, :3, :3].copy()
    local_rest = skel.local_rest()
    for side, (hip, knee, a, _) in enumerate(chains):
        H, K, A = w[hip, :3, 3], w[knee, :3, 3], w[a, :3, 3]
        forward = np.array([[1.0, 0.0, 0.0]])
        r_thigh, r_shin = two_bone_ik(
            H[None], K[None], A[None], targets[side][None], w[hip, :3, 0][None], forward
        )
        for j in _between(skel, hip, knee):
            glob[j] = r_thigh[0] @ w[j, :3, :3]
        for j in _between(skel, knee, a):
            glob[j] = r_shin[0] @ w[j, :3, :3]
        glob[a] = foot_rot[side]
        for j in _between(skel, hip, knee) + _between(skel, knee, a) + [a]:
            p = skel.parents[j]
            basis = (glob[p] @ local_rest[j, :3, :3]).T @ glob[j]
            q = quat.from_matrix(basis)
            rot[j] = q if np.dot(q, rot[j]) >= 0 else -q
    return root, rot


STANDS_KEPT = 4096  # stands remembered per feet (about 2 kB each)


def stand_of(
    skel: Skeleton, root_local: np.ndarray, rotations: np.ndarray, feet: FlatFeet
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`standing`, remembered on ``feet`` per skeleton and pose (the first
    ``STANDS_KEPT``): the walks of a crowd start and stop on a few hundred poses of the
    gait's frames (three stands in four were made before). Copies: the same arrays as
    :func:`standing` gives."""
    root, rot = np.asarray(root_local, float), np.asarray(rotations, float)
    key = (root.shape, rot.shape, root.tobytes(), rot.tobytes())
    kept = feet.__dict__.setdefault("_stands", {})
    got = kept.get(key)
    if got is None or got[0] is not skel:
        got = (skel, *standing(skel, root, rot, feet))
        if len(kept) < STANDS_KEPT:
            kept[key] = got
    return got[1].copy(), got[2].copy()


def _between(skel, upper, lower):
    """The bones from ``upper`` down to the one above ``lower`` (a leg bone and its limb
    segments), parents first."""
    out, j = [], int(skel.parents[lower])
    while j >= 0 and j != upper:
        out.append(j)
        j = int(skel.parents[j])
    return [upper] + out[::-1]


def settled(
    skel: Skeleton, motion: Motion, feet: FlatFeet, start: bool, end: bool, window: int
) -> Motion:
    """``motion`` easing out of standing over its first ``window`` frames (``start``)
    and / or into standing over its last (``end``): the stand of its first (last) frame
    (:func:`standing`), rotations slerped and the hips' height blended by a smoothstep,
    both feet planted while the stand weighs at least half, and each the whole of the
    contact it stands in then."""
    n = motion.frames
    if n < 3 or not (start or end):
        return motion
    k = int(max(min(window, (n - 1) // (int(start) + int(end))), 1))
    root, rot = motion.root_local.copy(), motion.rotations.copy()
    con = np.array(motion.contacts, bool)
    f = np.arange(n, dtype=float)
    for on, i, t in ((start, 0, 1.0 - f / k), (end, n - 1, 1.0 - (n - 1 - f) / k)):
        if not on:
            continue
        s_root, s_rot = stand_of(skel, motion.root_local[i], motion.rotations[i], feet)
        t = np.clip(t, 0.0, 1.0)
        wgt = t * t * (3.0 - 2.0 * t)
        some = np.flatnonzero(wgt > 0)
        root[some, 2] += wgt[some] * (s_root[2] - motion.root_local[i, 2])
        target = np.broadcast_to(s_rot, rot[some].shape)
        rot[some] = quat.slerp(rot[some], target, np.repeat(wgt[some, None], rot.shape[1], 1))
        con[wgt >= 0.5] = True
        # A foot that stands on its toe and then puts its heel down never left the
        # ground: one contact of the whole foot (a lock pins it once, not twice).
        step = 1 if i == 0 else -1
        for side in range(2):
            j = i
            while 0 <= j < n and con[j, 2 * side : 2 * side + 2].any():
                con[j, 2 * side : 2 * side + 2] = True
                j += step
    return Motion(motion.ground, root, quat.make_continuous(rot, axis=0), con)
