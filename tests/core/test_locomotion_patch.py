# SPDX-License-Identifier: GPL-3.0-or-later
import numpy as np
import pytest

from motion_patches.kinematics import clip as clipmod
from motion_patches.kinematics import contacts, quat
from motion_patches.patch import serialize
from motion_patches.patch.locomotion_patch import DIRECTIONS, split_node_id
from motion_patches.quality import metrics


def test_bake_reports_kept_and_culled_segments(walk_patch):
    st = walk_patch.stats
    assert st["kept"] == walk_patch.segment_count > 300
    # Candidates: every entry state (node, one of its edge's three inward headings) to every
    # exit state on the three other edges.
    states_per_edge = walk_patch.nodes * 3
    assert st["candidates"] == 4 * states_per_edge * 3 * states_per_edge
    # Each culled candidate counted under the reason that culled it, apart from the count
    # of kept ones ("culled" itself is candidates - kept).
    assert sum(st["culled_by"].values()) == st["candidates"] - st["kept"]


def test_patch_is_about_two_cycles_with_8x8_cells_and_8_nodes(walk_patch, walk_gait):
    assert np.isclose(walk_patch.side, 2 * walk_gait.cycle_distance)
    assert 2.2 < walk_patch.side < 2.9
    assert walk_patch.cells == 8 and walk_patch.nodes == 8


def test_segments_respect_the_gait_curvature_and_stay_inside(walk_patch):
    kmin, kmax = walk_patch.stats["curvature_limits"]
    for seg in range(0, walk_patch.segment_count, 17):
        c = walk_patch.curve(seg)
        assert c.kappa.min() >= kmin - 1e-6 and c.kappa.max() <= kmax + 1e-6
        assert np.all(c.pos >= -1e-6) and np.all(c.pos <= walk_patch.side + 1e-6)


def test_segment_headings_are_45_degree_steps_and_nodes_differ_in_edge(walk_patch):
    e0, _, h0 = split_node_id(walk_patch.seg_entry, walk_patch.nodes)
    e1, _, h1 = split_node_id(walk_patch.seg_exit, walk_patch.nodes)
    assert np.all(e0 != e1)

    # Every segment starts along its entry node's heading and ends along its exit node's
    # (direction d: d * 45 degrees), the headings the ids say, not just some multiple of 45.
    def off(angle, d):
        return np.abs((angle - d * 2 * np.pi / DIRECTIONS + np.pi) % (2 * np.pi) - np.pi)

    first = np.array([walk_patch.curve(k).heading[0] for k in range(len(h0))])
    last = np.array([walk_patch.curve(k).heading[-1] for k in range(len(h1))])
    assert off(first, h0).max() < 1e-6 and off(last, h1).max() < 1e-6
    assert len(np.unique(h0)) > 1  # not every segment along one heading


def test_segment_lasts_whole_cycles_and_ends_on_its_exit_node(walk_patch, walk_gait):
    seg = int(np.argmax(walk_patch.seg_turn > 0.5))
    m = walk_patch.motion(seg)
    assert m.frames == walk_patch.seg_cycles[seg] * walk_gait.frames + 1
    c = walk_patch.curve(seg)
    assert np.allclose(m.ground[-1, :2], c.pos[-1], atol=1e-6)


def test_bitmask_covers_every_cell_the_segment_crosses(walk_patch):
    seg = 11
    c = walk_patch.curve(seg)
    cs = walk_patch.cell_size
    cells = {(int(x // cs), int(y // cs)) for x, y in np.clip(c.pos, 0, walk_patch.side - 1e-9)}
    mask = int(walk_patch.seg_mask[seg])
    assert all(mask >> (j * 8 + i) & 1 for i, j in cells)
    assert bin(mask).count("1") == len(cells)


def test_consecutive_segments_join_without_a_pose_pop(walk_patch):
    a, b = walk_patch.motion(3), walk_patch.motion(40)
    jump = np.degrees(quat.angle_between(a.rotations[-1], b.rotations[0])).max()
    assert jump < 1e-6
    assert np.allclose(a.root_local[-1], b.root_local[0])


def test_straight_segment_skates_no_more_than_the_source_clip(walk_patch, walk_gait, walk16):
    src = clipmod.resample(walk16, walk_gait.fps)
    con, _, _ = contacts.foot_contacts(src)
    fj = contacts.foot_joints(walk16.skeleton)
    floor = metrics.foot_skate(src.joint_positions()[:, fj], src.fps, con)
    straight = [s for s in range(walk_patch.segment_count) if walk_patch.seg_turn[s] < 1e-6]
    assert straight, "the patch must keep straight edge-to-edge segments"
    m = walk_patch.motion(straight[0])
    fp = m.world_matrices(walk16.skeleton)[:, fj][..., :3, 3]
    skate = metrics.foot_skate(fp, walk_gait.fps, m.contacts)
    assert skate["mean_cm_per_s"] <= floor["mean_cm_per_s"] * 1.15


def test_mirrored_turns_are_labelled_as_such(walk_gait):
    assert any("mirrored" in lp.name for lp in walk_gait.loops)
    assert any("mirrored" in n for n in walk_gait.notes)
    k = walk_gait.curvatures
    assert k.min() < -0.5 and k.max() > 0.5 and np.isclose(np.abs(k).min(), 0)


def test_serialized_patch_round_trips(walk_patch):
    back = serialize.patch_from_bytes(serialize.patch_to_bytes(walk_patch))
    assert back.segment_count == walk_patch.segment_count
    assert np.array_equal(back.seg_mask, walk_patch.seg_mask)
    assert np.allclose(back.motion(7).rotations, walk_patch.motion(7).rotations)


def test_garbage_bytes_are_rejected_with_a_message():
    with pytest.raises(ValueError, match="not a stored locomotion patch"):
        serialize.patch_from_bytes(b"not a patch")


def test_gait_rejects_a_clip_without_locomotion(walk16):
    from motion_patches.patch.gait import build_gait

    still = clipmod.Clip(
        "still",
        walk16.skeleton,
        walk16.fps,
        np.repeat(walk16.root_pos[:1], 60, 0),
        np.repeat(walk16.rotations[:1], 60, 0),
    )
    with pytest.raises(ValueError, match="left-foot strike"):
        build_gait("walk", still)
