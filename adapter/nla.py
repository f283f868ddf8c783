# SPDX-License-Identifier: GPL-3.0-or-later
"""Plans -> NLA: one strip per motion segment on shared in-place actions, one root track.

Tracks the add-on makes are named with ``TRACK_PREFIX`` and listed on the object, so a
re-plan removes exactly those; user tracks and actions are never touched. Segment actions
are shared between strips and characters (keyed by patch, segment and the rig's bone
rotation modes, :func:`segment_action`); the other pieces (start, stop, connectors, turns,
clips) play one body action of the character (:func:`_body_action`), replaced with its
plan. The armature object carries the ground trajectory; its bones carry
in-place motion facing the rig's rest facing. Every channel is written in the rotation mode
of the bone (or object) it drives: a bone plays only the channel of its own mode.
"""

import hashlib
import json
import uuid

import numpy as np

from ..motion_patches.kinematics import foot_lock, loop_strips
from ..motion_patches.kinematics.rig_keys import (  # noqa: F401 (the adapter's names for them)
    body_keys,
    facing_angle,
    finer,
    in_units,
    inplace_channels,
    own_pieces,
    root_keys,
)
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
# On a shared action keyed one cycle long whose curves repeat (Cycles modifiers): the
# cycle's frames. A strip may play any cycle's worth of it from any frame of the cycle.
CYCLE_KEY = "motion_patches_cycle"
ACTIONS_KEY = "motion_patches_actions"  # object: {action id: name} of what planning made for it
ACTION_ID = "motion_patches_id"  # action: its id, kept by its character under ACTIONS_KEY
STASH_PREFIX = TRACK_PREFIX + "stash: "
# A piece played by more than one strip (a stretch of it by the shared loop action): its
# first strip has the piece's name, the others that name, this and "loop" or "body" and a
# number.
PART = " \u00b7 "


def check_rig(obj, skel, floor=0.0):
    """The :class:`~motion_patches.kinematics.retarget.RigMap` that puts the patch skeleton ``skel``
    on the armature ``obj`` (None: the armature holds that skeleton itself). Raises
    ValueError for an object that is no armature, is scaled unevenly (:func:`~.rig.world_scale`:
    any uniform scale plans; a tilted armature, an FBX import's Y-up bones under a 90
    degree X rotation, plans stood up, :func:`~.rig.world_tilt`), or whose bones cannot
    play the patch's hips, legs, feet and toes (naming those patch bones)."""
    if obj is None or obj.type != "ARMATURE":
        raise ValueError("the character must be an armature object")
    rig_io.world_scale(obj)
    return rig_io.rig_for(obj, skel, floor)


def drives_root(obj):
    """Whether the add-on's root track (unmuted) places ``obj``: its location and facing
    at any frame are then the plan's, not where the user put it."""
    ad = obj.animation_data
    names = json.loads(obj.get(TRACKS_KEY, "[]"))
    if ad is None or TRACK_ROOT not in names:
        return False
    track = ad.nla_tracks.get(TRACK_ROOT)
    return track is not None and not track.mute


def owned_actions(obj):
    """{action id: action name} of the actions planning made for ``obj``; None for a
    character planned before ids were kept."""
    raw = obj.get(ACTIONS_KEY)
    if raw is None:
        return None
    try:
        owned = json.loads(raw)
    except (TypeError, ValueError):
        return {}
    return owned if isinstance(owned, dict) else {}


def made_for(action, obj):
    """Whether planning made ``action`` for ``obj`` and may replace it: its id is one
    ``obj`` keeps, under the name it was made with. A user's copy (the id copied, another
    name) is the user's, and so is an action of the add-on the user renamed; a character
    renamed keeps its actions. Characters planned before ids were kept: the name tag."""
    if action is None:
        return False
    owned = owned_actions(obj)
    if owned is None:
        return action.get(CHARACTER_KEY) == obj.name
    return owned.get(action.get(ACTION_ID)) == action.name


def _claim_actions(obj, ad, tracks):
    """Give the character's own actions on ``tracks`` (not the shared segment actions) ids
    and keep them on ``obj``: what a later plan may replace."""
    made = {}
    for name in tracks:
        tr = ad.nla_tracks.get(name)
        for st in tr.strips if tr is not None else ():
            a = st.action
            if a is not None and a.get(SEGMENT_KEY) is None and a.get(ACTION_ID) is None:
                a[ACTION_ID] = uuid.uuid4().hex
                made[a[ACTION_ID]] = a.name
    obj[ACTIONS_KEY] = json.dumps(made)


def remove_owned(obj):
    """Remove the NLA tracks this add-on made on ``obj`` (and nothing else)."""
    ad = obj.animation_data
    names = json.loads(obj.get(TRACKS_KEY, "[]"))
    if ad is None:
        return
    for tr in list(ad.nla_tracks):
        if tr.name in names and tr.name.startswith(TRACK_PREFIX):
            ad.nla_tracks.remove(tr)


def _made_before(bpy, obj):
    """The actions planning made for ``obj`` (:func:`actions_made_for`), found while its
    tracks still play them (taken from its strips, not looked up by name); none for a
    character never planned (it has neither ids nor tracks of the add-on's)."""
    if owned_actions(obj) is None and TRACKS_KEY not in obj:
        return []
    return actions_made_for(bpy, obj)


def _remove_unused(bpy, actions):
    """Those of ``actions`` nothing uses any more (its tracks removed), removed."""
    for a in [a for a in actions if a.users == 0]:
        bpy.data.actions.remove(a)


def _played_by(obj):
    """{name: action} of the actions ``obj``'s NLA strips play."""
    ad = obj.animation_data
    out = {}
    for tr in ad.nla_tracks if ad is not None else ():
        for st in tr.strips:
            if st.action is not None:
                out.setdefault(st.action.name, st.action)
    return out


def actions_made_for(bpy, obj, tagged=None):
    """The actions planning made for ``obj`` (:func:`made_for`), found by the names it
    keeps: reading every action of the file for each character made a crowd's writes and
    snapshots quadratic (a snapshot of 1,000 planned characters: 5.4 s -> 0.16 s); those
    its strips play taken from them (Blender looks a name up through every action of the
    file: 1.4 s of a crowd of 1,000 planned again), the others by name. For a character
    planned before ids were kept, or never, by the name tag: ``tagged``
    (:func:`tagged_actions`, made once for many characters), else every action read."""
    owned = owned_actions(obj)
    if owned is not None:
        played = _played_by(obj)
        found = [
            played[name] if name in played else bpy.data.actions.get(name)
            for name in dict.fromkeys(owned.values())
        ]
    else:
        found = (tagged_actions(bpy) if tagged is None else tagged).get(obj.name, [])
    return [a for a in found if made_for(a, obj)]


def tagged_actions(bpy):
    """{character name: the actions with that name tag}, for :func:`actions_made_for`."""
    out = {}
    for a in bpy.data.actions:
        tag = a.get(CHARACTER_KEY)
        if isinstance(tag, str):
            out.setdefault(tag, []).append(a)
    return out


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


def segment_action(bpy, patch, patch_key, seg, skel, modes=None, rig=None, index=None, unit=1.0):
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
    many strips does not search every action of the file for each. ``unit``: the rig's
    world scale (:func:`~.rig.world_scale`), in which its root locations are keyed: rigs of
    another scale get their own actions. A segment whose motion is the straight loop's
    (:func:`~motion_patches.kinematics.loop_strips.loop_segments`) plays the shared loop
    action (:func:`loop_action`)."""
    if seg in loop_strips.loop_segments(patch):
        return loop_action(bpy, patch, patch_key, skel, modes, rig, index, unit)
    return _shared_action(
        bpy,
        patch,
        f"{patch_key}:{seg}",
        f"seg{seg:04d}",
        skel,
        modes,
        rig,
        index,
        unit,
        lambda: patch.motion(seg) if rig is None else rig.motion(patch.motion(seg)),
    )


def loop_action(bpy, patch, patch_key, skel, modes=None, rig=None, index=None, unit=1.0):
    """The shared in-place action of the gait's straight loop for a rig, created on first
    use and kept as :func:`segment_action` keeps a segment's (by patch, the rig's skeleton,
    rotation modes and scale): the stretches of characters' own pieces that play the loop
    frame by frame, and the straight segments, play it through repeating strips. It keys one
    cycle and a frame (:func:`~motion_patches.kinematics.loop_strips.one_cycle`), every
    curve repeating it (a Cycles modifier; :data:`CYCLE_KEY`), so a strip plays a cycle from
    any frame of it; one made before keys two cycles and a frame, which serves as well."""
    return _shared_action(
        bpy,
        patch,
        f"{patch_key}:loop",
        "loop",
        skel,
        modes,
        rig,
        index,
        unit,
        lambda: loop_strips.one_cycle(patch.gait, rig),
        cycle=int(patch.gait.straight.frames),
    )


def _shared_action(bpy, patch, base, label, skel, modes, rig, index, unit, motion_of, cycle=0):
    """The shared action keyed ``base`` (extended by the rig's skeleton, rotation modes and
    scale: :func:`segment_action`), named "MP <layer> ``label``" with the same marks,
    looked up in ``index`` (or the file) and made of ``motion_of()`` when missing; made with
    ``cycle``, its curves repeat that many frames (:func:`_inplace_action`). One found is
    played as it was made (a loop action made before keys two cycles, none repeating)."""
    sig = rotation_signature(skel, modes or {})
    rig_sig = rig.signature() if rig is not None else ""
    key = base + (f":rig-{rig_sig}" if rig_sig else "") + (f":{sig}" if sig else "")
    if unit != 1.0:
        key += f":unit-{unit:.6g}"
    found = (segment_index(bpy) if index is None else index).get(key)
    if found is not None:
        return found, compat.action_slot(found)
    name = (
        f"MP {patch.layer} {label}"
        + (f" rig-{rig_sig[:6]}" if rig_sig else "")
        + (f" {sig}" if sig else "")
        + (f" x{unit:.4g}" if unit != 1.0 else "")
    )
    action, slot = _inplace_action(
        name, skel, motion_of(), {SEGMENT_KEY: key}, modes, unit, cycle=cycle
    )
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


def _inplace_action(name, skel, motion, tags, modes=None, unit=1.0, tol=None, cycle=0):
    """A shared action of ``motion`` in place, keyed within ``tol`` (default the stored
    actions' :data:`~.actions.COMPACT`). ``cycle``: ``motion`` is one cycle and a frame,
    every curve of more than one point repeats it (a Cycles modifier), and the action is
    marked :data:`CYCLE_KEY`."""
    loc, rot = inplace_channels(skel, motion, unit)
    action, slot = compat.new_action(name)
    for k, v in tags.items():
        action[k] = v
    frames = np.arange(motion.frames, dtype=float)
    tol = act_io.COMPACT if tol is None else tol
    act_io.key_pose(
        action, slot, skel, frames, loc, rot, modes, tol=in_units(tol, unit), strip=True
    )
    if cycle:
        for fc in compat.fcurves(action, slot):
            if len(fc.keyframe_points) + len(fc.sampled_points) > 1:
                fc.modifiers.new("CYCLES")
        action[CYCLE_KEY] = int(cycle)
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
    segments=None,
    body=None,
    root=None,
    reads=None,
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
    play that patch's shared segment actions, on the one motion track. ``segments``:
    :func:`segment_index` of the file, kept up to date here (one for many writes).
    ``body``: :func:`body_keys` of this plan, fitted already (see :func:`own_pieces`,
    :func:`write_units`); ``root``: :func:`root_keys` of it, fitted already. ``reads``: a
    dict kept by the caller over many writes, in which the foot lock keeps the curves it
    reads of the shared (segment and loop) actions: a crowd reads them once. Each strip
    record (one per piece) lists the scene frames its piece's strips start on (``parts``:
    several where the loop action plays stretches of it)."""
    skel = rig.target if rig is not None else patch.gait.skeleton
    modes, unit = write_units(obj, skel)
    if bounds is None:
        bounds = np.concatenate(([0], np.cumsum([m.frames - 1 for m in motions])))
    bounds = np.asarray(bounds, int)
    ad = obj.animation_data or obj.animation_data_create()
    stashed = stash_active_action(obj)
    made = _made_before(bpy, obj)
    remove_owned(obj)
    _remove_unused(bpy, made)

    motion_track = ad.nla_tracks.new()
    motion_track.name = TRACK_MOTION
    strips, played = [], []
    first = int(frame_start)
    index = segment_index(bpy) if segments is None else segments
    own = own_pieces(plan)
    if own and body is None:
        loops = loop_strips.straight_loop(patch.gait, rig)
        body = body_keys(
            skel, world, locked, bounds, own, motions, modes, unit, act_io.COMPACT, loops
        )
    body = _body_action(obj, body) if own else None
    loop = None  # the shared loop action, looked up when a piece first plays it
    parts = []  # (piece, name, action, slot, first scene frame, last, action start, scale, cycle)
    for n, (piece, m) in enumerate(zip(plan.pieces, motions)):
        start, end = first + int(bounds[n]), first + int(bounds[n + 1])
        if piece.kind == "segment":
            layer_patch = getattr(piece, "patch", None) if layer_keys else None
            action, slot = segment_action(
                bpy,
                layer_patch or patch,
                layer_keys[layer_patch.layer] if layer_patch is not None else patch_key,
                piece.segment,
                skel,
                modes,
                rig,
                index,
                unit,
            )
            scale = (end - start) / float(max(m.frames - 1, 1))
            # a straight segment on the loop action keyed one cycle: its cycles repeated
            cycle = int(action.get(CYCLE_KEY, 0))
            at = 0.0 if cycle else None
            parts.append((n, f"{n:02d} {piece.label}", action, slot, start, end, at, scale, cycle))
        else:
            for i, (kind, a, b, at, scale) in enumerate(body[2][n]):
                name = f"{n:02d} {piece.label}" + (f"{PART}{kind} {i}" if i else "")
                if kind == "loop":
                    if loop is None:
                        loop = loop_action(bpy, patch, patch_key, skel, modes, rig, index, unit)
                    cycle = patch.gait.straight.frames
                    action, slot = loop
                    parts.append((n, name, action, slot, first + a, first + b, at, scale, cycle))
                else:
                    action, slot = body[0], body[1]
                    parts.append((n, name, action, slot, first + a, first + b, at, scale, 0))
        strips.append(
            {
                "name": f"{n:02d} {piece.label}",
                "start": start,
                "end": end,
                "action": action.name if piece.kind == "segment" else body[0].name,
                "kind": piece.kind,
                # where each of its strips starts (a stretch played by the loop: several)
                "parts": [p[4] for p in parts if p[0] == n],
            }
        )
    for i, (n, name, action, slot, start, end, at, scale, cycle) in enumerate(parts):
        played.append((action, slot, start - first, end - start + 1, scale, at, cycle))
        strip = motion_track.strips.new(name, start, action)
        compat.set_strip_slot(strip, slot)
        if at is not None:  # its own frames of the action (a loop's: one cycle, repeated)
            span = cycle if cycle else round((end - start) / scale)
            strip.action_frame_end = at + span
            strip.action_frame_start = at
        if abs(scale - 1.0) > 1e-9:
            _set_within(strip, "scale", scale, end)
        if cycle:
            _set_within(strip, "repeat", (end - start) / (cycle * float(strip.scale)), end)
        strip.extrapolation = (
            "HOLD" if i == 0 else ("HOLD_FORWARD" if i == len(parts) - 1 else "NOTHING")
        )
        strip.blend_in = strip.blend_out = 0.0

    root_action, root_slot = compat.new_action(f"MP {obj.name} root")
    root_action[CHARACTER_KEY] = obj.name
    if root is None:
        root = root_keys(skel, world, root_units(obj), act_io.COMPACT)
    # on the scene's frames, its strip unscaled: nothing plays between them
    act_io.key_curves(
        root_action,
        root_slot,
        root["frames"],
        root["curves"],
        finer(act_io.COMPACT),
        between=False,
        fitted=root["fitted"],
    )
    root_track = ad.nla_tracks.new()
    root_track.name = TRACK_ROOT
    rs = root_track.strips.new(f"{obj.name} root", first, root_action)
    compat.set_strip_slot(rs, root_slot)
    rs.extrapolation = "HOLD"
    rs.blend_in = rs.blend_out = 0.0
    owned = [TRACK_MOTION, TRACK_ROOT]
    if locked is not None:
        write_foot_lock(
            obj,
            foot_lock_curves(obj, skel, world, locked, frame_start, modes, played, body, reads),
        )
        owned.append(TRACK_FOOT)
    obj[TRACKS_KEY] = json.dumps(owned)
    _claim_actions(obj, ad, owned)
    return strips, stashed


def _set_within(strip, prop, value, end):
    """Set ``strip``'s ``prop`` ("scale", or "repeat": a fraction too, a loop strip ends
    mid-cycle) to ``value``, kept from ending after scene frame ``end``: Blender keeps it in
    single precision, and rounded up the strip would end a hair after the next one starts,
    which then could not be added."""
    single = np.float32(value)
    setattr(strip, prop, float(single))
    while strip.frame_end > end:
        single = np.nextafter(single, np.float32(0.0))
        setattr(strip, prop, float(single))


def root_units(obj):
    """(height, rotation mode, tilt or None) of the armature object ``obj``: what
    :func:`root_keys` needs from Blender, read before the fit."""
    return float(obj.location[2]), obj.rotation_mode, rig_io.world_tilt(obj)


def write_units(obj, skel):
    """(rotation modes, world scale) of the armature ``obj`` playing ``skel``: what
    :func:`body_keys` needs from Blender, read before the fit."""
    return rig_rotation_modes(obj, skel), rig_io.world_scale(obj)


def _body_action(obj, keys):
    """One action of the character's own pieces (connectors, turns, clips: the pieces no
    other character plays), keyed as :func:`body_keys` fitted them: one set of curves
    serves them all (an F-curve costs a few hundred bytes before any key), piece after
    piece, each strip playing its own frames. A quaternion's component holding its rest
    value throughout (held at 1, or 0) is left out: the strip plays it there
    (``key_curves``' ``left_out``).
    Returns (action, slot, {piece: (first action frame, strip scale, frames)}, whether keyed
    at the scene's rate)."""
    action, slot = compat.new_action(f"MP {obj.name} body")
    action[CHARACTER_KEY] = obj.name
    act_io.key_curves(
        action,
        slot,
        keys["frames"],
        keys["curves"],
        keys["tol"],
        values=keys["values"],
        rotations=keys["rotations"],
        between=keys["between"],
        fitted=keys["fitted"],
        left_out=act_io.rest_values(keys["curves"]),
    )
    return action, slot, keys["ranges"], keys["scene_keys"]


def _played_frames(played, n_frames):
    """Which strip plays each plan frame and the action frame it plays there: ``played`` =
    [(action, slot, first plan frame, scene frames it spans, strip scale, first action
    frame or None: the action's own start, frames of the cycle it repeats or 0)] in track
    order; where two strips meet on a frame the earlier one plays (Blender takes the first
    strip whose range holds the frame). A scaled strip plays action frame
    ``first + (frame - start) / scale``, a repeating one that within its cycle (Blender's
    ``fmod``). Returns {(action, slot): (plan frames, action frames)},
    the frames of every strip of one action together, so each channel is read once per
    action (a plan plays one segment action on many strips)."""
    owner = np.full(n_frames, -1)
    at = np.zeros(n_frames)
    for s, (action, _, start, frames, scale, first, *cycle) in enumerate(played):
        idx = np.arange(start, min(start + frames, n_frames))
        idx = idx[owner[idx] < 0]
        owner[idx] = s
        if cycle and cycle[0]:
            at[idx] = np.fmod(idx - start, cycle[0] * scale) / scale + first
            if action.get(CYCLE_KEY):  # one cycle keyed, repeating: what it plays there
                at[idx] = np.mod(at[idx], cycle[0])
        else:
            at[idx] = (idx - start) / scale + (first or 0)
    keys = {}  # (action, slot) -> its number, in the order strips first play them
    which = np.array([keys.setdefault((a, sl), len(keys)) for a, sl, *_ in played] + [-1])
    playing = which[owner]  # the action on each frame (-1: none; owner -1 picks the last)
    out = {}
    for key, n in keys.items():
        idx = np.flatnonzero(playing == n)
        out[key] = (idx, at[idx])
    return out


def _lower_channels(frames_of, bones, mode, n_frames, cache=None, reads=None):
    """What the motion track gives the ``mode`` channels of ``bones`` on each plan frame
    (F, K, C), read from the keys of its strips' actions (``frames_of``:
    :func:`_played_frames`), between keys linearly; the rest value on frames no strip
    plays. ``cache``: the curves read of this character's actions; ``reads``: those of the
    shared actions (:func:`write_plan`), else in ``cache`` too."""
    out = np.empty((n_frames, len(bones), act_io.rest_channels(mode).size))
    out[:] = act_io.rest_channels(mode)
    for (action, slot), (idx, at) in frames_of.items():
        shared = reads is not None and action.get(SEGMENT_KEY) is not None
        out[idx] = act_io.read_bones(action, slot, bones, mode, at, reads if shared else cache)
    return out


def foot_lock_curves(
    obj, skel, world, locked, frame_start, modes=None, played=(), body=None, reads=None
):
    """The foot lock's curves (frames, curves, values, first frame), to be written as an Add
    strip above the motion (:func:`write_foot_lock`), so segment actions stay shared.

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
    its delta is exactly zero (the motion plays unchanged; the curve stays compact), and so
    on the frames the character's ``body`` action plays (:func:`_body_action`: it holds the
    locked rotations itself). ``reads``: the curves of shared actions read so far (see
    :func:`write_plan`; a shared action is never changed once made)."""
    modes = modes or {}
    # of the bones the lock may turn (the legs), those it turned, and on which frames
    legs = foot_lock.locked_bones(skel)
    dots = np.einsum("fjc,fjc->fj", world.rotations[:, legs], locked[:, legs])
    moved = np.abs(np.abs(dots) - 1.0) > 1e-9  # (F, legs)
    frames_of = _played_frames(played, world.frames)
    if body is not None and body[3] and (body[0], body[1]) in frames_of:
        moved[frames_of.pop((body[0], body[1]))[0]] = False
    turned = moved.any(axis=0)
    changed, moved = legs[turned], moved[:, turned]
    frames = np.arange(world.frames, dtype=float)
    cache, curves, columns = {}, [], []
    by_mode = {}
    for k, j in enumerate(changed):
        by_mode.setdefault(modes.get(skel.names[j], "QUATERNION"), []).append(k)
    for mode, ks in by_mode.items():  # the bones of one rotation mode at once
        names = [skel.names[changed[k]] for k in ks]
        lower = _lower_channels(frames_of, names, mode, world.frames, cache, reads)
        delta = act_io.matching_channels(locked[:, changed[ks]], mode, lower) - lower
        delta[~moved[:, ks]] = 0.0
        path = act_io.rotation_path(mode)
        columns.append(delta.reshape(world.frames, -1))  # bone by bone, channels in order
        curves += [
            (f'pose.bones["{name}"].{path}', c, name, None)
            for name in names
            for c in range(delta.shape[-1])
        ]
    values = np.concatenate(columns, axis=1) if columns else None
    return frames, curves, values, int(frame_start)


LOCK_GAP = 2  # frames the lock leaves alone that still go in one strip with those round them


def lock_spans(values, frames):
    """[(first, last)] of the plan frames the foot lock's strips play: the runs of frames
    where it changes something (``values`` (F, C), the deltas; exactly 0 elsewhere: frames
    its character's body action plays locked already), runs closer than :data:`LOCK_GAP`
    joined, each at least two frames long. A curve kept as samples holds every frame it
    spans: one strip over a whole plan kept the legs' deltas on every frame of it."""
    if values is None or not np.any(values):
        return [(0, frames - 1)]
    idx = np.flatnonzero(np.any(values != 0.0, axis=1))
    cut = np.flatnonzero(np.diff(idx) > LOCK_GAP + 1)
    firsts, lasts = idx[np.r_[0, cut + 1]], idx[np.r_[cut, idx.size - 1]]
    out = []
    for a, b in zip(firsts.tolist(), lasts.tolist()):
        if b == a:  # a strip needs two frames
            a, b = (a, a + 1) if a + 1 < frames else (a - 1, a)
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], b)
        else:
            out.append((a, b))
    return out


def write_foot_lock(obj, lock):
    """The foot lock :func:`foot_lock_curves` made, as Add strips on a track above the
    character's others (its keys fitted finer than the body's: :func:`finer`), one over
    each stretch of frames it changes (:func:`lock_spans`)."""
    frames, curves, values, frame_start = lock
    spans = lock_spans(values, len(frames))
    rows = np.concatenate([np.arange(a, b + 1) for a, b in spans])
    action, slot = compat.new_action(f"MP {obj.name} foot lock")
    action[CHARACTER_KEY] = obj.name
    act_io.key_curves(
        action,
        slot,
        np.arange(rows.size, dtype=float),
        curves,
        finer(act_io.COMPACT),
        values=None if values is None else values[rows],
        between=False,
        left_out=np.zeros(len(curves)),  # a bone's zero delta adds nothing
        blend="ADD",
    )
    track = obj.animation_data.nla_tracks.new()
    track.name = TRACK_FOOT
    at = 0
    for i, (a, b) in enumerate(spans):
        name = f"{obj.name} foot lock" + (f" {i}" if i else "")
        strip = track.strips.new(name, int(frame_start) + a, action)
        compat.set_strip_slot(strip, slot)
        if len(spans) > 1:  # its own rows of the action
            strip.action_frame_end = at + b - a
            strip.action_frame_start = at
        at += b - a + 1
        strip.blend_type = "ADD"
        # Between its strips the lock must change nothing: a strip holding its last frame
        # would go on adding it until the next one.
        if spans == [(0, len(frames) - 1)]:
            strip.extrapolation = "HOLD"
        elif i == len(spans) - 1 and b == len(frames) - 1:
            strip.extrapolation = "HOLD_FORWARD"
        else:
            strip.extrapolation = "NOTHING"
        strip.blend_in = strip.blend_out = 0.0
