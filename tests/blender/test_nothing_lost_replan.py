# SPDX-License-Identifier: GPL-3.0-or-later
"""Re-planning from another frame keeps the start: a character planned once and re-planned
with the timeline mid-walk starts again where it stood before it was planned (its evaluated
position on the first frame), through the operator and the API with ``frame_start=1``;
"from here" (the operator's From Current Frame, the CLI's --from-here) starts where it is."""

import bpy
import numpy as np
import pytest

from scene_helpers import empty, walker_from

START = (0.4, 0.3, 0.0)


@pytest.fixture
def planned(mp, walk_blend):
    """Walker planned from START at frame 1 to a goal 6 m away; the timeline then at 100."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    scene.frame_set(1)
    walker = walker_from(scene.motion_patches.source_armature, location=START)
    goal = empty("Goal", 6.0, 0.3, -90.0)
    scene.motion_patches.goal = goal
    res = mp.api.plan_path(scene, walker, goal, frame_start=1)
    scene.frame_set(res.frame_start + (res.frame_end - res.frame_start) // 2)
    return scene, walker, goal


def hips_at(scene, walker, frame):
    """World (x, y) of the evaluated root bone's head at ``frame``."""
    scene.frame_set(frame)
    ev = walker.evaluated_get(bpy.context.evaluated_depsgraph_get())
    root = ev.pose.bones[0]
    return np.array(ev.matrix_world @ root.head)[:2]


def first_ground(mp, walker):
    return np.array(mp.api.load_plan_record(walker)[1]["ground"][0][:2])


def test_replanning_mid_walk_with_the_api_starts_where_it_stood(mp, planned):
    scene, walker, goal = planned
    before = hips_at(scene, walker, 1)
    start = first_ground(mp, walker)
    scene.frame_set(120)
    mid = hips_at(scene, walker, 120)
    assert np.linalg.norm(mid - before) > 1.0  # the timeline is mid-walk
    mp.api.plan_path(scene, walker, goal, frame_start=1)
    assert np.allclose(first_ground(mp, walker), start, atol=1e-6)
    assert np.linalg.norm(hips_at(scene, walker, 1) - before) < 0.001


def test_replanning_mid_walk_with_the_operator_starts_where_it_stood(mp, planned):
    scene, walker, goal = planned
    before = hips_at(scene, walker, 1)
    scene.frame_set(120)
    bpy.context.view_layer.objects.active = walker
    assert bpy.ops.motion_patches.plan_path() == {"FINISHED"}
    # The plan starts at the current frame, from where the character stood.
    rec = mp.api.load_plan_record(walker)[0]
    assert rec["frame_start"] == 120
    assert np.linalg.norm(hips_at(scene, walker, 120) - before) < 0.001
    assert np.linalg.norm(hips_at(scene, walker, 1) - before) < 0.001  # held before it


def test_from_here_continues_from_the_current_frame(mp, planned):
    scene, walker, goal = planned
    scene.frame_set(120)
    mid = hips_at(scene, walker, 120)
    bpy.context.view_layer.objects.active = walker
    assert bpy.ops.motion_patches.plan_path(from_here=True) == {"FINISHED"}
    assert np.linalg.norm(hips_at(scene, walker, 120) - mid) < 0.05


def test_the_cli_has_from_here(mp, planned, capsys):
    scene, walker, goal = planned
    scene.frame_set(120)
    mid = hips_at(scene, walker, 120)
    code = mp.cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--from-here"])
    assert code == 0, capsys.readouterr()
    assert np.linalg.norm(hips_at(scene, walker, 120) - mid) < 0.05


@pytest.mark.parametrize("frame", [1.5, True])
def test_a_start_frame_that_is_not_a_whole_number_is_refused(mp, planned, frame):
    scene, walker, goal = planned
    with pytest.raises(mp.api.MotionPatchesError, match="whole number"):
        mp.api.plan_path(scene, walker, goal, frame_start=frame)


# --- what the add-on made, known by id ------------------------------------------------------


def own_actions(walker):
    ad = walker.animation_data
    return [s.action for t in ad.nla_tracks if t.name.startswith("MP ") for s in t.strips]


def test_a_user_s_copy_of_an_add_on_action_is_never_deleted(mp, planned):
    scene, walker, goal = planned
    root = walker.animation_data.nla_tracks["MP root"]
    mine = root.strips[0].action.copy()
    mine.name = "my root edit"
    spare = root.strips[0].action.copy()
    spare.name = "my spare"  # not played by any strip: no user
    strip = root.strips.new("my strip", 2000, mine)
    with pytest.raises(mp.api.MotionPatchesError, match="my strip"):
        mp.api.plan_path(scene, walker, goal, frame_start=1)
    assert bpy.data.actions.get("my root edit") is mine and root.strips.get("my strip")
    # Moved to a track of the user's own, a re-plan replaces only what the add-on made.
    root.strips.remove(strip)
    walker.animation_data.nla_tracks.new().strips.new("my strip", 2000, mine)
    made = {a.name for a in own_actions(walker)}
    mp.api.plan_path(scene, walker, goal, frame_start=1)
    assert bpy.data.actions.get("my root edit") is mine
    assert bpy.data.actions.get("my spare") is spare and spare.users == 0
    left = {a.name for a in bpy.data.actions if a.users == 0} - {"my spare"}
    assert not left & made - {a.name for a in own_actions(walker)}, left


def test_a_renamed_character_is_planned_again_over_its_own_strips(mp, planned):
    scene, walker, goal = planned
    old = {a.name for a in own_actions(walker) if a.get("motion_patches_segment") is None}
    assert old and all("Walker" in n for n in old)
    walker.name = "Hero"
    res = mp.api.plan_path(scene, walker, goal, frame_start=1)
    assert res.frame_end > res.frame_start
    assert not old & {a.name for a in bpy.data.actions}  # replaced, none left behind


def test_a_re_plan_drops_the_last_plan_s_analysis(mp, planned):
    """The Analysis panel must not show the figures of a plan that is gone."""
    scene, walker, goal = planned
    mp.api.analyse(bpy.context, walker, keep=True)
    assert mp.api.last_analysis(walker) is not None
    mp.api.plan_path(scene, walker, goal, frame_start=1)
    assert mp.api.last_analysis(walker) is None


def test_a_long_plan_on_the_command_line_says_it_still_works(mp, planned, capsys, monkeypatch):
    """A 2 km plan took minutes without a word: the CLI says every few seconds that it still
    plans (here every 0.05 s, the plan slowed to 0.3 s)."""
    import time as _time

    plan_path = mp.api.plan_path

    def slow(*a, **kw):
        _time.sleep(0.3)
        return plan_path(*a, **kw)

    monkeypatch.setattr(mp.cli.output, "HEARTBEAT_S", 0.05)
    monkeypatch.setattr(mp.api, "plan_path", slow)
    code = mp.cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--frame-start", "1"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "plan 'Walker': still working" in err
    code = mp.cli.main(["plan", "--character", "Walker", "--goal", "Goal", "--json"])
    out, err = capsys.readouterr()
    assert code == 0 and "still working" not in err  # --json: stdout and stderr stay quiet


def test_a_character_planned_before_ids_were_kept_has_its_old_actions_replaced(mp, planned):
    """A character whose record keeps no action ids (planned by an earlier version): its
    old actions are found by their name tag and replaced by a re-plan; an action of the
    user's with no user of its own stays."""
    scene, walker, goal = planned
    nla = mp.adapter.nla
    old = [a for a in own_actions(walker) if a.get(nla.SEGMENT_KEY) is None]
    assert old and all(a.get(nla.CHARACTER_KEY) == walker.name for a in old)
    for a in old:
        a["made before"] = True
    del walker[nla.ACTIONS_KEY]
    spare = bpy.data.actions.new("my spare action")
    mp.api.plan_path(scene, walker, goal, frame_start=1)
    left = [a.name for a in bpy.data.actions if a.get("made before")]
    assert not left, left
    assert bpy.data.actions.get("my spare action") is spare and spare.users == 0
    assert nla.ACTIONS_KEY in walker  # ids kept again
