# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np

from motion_patches.kinematics import clip as clipmod
from motion_patches.kinematics import quat
from motion_patches.kinematics.inplace import facing_yaw, to_inplace, to_world
from motion_patches.patch.cycle import cycle_turns, detect_cycles


def test_quaternion_matrix_round_trip():
    rng = np.random.default_rng(0)
    q = quat.normalize(rng.normal(size=(200, 4)))
    q[q[:, 0] < 0] *= -1
    assert np.allclose(quat.from_matrix(quat.to_matrix(q)), q, atol=1e-9)


def test_slerp_hits_both_ends_and_halves_the_angle():
    a = quat.about_z(0.0)
    b = quat.about_z(1.0)
    assert np.allclose(quat.slerp(a, b, 0.0), a)
    assert np.allclose(quat.slerp(a, b, 1.0), b)
    assert np.isclose(quat.angle_between(a, quat.slerp(a, b, 0.5)), 0.5)


def test_bvh_reader_matches_blender_importer_positions(walk16):
    # Values printed by Blender 4.5's bundled BVH importer (global_scale 0.056444) at frame 10.
    p = walk16.joint_positions()[9]
    skel = walk16.skeleton
    assert np.allclose(p[skel.index("Hips")], [0.07395, 1.40746, 0.98513], atol=2e-4)
    assert np.allclose(p[skel.index("LeftFoot")], [0.10061, 1.22068, 0.08159], atol=2e-4)


def test_walk_cycle_matches_the_clip_documentation(walk16):
    # SOURCES-cmu.txt: 16_15 walks 4.28 m in 3.91 s at 1.10 m/s.
    info = detect_cycles(walk16)
    assert 1.0 < info.period < 1.3
    assert abs(info.speed - 1.10) < 0.06
    assert np.all(np.abs(np.degrees(cycle_turns(walk16, info))) < 8)


def test_turn_clip_turns_left_about_ninety_degrees(turn16):
    yaw = facing_yaw(turn16)
    total = np.degrees(np.median(yaw[-10:]) - np.median(yaw[:10]))
    assert 70 < total < 100


def test_mirror_turns_the_other_way_and_twice_is_identity(turn16):
    m = clipmod.mirror(turn16)
    yaw, myaw = facing_yaw(turn16), facing_yaw(m)
    assert np.isclose(myaw[-1] - myaw[0], -(yaw[-1] - yaw[0]), atol=np.radians(1))
    mm = clipmod.mirror(m)
    assert np.allclose(mm.joint_positions(), turn16.joint_positions(), atol=1e-6)


def test_mirror_swaps_left_and_right_foot_positions(walk16):
    m = clipmod.mirror(walk16)
    skel = walk16.skeleton
    lat = clipmod.lateral_axis(skel)
    left, right = skel.index("LeftFoot"), skel.index("RightFoot")
    p, pm = walk16.joint_positions(), m.joint_positions()
    # The mirrored right foot is the reflection of the original left foot, up to the
    # subject's own left/right bone-length difference (a few millimetres in CMU 16).
    reflect = pm[:, right] - 2 * np.outer(pm[:, right] @ lat, lat)
    assert np.abs(reflect - p[:, left]).max() < 0.01


def test_in_place_split_reassembles_the_world_motion(walk16):
    ground = np.column_stack((walk16.root_pos[:, :2] * 0.9, np.linspace(0, 1, walk16.frames)))
    local, rot = to_inplace(walk16, ground)
    pos, rot2 = to_world(walk16.skeleton, ground, local, rot)
    back = clipmod.Clip("back", walk16.skeleton, walk16.fps, pos, rot2)
    assert np.allclose(back.joint_positions(), walk16.joint_positions(), atol=1e-6)


def test_resample_keeps_duration_and_positions(walk16):
    r = clipmod.resample(walk16, 30)
    assert abs(r.duration - walk16.duration) < 1 / 30
    assert np.allclose(r.root_pos[10], walk16.root_pos[40], atol=1e-3)
