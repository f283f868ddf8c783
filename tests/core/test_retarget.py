# SPDX-License-Identifier: GPL-3.0-or-later
"""Bone maps and retargeting (issue 15, item 2), compact keys and scene-rate timing (items
4 and 6), on real CMU skeletons read without Blender."""

import numpy as np
import pytest

from motion_patches.kinematics import bvh, keys, retarget, scene_rate
from motion_patches.kinematics.retarget import RetargetError, rig_map
from motion_patches.kinematics.skeleton import Skeleton

from conftest import MOCAP, cmu
from rig_names import MIXAMO, RIGIFY


@pytest.fixture(scope="module")
def max16():
    path = MOCAP / "cmu16max" / "16_35.bvh"
    if not path.exists():
        pytest.fail(f"mocap clip missing: {path}")
    return bvh.read(path)


@pytest.fixture(scope="module")
def walk2():
    return cmu("02_01")


def renamed(skel, names):
    """The skeleton with bones renamed ({old: new}), dropping none."""
    return Skeleton([names.get(n, n) for n in skel.names], skel.parents.copy(), skel.rest.copy())


def positions(clip, names):
    p = clip.joint_positions()
    return p[:, [clip.skeleton.names.index(n) for n in names]]


def test_each_convention_is_recognised(walk16, max16):
    assert retarget.roles(walk16.skeleton)[0] == "CMU"
    assert retarget.roles(max16.skeleton)[0] == "3ds Max"
    assert retarget.roles(renamed(walk16.skeleton, MIXAMO))[0] == "Mixamo"
    assert retarget.roles(renamed(walk16.skeleton, RIGIFY))[0] == "Rigify"


def test_cmu_bones_pair_with_the_3ds_max_names_by_role(walk16, max16):
    """Both conventions use 'LeftShoulder' and 'Neck', for different bones: pairing goes by
    role, not by equal names."""
    m = rig_map(walk16.skeleton, max16.skeleton).mapping
    assert m["LeftUpLeg"] == "LeftHip" and m["LeftLeg"] == "LeftKnee"
    assert m["LeftFoot"] == "LeftAnkle" and m["LeftToeBase"] == "LeftToe"
    assert m["LeftShoulder"] == "LeftCollar" and m["LeftArm"] == "LeftShoulder"
    assert m["Neck"] == "lowerneck" and m["Neck1"] == "Neck"
    assert m["Spine"] == "Chest" and m["Spine1"] == "Chest2"
    assert len(m) == len(walk16.skeleton.names)


@pytest.mark.parametrize("names", [MIXAMO, RIGIFY], ids=["mixamo", "rigify"])
def test_mixamo_and_rigify_names_pair_and_follow(walk16, names):
    target = renamed(walk16.skeleton, names)
    rm = rig_map(walk16.skeleton, target)
    for src, tgt in names.items():
        if src in (
            "LowerBack",
            "Neck1",
            "LHipJoint",
            "RHipJoint",
            "LeftFingerBase",
            "RightFingerBase",
        ):
            continue  # no such bone in that convention (LowerBack is Mixamo's Spine)
        assert rm.mapping[src] == tgt, (src, rm.mapping.get(src))
    assert rm.scale == pytest.approx(1.0)
    moved = rm.clip(walk16)
    feet = ["LeftFoot", "LeftToeBase", "RightFoot", "RightToeBase"]
    np.testing.assert_allclose(
        positions(moved, [names[n] for n in feet]), positions(walk16, feet), atol=1e-9
    )


def test_a_clip_on_its_own_skeleton_is_unchanged(walk16):
    rm = rig_map(walk16.skeleton, walk16.skeleton)
    out = rm.clip(walk16)
    np.testing.assert_allclose(out.joint_positions(), walk16.joint_positions(), atol=1e-9)


def test_another_subject_gets_scaled_root_motion_and_the_same_limb_directions(walk16, walk2):
    rm = rig_map(walk16.skeleton, walk2.skeleton)
    assert rm.convention == ("CMU", "CMU") and rm.unmapped == []
    h16 = retarget.hip_height(walk16.skeleton, 0, [4, 5, 9, 10])
    h2 = retarget.hip_height(walk2.skeleton, 0, [4, 5, 9, 10])
    assert rm.scale == pytest.approx(h2 / h16)
    out = rm.clip(walk16)
    np.testing.assert_allclose(out.root_pos[:, :2], walk16.root_pos[:, :2] * rm.scale)
    # thigh -> knee directions are the source's (the rest poses are aligned)
    s, t = positions(walk16, ["LeftUpLeg", "LeftLeg"]), positions(out, ["LeftUpLeg", "LeftLeg"])
    ds, dt = s[:, 1] - s[:, 0], t[:, 1] - t[:, 0]
    cos = np.sum(ds * dt, axis=1) / np.linalg.norm(ds, axis=1) / np.linalg.norm(dt, axis=1)
    assert cos.min() > 0.9999


def test_arms_resting_down_follow_arms_resting_out(walk16, max16):
    """The 3ds Max conversion rests with its arms down, CMU's straight out: each arm bone
    is aligned to the source's rest direction before the rest-relative rotation."""
    rm = rig_map(walk16.skeleton, max16.skeleton)
    out = rm.clip(walk16)
    s = positions(walk16, ["LeftArm", "LeftForeArm", "LeftHand"])
    t = positions(out, ["LeftShoulder", "LeftElbow", "LeftWrist"])
    for a, b in ((0, 1), (1, 2)):
        ds, dt = s[:, b] - s[:, a], t[:, b] - t[:, a]
        cos = np.sum(ds * dt, axis=1) / np.linalg.norm(ds, axis=1) / np.linalg.norm(dt, axis=1)
        assert cos.min() > 0.9999
    # the legs of this same subject land exactly where the source's do
    np.testing.assert_allclose(
        positions(out, ["LeftToe", "RightAnkle"]),
        positions(walk16, ["LeftToeBase", "RightFoot"]),
        atol=1e-5,
    )


def test_an_unmappable_rig_is_refused_naming_the_patch_bones(walk16):
    rng = np.random.default_rng(1)
    n = len(walk16.skeleton.names)
    odd = renamed(
        walk16.skeleton,
        {b: f"bone_{rng.integers(1e6)}_{i}" for i, b in enumerate(walk16.skeleton.names)},
    )
    with pytest.raises(RetargetError) as e:
        rig_map(walk16.skeleton, odd)
    for b in ("Hips", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "RightUpLeg"):
        assert b in str(e.value)
    assert n == len(odd.names)


def test_a_user_map_pairs_what_the_names_do_not(walk16):
    odd = renamed(walk16.skeleton, {"LeftUpLeg": "thigh_left", "RightUpLeg": "thigh_right"})
    with pytest.raises(RetargetError, match="LeftUpLeg, RightUpLeg"):
        rig_map(walk16.skeleton, odd)
    rm = rig_map(walk16.skeleton, odd, {"LeftUpLeg": "thigh_left", "RightUpLeg": "thigh_right"})
    assert rm.mapping["LeftUpLeg"] == "thigh_left"
    left_out = rig_map(walk16.skeleton, walk16.skeleton, {"LThumb": ""})
    assert "LThumb" in left_out.unmapped and "LThumb" not in left_out.mapping
    with pytest.raises(RetargetError, match="not a bone of the rig"):
        rig_map(walk16.skeleton, odd, {"LeftUpLeg": "nope"})


def test_signature_tells_skeletons_apart(walk16, walk2, max16):
    a = rig_map(walk16.skeleton, walk2.skeleton).signature()
    assert a == rig_map(walk16.skeleton, walk2.skeleton).signature()
    assert a != rig_map(walk16.skeleton, max16.skeleton).signature()


def test_segment_parent_skips_rigify_limb_segments(walk16):
    names = list(walk16.skeleton.names)
    parents = list(walk16.skeleton.parents)
    rest = list(walk16.skeleton.rest)
    i_shin, i_foot = names.index("LeftLeg"), names.index("LeftFoot")
    names.append("LeftLeg.001")  # a segment between the shin and the foot
    parents.append(i_shin)
    rest.append(rest[i_shin])
    parents[i_foot] = len(names) - 1
    skel = Skeleton(names, np.array(parents), np.array(rest))
    assert retarget.segment_parent(skel, i_foot) == i_shin


def test_linear_keys_keep_every_value_within_the_tolerance():
    rng = np.random.default_rng(0)
    t = np.arange(600)
    v = np.column_stack(
        (
            np.sin(t * 0.05),
            np.cumsum(rng.normal(size=600)) * 1e-3,
            np.where(t < 300, 0.0, (t - 300) * 0.01),
            np.zeros(600),
        )
    )
    tol = 1e-5
    keep = keys.linear_keys(v, tol)
    assert keep[0].all() and keep[-1].all()
    for c in range(v.shape[1]):
        k = np.flatnonzero(keep[:, c])
        assert np.abs(np.interp(t, k, v[k, c]) - v[:, c]).max() <= tol
    assert keep[:, 2].sum() < 30 and keep[:, 3].sum() < 15  # straight parts need few keys
    assert keys.plan(v[:, 3], tol)[0] == "constant"
    assert keys.plan(v[:, 2], tol)[0] == "keys"
    assert keys.plan(v[:, 1], tol)[0] == "samples"  # noise: every frame, as samples


def test_piece_bounds_at_another_rate():
    patch, scene = scene_rate.piece_bounds([25, 49, 13], 5.0)
    assert list(patch) == [0, 24, 72, 84] and list(scene) == [0, 120, 360, 420]
    patch, scene = scene_rate.piece_bounds([25, 49, 13], 1.25)
    assert list(scene) == [0, 30, 90, 105]
    u = scene_rate.scene_positions(patch, scene)
    assert u[0] == 0 and u[-1] == 84 and np.all(np.diff(u) > 0)
