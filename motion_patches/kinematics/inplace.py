# SPDX-License-Identifier: GPL-3.0-or-later
"""In-place motion: the body relative to a moving ground frame.

A ground frame is (x, y, heading) per frame with heading measured from +X. The in-place
part is what remains: the root's position in ground coordinates and the root's rotation
channel re-expressed so the armature faces +X. Putting the ground frame on the armature
object and the in-place channels on its bones gives back the world motion exactly; this is
the split the NLA output uses (shared in-place actions, one root trajectory).
"""

import numpy as np

from . import quat
from .clip import Clip, lateral_axis
from .skeleton import Skeleton, per_skeleton


def rest_facing(skel: Skeleton) -> np.ndarray:
    """Horizontal facing of the skeleton in its rest pose (armature space)."""
    lat = lateral_axis(skel)  # towards the left hip
    f = np.cross(lat, [0.0, 0.0, 1.0])
    return f / np.linalg.norm(f)


def facing_yaw(clip: Clip) -> np.ndarray:
    """Heading (radians from +X, unwrapped) of the root bone's facing on every frame."""
    skel = clip.skeleton
    r = skel.root
    rest_rot = skel.rest[r, :3, :3]
    g = rest_rot[None] @ quat.to_matrix(clip.rotations[:, r])
    # Facing in the rest pose, expressed in the root bone's rest-local axes.
    f_local = rest_rot.T @ rest_facing(skel)
    f = g @ f_local
    return np.unwrap(np.arctan2(f[:, 1], f[:, 0]))


@per_skeleton
def _root_rest(skel):
    """The root bone's rest rotation as a quaternion."""
    return quat.from_matrix(skel.rest[skel.root, :3, :3])


def root_channel_to_ground(
    skel: Skeleton, root_rot: np.ndarray, heading: float | np.ndarray
) -> np.ndarray:
    """Root rotation channels relative to a ground frame turned by ``heading``."""
    q_rest = _root_rest(skel)
    # basis' = rest^-1 * Rz(-heading) * rest * basis; the turn before the basis is made
    # once per heading (a single one for a constant heading), not once per frame
    yaw = quat.about_z(-np.asarray(heading))
    q_rest = np.broadcast_to(q_rest, np.shape(yaw))
    return quat.mul(quat.mul(quat.mul(quat.conj(q_rest), yaw), q_rest), root_rot)


def to_inplace(clip: Clip, ground: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(root_local (F, 3), rotations (F, J, 4)) of ``clip`` relative to ``ground`` (F, 3)."""
    ground = np.asarray(ground, float)
    c, s = np.cos(ground[:, 2]), np.sin(ground[:, 2])
    d = clip.root_pos[:, :2] - ground[:, :2]
    local = np.stack(
        (c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], clip.root_pos[:, 2]), 1
    )
    rot = clip.rotations.copy()
    r = clip.skeleton.root
    rot[:, r] = root_channel_to_ground(clip.skeleton, rot[:, r], ground[:, 2])
    return local, quat.make_continuous(rot, axis=0)


def root_positions(ground: np.ndarray, root_local: np.ndarray) -> np.ndarray:
    """Armature-space root positions (F, 3): ``root_local`` carried by the ground frame
    (the first half of :func:`to_world`, for callers that need no rotation)."""
    ground = np.asarray(ground, float)
    c, s = np.cos(ground[:, 2]), np.sin(ground[:, 2])
    x = ground[:, 0] + c * root_local[:, 0] - s * root_local[:, 1]
    y = ground[:, 1] + s * root_local[:, 0] + c * root_local[:, 1]
    return np.stack((x, y, root_local[:, 2]), 1)


def to_world(
    skel: Skeleton, ground: np.ndarray, root_local: np.ndarray, rotations: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Armature-space (world, for an identity object) root positions and rotation channels."""
    ground = np.asarray(ground, float)
    pos = root_positions(ground, root_local)
    rot = np.array(rotations, float)
    r = skel.root
    rot[:, r] = root_channel_to_ground(skel, rot[:, r], -ground[:, 2])
    return pos, rot
