# SPDX-License-Identifier: GPL-3.0-or-later
"""The two-gait scene: walk and run patches of CMU subject 16 and a line of chairs whose
hurdle only the run layer takes; the walker planned with gait "auto" (walk, run through the
line, walk to the goal). Saves sample_blends/gaits_demo.blend for tools/render_demo.py
(``--blend sample_blends/gaits_demo.blend --view gaits``) and prints what was chosen.

    .venv/blender-4.5/bin/python tools/gaits_demo.py [--mocap DIR]

Built as a user builds it: Blender's BVH importer through the add-on (16_15, 16_18 and
16_06 in CMU naming; the runs 16_35 and 16_53 in 3ds Max naming imported onto the walk's
armature), boxes as chairs, the goal an empty. 16_06 is a standing forward jump, the one
jump subject 16 recorded: it stands in for a run hurdle (there is none in the shared mocap)
and is declared a run-layer clip, so the walk has to go round the line.
"""

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import blender_session  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
LINE_X, START_X, GOAL_X, Y = 5.0, -4.0, 14.0, 0.3


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mocap", default=str(REPO.parent / "shared" / "mocap"))
    p.add_argument("--out", default=str(REPO / "sample_blends" / "gaits_demo.blend"))
    args = p.parse_args(argv)
    mocap = Path(args.mocap)
    bpy, addon = blender_session.start()
    import numpy as np

    api = addon.api
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap(
        [mocap / "cmu" / "16_15.bvh", mocap / "cmu" / "16_18.bvh", mocap / "cmu" / "16_06.bvh"],
        name="Source",
    )
    walk = api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    _, runs = api.import_mocap(
        [mocap / "cmu16max" / "16_35.bvh", mocap / "cmu16max" / "16_53.bvh"], armature=arm
    )
    run = api.bake_locomotion_patch(scene, arm, runs[0], [runs[1]], layer="run")
    scene.motion_patches.source_armature = arm
    for k, y in enumerate(np.linspace(-5.0, 5.0, 21)):
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=(LINE_X, y, 0.075))
        chair = bpy.context.object
        chair.name, chair.scale = f"Chair.{k:02d}", (0.4, 0.44, 0.15)  # 16_06 clears it
        api.tag_object_patch(chair, [(acts[2], "TRAVERSAL", 8.0, 10.0)], patch_name="walk")
        for c in chair.motion_patch.clips:
            c.layer_in = c.layer_out = "run"
    walker = arm.copy()
    walker.name = "Walker"
    walker.animation_data_clear()
    scene.collection.objects.link(walker)
    walker.location = (START_X, Y, 0.0)
    walker.rotation_euler = (0.0, 0.0, np.pi / 2)  # the rig's rest faces -Y: face +X
    goal = bpy.data.objects.new("Goal", None)
    scene.collection.objects.link(goal)
    goal.location = (GOAL_X, Y, 0.0)
    goal.rotation_euler = (0.0, 0.0, np.pi / 2)  # facing +X, the way in
    scene.motion_patches.goal = goal
    bpy.context.view_layer.update()
    res = api.plan_path(scene, walker, goal, gait="auto", frame_start=1)
    f = api.analyse(bpy.context, walker)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(Path(args.out).resolve()))
    print()
    print(f"gaits demo (Blender {bpy.app.version_string})")
    print(f"  bake: walk {walk.seconds:.1f} s, run {run.seconds:.1f} s")
    costs = ", ".join(f"{k} {v:.2f}" for k, v in res.stats["layers"].items())
    print(f"  Eq. 5 cost of the motion played: {costs}; chosen: {res.stats['layer']}")
    print(f"  strips: {', '.join(res.pieces)}")
    skate = f.get("foot_skate_by_layer") or {}
    for layer, s in skate.items():
        print(f"  foot skate while planted, {layer}: {s['mean_cm_per_frame'] * 30:.1f} cm/s")
    print(
        f"  goal error {f['goal_root_position_error_cm']:.1f} cm, "
        f"{f['goal_heading_error_deg']:.1f} deg; root inside a chair outside the jump: "
        f"{f['frames_root_inside_obstacle'] - f['frames_root_over_prop_in_traversal']} frames"
    )
    print(f"  saved {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
