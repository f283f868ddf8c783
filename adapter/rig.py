# SPDX-License-Identifier: GPL-3.0-or-later
"""Characters on another skeleton than the patch's: the bone map stored on the armature and
the :class:`~motion_patches.kinematics.retarget.RigMap` of a character, the glue every writer uses.

The bone map is a property group on the armature *data*, ``Armature.motion_patches_rig``
(``bone_map``: rows of ``patch_bone`` -> ``rig_bone``), so every character made from one rig
shares it. It only overrides: patch bones it does not list are paired by their names
(:func:`motion_patches.kinematics.retarget.rig_map`). A row with an empty ``rig_bone`` leaves that
patch bone out. Users edit it in the sidebar (Motion Patches > Planning > Bone Map: *Fill
From Names* lists every patch bone with the rig bone the names give, then any row can be
changed), or from Python with :func:`set_bone_map`.
"""

import numpy as np

from ..motion_patches.kinematics.retarget import rig_map, same_skeleton
from ..motion_patches.kinematics.skeleton import Skeleton
from . import actions as act_io
from . import compat


def world_scale(obj):
    """The armature's uniform scale in the world (object and parents: an FBX import's 0.01
    over centimetre bones): its bone units per metre are ``1 / world_scale``. ValueError
    naming the object when the scale differs between axes or mirrors it (a pose then
    stretches or flips the planned motion)."""
    m = np.array(obj.matrix_world)[:3, :3]
    axes = np.linalg.norm(m, axis=0)
    s = float(axes.mean())
    if s <= 1e-9 or np.ptp(axes) > 1e-4 * s or np.linalg.det(m) < 0:
        raise ValueError(
            f"armature '{obj.name}' is scaled {tuple(round(v, 4) for v in obj.scale)}: not the "
            f"same on every axis, or mirrored; apply its scale first (Object > Apply > Scale)"
        )
    # an unscaled rig is exactly 1 (a turned one's float32 axes are 1 within 1e-7): its
    # skeleton, keys and shared actions stay those of before
    return 1.0 if abs(s - 1.0) < 1e-6 else s


def world_tilt(obj):
    """The armature's world rotation with its turn about Z taken out (3, 3), or None when
    it only turns about Z: what stands its bones up when its armature space is not Z-up
    (an FBX import's Y-up bones under a 90 degree X rotation). The turn taken out is the
    heading of its X axis, so the tilt is the same whichever way the rig faces."""
    m = np.array(obj.matrix_world)[:3, :3]
    r = m / np.linalg.norm(m, axis=0)
    psi = np.arctan2(r[1, 0], r[0, 0]) if np.hypot(r[0, 0], r[1, 0]) > 1e-6 else 0.0
    c, s = np.cos(psi), np.sin(psi)
    tilt = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]) @ r
    return None if np.allclose(tilt, np.eye(3), atol=1e-6) else tilt


def skeleton_in_metres(obj):
    """The armature's skeleton with its rest positions in world metres (bone lengths times
    :func:`world_scale`) and stood up by :func:`world_tilt`: what the planned motion, which
    is in metres with Z up, is put on. Bone rotation channels are the same in either space;
    only root locations are keyed back in the armature's units
    (:func:`motion_patches.adapter.nla.inplace_channels`)."""
    own = act_io.skeleton_of(obj)
    s, tilt = world_scale(obj), world_tilt(obj)
    if s == 1.0 and tilt is None:
        return own
    rest = own.rest.copy()
    rest[:, :3, 3] *= s
    if tilt is not None:  # stood up: Z is up, the object then turns it about Z only
        rest[:, :3, :] = tilt @ rest[:, :3, :]
    return Skeleton(own.names, own.parents, rest)


def bone_map(obj):
    """{patch bone: rig bone ('' = left out)} stored on the armature ``obj``, read without
    adding empty settings to a rig that has none (:func:`compat.stored_settings`)."""
    rig = compat.stored_settings(obj.data, "motion_patches_rig")
    if rig is None:
        return {}
    return {row.patch_bone: row.rig_bone for row in rig.bone_map if row.patch_bone}


def set_bone_map(obj, mapping):
    """Replace the armature's stored bone map by ``mapping`` ({patch bone: rig bone})."""
    rows = obj.data.motion_patches_rig.bone_map
    rows.clear()
    for patch_bone, rig_bone in mapping.items():
        row = rows.add()
        row.patch_bone, row.rig_bone = patch_bone, rig_bone or ""


def _plays_itself(skel, rig_skel):
    """Whether the rig holds the patch skeleton unchanged (every patch bone, its parent and
    its rest matrix), extra bones allowed: then no retargeting is needed."""
    index = {n: i for i, n in enumerate(rig_skel.names)}
    if any(n not in index for n in skel.names):
        return False
    sub = [index[n] for n in skel.names]
    parents = [
        rig_skel.names[rig_skel.parents[i]] if rig_skel.parents[i] >= 0 else None for i in sub
    ]
    want = [skel.names[p] if p >= 0 else None for p in skel.parents]
    return parents == want and np.allclose(rig_skel.rest[sub], skel.rest, atol=1e-4)


def rig_for(obj, skel, floor=0.0):
    """The RigMap that puts motion of skeleton ``skel`` on armature ``obj``, or None when
    the armature holds that skeleton itself (and its bone map changes nothing). Raises
    ValueError (a :class:`~motion_patches.kinematics.retarget.RetargetError`) naming the patch bones
    that cannot be mapped. The armature's skeleton is taken in metres
    (:func:`skeleton_in_metres`), whatever its object scale."""
    own = skeleton_in_metres(obj)
    stored = {p: r for p, r in bone_map(obj).items() if p in skel.names}
    if _plays_itself(skel, own) and all(r == p for p, r in stored.items()):
        return None
    try:
        rm = rig_map(skel, own, stored, floor=floor)
    except ValueError as exc:
        raise type(exc)(f"armature '{obj.name}': {exc}") from None
    if same_skeleton(rm.target, skel) and rm.mapping == {n: n for n in skel.names}:
        return None
    return rm


def guessed_map(obj, skel):
    """{patch bone: rig bone or ''} that the names give (no stored overrides), for filling
    the bone map in the UI; ValueError when even the legs cannot be paired."""
    own = act_io.skeleton_of(obj)
    try:
        mapping = rig_map(skel, own).mapping
    except ValueError:
        from ..motion_patches.kinematics.retarget import roles

        s_roles, t_roles = roles(skel)[1], roles(own)[1]
        mapping = {skel.names[i]: own.names[t_roles[r]] for r, i in s_roles.items() if r in t_roles}
    return {n: mapping.get(n, "") for n in skel.names}
