# SPDX-License-Identifier: GPL-3.0-or-later
"""How much one planned walk adds to a saved .blend (issue 15, item 6).

Bakes the demo's walk patch (CMU 16_15 + 16_18) at ``--bake-fps``, sets the scene to
``--scene-fps``, saves the file, plans one walker about ``--seconds`` of walking away
(open ground: the goal straight ahead, a little to the side), saves again and prints the
growth, with the keys and samples of each action the plan wrote. Files are saved
uncompressed (Blender 4.5's default; 5.x compresses by default, which shrinks them far
more).

    .venv/blender-4.5/bin/python tools/file_size.py                    # 30 fps patch, 120 fps scene
    .venv/blender-4.5/bin/python tools/file_size.py --bake-fps 120     # a patch baked at 120 fps
"""

import argparse
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_session  # noqa: E402

MOCAP = Path(
    os.environ.get("MOTION_PATCHES_MOCAP", Path(__file__).resolve().parents[2] / "shared" / "mocap")
)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bake-fps", type=int, default=30)
    ap.add_argument("--scene-fps", type=int, default=120)
    ap.add_argument("--seconds", type=float, default=30.0)
    args = ap.parse_args(argv)
    bpy, addon = blender_session.start()
    api, compat = addon.api, addon.adapter.compat
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = args.bake_fps
    arm, acts = api.import_mocap(
        [MOCAP / "cmu" / "16_15.bvh", MOCAP / "cmu" / "16_18.bvh"], name="Source"
    )
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    patch = addon.adapter.storage.load_patch(scene)
    speed = patch.gait.cycle_distance * patch.gait.fps / patch.gait.frames
    scene.render.fps = args.scene_fps
    walker = arm.copy()
    walker.name = "Walker"
    walker.animation_data_clear()
    scene.collection.objects.link(walker)
    tmp = Path(tempfile.mkdtemp(prefix="motion_patches-size-"))
    before, after = tmp / "before.blend", tmp / "after.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(before), compress=False)
    actions_before = set(bpy.data.actions)
    goal = bpy.data.objects.new("Goal", None)
    scene.collection.objects.link(goal)
    d = speed * args.seconds * 0.95  # starts and stops are slower than the stride
    goal.location = (0.3 * d, -0.95 * d, 0.0)  # the rig faces -Y
    goal.rotation_euler = (0.0, 0.0, 0.3)
    res = api.plan_path(scene, walker, goal, frame_start=1)
    bpy.ops.wm.save_as_mainfile(filepath=str(after), compress=False)
    grown = (after.stat().st_size - before.stat().st_size) / 1e6
    seconds = (res.frame_end - res.frame_start) / args.scene_fps
    print(
        f"Blender {bpy.app.version_string}: patch baked at {args.bake_fps} fps, scene at "
        f"{args.scene_fps} fps"
    )
    print(f"plan: {seconds:.1f} s of walking, {len(res.pieces)} pieces ({', '.join(res.pieces)})")
    for a in sorted(set(bpy.data.actions) - actions_before, key=lambda a: a.name):
        fcs = compat.fcurves(a)
        nkeys = sum(len(fc.keyframe_points) for fc in fcs)
        nsamp = sum(len(fc.sampled_points) for fc in fcs)
        print(
            f"  {a.name:32s} {len(fcs):4d} curves {nkeys:7d} keys {nsamp:8d} samples"
            f"  ~{(72 * nkeys + 16 * nsamp) / 1e6:5.2f} MB"
        )
    print(
        f"the .blend grows {grown:.2f} MB ({grown / seconds * 30:.2f} MB per 30 s), "
        f"uncompressed; {before.stat().st_size / 1e6:.2f} MB before"
    )
    for p in (before, after):
        p.unlink()
    tmp.rmdir()
    return 0


if __name__ == "__main__":
    sys.exit(main())
