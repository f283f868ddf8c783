# SPDX-License-Identifier: GPL-3.0-or-later
"""A pose as the curves a rig keys (the root's location, each bone's rotation in its own
mode) and their cubic keys fitted within a :class:`Tolerance`, touching no Blender data:
what is stored is decided here, the adapter only writes it."""

from collections.abc import Mapping, Sequence
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import foot_lock
from . import keys as key_plan
from .channels import (
    channels_to_quat,
    held_channels,
    rest_channels,
    rotation_channels,
    rotation_path,
)
from .skeleton import Skeleton


class Tolerance:
    """How far a compactly stored action may play from the plan: ``angle`` (radians) for
    a bone's rotation, ``length`` (metres) for a location (cubic keys,
    :func:`motion_patches.kinematics.keys.cubic_keys`). ``steady``: also how much a
    channel's error may change from one frame to the next, as a fraction of the tolerance
    (None: any)."""

    def __init__(self, angle=key_plan.ANGLE, length=key_plan.LENGTH, steady=None):
        self.angle, self.length, self.steady = float(angle), float(length), steady


# The root bone's keys are this much finer than the others': the whole body hangs from it,
# and a planted foot (locked against the planned hips) moves with it, a leg's length away.
ROOT_FINER = 8.0


# The legs' (the bones the foot lock turns) this much finer: a planted foot hangs from the
# hips by them, so their errors add up a leg's length away; it stays within a millimetre or
# two of the plan. Most of their curves are samples at any tolerance (stepping bones).
LEG_FINER = 4.0


def _column_tolerances(curves, tol):
    """Per-curve tolerance: ``tol.length`` for locations, half ``tol.angle`` for any other
    channel (a quaternion component off by e turns by about 2 e; an angle by e)."""
    return np.array(
        [tol.length if path.endswith("location") else 0.5 * tol.angle for path, *_ in curves]
    )


def fit_curves(
    frames: ArrayLike,
    curves: Sequence[tuple],
    tol: Any,
    values: np.ndarray | None = None,
    rotations: Sequence = (),
    between: bool = True,
) -> dict | None:
    """The cubic keys the adapter's ``actions.key_curves`` stores for ``curves`` within ``tol`` (a
    :class:`Tolerance`; see there), or None when they are stored otherwise. Touches no
    Blender data: a crowd fits the next characters' keys while one is written."""
    if not (isinstance(tol, Tolerance) and curves):
        return None
    frames = np.asarray(frames, float)
    if values is None:
        values = np.column_stack([np.asarray(c[3], float) for c in curves])
    # a curve that needs as many keys as samples cost is stored as samples: stop there
    samples = -(-frames.size * key_plan.SAMPLE_BYTES // key_plan.KEY_BYTES)
    return key_plan.cubic_keys(
        values,
        _column_tolerances(curves, tol),
        rotations,
        between,
        give_up_at=samples if whole_frames(frames) else None,
        steady=tol.steady,
    )


def whole_frames(frames: np.ndarray) -> bool:
    """Whether ``frames`` are whole frames one apart (where samples sit)."""
    return bool(frames.size and np.all(np.diff(frames) == 1.0) and frames[0] == int(frames[0]))


def pose_curves(
    skel: Skeleton,
    root_location: ArrayLike,
    rotations: np.ndarray,
    modes: Mapping[str, str] | None = None,
    tol: Any = None,
    between: bool = True,
) -> tuple[list, np.ndarray, Any, list]:
    """What the adapter's ``actions.key_pose`` keys: (curves, their values (F, C), the
    tolerance, the :class:`~motion_patches.kinematics.keys.Rotations` among them), for
    ``key_curves`` or :func:`fit_curves`. Touches no Blender data.

    Stored compactly (``tol`` a Tolerance) and played only on its frames (not
    ``between``: a strip unscaled on the scene's frames), a quaternion bone's keys hold a
    component at 1 (:func:`~motion_patches.kinematics.channels.held_channels`). Between
    frames the line through held quaternions turns at another pace than the line through
    unit ones (0.27 degrees off for a toe turning 20 degrees a frame), so a strip scaled
    to another rate keeps unit quaternions."""
    modes = modes or {}
    root = skel.names[skel.root]
    curves = [(f'pose.bones["{root}"].location', i, root, None) for i in range(3)]
    columns = [np.asarray(root_location, float)]  # every curve's values, in curve order
    by_mode: dict[str, list[int]] = {}
    for j, name in enumerate(skel.names):
        by_mode.setdefault(modes.get(name, "QUATERNION"), []).append(j)
    groups, start = [], 3
    for mode, joints in by_mode.items():
        path = rotation_path(mode)
        if mode != "QUATERNION":
            values = rotation_channels(rotations[:, joints], mode)
        elif isinstance(tol, Tolerance) and not between:  # a component held at 1: one key
            values = held_channels(rotations[:, joints])
        else:
            values = rotations[:, joints]
        columns.append(values.reshape(len(values), -1))  # bone by bone, channels in order
        k = values.shape[-1]
        if isinstance(tol, Tolerance):
            cols = start + np.arange(len(joints) * k).reshape(-1, k)
            is_root = np.array(joints) == skel.root
            is_leg = np.isin(joints, foot_lock.locked_bones(skel)) & ~is_root
            rest = ~is_root & ~is_leg
            groups.append(_rotations(mode, cols[rest], tol.angle))
            groups.append(_rotations(mode, cols[is_leg], tol.angle / LEG_FINER))
            groups.append(_rotations(mode, cols[is_root], tol.angle / ROOT_FINER))
        start += len(joints) * k
        for j in joints:
            name = skel.names[j]
            curves += [
                (f'pose.bones["{name}"].{path}', i, name, None) for i in range(values.shape[-1])
            ]
    values = np.concatenate(columns, axis=1)
    if isinstance(tol, Tolerance):  # the root's location: finer too (rotations judged apart)
        tol = Tolerance(tol.angle, tol.length / ROOT_FINER, tol.steady)
    return curves, values, tol, groups


def rest_values(curves: Sequence[tuple]) -> np.ndarray:
    """(C,) the value each of :func:`pose_curves`' ``curves`` has in the rest pose (Blender's
    default of the channel): what a channel the NLA animates plays where no strip keys it."""
    out = np.zeros(len(curves))
    for c, (path, index, *_) in enumerate(curves):
        if path.endswith("rotation_quaternion"):
            out[c] = rest_channels("QUATERNION")[index]
        elif path.endswith("rotation_axis_angle"):
            out[c] = rest_channels("AXIS_ANGLE")[index]
    return out


def _rotations(mode, columns, angle):
    """The :class:`~motion_patches.kinematics.keys.Rotations` of a ``mode``'s channel columns
    (B, 3 or 4), judged within ``angle`` of the rotation they play."""
    return key_plan.Rotations(columns, partial(channels_to_quat, mode=mode), angle)
