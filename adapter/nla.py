# SPDX-License-Identifier: GPL-3.0-or-later
"""Plans -> NLA: one strip per motion segment on shared in-place actions, one root track.

Tracks the add-on makes are named with ``TRACK_PREFIX`` and listed on the object, so a
re-plan removes exactly those; user tracks and actions are never touched. Segment actions
are shared between strips and characters (keyed by patch, segment and the rig's bone
rotation modes, :func:`segment_action`); connector actions belong to one character and are
replaced with its plan. The armature object carries the ground trajectory; its bones carry
in-place motion facing the rig's rest facing. Every channel is written in the rotation mode
of the bone (or object) it drives: a bone plays only the channel of its own mode.
"""

import hashlib
import json

import numpy as np

from ..motion_patches.kinematics import foot_lock, quat
from ..motion_patches.kinematics.inplace import rest_facing, root_channel_to_ground
from ..motion_patches.kinematics.skeleton import per_skeleton, root_position_to_location
from . import actions as act_io
from . import compat
from . import rig as rig_io

TRACK_PREFIX = "MP "
TRACK_MOTION = TRACK_PREFIX + "motion"
TRACK_ROOT = TRACK_PREFIX + "root"
TRACK_FOOT = TRACK_PREFIX + "foot lock"
TRACKS_KEY = "motion_patches_tracks"
SEGMENT_KEY = "motion_patches_segment"
CHARACTER_KEY = "motion_patches_character"
STASH_PREFIX = TRACK_PREFIX + "stash: "


@per_skeleton
def facing_angle(skel):
    """The rig's rest facing as an angle from +X (every action and root track of a write
    turns by it)."""
    f = rest_facing(skel)
    return float(np.arctan2(f[1], f[0]))


def inplace_channels(skel, motion):
    """Root location channels (F, 3) and rotations (F, J, 4) for an object whose Z rotation
    is the ground heading minus the rig's rest facing.

    That object is the motion's ground frame turned by -facing, so the body relative to it
    is the motion's own in-place channels turned by +facing: the root's position about Z,
    and its rotation by the same turn conjugated into the root's rest frame (what
    ``to_world`` then ``to_inplace`` against the object's headings gives, without the round
    trip through the world)."""
    facing = facing_angle(skel)
    c, s = np.cos(facing), np.sin(facing)
    x, y, z = np.asarray(motion.root_local, float).T
    local = np.stack((c * x - s * y, s * x + c * y, z), 1)
    rot = np.array(motion.rotations, float)
    r = skel.root
    rot[:, r] = root_channel_to_ground(skel, rot[:, r], -facing)
    return root_position_to_location(skel, local), quat.make_continuous(rot, axis=0)


def check_rig(obj, skel, floor=0.0):
    """The :class:`~motion_patches.kinematics.retarget.RigMap` that puts the patch skeleton ``skel``
    on the armature ``obj`` (None: the armature holds that skeleton itself). Raises
    ValueError for an object that is no armature, is scaled or tilted, or whose bones
    cannot play the patch's hips, legs, feet and toes (naming those patch bones)."""
    if obj is None or obj.type != "ARMATURE":
        raise ValueError("the character must be an armature object")
    if not np.allclose(np.array(obj.scale), 1.0, atol=1e-4):
        raise ValueError(
            f"armature '{obj.name}' is scaled {tuple(round(s, 3) for s in obj.scale)}; "
            f"apply its scale first (the patch is in metres)"
        )
    m = np.array(obj.matrix_world)
    if abs(m[2, 2] - 1.0) > 1e-6:
        raise ValueError(
            f"armature '{obj.name}' is tilted (X/Y rotation); the planned root turns about Z only"
        )
    return rig_io.rig_for(obj, skel, floor)


def remove_owned(obj):
    """Remove the NLA tracks this add-on made on ``obj`` (and nothing else)."""
    ad = obj.animation_data
    names = json.loads(obj.get(TRACKS_KEY, "[]"))
    if ad is None:
        return
    for tr in list(ad.nla_tracks):
        if tr.name in names and tr.name.startswith(TRACK_PREFIX):
            ad.nla_tracks.remove(tr)


def _orphan_connectors(bpy, character_name):
    for a in list(bpy.data.actions):
        if a.get(CHARACTER_KEY) == character_name and a.users == 0:
            bpy.data.actions.remove(a)


def stash_active_action(obj):
    """Move an active action into a muted track so it stops overriding the NLA (kept intact)."""
    ad = obj.animation_data
    if ad is None or ad.action is None:
        return None
    action, slot = ad.action, ad.action_slot
    tr = ad.nla_tracks.new()
    tr.name = STASH_PREFIX + action.name
    start = int(action.frame_range[0])
    strip = tr.strips.new(action.name, start, action)
    if slot is not None:
        compat.set_strip_slot(strip, slot)
    tr.mute = True
    ad.action = None
    return tr.name


def rig_rotation_modes(obj, skel):
    """{bone name: rotation_mode} of the rig's pose bones that the patch skeleton drives."""
    return {n: obj.pose.bones[n].rotation_mode for n in skel.names}


def rotation_signature(skel, modes):
    """A short name for the per-bone rotation modes: '' when every bone is in quaternion
    mode, the mode when all share one (e.g. 'ZYX'), else 'mixed-' and a hash of them."""
    used = [modes.get(n, "QUATERNION") for n in skel.names]
    if all(m == "QUATERNION" for m in used):
        return ""
    if len(set(used)) == 1:
        return used[0]
    text = ",".join(f"{n}={m}" for n, m in zip(skel.names, used))
    return "mixed-" + hashlib.sha1(text.encode()).hexdigest()[:10]


def segment_action(bpy, patch, patch_key, seg, skel, modes=None, rig=None, index=None):
    """The shared in-place action of a patch segment for a rig whose bones have rotation
    ``modes`` ({bone: rotation_mode}; default all quaternion), created on first use;
    ``rig`` (a :class:`~motion_patches.kinematics.retarget.RigMap`) when the rig is another skeleton
    than the patch's, ``skel`` then being the rig's.

    Shared actions are keyed by patch, segment, the rig's skeleton (:meth:`RigMap.signature
    <motion_patches.retarget.RigMap.signature>`: retargeted keys differ per skeleton) *and*
    a signature of the rig's per-bone rotation modes (:func:`rotation_signature`), not
    made to hold every channel set a rig could need: an action has one ``rotation_euler``
    F-curve per bone and axis, so Euler angles can be stored in one order only (the six
    orders give six different values for the same rotation), and writing the quaternion,
    Euler and axis-angle channels of every bone would triple the keys of every segment for
    channels most rigs never play. Rigs of one skeleton whose bones have the same modes
    (every character copied from one rig, every rig from one importer) still share one
    action per segment; the patch's own skeleton in all-quaternion mode uses the original
    key ``patch:seg``, so segment actions of earlier saved files are reused. Keys sit on
    the patch's frames whatever the scene's rate (strips are scaled, :func:`write_plan`).
    ``index``: {key: action} of the segment actions (:func:`segment_index`), so a plan of
    many strips does not search every action of the file for each."""
    sig = rotation_signature(skel, modes or {})
    rig_sig = rig.signature() if rig is not None else ""
    key = f"{patch_key}:{seg}" + (f":rig-{rig_sig}" if rig_sig else "") + (f":{sig}" if sig else "")
    found = (segment_index(bpy) if index is None else index).get(key)
    if found is not None:
        return found, compat.action_slot(found)
    motion = patch.motion(seg)
    if rig is not None:
        motion = rig.motion(motion)
    name = (
        f"MP {patch.layer} seg{seg:04d}"
        + (f" rig-{rig_sig[:6]}" if rig_sig else "")
        + (f" {sig}" if sig else "")
    )
    action, slot = _inplace_action(name, skel, motion, {SEGMENT_KEY: key}, modes)
    if index is not None:
        index[key] = action
    return action, slot


def segment_index(bpy):
    """{segment key: action} of the file's shared segment actions."""
    out = {}
    for a in bpy.data.actions:
        key = a.get(SEGMENT_KEY)
        if key is not None:
            out.setdefault(key, a)
    return out


def _inplace_action(name, skel, motion, tags, modes=None):
    loc, rot = inplace_channels(skel, motion)
    action, slot = compat.new_action(name)
    for k, v in tags.items():
        action[k] = v
    frames = np.arange(motion.frames, dtype=float)
    act_io.key_pose(action, slot, skel, frames, loc, rot, modes, tol=act_io.COMPACT)
    return action, slot


def write_plan(
    bpy,
    obj,
    patch,
    patch_key,
    plan,
    motions,
    world,
    frame_start,
    locked=None,
    rig=None,
    bounds=None,
    layer_keys=None,
):
    """Write a plan's strips and root trajectory on ``obj``; returns strip records.

    ``motions``: each piece's motion at the patch's frame rate, on the rig's skeleton (put
    there by ``rig``, a :class:`~motion_patches.kinematics.retarget.RigMap`, when the rig is another
    skeleton; None: the patch's). ``bounds``: the scene frames (offsets from
    ``frame_start``, P + 1 integers) where the pieces start and the last one ends; default
    the patch's own frames. When the scene runs at another rate than the patch, piece ``i``
    plays its patch-rate keys with strip scale ``(bounds[i+1] - bounds[i]) / (frames - 1)``
    (:mod:`motion_patches.kinematics.scene_rate`). ``world``: the whole motion on the scene's frames
    (``bounds[-1] + 1`` of them), which the per-character root trajectory is keyed from.
    ``locked``: rotation channels (F, J, 4) of ``world`` with the feet pinned
    (:func:`motion_patches.kinematics.foot_lock.lock_feet`); the difference is written as a
    per-character correction on its own track, added over the shared segment actions.
    ``layer_keys``: {layer: patch key} of a plan that changes layer, whose segment pieces
    name their own patch (:class:`motion_patches.planning.transitions.LayerPiece`): their strips
    play that patch's shared segment actions, on the one motion track."""
    skel = rig.target if rig is not None else patch.gait.skeleton
    modes = rig_rotation_modes(obj, skel)
    if bounds is None:
        bounds = np.concatenate(([0], np.cumsum([m.frames - 1 for m in motions])))
    bounds = np.asarray(bounds, int)
    ad = obj.animation_data or obj.animation_data_create()
    stashed = stash_active_action(obj)
    remove_owned(obj)
    _orphan_connectors(bpy, obj.name)

    motion_track = ad.nla_tracks.new()
    motion_track.name = TRACK_MOTION
    strips, played = [], []
    first = int(frame_start)
    index = segment_index(bpy)
    for n, (piece, m) in enumerate(zip(plan.pieces, motions)):
        if piece.kind == "segment":
            own = getattr(piece, "patch", None) if layer_keys else None
            action, slot = segment_action(
                bpy,
                own or patch,
                layer_keys[own.layer] if own is not None else patch_key,
                piece.segment,
                skel,
                modes,
                rig,
                index,
            )
        else:
            action, slot = _inplace_action(
                f"MP {obj.name} {piece.kind}", skel, m, {CHARACTER_KEY: obj.name}, modes
            )
        start, end = first + int(bounds[n]), first + int(bounds[n + 1])
        scale = (end - start) / float(max(m.frames - 1, 1))
        played.append((action, slot, int(bounds[n]), end - start + 1, scale))
        strip = motion_track.strips.new(f"{n:02d} {piece.label}", start, action)
        compat.set_strip_slot(strip, slot)
        if abs(scale - 1.0) > 1e-9:
            # Blender keeps the scale in single precision: rounded up, the strip would end a
            # hair after the next one starts, and that one could not be added.
            single = np.float32(scale)
            while float(single) * (m.frames - 1) > end - start:
                single = np.nextafter(single, np.float32(0.0))
            strip.scale = float(single)
        strip.extrapolation = (
            "HOLD" if n == 0 else ("HOLD_FORWARD" if n == len(plan.pieces) - 1 else "NOTHING")
        )
        strip.blend_in = strip.blend_out = 0.0
        strips.append(
            {
                "name": strip.name,
                "start": start,
                "end": end,
                "action": action.name,
                "kind": piece.kind,
            }
        )

    root_action, root_slot = compat.new_action(f"MP {obj.name} root")
    root_action[CHARACTER_KEY] = obj.name
    heading = np.unwrap(world.ground[:, 2]) - facing_angle(skel)
    frames = np.arange(world.frames, dtype=float)
    z0 = float(obj.location[2])
    curves = [
        ("location", i, "Object Transforms", v)
        for i, v in enumerate((world.ground[:, 0], world.ground[:, 1], np.full(world.frames, z0)))
    ]
    # A turn about Z only: (0, 0, heading) is that turn in every Euler order, (heading, +Z)
    # in axis-angle; the heading is unwrapped, so no channel jumps by a turn.
    zero = np.zeros(world.frames)
    if obj.rotation_mode == "QUATERNION":
        q = quat.make_continuous(quat.about_z(heading), axis=0)
        rot_path, rot_values = "rotation_quaternion", q.T
    elif obj.rotation_mode == "AXIS_ANGLE":
        rot_path, rot_values = "rotation_axis_angle", (heading, zero, zero, zero + 1.0)
    else:
        rot_path, rot_values = "rotation_euler", (zero, zero, heading)
    curves += [(rot_path, i, "Object Transforms", v) for i, v in enumerate(rot_values)]
    act_io.key_curves(root_action, root_slot, frames, curves, _finer(act_io.COMPACT))
    root_track = ad.nla_tracks.new()
    root_track.name = TRACK_ROOT
    rs = root_track.strips.new(f"{obj.name} root", first, root_action)
    compat.set_strip_slot(rs, root_slot)
    rs.extrapolation = "HOLD"
    rs.blend_in = rs.blend_out = 0.0
    owned = [TRACK_MOTION, TRACK_ROOT]
    if locked is not None:
        _write_foot_lock(obj, skel, world, locked, frame_start, modes, played)
        owned.append(TRACK_FOOT)
    obj[TRACKS_KEY] = json.dumps(owned)
    return strips, stashed


def _finer(tol):
    """A quarter of ``tol``'s angle for the root and foot-lock curves: each of their
    channels is judged alone (a quaternion turns by up to four component errors), the
    heading turns the whole body and the foot lock holds a planted foot; few curves."""
    if isinstance(tol, act_io.Tolerance):
        return act_io.Tolerance(tol.angle / 4.0, tol.length)
    return tol


def _played_frames(played, n_frames):
    """Which strip plays each plan frame and the action frame it plays there: ``played`` =
    [(action, slot, first plan frame, scene frames it spans, strip scale)] in track order;
    where two strips meet on a frame the earlier one plays (Blender takes the first strip
    whose range holds the frame). A scaled strip plays action frame
    ``(frame - start) / scale``. Returns {(action, slot): (plan frames, action frames)},
    the frames of every strip of one action together, so each channel is read once per
    action (a plan plays one segment action on many strips)."""
    owner = np.full(n_frames, -1)
    at = np.zeros(n_frames)
    for s, (_, _, start, frames, scale) in enumerate(played):
        idx = np.arange(start, min(start + frames, n_frames))
        idx = idx[owner[idx] < 0]
        owner[idx] = s
        at[idx] = (idx - start) / scale
    keys = {}  # (action, slot) -> its number, in the order strips first play them
    which = np.array([keys.setdefault((a, sl), len(keys)) for a, sl, *_ in played] + [-1])
    playing = which[owner]  # the action on each frame (-1: none; owner -1 picks the last)
    out = {}
    for key, n in keys.items():
        idx = np.flatnonzero(playing == n)
        out[key] = (idx, at[idx])
    return out


def _lower_channels(frames_of, bones, mode, n_frames, cache=None):
    """What the motion track gives the ``mode`` channels of ``bones`` on each plan frame
    (F, K, C), read from the keys of its strips' actions (``frames_of``:
    :func:`_played_frames`), between keys linearly; the rest value on frames no strip
    plays."""
    out = np.empty((n_frames, len(bones), act_io.rest_channels(mode).size))
    out[:] = act_io.rest_channels(mode)
    for (action, slot), (idx, at) in frames_of.items():
        out[idx] = act_io.read_bones(action, slot, bones, mode, at, cache)
    return out


def _write_foot_lock(obj, skel, world, locked, frame_start, modes=None, played=()):
    """The foot lock as an Add strip above the motion, so segment actions stay shared.

    Blender's Add blend (influence 1) adds each channel value, ``lower + delta``, in every
    rotation mode: the four quaternion components (the sum is normalised when the pose is
    built), the three Euler angles, the four axis-angle values. So for every bone the lock
    changes, the strip keys ``delta = locked - lower`` in the bone's own mode, ``locked``
    being the representation of the locked rotation nearest ``lower`` (quaternion sign,
    Euler triple of the bone's order, axis-angle axis and turns) and ``lower`` the values
    the motion strips really key on that frame (:func:`_lower_channels`). The sum is the
    locked rotation to float32 in every mode. (A Combine strip multiplies quaternions, and
    Blender takes the strip quaternion's angle as acos of its float32 w: corrections under
    ~0.0005 rad were lost on quaternion bones, 1.3e-3 off the plan; checked in
    tests/blender/test_rotation_modes.py.) On the frames where the lock leaves a bone alone
    its delta is exactly zero (the motion plays unchanged; the curve stays compact)."""
    modes = modes or {}
    # of the bones the lock may turn (the legs), those it turned, and on which frames
    legs = foot_lock.locked_bones(skel)
    dots = np.einsum("fjc,fjc->fj", world.rotations[:, legs], locked[:, legs])
    moved = np.abs(np.abs(dots) - 1.0) > 1e-9  # (F, legs)
    turned = moved.any(axis=0)
    changed, moved = legs[turned], moved[:, turned]
    action, slot = compat.new_action(f"MP {obj.name} foot lock")
    action[CHARACTER_KEY] = obj.name
    frames = np.arange(world.frames, dtype=float)
    cache, curves, columns = {}, [], []
    frames_of = _played_frames(played, world.frames)
    by_mode = {}
    for k, j in enumerate(changed):
        by_mode.setdefault(modes.get(skel.names[j], "QUATERNION"), []).append(k)
    for mode, ks in by_mode.items():  # the bones of one rotation mode at once
        names = [skel.names[changed[k]] for k in ks]
        lower = _lower_channels(frames_of, names, mode, world.frames, cache)  # (F, K, C)
        delta = act_io.closest_channels(locked[:, changed[ks]], mode, lower) - lower
        delta[~moved[:, ks]] = 0.0
        path = act_io.rotation_path(mode)
        columns.append(delta.reshape(world.frames, -1))  # bone by bone, channels in order
        curves += [
            (f'pose.bones["{name}"].{path}', c, name, None)
            for name in names
            for c in range(delta.shape[-1])
        ]
    values = np.concatenate(columns, axis=1) if columns else None
    act_io.key_curves(action, slot, frames, curves, _finer(act_io.COMPACT), values=values)
    track = obj.animation_data.nla_tracks.new()
    track.name = TRACK_FOOT
    strip = track.strips.new(f"{obj.name} foot lock", int(frame_start), action)
    compat.set_strip_slot(strip, slot)
    strip.blend_type = "ADD"
    strip.extrapolation = "HOLD"
    strip.blend_in = strip.blend_out = 0.0
