"""The keys of a planned character fitted without Blender (kinematics/rig_keys.py): what a
crowd's Dask worker sends back (packed) gives the writer the very arrays it reads, and the
channels of every rotation mode turn back into the rotations they were made from."""

import pickle

import numpy as np
import pytest
from test_cluster import crossing

from motion_patches.crowd import members
from motion_patches.kinematics import channels, foot_lock, keys, quat, rig_keys, scene_rate
from motion_patches.kinematics.pose_keys import Tolerance

MODES = ["QUATERNION", "AXIS_ANGLE", *channels.EULER_ORDERS]


@pytest.mark.parametrize("mode", MODES)
def test_channels_of_every_mode_play_the_rotations_back_continuously(mode):
    """A bone turning through several whole turns about a wandering axis: its channels
    give the same rotations back, and no channel jumps by a turn, a quaternion's sign, the
    other Euler solution or an axis's sign from frame to frame (each a jump of pi or more;
    Euler angles near gimbal lock and the axis leaving the rest one may move fast)."""
    t = np.linspace(0.0, 1.0, 400)
    axis = np.stack((np.cos(3 * t), np.sin(5 * t), 0.5 + t), axis=1)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = 5.0 * np.pi * t
    q = np.concatenate((np.cos(angle / 2)[:, None], np.sin(angle / 2)[:, None] * axis), 1)
    ch = channels.rotation_channels(q, mode)
    back = channels.channels_to_quat(ch, mode)
    assert np.abs(np.abs(np.sum(back * q, axis=1)) - 1.0).max() < 1e-12
    assert np.abs(np.diff(ch, axis=0)).max() < 1.5  # radians (or quaternion units) a frame


def _turning(frames, bones, seed):
    """(F, B, 4) unit quaternions of bones each turning smoothly about its own axis."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, frames)[:, None]
    axis = rng.normal(size=(bones, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = rng.uniform(-1.5, 1.5, bones) * np.sin(2 * np.pi * t + rng.uniform(0, 3, bones))
    return np.concatenate((np.cos(angle / 2)[..., None], np.sin(angle / 2)[..., None] * axis), -1)


def test_held_channels_play_the_same_rotations_with_one_component_at_one():
    """Blender normalises a bone's quaternion before it plays it: a bone whose quaternion
    keeps one component at least HELD of its length is keyed with that component exactly
    1 (one key), the others divided by it; one turning past 120 degrees from rest about an
    axis, whose components all come near 0 on some frame, is keyed as given."""
    q = _turning(90, 5, 3)
    half = np.linspace(0.0, np.pi, 90) / 2  # the last bone turns half a turn about x
    q[:, 4] = np.stack((np.cos(half), np.sin(half), 0 * half, 0 * half), 1)
    q[:, 2] *= -1.0  # either sign
    held = channels.held_channels(q)
    back = quat.normalize(held)
    assert np.abs(np.abs(np.sum(back * q, axis=-1)) - 1.0).max() < 1e-12
    for b in range(4):
        ones = np.all(held[:, b] == 1.0, axis=0)
        assert ones.sum() == 1, b
    assert np.array_equal(held[:, 4], q[:, 4])
    assert np.array_equal(channels.held_channels(q[:0]), q[:0])


def test_a_correction_added_to_held_channels_leaves_the_held_one_unchanged():
    """The foot lock adds ``matching_channels(locked) - lower`` to the motion's channels:
    the sum plays the locked rotation; where the motion holds a component at 1 that
    correction is exactly 0 (its curve one key), over unit quaternions w's; where w is too
    small for that, the representation nearest (the sign)."""
    lower = _turning(60, 3, 4)
    locked = quat.normalize(lower + 0.05 * _turning(60, 3, 5))
    held = channels.held_channels(lower)
    for ref in (held, lower):
        got = channels.matching_channels(locked, "QUATERNION", ref)
        back = quat.normalize(ref + (got - ref))
        assert np.abs(np.abs(np.sum(back * locked, axis=-1)) - 1.0).max() < 1e-12
    delta = channels.matching_channels(locked, "QUATERNION", held) - held
    at_one = held == 1.0
    assert at_one.any() and np.all(delta[at_one] == 0.0)
    # over unit quaternions, w takes the correction of none
    delta = channels.matching_channels(locked, "QUATERNION", lower) - lower
    assert np.all(delta[..., 0] == 0.0)
    far = np.array([[[0.1, 0.995, 0.0, 0.0]]]) / np.linalg.norm([0.1, 0.995])
    near = channels.closest_channels(far, "QUATERNION", lower[:1, :1])  # w too small: the sign
    assert np.array_equal(channels.matching_channels(far, "QUATERNION", lower[:1, :1]), near)
    e = np.zeros((4, 3))
    assert np.array_equal(
        channels.matching_channels(locked[:4, 0], "XYZ", e),
        channels.closest_channels(locked[:4, 0], "XYZ", e),
    )


@pytest.fixture(scope="module")
def planned(walk_patch):
    """Three members of the small crossing, planned and placed at 24 fps, as a crowd holds
    them before they are written."""
    world, tasks = crossing(walk_patch)
    out = []
    for task in tasks[:3]:
        m = members.plan_member(task, world)
        assert isinstance(m, members.Member), m
        own = rig_keys.own_pieces(m.plan)
        placed = scene_rate.placed(walk_patch, None, members.unpacked(m.raw), 24.0, own)
        out.append((m.plan, placed))
    return out


def test_a_workers_packed_answer_unpacks_to_what_the_writer_reads(walk_patch, planned):
    """pack, through pickle as a worker sends it, then unpack: the same motion and
    contacts, the same locked legs, the same root keys, the body keys on every kept frame and
    its values in single precision as prepare in process; and under half the bytes."""
    skel = walk_patch.gait.skeleton
    modes = {name: "XYZ" for name in skel.names[::3]}  # some bones keyed as Euler angles
    legs = foot_lock.locked_bones(skel)
    for plan, placed in planned:
        args = (skel, placed, True, 24.0, plan, (modes, 1.0), (0.0, "XYZ", None), Tolerance())
        # packed from this very answer: two fits of one plan can differ in a float's last
        # bit (an Euler channel's arctangent), which is not what this test is about
        here = rig_keys.prepare(*args)
        packed = pickle.dumps(rig_keys.pack(here, skel), protocol=pickle.HIGHEST_PROTOCOL)
        assert len(packed) < 0.5 * len(pickle.dumps(here, protocol=pickle.HIGHEST_PROTOCOL))
        there = rig_keys.unpack(pickle.loads(packed), skel, placed[2])
        for k in ("ground", "root_local", "rotations", "contacts"):
            assert np.array_equal(getattr(here[0], k), getattr(there[0], k))
        assert np.array_equal(here[1][:, legs], there[1][:, legs])
        assert not np.array_equal(here[1][:, legs], placed[2].rotations[:, legs])  # locked
        root_here, root_there = here[3]["curves"], there[3]["curves"]
        assert [c[:3] for c in root_here] == [c[:3] for c in root_there]
        assert all(np.array_equal(a[3], b[3]) for a, b in zip(root_here, root_there))
        assert all(
            np.array_equal(here[3]["fitted"][k], there[3]["fitted"][k])
            for k in "keep values slopes slopes_in".split()
        )
        body_here, body_there = here[2], there[2]
        keep = body_here["fitted"]["keep"]
        assert keep.any() and np.array_equal(keep, body_there["fitted"]["keep"])
        for k in ("values", "slopes", "slopes_in"):
            assert np.array_equal(body_here["fitted"][k][keep], body_there["fitted"][k][keep])
        # the values, read only as Blender stores them (a curve kept as samples), travel so
        f32 = np.float32
        assert np.array_equal(body_here["values"].astype(f32), body_there["values"].astype(f32))
        assert body_here["ranges"] == body_there["ranges"]


def test_a_member_prepared_from_its_packed_motions_is_prepared_as_in_process(
    walk_patch, monkeypatch
):
    """What a crowd's worker is sent (each member's packed piece motions, the patch shared)
    and prepares, several members a task (members.prepared_keys, through pickle): each
    prepared in turn from the motion placed as the writer places it (the same arrays, to the
    bit) with the other arguments as given. (The fit itself is prepare_packed, whose packing
    the test above checks.)"""
    world, tasks = crossing(walk_patch)
    skel = walk_patch.gait.skeleton
    jobs, placed_here = [], []
    for task in tasks[:3]:
        m = members.plan_member(task, world)
        assert isinstance(m, members.Member), m
        args = (skel, None, True, 24.0, m.plan, ({}, 1.0), (0.0, "XYZ", None), Tolerance())
        jobs.append((m.raw, None, args))
        own = rig_keys.own_pieces(m.plan)
        placed_here.append(scene_rate.placed(walk_patch, None, members.unpacked(m.raw), 24.0, own))
    seen = []
    monkeypatch.setattr(
        rig_keys, "prepare_packed", lambda *a, loop=None: seen.append(a) or len(seen)
    )
    sent = pickle.loads(pickle.dumps((jobs, 24.0), protocol=pickle.HIGHEST_PROTOCOL))
    assert members.prepared_keys(*sent, patch=walk_patch) == [1, 2, 3]
    for got, (_, _, args), (motions, bounds, whole) in zip(seen, jobs, placed_here):
        assert got[0] is not None and got[0].names == skel.names
        assert got[2:4] == args[2:4] and got[5:7] == args[5:7]
        plan, sent_plan = args[4], got[4]  # the plan, as sent
        assert sent_plan.cost == plan.cost
        assert [p.label for p in sent_plan.pieces] == [p.label for p in plan.pieces]
        assert vars(got[7]) == vars(args[7])
        g_motions, g_bounds, g_whole = got[1]
        assert np.array_equal(g_bounds, bounds) and len(g_motions) == len(motions)
        for a, b in zip([*g_motions, g_whole], [*motions, whole]):
            for k in ("ground", "root_local", "rotations", "contacts"):
                assert np.array_equal(getattr(a, k), getattr(b, k)), k


def test_the_body_keys_stay_within_their_tolerance(walk_patch, planned):
    """Every bone the body keys play (Hermite cubics between kept frames) within the
    tolerance its rotation is judged by (the legs finer), on every frame."""
    skel = walk_patch.gait.skeleton
    plan, placed = planned[0]
    tol = Tolerance()
    _, locked, body, _ = rig_keys.prepare(
        skel, placed, True, 24.0, plan, ({}, 1.0), (0.0, "XYZ", None), tol
    )
    fit, values = body["fitted"], body["values"]
    frames = np.arange(values.shape[0], dtype=float)
    played = np.empty_like(values)
    for c in range(values.shape[1]):
        if fit["constant"][c]:
            played[:, c] = fit["value"][c]
            continue
        if fit["gave_up"][c]:
            played[:, c] = values[:, c]
            continue
        k = np.flatnonzero(fit["keep"][:, c])
        played[:, c] = keys.hermite(
            k, fit["values"][k, c], fit["slopes"][k, c], frames, fit["slopes_in"][k, c]
        )
    for group in body["rotations"]:
        for cols in group.columns:
            q_plan = quat.normalize(values[:, cols])
            q_play = quat.normalize(played[:, cols])
            turn = 2.0 * np.arccos(np.clip(np.abs(np.sum(q_plan * q_play, axis=1)), 0.0, 1.0))
            assert turn.max() <= group.angle * (1.0 + 1e-6), np.degrees(turn.max())
    # keyed on the scene's frames, every quaternion bone of the walk holds a component at 1
    assert not body["between"]
    bones = np.concatenate([g.columns for g in body["rotations"]])
    assert all(np.all(values[:, cols] == 1.0, axis=0).sum() == 1 for cols in bones)
    assert all(fit["constant"][cols].any() for cols in bones)
