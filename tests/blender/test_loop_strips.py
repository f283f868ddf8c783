# SPDX-License-Identifier: GPL-3.0-or-later
"""A straight walk is played by the gait's shared loop action: one action for every
character of a rig, repeating strips starting mid-cycle at the walk's own pace, and the
evaluated rig still plays the plan (stored exactly: to float32; compactly: within the
compact keys' tolerance), with the foot lock over it."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, native_rig, pillar, spy_writes, walker_from, world_bone_matrices

# Degrees any bone may turn from the plan with keys stored within 1e-5. Not to float32, as
# test_rotation_modes.py's segments do: a loop strip plays its action between keys (the walk
# is a fraction of a frame off the loop's frames, at a pace a little off its own), where
# Blender interpolates each channel and the plan slerps; where a finger turns 20 degrees in
# one frame (the recorded loop's seam) they differ by 0.09 degrees on a quaternion rig and
# 0.24 on an Euler one. Cubic keys (the default) are fitted against the slerp between frames:
# every bone within their 0.5 degrees.
BETWEEN_DEG = 0.3


@pytest.fixture(scope="module", params=["linear", "compact"])
def walked(request, walk_blend, addon_module, mocap_dir):
    """Two walkers planned 12 m ahead round a pillar each, in the session's 30 fps scene
    (the patch's rate), evaluated on every frame; ``expected``: the world matrices of the
    plan itself (locked), from what api.plan_path hands to nla.write_plan."""
    api, nla, act_io = addon_module.api, addon_module.adapter.nla, addon_module.adapter.actions
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    assert scene.render.fps == 30
    source = bpy.data.objects["Source"]
    rigs = [walker_from(source, "A", (0.4, 0.3, 0.0)), walker_from(source, "B", (0.4, 3.3, 0.0))]
    # and Blender's own BVH import of the subject, its bones in Euler angles (ZYX)
    rigs.append(native_rig(mocap_dir, "cmu/16_15.bvh", "Euler"))
    rigs[-1].location = (0.4, 6.3, 0.0)
    goals = [empty(f"Goal{r.name}", 12.4, 2.3 + 3.0 * n, 0.0) for n, r in enumerate(rigs)]
    for n, r in enumerate(rigs):  # a pillar on each way: walked round, not through tiles
        pillar(f"Pillar{n}", 6.4, 1.3 + 3.0 * n)
    with pytest.MonkeyPatch.context() as mp:
        written = spy_writes(mp, addon_module)
        if request.param == "linear":
            mp.setattr(act_io, "COMPACT", act_io.LINEAR_TOL)
        results = [api.plan_path(scene, r, g, frame_start=1) for r, g in zip(rigs, goals)]
    out = {"rigs": rigs, "results": results, "storage": request.param, "expected": {}}
    for r, res in zip(rigs, results):
        # the foot lock is on by default (the plan written is the locked motion)
        assert nla.TRACK_FOOT in [t.name for t in r.animation_data.nla_tracks]
        skel, out["expected"][r.name] = written[r.name]
        frames = np.arange(res.frame_start, res.frame_end + 1)
        out.setdefault("frames", {})[r.name] = frames
        out["mats"] = {**out.get("mats", {}), **world_bone_matrices([r], frames, skel.names)}
    out["skel"] = skel
    return out


def _loop_strips(rig, nla):
    track = rig.animation_data.nla_tracks[nla.TRACK_MOTION]
    return [s for s in track.strips if ":loop" in str(s.action.get(nla.SEGMENT_KEY, ""))]


def test_a_straight_walk_plays_one_shared_loop_action(walked, addon_module):
    nla = addon_module.adapter.nla
    loops = {r.name: _loop_strips(r, nla) for r in walked["rigs"]}
    actions = {s.action for strips in loops.values() for s in strips}
    # one action for both characters of a rig, another for the Euler rig (its own channels)
    assert {s.action for s in loops["A"]} == {s.action for s in loops["B"]}
    assert len(actions) == 2, actions
    assert {a.name for a in bpy.data.actions if a.name.startswith("MP walk loop")} == {
        "MP walk loop",
        "MP walk loop ZYX",
    }
    for r, res in zip(walked["rigs"], walked["results"]):
        strips = loops[r.name]
        assert strips, r.name
        covered = sum(s.frame_end - s.frame_start for s in strips)
        # most of a straight walk: all but the start, the stop and the frames round them
        assert covered >= 0.5 * (res.frame_end - res.frame_start), (covered, res.frame_end)
        assert max(s.repeat for s in strips) > 1.0
        # its own body action keys only the frames the loop does not play
        body = rig_body(r, nla)
        length = body.frame_range[1] - body.frame_range[0]
        assert length <= (res.frame_end - res.frame_start) - covered + len(strips) + 2


def test_a_straight_segment_plays_the_loop_action(walked, addon_module):
    """A segment whose motion is the straight loop's (loop_strips.loop_segments) plays the
    shared loop action: no action of its own holds the same keys again; another segment
    keeps its own."""
    nla, storage = addon_module.adapter.nla, addon_module.adapter.storage
    loop_strips = addon_module.motion_patches.kinematics.loop_strips
    scene = bpy.context.scene
    patch, key = storage.load_patch(scene, "walk"), storage.patch_key(scene, "walk")
    skel = patch.gait.skeleton
    straight = loop_strips.loop_segments(patch)
    loop, _ = nla.loop_action(bpy, patch, key, skel)
    for seg in straight:
        assert nla.segment_action(bpy, patch, key, seg, skel)[0] == loop
    assert loop.name == "MP walk loop"
    keys = {a.get(nla.SEGMENT_KEY) for a in bpy.data.actions}
    assert not keys & {f"{key}:{seg}" for seg in straight}
    other = next(s for s in range(patch.segment_count) if s not in straight)
    own = nla.segment_action(bpy, patch, key, other, skel)[0]
    assert own != loop and own[nla.SEGMENT_KEY] == f"{key}:{other}"


def test_the_loop_action_keys_one_cycle_its_curves_repeat(walked, addon_module):
    """The shared loop action keys one cycle and a frame, every curve of more than one
    point repeating it (a Cycles modifier), and strips play a cycle from mid-cycle on,
    past the frames it keys (the evaluated rig is checked against the plan below)."""
    nla = addon_module.adapter.nla
    compat = addon_module.adapter.compat
    strips = [s for r in walked["rigs"] for s in _loop_strips(r, nla)]
    for action in {s.action for s in strips}:
        cycle = action[nla.CYCLE_KEY]
        assert action.frame_range[1] - action.frame_range[0] == pytest.approx(cycle)
        for fc in compat.fcurves(action):
            many = len(fc.keyframe_points) + len(fc.sampled_points) > 1
            assert [m.type for m in fc.modifiers] == (["CYCLES"] if many else []), fc.data_path
    assert any(s.action_frame_end > s.action[nla.CYCLE_KEY] + 1 for s in strips)


def test_a_two_cycle_loop_action_made_before_is_played_as_it_is(walk_blend, addon_module, tmp_path):
    """A file whose loop action keys two cycles (made before the loop action was one cycle)
    goes on playing it: no Cycles modifier added, the strips within its frames, and the
    evaluated rig plays the plan within the compact keys' 0.5 degrees."""
    api, nla, storage = addon_module.api, addon_module.adapter.nla, addon_module.adapter.storage
    loop_strips = addon_module.motion_patches.kinematics.loop_strips
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    patch, key = storage.load_patch(scene, "walk"), storage.patch_key(scene, "walk")
    old, _ = nla._shared_action(
        bpy,
        patch,
        f"{key}:loop",
        "loop",
        patch.gait.skeleton,
        {},
        None,
        None,
        1.0,
        lambda: loop_strips.straight_loop(patch.gait),
    )
    source = bpy.data.objects["Source"]
    rig = walker_from(source, "Old", (0.4, 0.3, 0.0))
    goal = empty("GoalOld", 12.4, 2.3, 0.0)
    with pytest.MonkeyPatch.context() as mp:
        written = spy_writes(mp, addon_module)
        res = api.plan_path(scene, rig, goal, frame_start=1)
    strips = _loop_strips(rig, nla)
    assert strips and {s.action for s in strips} == {old}
    assert nla.CYCLE_KEY not in old
    assert not any(fc.modifiers for fc in addon_module.adapter.compat.fcurves(old))
    assert all(s.action_frame_end <= old.frame_range[1] + 1e-3 for s in strips)
    skel, want = written[rig.name]
    frames = np.arange(res.frame_start, res.frame_end + 1)
    got = world_bone_matrices([rig], frames, skel.names)[rig.name]
    a, b = _local_angles(got, skel), _local_angles(want, skel)
    cos = (np.trace(np.swapaxes(a, -1, -2) @ b, axis1=-2, axis2=-1) - 1.0) / 2.0
    assert np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))).max() < 0.5 + 0.01


def rig_body(rig, nla):
    track = rig.animation_data.nla_tracks[nla.TRACK_MOTION]
    (body,) = {s.action for s in track.strips if s.action.get(nla.SEGMENT_KEY) is None}
    return body


def _local_angles(mats, skel):
    """(F, B) each bone's rotation relative to its parent's, as an angle (degrees) from
    the other matrix set's: what a bone plays, whatever the bones above it do."""
    rot = mats[..., :3, :3] / np.linalg.norm(mats[..., :3, 0], axis=-1)[..., None, None]
    par = np.where(skel.parents < 0, np.arange(len(skel.parents)), skel.parents)
    local = np.swapaxes(rot[:, par], -1, -2) @ rot
    local[:, skel.parents < 0] = rot[:, skel.parents < 0]
    return local


def test_the_evaluated_rig_plays_the_plan_over_its_loop_strips(walked):
    skel = walked["skel"]
    for r in walked["rigs"]:
        got, want = walked["mats"][r.name], walked["expected"][r.name]
        a, b = _local_angles(got, skel), _local_angles(want, skel)
        cos = (np.trace(np.swapaxes(a, -1, -2) @ b, axis1=-2, axis2=-1) - 1.0) / 2.0
        deg = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
        print(f"{r.name}, {walked['storage']} keys: worst bone {deg.max():.3f} deg from the plan")
        if walked["storage"] == "linear":
            assert deg.max() < BETWEEN_DEG, (r.name, deg.max())
            continue
        assert deg.max() < 0.5 + 0.01, (r.name, deg.max())
        hips = np.linalg.norm(got[:, skel.root, :3, 3] - want[:, skel.root, :3, 3], axis=-1)
        assert hips.max() < 1.5e-3, (r.name, hips.max())


def test_the_foot_lock_plays_only_where_it_changes_something(addon_module):
    nla = addon_module.adapter.nla
    v = np.zeros((40, 3))
    v[[3, 4, 5, 7, 20, 39], 1] = 0.1  # 6 -> 7: a gap of one frame; 20 alone; the last frame
    assert nla.lock_spans(v, 40) == [(3, 7), (20, 21), (38, 39)]
    v[10, 0] = 0.1  # 7 -> 10: a gap of LOCK_GAP frames, one strip
    assert nla.LOCK_GAP == 2 and nla.lock_spans(v, 40)[0] == (3, 10)
    assert nla.lock_spans(np.zeros((40, 3)), 40) == [(0, 39)]  # nothing: one strip, as before
    assert nla.lock_spans(None, 40) == [(0, 39)]


def test_the_walkers_feet_lock_over_the_loop(walked, addon_module):
    """The foot lock track of a walker has several strips (the loop's stretches, not the
    frames its body action plays locked already), none holding its last frame over a gap."""
    nla = addon_module.adapter.nla
    for r in walked["rigs"]:
        strips = list(r.animation_data.nla_tracks[nla.TRACK_FOOT].strips)
        assert len(strips) >= 2, r.name
        assert all(s.blend_type == "ADD" for s in strips)
        assert all(s.extrapolation == "NOTHING" for s in strips[:-1])
        loops = _loop_strips(r, nla)
        for lp in loops:  # the lock corrects the legs the loop plays
            assert any(
                s.frame_start < lp.frame_end and s.frame_end > lp.frame_start for s in strips
            ), (r.name, lp.name)


def test_no_pop_where_a_loop_strip_meets_the_body(walked, addon_module):
    """The plan record lists every strip's start (its pieces' and their loop stretches'),
    and the analysis finds no joint jumping there more than anywhere else."""
    api, nla = addon_module.api, addon_module.adapter.nla
    for r in walked["rigs"]:
        meta, _ = api.load_plan_record(r)
        track = r.animation_data.nla_tracks[nla.TRACK_MOTION]
        starts = sorted(int(round(s.frame_start)) for s in track.strips)
        assert meta["joins"] == starts[1:] and len(meta["joins"]) > len(meta["boundaries"])
        pop = api.analyse(bpy.context, r)["boundary_pop"]
        print(f"{r.name}: largest jump where strips meet {pop['max_boundary_jump_deg']:.2f} deg")
        assert pop["max_boundary_jump_deg"] < pop["p99_step_deg"], (r.name, pop)


def test_a_scene_twice_the_patchs_rate_keys_its_own_frames_and_plays_the_plan(
    walk_blend, addon_module
):
    """In a 60 fps scene from the 30 fps patch the walker's own pieces are keyed on the
    scene's frames with its feet locked (unscaled body strips, the shared loop action over
    its straight walking), and the evaluated rig plays the plan written: every bone within
    the compact keys' 0.5 degrees of its parent, the hips within 1.5 mm."""
    api, nla = addon_module.api, addon_module.adapter.nla
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 60, 1.0
    rig = walker_from(bpy.data.objects["Source"], "Fast", (0.4, 0.3, 0.0))
    goal = empty("GoalFast", 12.4, 2.3, 0.0)
    with pytest.MonkeyPatch.context() as mp:
        written = spy_writes(mp, addon_module)
        res = api.plan_path(scene, rig, goal, frame_start=1)
    track = rig.animation_data.nla_tracks[nla.TRACK_MOTION]
    body = rig_body(rig, nla)
    own = [s for s in track.strips if s.action == body]
    assert own and all(s.scale == pytest.approx(1.0) for s in own)
    assert _loop_strips(rig, nla)
    skel, want = written[rig.name]
    frames = np.arange(res.frame_start, res.frame_end + 1)
    got = world_bone_matrices([rig], frames, skel.names)[rig.name]
    a, b = _local_angles(got, skel), _local_angles(want, skel)
    cos = (np.trace(np.swapaxes(a, -1, -2) @ b, axis1=-2, axis2=-1) - 1.0) / 2.0
    deg = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    assert deg.max() < 0.5 + 0.01, deg.max()
    hips = np.linalg.norm(got[:, skel.root, :3, 3] - want[:, skel.root, :3, 3], axis=-1)
    assert hips.max() < 1.5e-3, hips.max()
