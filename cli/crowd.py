# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``crowd`` command: several characters planned, each to its goal, kept apart in time."""

import bpy

from .. import api
from .lookup import object_named, save_blend, save_target, settings_given
from .output import FAILED, OK, BadInput, Progress, Result
from .plan import bodies_doc, bodies_text, plan_doc, plan_line


def _crowd_pairs(args, scene):
    """--pair CHARACTER GOAL as given (each starting on its Start Prop where it has one:
    api.crowd_member); else the crowd the API makes of --character (or of the scene, none
    given): api.crowd_members, the rule the Plan Crowd button follows."""
    if args.pair and args.character:
        raise BadInput("give either --pair or --character, not both")
    if args.pair:
        return [
            api.crowd_member(object_named(c, "character", {"ARMATURE"}), object_named(g, "goal"))
            for c, g in args.pair
        ]
    if args.character:
        return api.crowd_members(
            scene, [object_named(c, "character", {"ARMATURE"}) for c in args.character]
        )
    return api.crowd_members(scene)


def cmd_crowd(args):
    scene = bpy.context.scene
    pairs = _crowd_pairs(args, scene)
    w = api.planning_settings(scene, **settings_given(args))
    save = save_target(args)
    progress = Progress("crowd", enabled=not args.json)
    wait = {} if args.max_wait is None else {"max_wait_seconds": args.max_wait}
    try:
        with api.cluster_executor(args.workers, args.scheduler) as executor:
            res = api.plan_crowd(
                scene,
                pairs,
                patch_name=args.patch,
                frame_start=args.frame_start,
                progress=progress,
                spacing=args.spacing,
                executor=executor,
                **wait,
                **w,
            )
    finally:
        progress.close()
    bodies = api.add_bodies([entry[0] for entry in pairs]) if args.bodies else None
    fps = api.scene_fps(scene)
    moving = list(getattr(res, "moving_conflicts", []))
    ok = not res.failed and not res.conflicts and not moving
    saved = save_blend(save) if ok or (args.save_anyway and res.plans) else None
    doc = {
        "characters": len(pairs),
        "planned": [plan_doc(p, fps) for p in res.plans],
        "failed": [{"character": c, "error": e} for c, e in res.failed],
        "conflicts": res.conflicts,
        "moving_prop_conflicts": moving,
        "delays_frames": res.delays,
        "rerouted": res.rerouted,
        "seconds": res.seconds,
        "patch": args.patch or api.active_patch_name(scene),
        "weights": w,
        "workers": args.workers,
        "scheduler": args.scheduler,
        "bodies": bodies_doc(bodies),
        "saved": saved,
    }
    text = [
        f"crowd: {len(res.plans)} of {len(pairs)} characters planned in "
        f"{res.seconds:.1f} s, {len(res.conflicts)} conflict(s)"
    ]
    for p in res.plans:
        wait = res.delays[p.character]
        text.append(
            "  "
            + plan_line(p, fps)
            + (f", waits {wait} frames" if wait else "")
            + (", re-routed round the others" if p.character in res.rerouted else "")
        )
    text += ["  " + t for t in bodies_text(bodies)]
    for c, e in res.failed:
        text.append(f"  FAILED {e}")
    for c in res.conflicts:
        text.append(
            f"  CONFLICT '{c['a']}' and '{c['b']}' come {c['distance_m'] * 100:.0f} cm "
            f"apart at frame {c['frame']}"
        )
    for c in moving:
        text.append(
            f"  CONFLICT '{c['character']}' meets the moving prop '{c['prop']}' at frame "
            f"{c['frame']} ({c['distance_m'] * 100:.0f} cm from its footprint)"
        )
    if saved:
        text.append(f"saved {saved}")
    elif save is not None:
        text.append(
            "not saved: the crowd has failures or conflicts (--save-anyway saves what was planned)"
        )
    return Result(doc, OK if ok else FAILED, text)
