# SPDX-License-Identifier: GPL-3.0-or-later
"""Demo: bake a walk patch from real CMU mocap, plan through a pillar field, write NLA.

Run with ``./dev demo``. Builds the scene from scratch with the add-on's operators,
evaluates the result through the depsgraph, prints a summary and saves
``sample_blends/demo_walk.blend`` (saved by the oldest supported Blender, so every
supported version opens it).
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blender_session  # noqa: E402
import demo_layout  # noqa: E402

REPO = blender_session.REPO_ROOT


def plural(n, noun):
    """'1 piece', '3 pieces'."""
    return f"{n} {noun}" + ("" if n == 1 else "s")


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument(
        "--mocap",
        default=os.environ.get("MOTION_PATCHES_MOCAP", str(REPO.parent / "shared" / "mocap")),
        help="folder holding cmu/16_15.bvh and cmu/16_18.bvh",
    )
    p.add_argument("--output", default=str(REPO / "sample_blends" / "demo_walk.blend"))
    p.add_argument("--json", help="also write the summary as JSON to this file")
    p.add_argument("--seed", type=int, default=7, help="pillar layout seed")
    return p.parse_args(argv)


def pillar_field(bpy, seed):
    """Cylinders at the shared demo layout's pillar positions."""
    made = []
    for x, y, r in demo_layout.pillar_positions(seed):
        bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=2.5, location=(x, y, 1.25))
        ob = bpy.context.object
        ob.name = f"Pillar.{len(made):02d}"
        made.append(ob)
    return made


def chair_lines(bpy, api, source, jump, seed):
    """Two lines of eleven low hurdles (a chair's footprint, 15 cm high: the real CMU jump
    16_06, a standing broad jump, clears about 18 cm over them) tagged with that jump; a
    hurried and a calm walker cross them. Each is planned with dynamic and with static stitching."""
    import numpy as np

    scene = bpy.context.scene
    out = {}
    for name, y0, weights in (("Hurried", 15.0, (4.0, 0.5, 0.1)), ("Calm", 25.0, (0.3, 0.1, 3.0))):
        for k, y in enumerate(np.linspace(y0 - 2.5, y0 + 2.5, 11)):
            bpy.ops.mesh.primitive_cube_add(size=1.0, location=(5.0, y, 0.075))
            ob = bpy.context.object
            ob.name = f"{name} hurdle.{k:02d}"
            ob.scale = (0.4, 0.44, 0.15)
            api.tag_object_patch(ob, [(jump, "TRAVERSAL", 8.0, 10.0)])
        walker = source.copy()
        walker.name = name
        walker.animation_data_clear()
        scene.collection.objects.link(walker)
        walker.hide_set(False)
        walker.location = (1.0, y0 + 0.3, 0.0)
        walker.rotation_euler = (0, 0, np.pi / 2)
        goal = bpy.data.objects.new(f"{name} goal", None)
        goal.empty_display_type = "SINGLE_ARROW"
        scene.collection.objects.link(goal)
        goal.location = (9.0, y0 + 0.3, 0.0)
        goal.rotation_euler = (0, 0, np.pi / 2)
        rows = {}
        for mode in ("static", "dynamic"):  # dynamic last: its NLA stays in the file
            res = api.plan_path(
                scene,
                walker,
                goal,
                alpha=weights[0],
                beta=weights[1],
                gamma=weights[2],
                frame_start=1,
                stitching=mode,
            )
            rows[mode] = {
                "seconds": res.seconds,
                "cost": res.cost,
                "copies_stitched": res.stats["copies_stitched"],
                "stitch_edges": res.stats["stitch_edges"],
                "traversals": res.stats["traversals_used"],
                "pieces": res.pieces,
            }
        rows["evaluated"] = api.analyse(bpy.context, walker)
        out[name] = rows
    return out


def crowd_crossing(bpy, api, evaluate, source):
    """Six walkers cross the pillar field from its west side to goals on the east side in
    a shuffled order, so their ways cross; planned as a crowd (later ones wait at their
    start until they keep a metre from the earlier ones) and evaluated together."""
    import numpy as np

    scene = bpy.context.scene
    pairs = []
    ys = [-2.0, -0.2, 1.6, 3.4, 5.2, 7.0]
    for n, (y0, y1) in enumerate(zip(ys, [5.2, 7.0, -2.0, -0.2, 3.4, 1.6])):
        walker = source.copy()
        walker.name = f"Crowd.{n}"
        walker.animation_data_clear()
        scene.collection.objects.link(walker)
        walker.hide_set(False)
        walker.location = (-2.5, y0, 0.0)
        walker.rotation_euler = (0, 0, np.pi / 2)  # faces +X
        goal = bpy.data.objects.new(f"Crowd.{n} goal", None)
        goal.empty_display_type = "SINGLE_ARROW"
        scene.collection.objects.link(goal)
        goal.location = (14.0, y1, 0.0)
        goal.rotation_euler = (0, 0, np.pi / 2)
        pairs.append((walker, goal))
    res = api.plan_crowd(scene, pairs, frame_start=1, spacing=1.0)
    names = [p.character for p in res.plans]
    end = max(p.frame_end for p in res.plans)
    frames = np.arange(1, end + 1)
    roots = []
    for name in names:
        ob = bpy.data.objects[name]
        pos, _, _, _ = evaluate.sample_armature(bpy.context, ob, frames, [ob.pose.bones[0].name])
        roots.append(pos[:, 0, :2])
    roots = np.array(roots)
    gap = min(
        (
            np.linalg.norm(roots[i] - roots[j], axis=1).min()
            for i in range(len(names))
            for j in range(i)
        ),
        default=np.inf,
    )
    inside = sum(
        api.analyse(bpy.context, bpy.data.objects[n])["frames_root_inside_obstacle"] for n in names
    )
    return {
        "characters": len(pairs),
        "planned": len(res.plans),
        "failed": res.failed,
        "seconds": res.seconds,
        "delays_frames": res.delays,
        "conflicts": res.conflicts,
        "evaluated_closest_m": float(gap),
        "frames_root_inside_obstacle": int(inside),
        "frames": int(end),
    }


def source_feet(bpy, addon, arm, action):
    """The label-free foot figures of the source armature playing its recorded ``action``,
    evaluated through the depsgraph frame by frame as the planned walker is (api.analyse):
    the floor the walker's feet are held against, by the same measure."""
    import numpy as np

    compat, fm = addon.adapter.compat, addon.motion_patches.quality.foot_measure
    skel = addon.adapter.rig.skeleton_in_metres(arm)
    ankles, toes = fm.foot_bones(skel)
    ad = arm.animation_data or arm.animation_data_create()
    keep = ad.action, ad.action_slot
    compat.assign_action(arm, action, compat.action_slot(action))
    try:
        first, last = (int(round(f)) for f in action.frame_range)
        names = [skel.names[i] for i in ankles + toes]
        pos, _, _, _ = addon.adapter.evaluate.sample_armature(
            bpy.context, arm, np.arange(first, last + 1), names
        )
    finally:
        ad.action = keep[0]
        if keep[0] is not None and keep[1] is not None:
            ad.action_slot = keep[1]
    fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
    return fm.measure(pos[:, 2:], pos[:, :2], fps)


def feet_text(m):
    """The label-free figures in one line (motion_patches.quality.foot_measure)."""
    return (
        "skate %.1f cm/s (height-weighted %.1f), %d one-frame pops, swing clearance %.1f cm,"
        " end ankles within %.1f cm of standing"
        % (
            m["skate"]["mean_cm_per_s"],
            m["weighted_skate"]["mean_cm_per_s"],
            m["pops"],
            m["min_swing_clearance_cm"],
            m["max_end_ankle_off_cm"],
        )
    )


def main(argv):
    args = parse_args(argv)
    mocap = Path(args.mocap)
    clips = [mocap / "cmu" / "16_15.bvh", mocap / "cmu" / "16_18.bvh", mocap / "cmu" / "16_06.bvh"]
    for c in clips:
        if not c.is_file():
            print(
                f"demo: mocap clip not found: {c} (use --mocap or MOTION_PATCHES_MOCAP)",
                file=sys.stderr,
            )
            return 2
    bpy, addon = blender_session.start()
    import numpy as np

    api = addon.api
    from_core = addon.motion_patches

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps = 30
    arm, acts = api.import_mocap(clips, name="CMU16 source")
    s = scene.motion_patches
    s.source_armature = arm
    s.straight_action = acts[0]
    s.turn_actions.add().action = acts[1]
    arm.hide_set(True)

    t0 = time.perf_counter()
    bake = api.bake_locomotion_patch(scene, arm, acts[0], [acts[1]], layer="walk")
    bake_s = time.perf_counter() - t0

    start, goal = demo_layout.START, demo_layout.GOAL
    bpy.ops.mesh.primitive_plane_add(size=30, location=(5, 2, 0))
    bpy.context.object.name = "Ground"
    pillars = pillar_field(bpy, args.seed)
    walker = arm.copy()
    walker.name = "Walker"
    walker.animation_data_clear()
    scene.collection.objects.link(walker)
    walker.hide_set(False)
    walker.location = (start[0], start[1], 0)
    walker.rotation_euler = (0, 0, np.pi / 2 + start[2])  # rest faces -Y; face start[2]
    goal_ob = bpy.data.objects.new("Goal", None)
    goal_ob.empty_display_type = "SINGLE_ARROW"
    scene.collection.objects.link(goal_ob)
    goal_ob.location = (goal[0], goal[1], 0)
    goal_ob.rotation_euler = (0, 0, np.pi / 2 + goal[2])  # its -Y axis (the facing) at goal[2]
    s.goal = goal_ob

    # The same plan without foot locking first: the skate the synthesis alone leaves. The
    # weights and radius are the scene's Planning settings, which the API fills in itself.
    api.plan_path(scene, walker, goal_ob, frame_start=1, foot_lock=False)
    unlocked_figures = api.analyse(bpy.context, walker)
    unlocked, unlocked_feet = unlocked_figures["foot_skate"], unlocked_figures["feet"]
    plan = api.plan_path(scene, walker, goal_ob, frame_start=1)
    scene.frame_start, scene.frame_end = plan.frame_start, plan.frame_end
    figures = api.analyse(bpy.context, walker)
    chairs = chair_lines(bpy, api, arm, acts[2], args.seed)
    crowd = crowd_crossing(bpy, api, addon.adapter.evaluate, arm)

    # The floor: the source clip's own skate, measured the same way.
    src = addon.adapter.actions.clip_from_action(acts[0], arm, 30.0)
    src30 = from_core.kinematics.clip.resample(src, 30.0)
    con, _, _ = from_core.kinematics.contacts.foot_contacts(src30)
    fj = from_core.kinematics.contacts.foot_joints(src30.skeleton)
    floor = from_core.quality.metrics.foot_skate(src30.joint_positions()[:, fj], 30.0, con)
    floor_feet = source_feet(bpy, addon, arm, acts[0])

    out = Path(args.output)
    out.parent.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(out))

    summary = {
        "blender": bpy.app.version_string,
        "clips": [c.name for c in clips],
        "gait_notes": bake.notes,
        "bake": {
            "seconds": round(bake_s, 2),
            "kept": bake.stats["kept"],
            "culled": bake.stats["culled"],
            "culled_by": bake.stats["culled_by"],
        },
        "scene": {"pillars": len(pillars), "start": start, "goal": goal},
        "plan": {
            "seconds": round(plan.seconds, 3),
            "pieces": len(plan.pieces),
            "expansions": plan.expansions,
            "frames": plan.frame_end - plan.frame_start + 1,
            "cost": round(plan.cost, 3),
        },
        "evaluated": figures,
        "source_clip_skate": floor,
        "source_clip_feet": floor_feet,
        "skate_without_foot_lock": unlocked,
        "feet_without_foot_lock": unlocked_feet,
        "chair_lines": chairs,
        "crowd": crowd,
        "saved": str(out),
    }
    sk, f = figures["foot_skate"], figures
    print()
    print("Dynamic Motion Patches demo  (Blender %s)" % bpy.app.version_string)
    print(
        "  clips:       %s (real CMU mocap, subject 16; 16_06 is a standing forward jump,"
        " the closest recorded hurdle)" % ", ".join(c.name for c in clips)
    )
    for n in bake.notes:
        print("               " + n)
    print(
        "  bake:        %.1f s, %d segments kept, %d culled (%s)"
        % (
            bake_s,
            bake.stats["kept"],
            bake.stats["culled"],
            ", ".join(f"{k} {v}" for k, v in bake.stats["culled_by"].items()),
        )
    )
    print(
        "  plan:        %.0f ms, %s, %d nodes expanded, %d frames (%.1f s of motion)"
        % (
            plan.seconds * 1000,
            plural(len(plan.pieces), "piece"),
            plan.expansions,
            plan.frame_end - plan.frame_start + 1,
            f["seconds"],
        )
    )
    print("  evaluated through the depsgraph, frame by frame:")
    print(
        "    foot skate while planted: %.2f cm/frame mean, %.2f p95  "
        "(%.1f cm/s; source clip %.1f cm/s;"
        " without foot locking %.1f cm/s)"
        % (
            sk["mean_cm_per_frame"],
            sk["p95_cm_per_frame"],
            sk["mean_cm_per_s"],
            floor["mean_cm_per_s"],
            unlocked["mean_cm_per_s"],
        )
    )
    print("    feet by the label-free measure (toe within 3 cm of its lowest for 0.2 s):")
    print("      walker:              " + feet_text(f["feet"]))
    print("      without foot lock:   " + feet_text(unlocked_feet))
    print("      source clip 16_15:   " + feet_text(floor_feet))
    print(
        "    goal error: root motion %.1f cm, %.1f deg; hips %.1f cm from the goal point"
        % (
            f["goal_position_error_cm"],
            f["goal_heading_error_deg"],
            f["goal_root_position_error_cm"],
        )
    )
    print(
        "    hips within %.2f cm of the planned root trajectory (max over all frames)"
        % (f["root_from_plan_cm"]["max"])
    )
    print(
        "    frames with the root inside a pillar (+%.2f m radius): %d"
        % (s.radius, f["frames_root_inside_obstacle"])
    )
    tracks = walker.animation_data.nla_tracks
    if len(plan.pieces) > 1 or len(tracks["MP motion"].strips) > 1:
        print(
            "    largest joint jump where %d strips meet: %.1f deg (p99 elsewhere %.1f deg)"
            % (
                len(tracks["MP motion"].strips),
                f["boundary_pop"]["max_boundary_jump_deg"],
                f["boundary_pop"]["p99_step_deg"],
            )
        )
    else:
        print("    one strip (the path was shortened to one curve): no strip boundary to jump at")
    for name, rows in chairs.items():
        d, st, ev = rows["dynamic"], rows["static"], rows["evaluated"]
        print(
            "  %-8s hurdle line (alpha, beta, gamma = %s): %s"
            % (
                name,
                "4, 0.5, 0.1" if name == "Hurried" else "0.3, 0.1, 3",
                "jumps a hurdle (16_06 jump)" if d["traversals"] else "walks around",
            )
        )
        print(
            "    dynamic stitching: %4.0f ms, %3d clip copies stitched, %5d edges, cost %.2f"
            % (d["seconds"] * 1000, d["copies_stitched"], d["stitch_edges"], d["cost"])
        )
        print(
            "    static  stitching: %4.0f ms, %3d clip copies stitched, %5d edges, cost %.2f"
            % (st["seconds"] * 1000, st["copies_stitched"], st["stitch_edges"], st["cost"])
        )
        print(
            "    evaluated: skate %.2f cm/frame, root inside a hurdle outside the jump: %d frames, "
            "any bone inside a hurdle: %d frames, goal %.1f cm / %.1f deg"
            % (
                ev["foot_skate"]["mean_cm_per_frame"],
                ev["frames_root_inside_obstacle"],
                ev["frames_body_inside_prop"],
                ev["goal_root_position_error_cm"],
                ev["goal_heading_error_deg"],
            )
        )
    waits = [d for d in crowd["delays_frames"].values() if d]
    print(
        "  crowd:       %d of %d walkers planned across the pillars in %.1f s; %s; %s left"
        % (
            crowd["planned"],
            crowd["characters"],
            crowd["seconds"],
            f"{plural(len(waits), 'walker')} wait at their start "
            f"({', '.join(map(str, waits))} frames)"
            if waits
            else "none waits at its start",
            plural(len(crowd["conflicts"]), "conflict"),
        )
    )
    print(
        "    evaluated: closest two walkers come %.2f m apart (spacing 1.0 m); frames with a "
        "root inside a pillar: %d"
        % (crowd["evaluated_closest_m"], crowd["frames_root_inside_obstacle"])
    )
    print("  saved:       %s" % out)
    if args.json:
        Path(args.json).write_text(json.dumps(summary, indent=2))
    ok = (
        f["goal_root_position_error_cm"] < 10
        and f["goal_heading_error_deg"] < 10
        and f["frames_root_inside_obstacle"] == 0
        and all(r["evaluated"]["frames_root_inside_obstacle"] == 0 for r in chairs.values())
        and all(r["evaluated"]["frames_body_inside_prop"] == 0 for r in chairs.values())
        and crowd["frames_root_inside_obstacle"] == 0
        and not crowd["failed"]
        and (crowd["conflicts"] or crowd["evaluated_closest_m"] >= 0.95)
    )
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
