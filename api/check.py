# SPDX-License-Identifier: GPL-3.0-or-later
"""Checking: figures of the evaluated motion against its plan (:func:`analyse`) and a
layout spec's pairs planned without writing (:func:`check_layout`)."""

from __future__ import annotations

import math
from collections.abc import Iterable

import bpy
import numpy as np

from ..adapter import evaluate, props_io, storage
from ..adapter import rig as rig_io
from ..adapter import scene as scene_io
from ..motion_patches.cluster import DaskCluster, InProcess
from ..motion_patches.planning import layout_check
from ..motion_patches.props.environment import Obstacle, inside_convex
from ..motion_patches.quality import foot_measure, layout_spec, metrics
from .common import (
    _check_character,
    _check_far,
    _children_map,
    _descendants,
    _limit_text,
    _same_place,
    _shrunk,
    _size,
    _some_names,
    load_plan_record,
    object_patches,
    scene_fps,
    state_dict,
)
from .errors import MotionPatchesError, cluster_kept
from .settings import plan_settings
from .solve import _start_matrix


def analyse(context: bpy.types.Context, character: bpy.types.Object, keep: bool = False) -> dict:
    """Figures of the evaluated (depsgraph) motion against the last plan on ``character``;
    ``keep`` stores them on it (:func:`last_analysis`, the Analysis panel)."""
    figures = _analyse(context, character)
    if keep:
        storage.store_analysis(character, figures)
    return figures


def _analyse(context, character):
    meta, arrays = load_plan_record(character)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    nf = len(meta["foot_names"])
    ankles, toes = _foot_bones(character, meta)
    names = [pb.name for pb in character.pose.bones]
    bones = [meta["root_name"]] + list(meta["foot_names"]) + ankles + toes
    body, ground, rot, _ = evaluate.sample_armature(context, character, frames, names)
    pos = body[:, [names.index(b) for b in bones]]
    fps = scene_fps(context.scene)
    root, feet = pos[:, 0], pos[:, 1 : 1 + nf]
    ankle_pos, toe_pos = pos[:, 1 + nf : 1 + nf + len(ankles)], pos[:, 1 + nf + len(ankles) :]
    skate = metrics.foot_skate(feet, fps, arrays["contacts"])
    by_layer = _skate_by_layer(meta, frames, feet, fps, arrays["contacts"])
    goal = np.array(meta["goal"])
    planned_root = arrays["root"]
    root_err = np.linalg.norm(root[:, :2] - planned_root[:, :2], axis=1)
    path_err = metrics.distance_to_polyline(ground[:, :2], arrays["ground"][:, :2])
    env = storage.plan_environment(meta)
    inside_mask = env.blocked(root[:, :2]) if meta["obstacles"] else np.zeros(frames.size, bool)
    during = np.zeros(frames.size, bool)
    for a, b in meta.get("traversals", []) + meta.get("interactions", []):
        during[(frames >= a) & (frames <= b)] = True  # clips that touch their prop
    inside = int((inside_mask & ~during).sum())
    # every strip's start (plans written before strips were cut within a piece: each piece's)
    joins = meta.get("joins", meta["boundaries"])
    boundaries = [b - meta["frame_start"] for b in joins]
    pops = metrics.boundary_pops(rot, boundaries, fps)
    end_heading = ground[-1, 2] + meta["facing"]
    return {
        "frames": int(frames.size),
        "seconds": float((frames.size - 1) / fps),
        "foot_skate": skate,
        "feet": foot_measure.measure(toe_pos, ankle_pos, fps),
        **({"foot_skate_by_layer": by_layer} if by_layer else {}),
        "root_from_plan_cm": {
            "mean": float(root_err.mean() * 100),
            "max": float(root_err.max() * 100),
        },
        "ground_from_path_cm": {"max": float(path_err.max() * 100)},
        "goal_position_error_cm": float(np.linalg.norm(ground[-1, :2] - goal[:2]) * 100),
        "goal_root_position_error_cm": float(np.linalg.norm(root[-1, :2] - goal[:2]) * 100),
        "goal_heading_error_deg": float(
            abs(np.degrees(metrics.angle_difference(end_heading, goal[2])))
        ),
        "frames_root_inside_obstacle": inside,
        "frames_root_over_prop_in_traversal": int((inside_mask & during).sum()),
        "frames_body_inside_prop": _body_inside_props(context, character, body),
        "traversals": len(meta.get("traversals", [])),
        "boundary_pop": pops,
    }


def _body_inside_props(context, character, heads):
    """Frames on which a bone of ``character`` (its head or its middle; ``heads`` (F, J, 3)
    evaluated, in pose-bone order) is inside a prop of the scene: over its footprint and
    more than a centimetre below its top. Traversal clips count too: a jump must clear."""
    parents = [pb.parent for pb in character.pose.bones]
    index = {pb.name: j for j, pb in enumerate(character.pose.bones)}
    kids = [j for j, p in enumerate(parents) if p is not None]
    mids = 0.5 * (heads[:, kids] + heads[:, [index[parents[j].name] for j in kids]])
    points = np.concatenate((heads, mids), axis=1)  # (F, P, 3)
    depsgraph = context.evaluated_depsgraph_get()
    own = [character, *character.children_recursive]
    inside = np.zeros(points.shape[0], bool)
    flat = points.reshape(-1, 3)
    for prop, obs in scene_io.obstacles_of_objects(context.scene, depsgraph, own):
        top = props_io.height(prop, depsgraph) if obs else 0.0
        for ob in obs:
            hit = inside_convex(flat[:, :2], ob.polygon) & (flat[:, 2] < top - 0.01)
            inside |= hit.reshape(points.shape[:2]).any(axis=1)
    return int(inside.sum())


def _foot_bones(character, meta):
    """([ankle bones], [toe bones]) of the character by bone role (its own armature's
    names: the label-free measure reads no plan), the plan's foot bones when its names
    follow no convention."""
    skel = rig_io.skeleton_in_metres(character)
    try:
        ankles, toes = foot_measure.foot_bones(skel)
    except ValueError:
        names = list(meta["foot_names"])
        ankles, toes = (
            [skel.names.index(n) for n in names[0::2]],
            [skel.names.index(n) for n in names[1::2]],
        )
    return [skel.names[i] for i in ankles], [skel.names[i] for i in toes]


def _skate_by_layer(meta, frames, feet, fps, planted):
    """{layer: foot skate} over the frames of each layer's strips (blends and clips counted
    in none) of a plan that changes layer; None for a plan in one layer."""
    spans = meta.get("layers") or []
    names = sorted({n for _, _, n in spans if n != "clip" and "->" not in n})
    if len(names) < 2:
        return None
    out = {}
    for name in names:
        mine = np.zeros(frames.size, bool)
        for a, b, n in spans:
            if n == name:
                mine[(frames >= a) & (frames <= b)] = True
        out[name] = metrics.foot_skate(feet, fps, np.asarray(planted, bool) & mine[:, None])
    return out


def _resolve(scene, objects, place, what, patch):
    """(state, object or None, size) for the name of an object of ``scene`` (``objects``:
    its objects by name) or [x, y, heading_deg]; a start that is an armature starts where
    its own skeleton stands (it may be retargeted) and plans in the world shrunk by its
    size (:func:`_size`; 1 otherwise)."""
    if what == "exclude":
        ob = objects.get(place)
        if ob is None:
            raise MotionPatchesError(f"layout spec: no object named '{place}' to exclude")
        return None, ob, 1.0
    if not isinstance(place, str):
        return np.array([place[0], place[1], math.radians(place[2])]), None, 1.0
    ob = objects.get(place)
    if ob is None:
        raise MotionPatchesError(
            f"layout spec: no object named '{place}' for a {what} "
            f"(have: {_some_names(scene.objects)})"
        )
    if what == "character" or (what == "start" and ob.type == "ARMATURE"):
        rig = _check_character(ob, patch)  # the rule plan_path applies to its character
        skel = rig.target if rig else patch.gait.skeleton
        return scene_io.character_state(ob, skel, _start_matrix(ob)), ob, _size(rig)
    return scene_io.ground_state(ob), ob, 1.0


def planned_pairs(
    scene: bpy.types.Scene,
    characters: Iterable[bpy.types.Object] = (),
    goals: Iterable[bpy.types.Object] = (),
) -> list[dict]:
    """Layout-spec pairs (:func:`check_layout`) for ``characters``: each from the character
    to the goal object at the same place in ``goals``, or (no goals) from where its stored
    plan starts to the goal that plan reached. No characters: every armature of the scene
    that has a plan."""
    characters, goals = list(characters), list(goals)
    if goals and len(goals) != len(characters):
        raise MotionPatchesError(
            f"give one goal per character ({len(characters)} characters, "
            f"{len(goals)} goals), or none to use each one's planned goal"
        )
    if not characters:
        characters = [ob for ob in scene.objects if ob.type == "ARMATURE" and storage.has_plan(ob)]
        if not characters:
            raise MotionPatchesError(
                "nothing to check: no pairs given and no character in the scene has a planned path"
            )
    pairs = []
    for n, ob in enumerate(characters):
        if ob is None or ob.type != "ARMATURE":
            raise MotionPatchesError("a character to check must be an armature")
        if goals:
            pairs.append({"name": ob.name, "character": ob.name, "goal": goals[n].name})
            continue
        meta, arrays = load_plan_record(ob)
        g0, goal = arrays["ground"][0], meta["goal"]
        pairs.append(
            {
                "name": ob.name,
                "start": [float(g0[0]), float(g0[1]), math.degrees(g0[2])],
                "goal": [float(goal[0]), float(goal[1]), math.degrees(goal[2])],
                "exclude": [ob.name],
            }
        )
    return pairs


def check_layout(
    scene: bpy.types.Scene,
    spec: dict,
    context: bpy.types.Context | None = None,
    executor: InProcess | DaskCluster | None = None,
) -> list[dict]:
    """Plan every start/goal pair of a layout ``spec`` WITHOUT writing to the scene.

    Returns one dict per pair: reachable, seconds of motion, length, cost, the props
    blocking it when it is not reachable, and whether it passed its limits. Raises
    :class:`MotionPatchesError` for a bad spec (unknown object or patch), before planning.
    The pairs are planned from the patch and the footprints alone
    (:func:`layout_check.plan_pair`): here, or on ``executor`` (:func:`cluster_executor`),
    with the same results. What a check builds (footprints, each world's planner) is kept
    for the next check of the same scene.
    """
    try:
        spec = layout_spec.normalise(spec)
    except layout_spec.SpecError as exc:
        raise MotionPatchesError(str(exc)) from None
    try:
        patch = storage.load_patch(scene, spec["patch"])
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    try:
        weights = plan_settings(scene, **{k: spec[k] for k in ("alpha", "beta", "gamma", "radius")})
    except MotionPatchesError as exc:
        raise MotionPatchesError(f"layout spec: {exc}") from None
    margin = 3 if spec["margin_tiles"] is None else int(spec["margin_tiles"])
    # Evaluate first: it also brings the objects' world matrices up to date.
    depsgraph = (context or bpy.context).evaluated_depsgraph_get()
    jobs: list = []
    refused: dict[int, str] = {}
    # The file's children and the scene's objects by name, read once: children_recursive
    # and a lookup in scene.objects each walk them all (0.2 ms among 5,000 objects).
    children = _children_map()
    objects = {o.name: o for o in scene.objects}
    for p in spec["pairs"]:
        # A retargeted character plans in the world shrunk by its size (see _size).
        start, sob, size = _resolve(
            scene, objects, p["start"], "character" if p.get("character") else "start", patch
        )
        goal, gob, _ = _resolve(scene, objects, p["goal"], "goal", patch)
        # Not obstacles: the start and goal objects with their children (a character's own
        # body mesh) and whatever the spec excludes.
        exclude = {}
        for ob in [sob, gob] + [
            _resolve(scene, objects, n, "exclude", patch)[1] for n in spec["exclude"] + p["exclude"]
        ]:
            if ob is not None:
                for o in (ob, *_descendants(ob, children)):
                    exclude[o.name] = o
        # Coordinates no plan can take are bad input (the spec's), not a failed pair.
        facing_goal = goal if p["goal_facing"] != "any" else np.array([*goal[:2], np.nan])
        planner_start, planner_goal = _shrunk(start, size), _shrunk(facing_goal, size)
        try:
            _check_far(
                planner_start,
                planner_goal,
                f"pair '{p['name']}'",
                size,
                same_place=False,  # a goal where it stands: that pair fails, reported
            )
        except MotionPatchesError as exc:
            raise MotionPatchesError(f"layout spec: {exc}") from None
        # a goal where it stands: nothing to plan, that pair fails (reported)
        same = _same_place(planner_start, planner_goal, "start", size)
        if same:
            refused[len(jobs)] = same
        jobs.append((p, start, sob, goal, gob, exclude, size))
    worlds, tasks, props = {}, [], {}
    # The scene's footprints are read once for every pair (each pair leaves out its own
    # excludes), and pairs that leave out the same meshes and props share their world:
    # read per pair, a spec of 200 pairs among 2,000 props spent 7 of its 20 s there.
    parts = scene_io.obstacles_of_objects(scene, depsgraph)
    every = [ob for _, obs in parts for ob in obs]
    owners = [prop.name for prop, obs in parts for _ in obs]
    meshes = set(owners)
    shrunk: dict[float, list] = {1.0: every}  # every footprint in the world of a size
    made: dict[tuple, layout_check.World] = {}
    for p, start, sob, goal, gob, exclude, size in jobs:
        allow = bool(p["limits"]["allow_traversal"])
        if size not in props:  # tagged props offer traversals
            props[size] = object_patches(scene, depsgraph, patch, size)
        gone = frozenset(n for n in exclude if n in meshes)
        unused = frozenset(pr.name for pr in props[size] if pr.name in exclude)
        key = (size, gone, allow, unused)
        w = made.get(key)
        if w is None:
            if size not in shrunk:  # the planner's world, shrunk by the character's size
                shrunk[size] = [Obstacle(ob.name, ob.polygon / size) for ob in every]
            obstacles = [ob for ob, o in zip(shrunk[size], owners) if o not in gone]
            usable = [pr for pr in props[size] if pr.name not in unused] if allow else []
            w = made[key] = layout_check.world(
                obstacles,
                weights.radius / size,
                weights.alpha,
                weights.beta,
                weights.gamma,
                weights.turn_in_place,
                usable,
            )
        worlds[w.key] = w
        facing = goal if p["goal_facing"] != "any" else np.array([goal[0], goal[1], np.nan])
        tasks.append(
            {
                "world": w.key,
                "start": _shrunk(start, size).tolist(),
                "goal": _shrunk(facing, size).tolist(),
                "margin": margin,
                "scale": size,
            }
        )
    run = executor if executor is not None else InProcess()
    with cluster_kept():
        planned = run.map(layout_check.plan_pair, tasks, patch=patch, worlds=worlds)
    results = []
    for k, ((p, start, sob, goal, gob, exclude, size), got) in enumerate(zip(jobs, planned)):
        if "planner_error" in got:
            raise MotionPatchesError(got["planner_error"])
        r = _pair_result(scene, p, start, sob, goal, gob, size, got)
        if k in refused:
            r.update(reachable=False, error=refused[k], blocked_reason="refused")
            r.update(seconds=None, frames=None, length_m=None, cost=None, pieces=None)
            r["failures"] = layout_spec.judge(r, p["limits"])
            r["passed"] = not r["failures"]
        results.append(r)
    return results


def _pair_result(scene, p, start, sob, goal, gob, size, got):
    """The report of one pair from what :func:`layout_check.plan_pair` found."""
    r = {
        "name": p["name"],
        "start": state_dict(start, sob and sob.name),
        "goal": state_dict(goal, gob and gob.name),
        "reachable": False,
        "seconds": None,
        "frames": None,
        "length_m": None,
        "cost": None,
        "pieces": None,
        "traversals": 0,
        "expansions": None,
        "plan_seconds": None,
        "blocked_by": [],
        "blocked_reason": got["blocked_reason"],
        "error": got["error"],
        "limits": p["limits"],
        "goal_facing": p["goal_facing"],
        "reused": got["reused"],  # answered from the same pair's plan in an unchanged world
    }
    if got["blocked_reason"] == "search limit":
        r["error"] = _limit_text(got["expanded"])
    elif not got["reachable"]:
        r["blocked_by"] = scene_io.owners(got["blocked"])
    else:
        r["goal"] = state_dict(_shrunk(got["goal"], 1.0 / size), gob and gob.name)
        r.update(
            reachable=True,
            frames=int(round(got["seconds"] * scene_fps(scene))) + 1,
            seconds=got["seconds"],
            length_m=got["length_m"] * size,
            **{k: got[k] for k in ("cost", "pieces", "expansions", "plan_seconds", "traversals")},
        )
    r["failures"] = layout_spec.judge(r, p["limits"])
    r["passed"] = not r["failures"]
    return r
