# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``plan`` command (one character to its goal, written as NLA strips) and ``analyse``
(figures of a planned character's evaluated motion)."""

import math

import bpy

from .. import api
from .lookup import object_named, save_blend, save_target, settings_given
from .output import OK, BadInput, Failed, Heartbeat, Result, count


def _goal_of(args, scene, character):
    """(goal for api.plan_path, goal object or None) from --goal / --goal-xyh; neither:
    None, which api.plan_path reads as the character's Own Goal, else the scene's goal."""
    if args.goal:
        ob = object_named(args.goal, "goal")
        return ob, ob
    if args.goal_xyh:
        x, y, h = args.goal_xyh
        return (x, y, math.radians(h)), None
    return None, api.own_goal(scene, character)


def plan_doc(res, fps):
    return {
        "character": res.character,
        "frame_start": res.frame_start,
        "frame_end": res.frame_end,
        "frames": res.frame_end - res.frame_start + 1,
        "seconds_of_motion": (res.frame_end - res.frame_start) / fps,
        "length_m": res.length_m,
        "cost": res.cost,
        "plan_seconds": res.seconds,
        "expansions": res.expansions,
        "pieces": res.pieces,
        "strips": len(res.strips),
        "stashed_action_track": res.stashed_action_track,
        "stats": res.stats,
    }


def plan_line(res, fps):
    return (
        f"planned '{res.character}': {count(len(res.pieces), 'piece')}, frames {res.frame_start}-"
        f"{res.frame_end} ({(res.frame_end - res.frame_start) / fps:.1f} s of motion, "
        f"{res.length_m:.1f} m), cost {res.cost:.2f}, {res.seconds * 1000:.0f} ms"
    )


def bodies_doc(res):
    """The JSON of an ``api.add_bodies`` result (None: no --bodies)."""
    if res is None:
        return None
    return {"characters": res.characters, "parts": res.parts, "meshes": res.meshes}


def bodies_text(res):
    if res is None:
        return []
    n = len(res.characters)
    return [
        f"{count(n, 'body', 'bodies')}: {count(res.parts, 'capsule')} sharing "
        f"{count(res.meshes, 'mesh', 'meshes')}"
    ]


def cmd_plan(args):
    scene = bpy.context.scene
    char = object_named(args.character, "character", {"ARMATURE"})
    goal, goal_obj = _goal_of(args, scene, char)
    # What is used: the flags over the scene's.
    w = api.planning_settings(scene, **settings_given(args))
    save = save_target(args)
    # --start-prop, else the character's own Start Prop, as the Plan Path button reads it
    seat = (
        object_named(args.start_prop, "start prop", {"MESH"})
        if args.start_prop
        else api.character_start_prop(char)
    )
    try:
        with Heartbeat(f"plan '{char.name}'", enabled=not args.json):
            res = api.plan_path(
                scene,
                char,
                goal,
                patch_name=args.patch,
                frame_start=args.frame_start,
                gait=args.gait,
                from_here=args.from_here,
                start_prop=seat,
                **w,
            )
    except api.PathNotFound as exc:
        raise Failed(str(exc)) from None
    bodies = api.add_bodies([char]) if args.bodies else None
    fps = api.scene_fps(scene)
    saved = save_blend(save)
    doc = plan_doc(res, fps)
    if args.gait:
        doc.update(layer=res.stats.get("layer"), layer_costs=res.stats.get("layers"))
    doc.update(
        goal=api.state_dict(res.goal, goal_obj and goal_obj.name),
        patch=args.patch or api.active_patch_name(scene),
        weights=w,
        bodies=bodies_doc(bodies),
        saved=saved,
    )
    text = [plan_line(res, fps)] + bodies_text(bodies)
    if args.gait:
        text.append(
            f"  layer '{res.stats.get('layer')}' (Eq. 5 cost per layer: "
            + ", ".join(
                f"{k} {'no path' if v is None else f'{v:.2f}'}"
                for k, v in res.stats.get("layers", {}).items()
            )
            + ")"
        )
    if res.stashed_action_track:
        text.append(
            f"  its active action was moved to the muted track '{res.stashed_action_track}'"
        )
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


def cmd_analyse(args):
    char = object_named(args.character, "character", {"ARMATURE"})
    try:
        figures = api.analyse(bpy.context, char)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    f = figures
    sk = f["foot_skate"]
    text = [
        f"'{char.name}': {f['frames']} frames ({f['seconds']:.1f} s), evaluated",
        f"  foot skate while planted: {sk.get('mean_cm_per_frame', float('nan')):.2f} "
        f"cm/frame mean, {sk.get('p95_cm_per_frame', float('nan')):.2f} p95",
        f"  goal error: {f['goal_position_error_cm']:.1f} cm, "
        f"{f['goal_heading_error_deg']:.1f} deg "
        f"(hips {f['goal_root_position_error_cm']:.1f} cm)",
        f"  root from plan: max {f['root_from_plan_cm']['max']:.2f} cm; frames inside an "
        f"obstacle: root {f['frames_root_inside_obstacle']}, any bone "
        f"{f['frames_body_inside_prop']}",
        f"  largest joint jump at a strip boundary: "
        f"{f['boundary_pop'].get('max_boundary_jump_deg', float('nan')):.1f} deg",
    ]
    return Result({"character": char.name, "figures": figures}, OK, text)
