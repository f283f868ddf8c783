# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender benchmark of feet on rigs the patch was not baked from: retargeted contacts.

Prints numbers next to their bounds, asserts nothing. Run from the repository root with a
Blender Python (bpy from PyPI):

    .venv/blender-4.5/bin/python bench/bench_rigs.py [--rigs s2,mixamo,own] [--json out.json]

Set-up: the walk patch of CMU subject 16 (16_15 straight, 16_18 left turn) baked through the
API at 30 fps in a fresh scene, the add-on enabled as an installed extension
(tools/blender_session.py). Then three rigs:

* ``s2``: Blender's own BVH import of CMU subject 2's walk (``shared/mocap/cmu/02_01.bvh``,
  ``bpy.ops.import_anim.bvh`` at its defaults, animation cleared): the same joint names,
  other bone lengths and another rest pose;
* ``mixamo``: the same subject 2 as an FBX importer leaves a Mixamo character: bones named
  ``mixamorig:...``, centimetre bones, Y-up armature data under a 90 degree X rotation,
  object scale 0.01, quaternion bones;
* ``own``: a copy of the patch's own source armature (subject 16), for comparison.

Each rig is planned (``api.plan_path``, foot lock on) through three scenes, set out in the
rig's own start frame (its root over the origin, facing +X): open ground (a goal 6 m ahead,
1.5 m to the side), a pillar field (two pillars across the way) and a U-turn round the end
of a 6 m wall. Per plan the label-free foot measure of the evaluated rig
(``api.analyse(...)["feet"]``, :mod:`motion_patches.quality.foot_measure`): both ankles'
first and last frame against their standing height, one-frame pops of a planted toe, the
lowest swing clearance, the height-weighted skate; beside the rig's own subject's recording
(02_01 for ``s2`` and ``mixamo``, 16_15 for ``own``) by the same measure at the scene's rate.
The bounds: ankles within 3 cm of standing, no pop over 1 cm, swings at least 0.5 cm above
their planted height, height-weighted skate at most 1.25 x the recording's.
"""

import argparse
import json
import os
import sys
import time
from importlib import import_module
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tools"))
sys.path[:0] = [str(REPO / "tests"), str(REPO / "tests" / "blender")]  # the tests' rigs
import blender_session  # noqa: E402

CMU_SCALE = 0.056444
FPS = 30
RIGS = ("s2", "mixamo", "own")
BOUNDS = {"ends_cm": 3.0, "pop_cm": 1.0, "clearance_cm": 0.5, "skate_ratio": 1.25}
RECORDING = {"s2": "02_01", "mixamo": "02_01", "own": "16_15"}

# The scenes in the rig's start frame (root over the origin, facing +X): goal (x, y,
# heading), pillars [(x, y)], walls [((x0, y0), (x1, y1))].
SCENES = {
    "open": {"goal": (6.0, -1.5, -0.2), "pillars": [], "walls": []},
    "pillars": {"goal": (6.6, 3.7, 0.3), "pillars": [(2.6, 0.7), (4.1, 2.7)], "walls": []},
    "uturn": {"goal": (0.0, -2.0, np.pi), "pillars": [], "walls": [((-3.5, -1.0), (2.5, -1.0))]},
}


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--rigs", default=",".join(RIGS), help=f"comma-separated ({', '.join(RIGS)})")
    p.add_argument(
        "--scenes", default=",".join(SCENES), help=f"comma-separated ({', '.join(SCENES)})"
    )
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
    )
    p.add_argument("--no-lock", action="store_true", help="plan with the foot lock off")
    p.add_argument("--json", metavar="PATH", help="also write every figure as JSON")
    a = p.parse_args(argv)
    a.rigs = [r for r in a.rigs.split(",") if r]
    a.scenes = [s for s in a.scenes.split(",") if s]
    bad = (set(a.rigs) - set(RIGS)) | (set(a.scenes) - set(SCENES))
    if bad:
        p.error(f"unknown rigs or scenes {sorted(bad)}")
    return a


def baked_scene(bpy, api, mocap):
    """A fresh 30 fps scene with the subject-16 walk patch baked; (scene, source armature)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = FPS
    cmu = Path(mocap) / "cmu"
    arm, acts = api.import_mocap([cmu / "16_15.bvh", cmu / "16_18.bvh"], name="Source")
    api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    scene.motion_patches.source_armature = arm
    return scene, arm


def bvh_rig(bpy, mocap, name):
    """Subject 2 through Blender's BVH importer at its defaults, animation cleared."""
    before = set(bpy.data.objects)
    assert bpy.ops.import_anim.bvh(
        filepath=str(Path(mocap) / "cmu" / "02_01.bvh"),
        global_scale=CMU_SCALE,
        update_scene_fps=False,
    ) == {"FINISHED"}
    (ob,) = [o for o in bpy.data.objects if o not in before]
    ob.name = name
    ob.animation_data_clear()
    bpy.context.view_layer.update()
    return ob


def mixamo_rig(bpy, mocap, name):
    """Subject 2 as Blender's FBX importer leaves a Mixamo character (centimetre bones,
    Y-up data under a 90 degree X rotation, object scale 0.01), built as the Blender tests
    build it (tests/blender/scene_helpers.py), standing at the origin."""
    import scene_helpers  # needs bpy, which the session started

    ob = scene_helpers.fbx_like_mixamo(Path(mocap), name, rel="cmu/02_01.bvh")
    ob.location = (0.0, 0.0, 0.0)
    bpy.context.view_layer.update()
    return ob


def own_rig(bpy, source):
    ob = source.copy()
    ob.name = "Own"
    ob.animation_data_clear()
    bpy.context.scene.collection.objects.link(ob)
    bpy.context.view_layer.update()
    return ob


def build_scene(bpy, addon, rig, spec, tag):
    """The scene ``spec`` in the rig's start frame; returns the goal empty and what was made."""
    skel = addon.adapter.rig.skeleton_in_metres(rig)
    x0, y0, h0 = addon.adapter.scene.character_state(rig, skel)
    c, s = np.cos(h0), np.sin(h0)

    def at(x, y):
        return (x0 + c * x - s * y, y0 + s * x + c * y)

    made = []
    for k, (x, y) in enumerate(spec["pillars"]):
        bpy.ops.mesh.primitive_cylinder_add(radius=0.25, depth=2.0, location=(*at(x, y), 1.0))
        bpy.context.object.name = f"{tag}Pillar{k}"
        made.append(bpy.context.object)
    for k, (p, q) in enumerate(spec["walls"]):
        a, b = np.array(at(*p)), np.array(at(*q))
        mid, d = (a + b) / 2, b - a
        bpy.ops.mesh.primitive_cube_add(size=1.0, location=(*mid, 1.0))
        ob = bpy.context.object
        ob.name = f"{tag}Wall{k}"
        ob.scale = (float(np.linalg.norm(d)), 0.2, 2.0)
        ob.rotation_euler = (0.0, 0.0, float(np.arctan2(d[1], d[0])))
        made.append(ob)
    gx, gy, gh = spec["goal"]
    goal = bpy.data.objects.new(f"{tag}Goal", None)
    bpy.context.scene.collection.objects.link(goal)
    goal.location = (*at(gx, gy), 0.0)
    goal.rotation_euler = (0.0, 0.0, h0 + gh + np.pi / 2)  # its -Y faces the heading
    made.append(goal)
    bpy.context.view_layer.update()
    return goal, made


def recording(addon, mocap, name):
    """The label-free foot figures of a recording at the scene's rate."""
    core = addon.__name__ + ".motion_patches"
    bvh = import_module(core + ".kinematics.bvh")
    clip = import_module(core + ".kinematics.clip")
    foot_measure = import_module(core + ".quality.foot_measure")
    return foot_measure.of_clip(clip.resample(bvh.read(Path(mocap) / "cmu" / f"{name}.bvh"), FPS))


def figures(feet, rec):
    """The figures against the bounds from a label-free measure and the recording's."""
    ends = np.abs(
        np.array([feet["first_ankle_cm"], feet["last_ankle_cm"]])
        - np.array(feet["standing_ankle_cm"])[None]
    )
    hw = feet["weighted_skate"]["mean_cm_per_s"]
    ref = rec["weighted_skate"]["mean_cm_per_s"]
    return {
        "ends_cm": float(ends.max()),
        "pops": int(feet["pops"]),
        "pop_cm": float(feet["max_pop_cm"]),
        "clearance_cm": float(feet["min_swing_clearance_cm"]),
        "swings": int(feet["swings"]),
        "hw_skate": float(hw),
        "recording_hw_skate": float(ref),
        "skate_ratio": float(hw / ref),
        "skate": float(feet["skate"]["mean_cm_per_s"]),
        "planted_fraction": float(feet["planted_fraction"]),
    }


def met(f):
    return {
        "ends": f["ends_cm"] <= BOUNDS["ends_cm"],
        "pops": f["pops"] == 0,
        "clearance": f["clearance_cm"] >= BOUNDS["clearance_cm"],
        "skate": f["skate_ratio"] <= BOUNDS["skate_ratio"],
    }


def markdown(rows, recs):
    out = [
        "| rig | scene | ends off standing (cm) | pops (worst cm) | lowest swing (cm) | "
        "hw skate (cm/s) | x recording | met |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        f = r["figures"]
        ok = met(f)
        out.append(
            f"| {r['rig']} | {r['scene']} | {f['ends_cm']:.2f} | {f['pops']} ({f['pop_cm']:.2f}) "
            f"| {f['clearance_cm']:.2f} | {f['hw_skate']:.2f} | {f['skate_ratio']:.2f} | "
            + (
                "all"
                if all(ok.values())
                else "not: " + ", ".join(k for k, v in ok.items() if not v)
            )
            + " |"
        )
    out.append("")
    out.append(
        "Recordings at 30 fps, height-weighted skate: "
        + ", ".join(f"{n} {v['weighted_skate']['mean_cm_per_s']:.2f} cm/s" for n, v in recs.items())
        + "; bounds: ends <= 3 cm, no pop > 1 cm, swings >= 0.5 cm, hw skate <= 1.25 x."
    )
    return "\n".join(out)


def main(argv=None):
    args = parse_args(argv)
    bpy, addon = blender_session.start()
    api = addon.api
    t0 = time.perf_counter()
    scene, source = baked_scene(bpy, api, args.mocap)
    bake_s = time.perf_counter() - t0
    recs = {n: recording(addon, args.mocap, n) for n in sorted({RECORDING[r] for r in args.rigs})}
    rows = []
    for rig_name in args.rigs:
        for scene_name in args.scenes:
            # each plan on a fresh rig in a scene of its own props only
            for ob in [o for o in bpy.data.objects if o.get("bench_rigs")]:
                bpy.data.objects.remove(ob)
            if rig_name == "s2":
                rig = bvh_rig(bpy, args.mocap, "S2")
            elif rig_name == "mixamo":
                rig = mixamo_rig(bpy, args.mocap, "Mixamo cm")
            else:
                rig = own_rig(bpy, source)
            goal, made = build_scene(bpy, addon, rig, SCENES[scene_name], scene_name)
            for ob in [rig, *made]:
                ob["bench_rigs"] = True
            t = time.perf_counter()
            res = api.plan_path(scene, rig, goal, frame_start=1, foot_lock=not args.no_lock)
            seconds = time.perf_counter() - t
            a = api.analyse(bpy.context, rig)
            f = figures(a["feet"], recs[RECORDING[rig_name]])
            row = {
                "rig": rig_name,
                "scene": scene_name,
                "pieces": len(res.pieces),
                "frames": a["frames"],
                "goal_cm": a["goal_position_error_cm"],
                "plan_s": seconds,
                "figures": f,
                "met": met(f),
            }
            rows.append(row)
            print(
                f"{rig_name:7s} {scene_name:8s} ends {f['ends_cm']:5.2f} cm  pops {f['pops']} "
                f"({f['pop_cm']:.2f})  swing {f['clearance_cm']:6.2f} cm  hw skate "
                f"{f['hw_skate']:5.2f} cm/s = {f['skate_ratio']:.2f} x  goal "
                f"{row['goal_cm']:.1f} cm  ({seconds:.1f} s)",
                flush=True,
            )
    res = {
        "bake_s": bake_s,
        "foot_lock": not args.no_lock,
        "recordings": {
            n: {
                "weighted_skate": v["weighted_skate"]["mean_cm_per_s"],
                "skate": v["skate"]["mean_cm_per_s"],
                "min_swing_clearance_cm": v["min_swing_clearance_cm"],
            }
            for n, v in recs.items()
        },
        "rows": rows,
    }
    print()
    print(json.dumps(res, default=float))
    print()
    print(markdown(rows, recs))
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1, default=float)
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
