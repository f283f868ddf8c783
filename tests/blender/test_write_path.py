# SPDX-License-Identifier: GPL-3.0-or-later
"""The fast write path plays what the plain one did: continuous channels without a loop
over frames, F-curves keyed in bulk, the foot lock's reading of the strips below it."""

import numpy as np
import pytest


def sequential_channels(act_io, q, mode, first=None):
    """rotation_channels frame by frame: each frame the representation nearest the last."""
    rest = act_io.rest_channels(mode)
    prev = np.broadcast_to(rest if first is None else first, q.shape[1:-1] + rest.shape)
    out = np.empty(q.shape[:-1] + rest.shape)
    for f in range(q.shape[0]):
        prev = out[f] = act_io.closest_channels(q[f], mode, prev)
    return out


def walks(quat, rng):
    """Rotation sequences (F, J, 4): slow, fast and wild random walks with random signs,
    one bone through gimbal lock in every Euler order, one resting (no axis) for a while."""
    out = []
    for speed in (0.01, 0.2, 1.0):
        w = np.cumsum(rng.normal(size=(150, 6, 3)) * speed, axis=0)
        out.append(quat.exp(w) * np.where(rng.random((150, 6, 1)) < 0.3, -1.0, 1.0))
    t = np.linspace(-1.0, 1.0, 80)[:, None]
    near = np.pi / 2 + 0.3 * t  # middle angle sweeping through 90 degrees
    axes = np.zeros((80, 3, 3))
    axes[:, 0, 0] = axes[:, 1, 1] = axes[:, 2, 2] = 1.0
    lock = quat.exp(axes * near[:, None] + 0.2 * t[:, None])  # about X, Y, Z (+ a drift)
    rest = np.zeros((80, 1, 4))
    rest[:, 0, 0] = 1.0
    rest[40:, 0] = quat.exp(np.array([0.3, -0.2, 0.1]) * t[40:])
    out.append(np.concatenate((lock, rest), axis=1))
    return out


@pytest.mark.parametrize("mode", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX", "AXIS_ANGLE"])
def test_channels_match_the_frame_by_frame_choice(addon_module, mode):
    act_io = addon_module.adapter.actions
    quat = addon_module.motion_patches.kinematics.quat
    rng = np.random.default_rng(sum(map(ord, mode)))
    for q in walks(quat, rng):
        for first in (None, "random"):
            if first is not None:  # a first value some turns away, in this mode
                size = (q.shape[1], act_io.rest_channels(mode).size)
                start = quat.exp(rng.normal(size=(q.shape[1], 3)))
                first = act_io.closest_channels(start, mode, np.zeros(size))
                first = first + 2 * np.pi * rng.integers(-2, 3, size=size)
            want = sequential_channels(act_io, q, mode, first)
            got = act_io.rotation_channels(q, mode, first)
            assert np.allclose(got, want, atol=1e-9), np.abs(got - want).max()


def test_a_half_turn_jump_stays_within_half_a_turn(addon_module):
    """A rotation that jumps by exactly half a turn is as near one way as the other (the
    two versions may pick either): every frame is within half a turn of the last."""
    act_io = addon_module.adapter.actions
    q = np.zeros((20, 1, 4))
    q[:, 0, 0] = 1.0
    q[10:, 0] = [0.0, 0.0, 0.0, 1.0]  # half a turn about Z
    for mode in act_io.EULER_ORDERS:
        e = act_io.rotation_channels(q, mode, np.full((1, 3), 2 * np.pi))
        assert np.all(np.abs(np.diff(e, axis=0)) <= np.pi + 1e-9)
        back = act_io.channels_to_quat(e, mode)
        assert np.allclose(np.abs(np.sum(back * q, axis=-1)), 1.0)


def test_curves_keyed_in_bulk_play_their_values(addon_module, clean_scene):
    """Every way a curve is stored (one key, linear keys, samples; and all keys on
    frames that are not whole) plays the values on every frame, to float32 and the
    compact tolerance; curves of one bone share its group."""
    act_io = addon_module.adapter.actions
    compat = addon_module.adapter.compat
    keys = addon_module.motion_patches.kinematics.keys
    t = np.arange(120.0)
    rng = np.random.default_rng(3)
    values = {
        ("location", 0): np.full(t.size, 0.25),  # constant
        ("location", 1): np.where(t < 60, 0.0, (t - 60) * 0.01),  # a kink: keys
        ("location", 2): np.cumsum(rng.normal(size=t.size)) * 1e-2,  # noise: samples
    }
    curves = [(p, i, "Bone", v) for (p, i), v in values.items()]
    plans = keys.plan_columns(np.column_stack(list(values.values())), act_io.LINEAR_TOL)
    assert [h for h, _ in plans] == ["constant", "keys", "samples"]
    for frames in (t, t * 0.5 + 0.25):  # the second: not whole frames, every value keyed
        action, slot = compat.new_action("bulk")
        fcs = act_io.key_curves(action, slot, frames, curves, act_io.LINEAR_TOL)
        for fc, (p, i, _, v) in zip(fcs, curves):
            assert (fc.data_path, fc.array_index, fc.group.name) == (p, i, "Bone")
            played = np.array([fc.evaluate(f) for f in frames])
            assert np.allclose(played, v, atol=act_io.LINEAR_TOL + 1e-6)
        sampled = [len(fc.keyframe_points) == 0 for fc in fcs]
        assert sampled == ([False, False, True] if frames is t else [False] * 3)
        if frames is t:
            assert [len(fc.keyframe_points) for fc in fcs[:2]] == [1, plans[1][1].size]
            co = act_io.curve_points(fcs[2])
            assert np.array_equal(co[:, 1], values[("location", 2)].astype(np.float32))
        else:  # no samples off whole frames: the noise keyed on every frame
            counts = [len(fc.keyframe_points) for fc in fcs]
            assert counts == [1, plans[1][1].size, t.size]
            assert {k.interpolation for fc in fcs for k in fc.keyframe_points} == {"LINEAR"}


def test_the_foot_lock_reads_the_strip_that_plays_each_frame(addon_module, clean_scene):
    """Where two strips meet on a frame the earlier plays; a scaled strip plays its action
    at (frame - start) / scale; a strip of part of an action (a character's body action)
    from its first action frame on; frames no strip plays keep the rest value; one action
    played by several strips is read on all their frames."""
    import bpy

    act_io = addon_module.adapter.actions
    compat = addon_module.adapter.compat
    nla = addon_module.adapter.nla
    path = 'pose.bones["Bone"].rotation_quaternion'
    made = {}
    for name, ramp in (("a", 1.0), ("b", -1.0)):
        action, slot = compat.new_action(name)
        curves = [(path, i, "Bone", ramp * np.arange(11.0) + 10 * i) for i in range(4)]
        act_io.key_curves(action, slot, np.arange(11.0), curves)
        made[name] = (action, slot)
    a, b = made["a"], made["b"]
    # plan frames: a on 0..10, b on 10..20 (scale 2: action frames 0..5), a again 20..30
    # from its action frame 3 on (action frames 3..10, then nothing)
    played = [(*a, 0, 11, 1.0, None), (*b, 10, 11, 2.0, None), (*a, 20, 11, 1.0, 3)]
    n = 35
    frames_of = nla._played_frames(played, n)
    assert set(frames_of) == {a, b}
    out = nla._lower_channels(frames_of, ["Bone"], "QUATERNION", n, {})[:, 0]
    want = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    f = np.arange(n)
    on_a = f <= 10
    want[on_a] = f[on_a, None] + 10 * np.arange(4)  # frame 10 is a's (the earlier strip)
    on_b = (f > 10) & (f <= 20)  # frame 20 is b's too
    want[on_b] = -(f[on_b, None] - 10) / 2.0 + 10 * np.arange(4)
    on_a2 = (f > 20) & (f <= 30)
    want[on_a2] = np.minimum(f[on_a2, None] - 20 + 3, 10) + 10 * np.arange(4)
    assert np.allclose(out, want), np.argwhere(~np.isclose(out, want))[:5]
    assert len(bpy.data.actions) >= 2


def test_inplace_channels_are_the_round_trip_through_the_world(addon_module, mocap_dir):
    """The in-place channels for the object turned by the rig's facing equal putting the
    motion in the world (to_world) and taking it back against the object's headings
    (to_inplace), as they were computed before."""
    import importlib

    name = addon_module.__name__ + ".motion_patches.kinematics."
    mp = {m: importlib.import_module(name + m) for m in ("bvh", "motion", "inplace", "clip")}
    skeleton = importlib.import_module(name + "skeleton")
    nla = addon_module.adapter.nla
    clip = mp["bvh"].read(mocap_dir / "cmu" / "16_15.bvh")
    skel = clip.skeleton
    rng = np.random.default_rng(7)
    n = 90
    ground = np.column_stack(
        (rng.normal(size=n).cumsum(), rng.normal(size=n).cumsum(), rng.normal(size=n).cumsum())
    )
    motion = mp["motion"].Motion(
        ground, rng.normal(size=(n, 3)), clip.rotations[:n], np.zeros((n, 4), bool)
    )
    loc, rot = nla.inplace_channels(skel, motion)
    pos, world_rot = mp["inplace"].to_world(skel, ground, motion.root_local, motion.rotations)
    obj_ground = ground.copy()
    obj_ground[:, 2] -= nla.facing_angle(skel)
    local, want_rot = mp["inplace"].to_inplace(
        mp["clip"].Clip("round trip", skel, 1.0, pos, world_rot), obj_ground
    )
    assert abs(nla.facing_angle(skel)) > 0.1  # the turn matters for this rig
    assert np.allclose(loc, skeleton.root_position_to_location(skel, local), atol=1e-9)
    assert np.allclose(rot, want_rot, atol=1e-9)


def test_the_plan_range_is_read_from_the_records_head(addon_module, clean_scene):
    """plan_range (what fitting the frame range reads of every character) gives the
    record's own frame range, from a record as store_plan writes it (range first, the
    arrays stored uncompressed) and from one written before (meta and compressed arrays
    only); the rest of the record loads as it was stored."""
    import base64
    import io
    import json

    import bpy

    storage = addon_module.adapter.storage
    ob = bpy.data.objects.new("Walker", None)
    clean_scene.collection.objects.link(ob)
    with pytest.raises(ValueError, match="no planned motion"):
        storage.plan_range(ob)
    ground = np.arange(12.0).reshape(4, 3)
    meta = {"frame_start": 7, "frame_end": 10, "obstacles": {"Box": [[0.0, 0.0], [1.0, 0.5]]}}
    storage.store_plan(ob, dict(meta, ground=ground))
    assert ob[storage.PLAN_KEY].startswith('{"range": [7, 10]')
    assert storage.plan_range(ob) == (7, 10)
    got_meta, arrays = storage.load_plan(ob)
    assert got_meta == meta and np.array_equal(arrays["ground"], ground)
    buf = io.BytesIO()
    np.savez_compressed(buf, ground=ground)
    old = {"frame_start": 3, "frame_end": 90, "obstacles": {}}
    ob[storage.PLAN_KEY] = json.dumps(
        {"meta": old, "arrays": base64.b64encode(buf.getvalue()).decode()}
    )
    assert storage.plan_range(ob) == (3, 90)
    assert np.array_equal(storage.load_plan(ob)[1]["ground"], ground)


def test_a_records_fingerprint_is_kept_beside_it(addon_module, clean_scene):
    """The overlay asks every redraw whether a plan changed: store_plan keeps the record's
    fingerprint beside it (16 characters to read, not the record), equal to the one made
    from the record itself, so records of older versions (none kept) compare alike; a
    record gone is "" whatever is left beside it."""
    import hashlib
    import json

    import bpy

    storage = addon_module.adapter.storage
    ob = bpy.data.objects.new("Walker", None)
    clean_scene.collection.objects.link(ob)
    assert storage.plan_fingerprint(ob) == ""
    storage.store_plan(ob, {"frame_start": 1, "frame_end": 9, "ground": np.ones((3, 3))})
    made = hashlib.sha1(ob[storage.PLAN_KEY].encode()).hexdigest()[:16]
    assert ob[storage.PLAN_ID_KEY] == made == storage.plan_fingerprint(ob)
    storage.store_plan(ob, {"frame_start": 1, "frame_end": 12, "ground": np.ones((3, 3))})
    assert storage.plan_fingerprint(ob) not in ("", made)
    ob[storage.PLAN_ID_KEY] = "kept"  # read, not made again from the record
    assert storage.plan_fingerprint(ob) == "kept"
    del ob[storage.PLAN_ID_KEY]  # a record an older version wrote
    raw = json.dumps({"meta": {"frame_start": 2, "frame_end": 5}, "arrays": ""})
    ob[storage.PLAN_KEY] = raw
    assert storage.plan_fingerprint(ob) == hashlib.sha1(raw.encode()).hexdigest()[:16]
    ob[storage.PLAN_ID_KEY] = "left"
    del ob[storage.PLAN_KEY]
    assert storage.plan_fingerprint(ob) == ""


def test_a_records_tracks_are_kept_in_whole_steps(addon_module, clean_scene):
    """store_plan keeps a smooth track (a walk 100 m from the origin) within half a step
    (5 micrometres, about what single precision kept there) in under half the bytes of
    deflated single precision; a track of two rows, one with a NaN, contacts and integers
    load as before (single precision, or exactly)."""
    import base64
    import io
    import json

    import bpy

    storage = addon_module.adapter.storage
    ob = bpy.data.objects.new("Walker", None)
    clean_scene.collection.objects.link(ob)
    rng = np.random.default_rng(7)
    t = np.arange(559) / 30.0  # 1.4 m/s on a slow curve, heading turning with it
    walk = np.column_stack((100.0 + 8.0 * np.sin(0.17 * t), -80.0 + 8.0 * np.cos(0.17 * t), t))
    walk += rng.normal(0.0, 2e-4, walk.shape)  # what a plan's blends leave
    short = np.array([[1.25, 2.5, 3.0], [1.5, 2.75, 3.25]])
    gap = walk[:5].copy()
    gap[2, 1] = np.nan
    contacts = rng.random((559, 4)) < 0.5
    data = {"frame_start": 1, "frame_end": 559, "ground": walk, "short": short, "gap": gap}
    storage.store_plan(ob, dict(data, contacts=contacts, index=np.arange(9)))
    meta, arrays = storage.load_plan(ob)
    assert meta == {"frame_start": 1, "frame_end": 559}
    assert np.abs(arrays["ground"] - walk).max() <= 0.5 / storage.TRACK_STEPS + 1e-12
    assert arrays["ground"].dtype == np.float64 and arrays["ground"].shape == walk.shape
    assert np.array_equal(arrays["short"], short)
    assert np.allclose(arrays["gap"], gap.astype(np.float32), equal_nan=True, rtol=0, atol=0)
    assert np.array_equal(arrays["contacts"], contacts)
    assert np.array_equal(arrays["index"], np.arange(9))
    storage.store_plan(ob, {"ground": walk})
    stored = len(base64.b64decode(json.loads(ob[storage.PLAN_KEY])["arrays"]))
    single = io.BytesIO()
    np.savez_compressed(single, ground=walk.astype(np.float32))
    assert stored < 0.5 * len(single.getvalue())


def test_compact_keys_leave_out_what_the_strip_plays_anyway(addon_module, clean_scene):
    """A curve holding its ``left_out`` value on every frame is not made, stored compactly:
    in a Replace strip a quaternion component at its default while another of the bone's
    stays (no other channel); in an Add strip a bone's quaternion only whole (a zero delta),
    an Euler angle alone. Every curve is made when keyed on every frame (the reference)."""
    act_io = addon_module.adapter.actions
    compat = addon_module.adapter.compat
    t = np.arange(30.0)
    moving = np.sin(t / 5.0)
    q, e = "rotation_quaternion", "rotation_euler"
    spec = [  # bone, path, index, values
        ("Held", q, 0, np.ones_like(t)),  # w held at 1
        ("Held", q, 1, moving),
        ("Held", q, 2, np.zeros_like(t)),
        ("Held", q, 3, 0.5 * moving),
        ("Rest", q, 0, np.ones_like(t)),  # a bone at rest throughout
        ("Rest", q, 1, np.zeros_like(t)),
        ("Rest", q, 2, np.zeros_like(t)),
        ("Rest", q, 3, np.zeros_like(t)),
        ("Zero", q, 0, np.zeros_like(t)),  # a delta of zero
        ("Zero", q, 1, np.zeros_like(t)),
        ("Zero", q, 2, np.zeros_like(t)),
        ("Zero", q, 3, np.zeros_like(t)),
        ("Euler", e, 0, np.zeros_like(t)),
        ("Euler", e, 1, moving),
        ("Euler", e, 2, np.zeros_like(t)),
    ]
    curves = [(f'pose.bones["{b}"].{p}', i, b, v) for b, p, i, v in spec]
    made_of = {}
    for blend, tol in (("REPLACE", act_io.CUBIC), ("ADD", act_io.CUBIC), ("ADD", None)):
        action, slot = compat.new_action(f"left out {blend}")
        left = act_io.rest_values(curves) if blend == "REPLACE" else np.zeros(len(curves))
        act_io.key_curves(action, slot, t, curves, tol, left_out=left, blend=blend)
        made_of[blend, tol is None] = {
            (fc.data_path.split('"')[1], fc.array_index) for fc in compat.fcurves(action)
        }
    assert made_of["REPLACE", False] == {
        ("Held", 1),
        ("Held", 3),
        ("Rest", 0),
        ("Zero", 0),
        ("Euler", 0),
        ("Euler", 1),
        ("Euler", 2),
    }
    # zeros left out: the zero bone's quaternion whole, none of the others' (a w of 1)
    quats = {(b, i) for b in ("Held", "Rest") for i in range(4)}
    assert made_of["ADD", False] == quats | {("Euler", 1)}
    assert made_of["ADD", True] == {(b, i) for b, _, i, _ in spec}
