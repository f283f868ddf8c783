# SPDX-License-Identifier: GPL-3.0-or-later
"""Long work cancelled part way (Esc in Blender) leaves the scene as it was: a crowd
stopped while its members are planned or after some were written, a bake stopped half way;
the conflicts a crowd is written with can be selected again."""

import bpy
import numpy as np
import pytest
from test_nothing_lost_writes import assert_same, scene_state
from test_ui import draw_panels

from scene_helpers import empty, walker_from


@pytest.fixture
def crowd(walk_blend, addon_module):
    """Three walkers planned once as a crowd (their tracks, actions and plan records
    exist), and three other goals to plan them to again."""
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    src = scene.motion_patches.source_armature
    walkers = [walker_from(src, f"W{k}", (-5.0, 2.0 * k - 2.0, 0.0)) for k in range(3)]
    goals = [empty(f"G{k}", 5.0, 2.0 * k - 2.0, 0.0) for k in range(3)]
    others = [empty(f"H{k}", 4.0, 3.0 - 2.5 * k, -0.5) for k in range(3)]
    bpy.context.view_layer.update()
    addon_module.api.plan_crowd(scene, list(zip(walkers, goals)))
    return scene, walkers, others


def stop_after(reports):
    """(progress, cancelled): cancelled once ``progress`` was called ``reports`` times,
    or, given a fraction, once the progress reached it."""
    seen = []

    def progress(f):
        seen.append(f)

    def cancelled():
        if isinstance(reports, float):
            return bool(seen) and seen[-1] >= reports
        return len(seen) >= reports

    return progress, cancelled, seen


@pytest.mark.parametrize(
    "when", [1, 2, 0.92], ids=["after one member", "after two members", "while writing"]
)
def test_a_crowd_cancelled_part_way_leaves_the_scene_as_it_was(crowd, addon_module, when):
    api = addon_module.api
    scene, walkers, others = crowd
    before = scene_state()
    progress, cancelled, seen = stop_after(when)
    with pytest.raises(api.Cancelled, match="cancelled; the scene was left as it was"):
        api.plan_crowd(scene, list(zip(walkers, others)), progress=progress, cancelled=cancelled)
    assert seen and max(seen) < 1.0  # stopped before the end
    if when == 0.92:
        assert max(seen) > 0.9  # one character was written, then put back
    assert_same(before, scene_state())
    # never cancelled: the same crowd is planned as without the argument
    res = api.plan_crowd(scene, list(zip(walkers, others)), cancelled=lambda: False)
    assert len(res.plans) == 3 and not res.failed
    assert scene_state() != before


def test_the_operators_stepper_runs_the_crowd_in_turns_and_cancels_it(crowd, addon_module):
    """What Plan Crowd does from a button, without the window: the API call run a step at a
    time (each step ends at a progress report), then Esc: the run is stopped, the scene kept."""
    api = addon_module.api
    Stepper = addon_module.operators.common.Stepper
    scene, walkers, others = crowd
    before = scene_state()
    stepper = Stepper(
        lambda progress, cancelled: api.plan_crowd(
            scene, list(zip(walkers, others)), progress=progress, cancelled=cancelled
        )
    )
    stepper.step()
    first = stepper.fraction
    stepper.step()
    assert not stepper.done and 0 < first < stepper.fraction < 0.9
    stepper.cancel()
    assert stepper.done and isinstance(stepper.error, api.Cancelled)
    assert_same(before, scene_state())
    # run to its end, a step at a time: the same as in one go
    stepper = Stepper(
        lambda progress, cancelled: api.plan_crowd(
            scene, list(zip(walkers, others)), progress=progress, cancelled=cancelled
        )
    )
    steps = 0
    while not stepper.done:
        stepper.step()
        steps += 1
    assert stepper.error is None and len(stepper.result.plans) == 3
    assert steps >= 5 and stepper.fraction == 1.0


def test_the_conflicts_left_are_written_and_can_be_selected(walk_blend, addon_module, capfd):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    src = scene.motion_patches.source_armature
    # starting 0.4 m apart with 0.5 m spacing: too close before either moves
    a = walker_from(src, "A", (-5.0, 0.0, 0.0))
    b = walker_from(src, "B", (-5.0, 0.4, 0.0))
    c = walker_from(src, "C", (-5.0, 4.0, 0.0))
    for ob, (x, y) in zip((a, b, c), ((5.0, -3.0), (5.0, 1.5), (5.0, 4.0))):
        ob.motion_patches_character.goal = empty(f"Goal{ob.name}", x, y, 0.0)
    bpy.context.view_layer.update()
    for ob in bpy.context.view_layer.objects:
        ob.select_set(ob in (a, b, c))
    assert bpy.ops.motion_patches.plan_crowd() == {"FINISHED"}
    for ob in (a, b, c):  # what was planned is written, conflicts or not
        assert api.load_plan_record(ob)[0]["frame_end"] > scene.frame_start
    left = api.crowd_conflicts(scene)
    assert left and {(x["a"], x["b"]) for x in left} <= {("A", "B"), ("B", "A")}
    first = min(x["frame"] for x in left)
    said = capfd.readouterr().out  # the operator's reports (printed in background Blender)
    for x in left:  # each pair and frame
        pair, d, f = f"'{x['a']}' and '{x['b']}'", x["distance_m"], x["frame"]
        assert f"{pair} come within {d:.2f} m at frame {f}\n" in said
    assert "Select Conflicts (Planning panel) selects the characters" in said
    button = ("operator", "motion_patches.select_crowd_conflicts")
    assert button in draw_panels(addon_module)["Planning"]
    scene.frame_set(first + 40)
    for ob in bpy.context.view_layer.objects:
        ob.select_set(ob == c)
    assert bpy.ops.motion_patches.select_crowd_conflicts() == {"FINISHED"}
    assert {ob.name for ob in bpy.context.selected_objects} == {"A", "B"}
    assert bpy.context.view_layer.objects.active.name in ("A", "B")
    assert scene.frame_current == first
    # the pair checked on the motion as written: closer than the spacing on that frame
    roots = [np.array(ob.matrix_world.translation[:2]) for ob in (a, b)]
    assert np.linalg.norm(roots[0] - roots[1]) < 2 * scene.motion_patches.radius + 0.01
    # planned again the same: still listed; elsewhere: no longer
    api.plan_path(scene, a, a.motion_patches_character.goal)
    assert api.crowd_conflicts(scene) == left
    api.plan_path(scene, a, empty("Elsewhere", 4.0, -5.0, 0.0))
    assert api.crowd_conflicts(scene) == []
    with pytest.raises(RuntimeError, match="no crowd conflicts"):
        bpy.ops.motion_patches.select_crowd_conflicts()


def test_a_bake_cancelled_half_way_leaves_the_scene_as_it_was(walk_blend, addon_module):
    api = addon_module.api
    bpy.ops.wm.open_mainfile(filepath=str(walk_blend))
    scene = bpy.context.scene
    src = scene.motion_patches.source_armature
    patches = [p.name for p in scene.motion_patches.patches]
    before = scene_state()
    progress, cancelled, seen = stop_after(2)
    with pytest.raises(api.Cancelled, match="the bake was cancelled"):
        api.bake_locomotion_patch(
            scene, src, "16_15", ["16_18"], layer="again", progress=progress, cancelled=cancelled
        )
    assert len(seen) == 2 and seen[-1] < 1.0
    assert [p.name for p in scene.motion_patches.patches] == patches
    assert_same(before, scene_state())
