# SPDX-License-Identifier: GPL-3.0-or-later
"""The keys a planned character's rig plays, fitted without Blender: its body action (the
pieces only it plays), its root action (the ground track and heading) and its foot lock.
Blender's data is read before (rotation modes, scale, height: the ``units``) and written
after, by the adapter; in between the work is pure numpy, so a crowd fits its characters'
keys on the cluster's workers while Blender writes the ones before."""

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from . import foot_lock, loop_strips, quat
from .channels import closest_channels, rest_channels, rotation_path
from .inplace import rest_facing, root_channel_to_ground
from .motion import Motion
from .pose_keys import Tolerance, fit_curves, pose_curves
from .skeleton import Skeleton, per_skeleton, root_position_to_location


@per_skeleton
def facing_angle(skel: Skeleton) -> float:
    """The rig's rest facing as an angle from +X (every action and root track of a write
    turns by it)."""
    f = rest_facing(skel)
    return float(np.arctan2(f[1], f[0]))


def inplace_channels(
    skel: Skeleton, motion: Motion, unit: float = 1.0
) -> tuple[np.ndarray, np.ndarray]:
    """Root location channels (F, 3) and rotations (F, J, 4) for an object whose Z rotation
    is the ground heading minus the rig's rest facing. ``unit``: the armature's world
    scale (the adapter's ``rig.world_scale``; ``skel`` and ``motion`` are in metres, the root's
    location channel in the armature's own units, so it is divided by it).

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
    loc = root_position_to_location(skel, local)
    if unit != 1.0:
        loc = loc / unit
    return loc, quat.make_continuous(rot, axis=0)


def root_keys(skel: Skeleton, world: Motion, units: tuple, tol: Any) -> dict:
    """The keys of a character's root action (its object's location and turn over the
    plan's ``world`` motion, on the scene's frames) fitted, touching no Blender data (a
    crowd fits the next characters' while one is written): {"frames", "curves",
    "fitted"}. ``units``: the adapter's ``nla.root_units`` of the character."""
    z0, rotation_mode, tilt = units
    heading = np.unwrap(world.ground[:, 2]) - facing_angle(skel)
    frames = np.arange(world.frames, dtype=float)
    curves = [
        ("location", i, "Object Transforms", v)
        for i, v in enumerate((world.ground[:, 0], world.ground[:, 1], np.full(world.frames, z0)))
    ]
    # A turn about Z only: (0, 0, heading) is that turn in every Euler order, (heading, +Z)
    # in axis-angle; the heading is unwrapped, so no channel jumps by a turn.
    zero = np.zeros(world.frames)
    rot_values: Any
    if tilt is not None:  # the turn over the armature's own tilt
        rot_path, rot_values = tilted_rotation(rotation_mode, heading, tilt)
    elif rotation_mode == "QUATERNION":
        q = quat.make_continuous(quat.about_z(heading), axis=0)
        rot_path, rot_values = "rotation_quaternion", q.T
    elif rotation_mode == "AXIS_ANGLE":
        rot_path, rot_values = "rotation_axis_angle", (heading, zero, zero, zero + 1.0)
    else:
        rot_path, rot_values = "rotation_euler", (zero, zero, heading)
    curves += [(rot_path, i, "Object Transforms", v) for i, v in enumerate(rot_values)]
    tol = finer(tol)
    return {
        "frames": frames,
        "curves": curves,
        "fitted": fit_curves(frames, curves, tol, between=False),
    }


def tilted_rotation(mode: str, heading: np.ndarray, tilt: np.ndarray) -> tuple[str, np.ndarray]:
    """(property, channel rows) of the object rotation ``Rz(heading) @ tilt`` per frame in
    rotation ``mode``, each frame's channels the ones nearest the frame before (no jump by a
    turn; the first nearest the tilt's own)."""
    q = quat.mul(quat.about_z(heading), quat.from_matrix(tilt)[None])
    q = quat.make_continuous(q, axis=0)
    if mode == "QUATERNION":
        return "rotation_quaternion", q.T
    out = np.empty((len(q), rest_channels(mode).size))
    prev = closest_channels(q[:1], mode, rest_channels(mode)[None])[0]
    for f in range(len(q)):
        prev = out[f] = closest_channels(q[f : f + 1], mode, prev[None])[0]
    return rotation_path(mode), out.T


def in_units(tol: Any, unit: float) -> Any:
    """``tol`` for locations keyed in the armature's units (``unit`` metres each): its
    length, in metres, divided by it, so a centimetre rig is held as a metre rig is."""
    if isinstance(tol, Tolerance) and unit != 1.0:
        return Tolerance(tol.angle, tol.length / unit, tol.steady)
    return tol


def own_pieces(plan: Any) -> list[int]:
    """The pieces of ``plan`` only its character plays (all but segments): its body action's."""
    return [n for n, p in enumerate(plan.pieces) if p.kind != "segment"]


def body_keys(
    skel: Skeleton,
    world: Motion,
    locked: np.ndarray | None,
    bounds: np.ndarray,
    own: Sequence[int],
    motions: Sequence[Motion],
    modes: Mapping[str, str],
    unit: float,
    tol: Any,
    loop: Motion | None = None,
) -> dict:
    """The keys of a character's body action (the adapter's ``nla._body_action``) fitted,
    touching no Blender data (a crowd fits the next characters' while one is written): {"frames",
    "curves", "values", "tol", "rotations", "between", "fitted", "ranges", "scene_keys"}.

    Keyed at the scene's rate (up to :data:`~.loop_strips.SCENE_KEYS_UP_TO` times the
    patch's) from ``world`` with the feet already locked (``locked``; these frames then
    need no foot-lock correction, and no scaled strip plays keys between frames); above it
    from the pieces' own ``motions`` at the patch's, their strips scaled as segments' are.
    Keyed at the scene's rate, the stretches of a piece that play ``loop`` (the gait's
    :func:`~.loop_strips.straight_loop` on this rig; ``world`` plays it there,
    :func:`~.scene_rate.placed`) are left to a shared loop action.
    ``ranges``: {piece: [(kind "body" or "loop", first scene frame, last scene frame, first
    action frame, strip scale)]}: the strips the piece is played by, in order."""
    scene_keys = loop_strips.keyed_on_scene_frames(motions, bounds, own)
    parts = loop_strips.played_parts(motions, bounds, own, loop)
    ranges: dict[int, list] = {}
    at = 0
    if scene_keys:
        rot = world.rotations if locked is None else locked
        pose = Motion(world.ground, world.root_local, rot, world.contacts)
        loc, rot = inplace_channels(skel, pose, unit)
        rows = []
        for n in own:
            ranges[n] = []
            for kind, a, b, first, scale in parts[n]:
                if kind == "body":
                    rows.append(np.arange(a, b + 1))
                    ranges[n].append((kind, a, b, float(at), 1.0))
                    at += b - a + 1
                else:
                    ranges[n].append((kind, a, b, first, scale))
        loc = np.concatenate([loc[r] for r in rows])
        rot = np.concatenate([rot[r] for r in rows])
    else:
        chans = [inplace_channels(skel, motions[n], unit) for n in own]
        loc = np.concatenate([c[0] for c in chans])
        rot = np.concatenate([c[1] for c in chans])
        for n, c in zip(own, chans):
            lo, hi = int(bounds[n]), int(bounds[n + 1])
            ranges[n] = [("body", lo, hi, float(at), (hi - lo) / float(max(len(c[0]) - 1, 1)))]
            at += len(c[0])
    frames = np.arange(len(loc), dtype=float)
    rot = quat.make_continuous(rot, axis=0)
    # keyed on the scene's frames, its strips unscaled play nothing between them
    between = not scene_keys
    curves, values, tol, groups = pose_curves(skel, loc, rot, modes, in_units(tol, unit), between)
    return {
        "frames": frames,
        "curves": curves,
        "values": values,
        "tol": tol,
        "rotations": groups,
        "between": between,
        "fitted": fit_curves(frames, curves, tol, values, groups, between),
        "ranges": ranges,
        "scene_keys": scene_keys,
    }


FINER = 16.0  # the root's and foot lock's angle tolerance is this much finer (lengths: 4)


# How much the root's and foot lock's error may change from one scene frame to the next, as
# a fraction of their tolerance: a planted foot moves with it. Any change within the
# tolerance made planted feet slide 3.13 cm/s in a 60 fps scene, 2.35 with half of it (2.34
# with the keys before their slopes were fitted; bench_files' crowd of three at 30/60).
STEADY = 0.5


def finer(tol: Any) -> Any:
    """A finer ``tol`` for the root and foot-lock curves: each of their channels is judged
    alone (a quaternion turns by up to four component errors), the heading turns the whole
    body, the ground track carries a planted foot with the hips and the foot lock holds it
    (at a quarter of the angle the feet drifted 2 mm from the plan; at a sixteenth 0.5 mm,
    bench_files), and steady from frame to frame (:data:`STEADY`); few curves."""
    if isinstance(tol, Tolerance):
        return Tolerance(tol.angle / FINER, tol.length / 4.0, STEADY)
    return tol


def prepare(
    skel: Skeleton,
    placed: tuple,
    locks: bool,
    fps: float,
    plan: Any,
    units: tuple,
    root_units: tuple,
    tol: Any,
    *,
    loop: Motion | None = None,
) -> tuple:
    """What writing a plan computes before it touches Blender (a crowd makes the next
    characters' while one is written, on the cluster's workers when it has some): (the
    motion on the scene's frames with the contacts that hold, its rotations with the feet
    locked or None, the body action's fitted keys, :func:`body_keys`, or None; the root
    action's, :func:`root_keys`). ``placed``: (piece motions, bounds, the whole motion on
    the scene's frames); ``locks``: pin the planted feet; ``fps``: the scene's rate;
    ``units`` (rotation modes, world scale), ``root_units`` (height, rotation mode, tilt):
    read from the character; ``tol``: what the actions are stored within; ``loop``: the
    gait's straight loop on this rig (:func:`~.loop_strips.straight_loop`), whose stretches
    a shared loop action plays (None: every own frame in the body action)."""
    motions, bounds, world = placed
    # Feet moving fast while labelled planted (through a blend) are not planted: neither
    # pinned nor measured as skating (foot_lock.still_contacts). Both read the motion as
    # the character plays it: on its own rig (``skel``), at the scene's rate.
    posed = foot_lock.pose_legs(skel, world)
    world = Motion(
        world.ground,
        world.root_local,
        world.rotations,
        foot_lock.still_contacts(skel, world, fps, posed),
    )
    locked = foot_lock.lock_feet(skel, world, posed=posed, fps=fps) if locks else None
    own = own_pieces(plan)
    modes, unit = units
    body = (
        body_keys(skel, world, locked, bounds, own, motions, modes, unit, tol, loop)
        if own
        else None
    )
    return world, locked, body, root_keys(skel, world, root_units, tol)


def prepare_packed(*args: Any, loop: Motion | None = None) -> tuple:
    """:func:`prepare` as a worker sends it back: :func:`pack` of it."""
    return pack(prepare(*args, loop=loop), args[0])


def pack(prepared: tuple, skel: Skeleton) -> tuple:
    """:func:`prepare`'s answer ``prepared`` as a worker sends it back (:func:`unpack`):
    what the writer has already (the motion's rotations, the bones the lock leaves alone,
    what the keys leave between them) left out: about a third of the bytes."""
    world, locked, body, root = prepared
    legs = None if locked is None else locked[:, foot_lock.locked_bones(skel)]
    if body is not None:
        fit = body["fitted"]
        if fit is not None:
            keep = fit["keep"]
            kept = {k: fit[k][keep] for k in ("values", "slopes", "slopes_in")}
            # with fitted keys the values are only read as Blender stores them (a curve kept
            # as samples), so single precision loses nothing
            values = np.asarray(body["values"], np.float32)
            body = {**body, "values": values, "fitted": {**fit, **kept, "sparse": True}}
    return world.contacts, legs, body, root


def unpack(packed: tuple, skel: Skeleton, world: Motion) -> tuple:
    """:func:`prepare`'s answer from :func:`pack`'s, given the motion ``world``
    it was prepared from: the same arrays wherever the writer reads them (the lock's legs,
    the keys' kept frames)."""
    contacts, legs, body, root = packed
    world = Motion(world.ground, world.root_local, world.rotations, contacts)
    locked = None
    if legs is not None:
        locked = world.rotations.copy()
        locked[:, foot_lock.locked_bones(skel)] = legs
    if body is not None and body["fitted"] is not None and body["fitted"].get("sparse"):
        fit = dict(body["fitted"])
        keep = fit.pop("sparse") and fit["keep"]
        for k in ("values", "slopes", "slopes_in"):
            full = np.zeros(keep.shape)
            full[keep] = fit[k]
            fit[k] = full
        body = {**body, "values": np.asarray(body["values"], float), "fitted": fit}
    return world, locked, body, root
