# SPDX-License-Identifier: GPL-3.0-or-later
"""Rigs in any rotation mode (issue 15, item 1).

Blender's own BVH importer, at its default rotate_mode='NATIVE', makes pose bones in Euler
mode (CMU files: 'ZYX'); a bone plays only the channel of its own rotation mode, so keys
written as quaternions leave such a rig a statue sliding along the path. The planner now
writes every channel in the mode of the bone (or object) it drives: here the same plan, on
rigs in every mode, evaluated through the depsgraph, must give the quaternion rig's bone
world matrices on every frame, with and without the foot-lock Add track.
"""

import bpy
import numpy as np
import pytest
from mathutils import Euler, Quaternion

from scene_helpers import empty, pillar, spy_writes, walker_from, world_bone_matrices

EULER_ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")
MODES = ("QUATERNION",) + EULER_ORDERS + ("AXIS_ANGLE",)
CMU_SCALE = 0.056444
TOL = 1e-4  # metres / matrix entries


# --- helpers --------------------------------------------------------------------------------


def native_bvh(mocap_dir, name):
    """16_15 through Blender's BVH importer at its defaults (Euler bones), renamed ``name``."""
    before = set(bpy.data.objects)
    result = bpy.ops.import_anim.bvh(
        filepath=str(mocap_dir / "cmu" / "16_15.bvh"),
        global_scale=CMU_SCALE,
        update_scene_fps=False,
    )
    assert result == {"FINISHED"}
    (ob,) = [o for o in bpy.data.objects if o not in before]
    ob.name = name
    return ob


def set_modes(obj, bone_modes, object_mode=None):
    for pb in obj.pose.bones:
        pb.rotation_mode = bone_modes(pb.name)
    if object_mode:
        obj.rotation_mode = object_mode


def curves_of(addon_module, action):
    fcs = addon_module.adapter.compat.fcurves(action)
    out = {}
    for fc in fcs:
        n = len(fc.keyframe_points)
        co = np.empty(2 * n)
        fc.keyframe_points.foreach_get("co", co)
        out[(fc.data_path, fc.array_index)] = co.reshape(n, 2)[:, 1]
    return out


def random_quats(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def same_rotation(a, b, atol=1e-9):
    return np.allclose(np.abs(np.sum(a * b, axis=-1)), 1.0, atol=atol)


# --- conversions (no scene) -----------------------------------------------------------------


def test_conversions_agree_with_mathutils(addon_module):
    act_io = addon_module.adapter.actions
    rng = np.random.default_rng(15)
    q = random_quats(rng, 300)
    q[:4] = [
        [1, 0, 0, 0],
        [0, 1, 0, 0],
        [np.sqrt(0.5), 0, np.sqrt(0.5), 0],  # identity, 180
        [np.sqrt(0.5), 0, 0, -np.sqrt(0.5)],
    ]  # degrees, gimbal
    rest = np.zeros((len(q), 3))
    for order in EULER_ORDERS:  # mathutils computes in float32
        e = act_io.closest_channels(q, order, rest)
        assert np.abs(e).max() <= np.pi + 1e-9
        back = np.array([tuple(Euler(v, order).to_quaternion()) for v in e])
        assert same_rotation(back, q, 1e-6), order
        assert same_rotation(act_io.euler_to_quat(e, order), back, 1e-6), order
        theirs = np.array([tuple(Quaternion(v).to_euler(order)) for v in q])
        assert same_rotation(act_io.channels_to_quat(theirs, order), q, 1e-6), order
    aa = act_io.closest_channels(q, "AXIS_ANGLE", np.tile([0.0, 0, 1, 0], (len(q), 1)))
    assert np.allclose(np.linalg.norm(aa[:, 1:], axis=1), 1.0)
    back = np.array([tuple(Quaternion(v[1:], v[0])) for v in aa])
    assert same_rotation(back, q, 1e-6)
    assert same_rotation(act_io.axis_angle_to_quat(aa), back, 1e-6)
    assert np.allclose(
        act_io.channels_to_quat(np.array([[0.0, 0.0, 0.0, 0.0]]), "AXIS_ANGLE"), [[1, 0, 0, 0]]
    )  # zero axis: no rotation, as in Blender


def test_channels_are_continuous_over_frames(addon_module):
    """A bone spinning three turns about a wandering axis (through the identity and past
    90 degrees on every Euler middle axis): the keys follow it without a jump, in every mode."""
    act_io = addon_module.adapter.actions
    quat = addon_module.motion_patches.kinematics.quat
    t = np.linspace(0.0, 1.0, 720)
    axis = np.column_stack((np.cos(5 * t), np.sin(3 * t), 0.6 * np.cos(2 * t)))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = 6 * np.pi * t  # three turns
    q = quat.exp(axis * angle[:, None])
    for mode in MODES:
        v = act_io.rotation_channels(q[:, None], mode)[:, 0]
        assert same_rotation(act_io.channels_to_quat(v, mode), q), mode
        if mode in EULER_ORDERS:
            step = np.abs(np.diff(v, axis=0)).max()
        elif mode == "AXIS_ANGLE":
            step = np.linalg.norm(np.diff(v[:, :1] * v[:, 1:], axis=0), axis=1).max()
            assert np.ptp(v[:, 0]) > 5 * np.pi  # the angle keeps turning (no wrap to 0)
        else:
            step = np.linalg.norm(np.diff(v, axis=0), axis=1).max()
        # 3 turns over 720 frames is 1.5 degrees a frame. Near gimbal lock (the middle angle
        # at 90 degrees) the first and last Euler angles swing fast in opposite senses, but a
        # whole turn (6.28) or a switch to the other Euler solution (about 3.14) is a jump.
        assert step < 1.0, (mode, step)


def probe_rig(scene, bones):
    """An armature object of one-unit bones named ``bones``, all at the origin."""
    arm = bpy.data.armatures.new("Probe")
    ob = bpy.data.objects.new("Probe", arm)
    scene.collection.objects.link(ob)
    bpy.context.view_layer.objects.active = ob
    bpy.ops.object.mode_set(mode="EDIT")
    for name in bones:
        b = arm.edit_bones.new(name)
        b.head, b.tail = (0, 0, 0), (0, 0, 1)
    bpy.ops.object.mode_set(mode="OBJECT")
    return ob


def probe_strip(ob, name, blend, keys):
    """A strip of ``blend`` on a track of its own over ``ob``'s others, playing an action
    keyed on frame 1 with ``keys`` = {(data path, index): value}."""
    act = bpy.data.actions.new(name)
    slot = act.slots.new(id_type="OBJECT", name=name)
    bag = act.layers.new("L").strips.new(type="KEYFRAME").channelbag(slot, ensure=True)
    for (path, i), x in keys.items():
        bag.fcurves.new(path, index=i).keyframe_points.insert(1, x)
    strip = ob.animation_data_create().nla_tracks.new().strips.new(name, 1, act)
    strip.action_slot = slot
    strip.blend_type = blend


def test_blender_add_rule(clean_scene):
    """What the foot-lock track relies on, on this Blender version: an Add strip over a
    Replace strip adds every channel value, the four quaternion components (of a lower
    quaternion that is not unit, as keys interpolated linearly are), the Euler angles in
    every order and the four axis-angle values; and a quaternion strip that adds a tiny
    rotation (w within float32 rounding of 1) still gets it, exactly (a Combine strip,
    lower @ pow(strip, 1) with the angle taken as acos of float32 w, loses it)."""
    ob = probe_rig(clean_scene, MODES)
    for m in MODES:
        ob.pose.bones[m].rotation_mode = m
    paths = {
        m: "rotation_quaternion"
        if m == "QUATERNION"
        else "rotation_axis_angle"
        if m == "AXIS_ANGLE"
        else "rotation_euler"
        for m in MODES
    }
    lower = {m: (0.3, 0.5, 0.7) for m in EULER_ORDERS}
    upper = {m: (0.1, -0.2, 0.3) for m in EULER_ORDERS}
    lower["QUATERNION"] = tuple(0.97 * np.array(Quaternion((1, 2, 3, 4)).normalized()))
    locked = Quaternion((1, 2, 3, 4)).normalized() @ Quaternion((1.0, 1e-4, -2e-4, 1e-4))
    locked.normalize()  # 0.0005 rad from the unit lower: w of the step rounds to 1 in float32
    upper["QUATERNION"] = tuple(np.array(locked) - lower["QUATERNION"])
    lower["AXIS_ANGLE"] = (0.8, 0.0, 0.6, 0.8)
    upper["AXIS_ANGLE"] = (0.5, 1.0, 0.0, 0.0)
    for name, vals, blend in (("lower", lower, "REPLACE"), ("upper", upper, "ADD")):
        keys = {
            (f'pose.bones["{m}"].{paths[m]}', i): x
            for m, v in vals.items()
            for i, x in enumerate(v)
        }
        probe_strip(ob, name, blend, keys)
    clean_scene.frame_set(1)
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    got = {m: np.array(getattr(ev.pose.bones[m], paths[m])) for m in MODES}
    assert np.allclose(got["QUATERNION"], np.array(locked), atol=1e-7), got["QUATERNION"]
    pose = (
        np.array(ob.data.bones["QUATERNION"].matrix_local.inverted())[:3, :3]
        @ np.array(ev.pose.bones["QUATERNION"].matrix)[:3, :3]
    )
    assert np.allclose(pose, np.array(locked.to_matrix()), atol=1e-6)
    for m in EULER_ORDERS + ("AXIS_ANGLE",):
        assert np.allclose(got[m], np.add(lower[m], upper[m]), atol=1e-6), (m, got[m])


def test_blender_plays_a_quaternion_a_strip_keys_in_part_at_its_defaults(clean_scene):
    """What compact keys rely on to leave out a quaternion component at its rest value
    (adapter.actions.key_curves' ``left_out``), on this Blender version: a Replace strip
    keying some of a bone's quaternion components plays the others at their defaults (w 1,
    x y z 0), not the strip's below; a strip keying none of a bone's components (of
    either blend) leaves it as the strips below play it: a body action keeps a component of
    every bone, a foot lock leaves a bone's zero delta out only whole (an Add strip keying
    some components adds the others' defaults)."""
    ob = probe_rig(clean_scene, ("Part", "Kept", "Other"))
    below = (0.5, 0.5, -0.5, 0.5)
    keyed = {
        "below": ("REPLACE", {b: dict(enumerate(below)) for b in ("Part", "Kept", "Other")}),
        "part": ("REPLACE", {"Part": {1: 0.1, 2: -0.2, 3: 0.3}, "Kept": dict(enumerate(below))}),
        "add": ("ADD", {"Kept": {0: 0.0, 1: 0.0, 2: 0.0, 3: 0.0}}),
    }
    for name, (blend, bones) in keyed.items():
        path = 'pose.bones["{}"].rotation_quaternion'.format
        keys = {(path(b), i): x for b, comps in bones.items() for i, x in comps.items()}
        probe_strip(ob, name, blend, keys)
    clean_scene.frame_set(1)
    ev = ob.evaluated_get(bpy.context.evaluated_depsgraph_get())
    got = {b: np.array(ev.pose.bones[b].rotation_quaternion) for b in ("Part", "Kept", "Other")}
    assert np.allclose(got["Part"], (1.0, 0.1, -0.2, 0.3), atol=1e-7), got["Part"]
    assert np.allclose(got["Kept"], below, atol=1e-7), got["Kept"]
    assert np.allclose(got["Other"], below, atol=1e-7), got["Other"]


# --- reading clips --------------------------------------------------------------------------


def test_clips_read_the_same_in_every_rotation_mode(addon_module, mocap_dir, clean_scene):
    """16_15 read from Blender's default import (ZYX Euler keys) equals the add-on's own
    quaternion import; keyed back in every mode on bones in that mode it reads the same."""
    api, act_io = addon_module.api, addon_module.adapter.actions
    clean_scene.render.fps = 30
    rig_q, (act_q,) = api.import_mocap([mocap_dir / "cmu" / "16_15.bvh"], name="Quat")
    rig_n = native_bvh(mocap_dir, "Native")
    assert {pb.rotation_mode for pb in rig_n.pose.bones} == {"ZYX"}
    ref = act_io.clip_from_action(act_q, rig_q, 30.0)
    clip = act_io.clip_from_action(rig_n.animation_data.action, rig_n, 30.0)
    assert clip.frames == ref.frames
    assert np.allclose(clip.root_pos, ref.root_pos, atol=1e-5)
    assert same_rotation(clip.rotations, ref.rotations, 1e-6)

    skel = ref.skeleton
    frames = np.arange(ref.frames, dtype=float)
    loc = addon_module.motion_patches.kinematics.skeleton.root_position_to_location(
        skel, ref.root_pos
    )
    for mode in MODES:
        set_modes(rig_n, lambda _: mode)
        act, slot = addon_module.adapter.compat.new_action(f"keyed {mode}")
        act_io.key_pose(act, slot, skel, frames, loc, ref.rotations, {n: mode for n in skel.names})
        paths = {p.rsplit(".", 1)[1] for p, _ in curves_of(addon_module, act)}
        assert paths == {"location", act_io.rotation_path(mode)}, mode
        back = act_io.clip_from_action(act, rig_n, 30.0)
        assert same_rotation(back.rotations, ref.rotations, 1e-6), mode
    # Euler keys with no armature to give their order cannot be read: say so, do not guess.
    with pytest.raises(ValueError, match="Euler"):
        act_io.clip_from_action(bpy.data.actions["keyed XYZ"], None, 30.0, skeleton=skel)


# --- planning on rigs in every mode ---------------------------------------------------------


@pytest.fixture(scope="module")
def baked(walk_blend):
    """The session's walk patch (CMU 16_15 + 16_18, conftest.walk_blend)."""
    return walk_blend


# The foot lock's changed bones in the mixed rig: an axis-angle thigh and five Euler orders.
MIXED_LEGS = {
    "LeftUpLeg": "AXIS_ANGLE",
    "LeftLeg": "XZY",
    "LeftFoot": "YXZ",
    "RightUpLeg": "YZX",
    "RightLeg": "ZXY",
    "RightFoot": "XYZ",
}


def _mixed(names):
    """Leg bones as MIXED_LEGS, the other bones through all eight modes in turn."""
    others = [n for n in names if n not in MIXED_LEGS]
    modes = {n: MODES[i % len(MODES)] for i, n in enumerate(others)}
    modes.update(MIXED_LEGS)
    return modes.get


@pytest.fixture(scope="module", params=[False, True], ids=["no_foot_lock", "foot_lock"])
def planned(request, baked, addon_module, mocap_dir):
    """One goal planned for rigs in every rotation mode, evaluated on every frame.

    Quat: quaternion bones, quaternion object (the reference). Native / Native2: Blender's
    BVH import at its defaults (ZYX bones, XYZ object). Mixed: bones in all eight modes,
    axis-angle object. AxisAngle: axis-angle bones, ZXY object. ``expected``: the bone
    world matrices of the plan itself (the motion, and the locked rotations with the foot
    lock), computed in float64 from what api.plan_path hands to nla.write_plan. Stored with
    linear keys within 1e-5, so every mode plays the plan to float32 (cubic keys, the
    default, play it within their tolerance in each mode: test_compact_keys.py), every
    piece by strips playing keys on whole frames (loop strips do not:
    test_loop_strips.py)."""
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(baked))
    scene = bpy.context.scene
    source = bpy.data.objects["Source"]
    rigs = [
        walker_from(source, "Quat"),
        native_bvh(mocap_dir, "Native"),
        native_bvh(mocap_dir, "Native2"),
        walker_from(source, "Mixed"),
        walker_from(source, "AxisAngle"),
    ]
    quat_rig, _, _, mixed, axis_angle = rigs
    set_modes(quat_rig, lambda _: "QUATERNION", "QUATERNION")
    set_modes(mixed, _mixed([pb.name for pb in mixed.pose.bones]), "AXIS_ANGLE")
    set_modes(axis_angle, lambda _: "AXIS_ANGLE", "ZXY")
    for r in rigs:
        r.location = (0.4, 0.3, 0.0)
    for n, (x, y) in enumerate([(3.0, 1.0), (4.5, 3.0), (2.5, 4.0), (6.0, 1.5)]):
        pillar(f"Pillar{n}", x, y)
    goal = empty("Goal", 9.0, 7.0, 2.0)
    with pytest.MonkeyPatch.context() as mp:
        written = spy_writes(mp, addon_module)
        mp.setattr(addon_module.adapter.actions, "COMPACT", addon_module.adapter.actions.LINEAR_TOL)
        # no stretch played by the shared loop action: it plays between its keys, where
        # Blender interpolates channels and the plan slerps (test_loop_strips.py)
        mp.setattr(addon_module.motion_patches.kinematics.loop_strips, "MIN_CYCLES", 1e6)
        results = {
            r.name: api.plan_path(scene, r, goal, frame_start=1, foot_lock=request.param)
            for r in rigs
        }
    skel, expected = written["Quat"]
    ref = results["Quat"]
    frames = np.arange(ref.frame_start, ref.frame_end + 1)
    mats = world_bone_matrices(rigs, frames, skel.names)
    return {
        "rigs": {r.name: r for r in rigs},
        "results": results,
        "frames": frames,
        "names": skel.names,
        "matrices": mats,
        "expected": expected,
        "foot_lock": request.param,
    }


def worst(planned, a, b):
    """Largest difference of two (F, B, 4, 4) matrix sets, with where it is."""
    err = np.abs(a - b).max(axis=(2, 3))
    f, j = np.unravel_index(err.argmax(), err.shape)
    return err.max(), f"frame {planned['frames'][f]}, bone {planned['names'][j]}: {err.max():.2e}"


def test_default_bvh_import_rig_follows_the_plan(planned):
    native = planned["rigs"]["Native"]
    assert {pb.rotation_mode for pb in native.pose.bones} == {"ZYX"}  # the case in question
    assert native.rotation_mode == "XYZ"
    m = planned["matrices"]["Native"]
    names = planned["names"]
    # not a statue: the shin swings back and forth relative to the hips
    hips, shin = names.index("Hips"), names.index("LeftLeg")
    rel = np.linalg.inv(m[:, hips, :3, :3]) @ m[:, shin, :3, :3]
    swing = np.degrees(
        np.arccos(
            np.clip(
                (np.trace(rel[1:] @ np.swapaxes(rel[:1], 1, 2), axis1=1, axis2=2) - 1) / 2, -1, 1
            )
        )
    )
    assert swing.max() > 20.0, swing.max()
    err, where = worst(planned, m, planned["expected"])
    assert err < TOL, where


@pytest.mark.parametrize("rig", ["Native", "Native2", "Mixed", "AxisAngle"])
def test_every_rotation_mode_evaluates_like_the_quaternion_rig(planned, rig):
    r = planned["results"]
    assert r[rig].pieces == r["Quat"].pieces and r[rig].cost == r["Quat"].cost
    assert (r[rig].frame_start, r[rig].frame_end) == (r["Quat"].frame_start, r["Quat"].frame_end)
    tracks = [t.name for t in planned["rigs"][rig].animation_data.nla_tracks]
    assert ("MP foot lock" in tracks) == planned["foot_lock"]
    m = planned["matrices"]
    err, where = worst(planned, m[rig], planned["expected"])
    assert err < TOL, "from the plan: " + where
    err, where = worst(planned, m[rig], m["Quat"])
    assert err < TOL, "from Quat: " + where


def test_quaternion_rig_evaluates_the_plan(planned):
    """The reference itself, foot lock on or off: the Add track sums float32 quaternion
    components to the locked rotation (a Combine track was 1.3e-3 off: Blender takes the
    angle of a Combine quaternion as acos of its float32 w)."""
    err, where = worst(planned, planned["matrices"]["Quat"], planned["expected"])
    print(f"\nquaternion rig from the plan, foot lock {planned['foot_lock']}: worst {where}")
    assert err < TOL, where


def test_foot_skate_is_the_quaternion_rigs(planned, addon_module):
    api = addon_module.api
    figures = {
        n: api.analyse(bpy.context, planned["rigs"][n])
        for n in ("Quat", "Native", "Mixed", "AxisAngle")
    }
    ref = figures["Quat"]["foot_skate"]
    # cm/s and cm/frame, foot lock on or off: the rigs evaluate the same bones to 1e-4 m
    rel, tol = 1e-3, 1e-2
    for n in ("Native", "Mixed", "AxisAngle"):
        sk = figures[n]["foot_skate"]
        assert sk.keys() == ref.keys()
        for k, v in ref.items():
            assert sk[k] == pytest.approx(v, rel=rel, abs=tol), (n, k, sk[k], v)
    assert ref["mean_cm_per_frame"] < 1.0


def test_segment_actions_are_shared_by_rigs_with_the_same_modes(planned, addon_module):
    nla, storage = addon_module.adapter.nla, addon_module.adapter.storage
    scene = bpy.context.scene
    patch, key = storage.load_patch(scene, "walk"), storage.patch_key(scene, "walk")
    skel = patch.gait.skeleton
    rigs = planned["rigs"]
    modes = {n: nla.rig_rotation_modes(r, skel) for n, r in rigs.items()}
    before = len(bpy.data.actions)
    acts = {n: nla.segment_action(bpy, patch, key, 0, skel, m)[0] for n, m in modes.items()}
    assert acts["Native"] == acts["Native2"]  # same modes: one shared action
    assert len({acts[n].name for n in ("Quat", "Native", "Mixed", "AxisAngle")}) == 4
    assert len(bpy.data.actions) - before <= 4
    # an all-quaternion rig keeps the original key: earlier files' actions are reused
    assert acts["Quat"][nla.SEGMENT_KEY] == f"{key}:0"
    assert acts["Native"][nla.SEGMENT_KEY] == f"{key}:0:ZYX"
    assert acts["Mixed"][nla.SEGMENT_KEY].startswith(f"{key}:0:mixed-")
    for n, want in (
        ("Quat", "rotation_quaternion"),
        ("Native", "rotation_euler"),
        ("AxisAngle", "rotation_axis_angle"),
    ):
        paths = {p.rsplit(".", 1)[1] for p, _ in curves_of(addon_module, acts[n])}
        assert paths == {"location", want}, n
    mixed = {p for p, _ in curves_of(addon_module, acts["Mixed"])}
    for b, m in modes["Mixed"].items():
        assert f'pose.bones["{b}"].{addon_module.adapter.actions.rotation_path(m)}' in mixed
    assert nla.segment_action(bpy, patch, key, 0, skel, modes["Native2"])[0] == acts["Native"]

    # in the plan: the segment strips of Native and Native2 play the same actions
    def segment_strip_actions(name):
        strips = rigs[name].animation_data.nla_tracks["MP motion"].strips
        return [s.action for s in strips if s.action.get(nla.SEGMENT_KEY)]

    assert segment_strip_actions("Native") == segment_strip_actions("Native2")
    quat_names = {a.name for a in segment_strip_actions("Quat")}
    assert not quat_names & {a.name for a in segment_strip_actions("Native")}
    assert len(segment_strip_actions("Native")) == sum(
        p.startswith("seg") for p in planned["results"]["Native"].pieces
    )


def test_foot_lock_keys_the_bones_own_channels(planned, addon_module):
    rigs = planned["rigs"]
    if not planned["foot_lock"]:
        for r in rigs.values():
            assert "MP foot lock" not in [t.name for t in r.animation_data.nla_tracks]
        return
    mixed_legs = {
        f'pose.bones["{n}"].{addon_module.adapter.actions.rotation_path(m)}'
        for n, m in MIXED_LEGS.items()
    }
    for name, want in (
        ("Quat", {"rotation_quaternion"}),
        ("Native", {"rotation_euler"}),
        ("AxisAngle", {"rotation_axis_angle"}),
        ("Mixed", None),
    ):
        ad = rigs[name].animation_data
        strip = ad.nla_tracks["MP foot lock"].strips[0]
        assert strip.blend_type == "ADD"
        paths = {p for p, _ in curves_of(addon_module, strip.action)}
        # the character's own pieces hold the locked legs in its body action, in the
        # bones' own channels too; the foot lock keys what the shared segments play
        played = {s.action for s in ad.nla_tracks["MP motion"].strips}
        body = [a for a in played if a.get(addon_module.adapter.nla.CHARACTER_KEY)]
        assert paths or body, name
        held = {p for a in body for p, _ in curves_of(addon_module, a)}
        if want is None:
            assert paths <= mixed_legs, name
            assert not body or mixed_legs <= held, name
        else:
            assert {p.rsplit(".", 1)[1] for p in paths} <= want, name
            assert {p.rsplit(".", 1)[1] for p in held} <= want | {"location"}, name
