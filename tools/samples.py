# SPDX-License-Identifier: GPL-3.0-or-later
"""Build the ready sample scenes in ``samples/``: open one, select a character, Plan Path.

Run with ``.venv/blender-4.5/bin/python tools/samples.py`` (Blender 4.5, the oldest supported
version, so 4.5, 5.0 and 5.2 all open the files; tests/blender/test_samples.py opens and plans
each one on every supported version). Nothing is planned in the files: what a user starts
from, not a result.

* ``samples/props.blend``: the walk patch baked from CMU subject 16 (16_15 straight, 16_18
  turns); a line of low hurdles tagged with the standing jump 16_06 (which clears them); two
  chairs tagged with subject 13's sit-down and stand-up (13_05, retargeted onto subject 16);
  pillars; ``Walker`` with ``Goal`` across the hurdles; ``Sitter`` on ``Chair A`` whose goal is
  ``Chair B`` and whose Start Prop is ``Chair A`` (set the Goal to ``Chair B``, Plan Path: it
  stands up, walks and sits down).
* ``samples/crowd.blend``: the same patch, a plaza of pillars and twelve walkers crossing it
  in two groups, each with its own goal (select them all, Plan Crowd).
"""

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_session  # noqa: E402

REPO = blender_session.REPO_ROOT
HURDLE = (0.4, 0.44, 0.15)  # a chair's footprint, 15 cm high: 16_06 clears it
CHAIR = (0.45, 0.45, 0.45)


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
        help="folder holding cmu/16_15.bvh, 16_18, 16_06, 13_05, 13_05_standup",
    )
    p.add_argument("--out", default=str(REPO / "samples"))
    return p.parse_args(argv)


def box(bpy, name, x, y, size):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, size[2] / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = size
    return ob


def pillar(bpy, name, x, y, r=0.25):
    bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=2.5, location=(x, y, 1.25))
    bpy.context.object.name = name


def character(bpy, source, name, x, y, heading):
    """A copy of the source armature standing at (x, y) facing ``heading`` (radians from +X;
    the rig's rest faces -Y)."""
    import math

    ob = source.copy()
    ob.name = name
    ob.animation_data_clear()
    bpy.context.scene.collection.objects.link(ob)
    ob.hide_set(False)
    ob.location = (x, y, 0.0)
    ob.rotation_euler = (0.0, 0.0, heading + math.pi / 2)
    return ob


def goal(bpy, name, x, y, heading):
    """An empty facing ``heading`` with its -Y axis, as goals face."""
    import math

    ob = bpy.data.objects.new(name, None)
    ob.empty_display_type = "SINGLE_ARROW"
    bpy.context.scene.collection.objects.link(ob)
    ob.location = (x, y, 0.0)
    ob.rotation_euler = (0.0, 0.0, heading + math.pi / 2)
    return ob


def baked(bpy, api, mocap, extra=()):
    """A fresh 30 fps scene with the walk patch baked; returns (source armature, actions)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    cmu = mocap / "cmu"
    files = [cmu / "16_15.bvh", cmu / "16_18.bvh", *(cmu / f"{n}.bvh" for n in extra)]
    arm, acts = api.import_mocap(files, name="CMU16 source")
    s = scene.motion_patches
    s.source_armature, s.straight_action = arm, acts[0]
    s.turn_actions.add().action = acts[1]
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    arm.hide_set(True)
    bpy.ops.mesh.primitive_plane_add(size=40, location=(5.0, 0.0, 0.0))
    bpy.context.object.name = "Ground"
    return arm, dict(zip([f.stem for f in files], acts))


def props_scene(bpy, api, mocap, out):
    import math

    arm, acts = baked(bpy, api, mocap, ("16_06", "13_05", "13_05_standup"))
    for k in range(7):
        ob = box(bpy, f"Hurdle.{k:02d}", 5.0, -1.5 + 0.5 * k, HURDLE)
        api.tag_object_patch(ob, [(acts["16_06"], "TRAVERSAL", 8.0, 10.0)])
    for k, (x, y) in enumerate(((2.5, 3.5), (7.5, -3.0), (3.0, -3.5), (8.0, 4.0))):
        pillar(bpy, f"Pillar.{k:02d}", x, y)
    walker = character(bpy, arm, "Walker", 1.0, 0.3, 0.0)
    bpy.context.scene.motion_patches.goal = goal(bpy, "Goal", 9.0, 0.3, 0.0)
    a = box(bpy, "Chair A", 1.0, -6.0, CHAIR)
    b = box(bpy, "Chair B", 9.0, -6.5, CHAIR)
    api.tag_object_patch(a, [(acts["13_05_standup"], "INTERACTION", 2.0, 0.0)])
    api.tag_object_patch(b, [(acts["13_05"], "INTERACTION", 2.0, 0.0)])
    sitter = character(bpy, arm, "Sitter", 1.0, -5.0, -math.pi / 2)
    sitter.motion_patches_character.goal = b
    sitter.motion_patches_character.start_prop = a
    bpy.context.view_layer.objects.active = walker
    return save(bpy, out / "props.blend")


def crowd_scene(bpy, api, mocap, out):
    import math

    arm, _ = baked(bpy, api, mocap)
    for k, (x, y) in enumerate(((3.0, 1.0), (5.0, -1.5), (7.0, 1.5), (5.0, 3.5), (3.5, -3.5))):
        pillar(bpy, f"Pillar.{k:02d}", x, y, r=0.3)
    for k in range(12):
        east = k % 2 == 0
        y = -4.5 + 1.5 * (k // 2)
        x0, x1 = (0.0, 10.0) if east else (10.0, 0.0)
        heading = 0.0 if east else math.pi
        ob = character(bpy, arm, f"Walker.{k:02d}", x0, y, heading)
        ob.motion_patches_character.goal = goal(bpy, f"Goal.{k:02d}", x1, -y * 0.6, heading)
        ob.select_set(True)
    return save(bpy, out / "crowd.blend")


def save(bpy, path):
    path.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    print(f"samples: {path.relative_to(REPO)} {path.stat().st_size / 1e6:.2f} MB")
    return path


def main(argv):
    args = parse_args(argv)
    mocap = Path(args.mocap)
    if not (mocap / "cmu" / "16_15.bvh").is_file():
        print(f"samples: mocap not found under {mocap} (use --mocap)", file=sys.stderr)
        return 2
    bpy, addon = blender_session.start()
    out = Path(args.out)
    props_scene(bpy, addon.api, mocap, out)
    crowd_scene(bpy, addon.api, mocap, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
