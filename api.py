"""Python API: the functions behind every operator (and, later, the CLI).

Arguments are plain Blender objects, actions, names and numbers; results are small
dataclasses. Every failure is a :class:`MotionPatchesError` with a message meant for the
user, raised before the scene is changed.
"""

import base64
import io
import json
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from .adapter import actions as act_io
from .adapter import evaluate, mocap, nla, props_io, scene as scene_io, storage
from .motion_patches import contacts, metrics, object_patch
from .motion_patches.gait import build_gait
from .motion_patches.locomotion_patch import bake
from .motion_patches.motion import concatenate
from .motion_patches.planner import (PlanError, SegmentPlanner, interaction_states,
                                     plan_motions, with_interactions)

PLAN_KEY = "motion_patches_plan"


class MotionPatchesError(ValueError):
    """A request the add-on cannot carry out; the message says why and what to do."""


@dataclass
class BakeResult:
    name: str
    layer: str
    stats: dict
    seconds: float
    notes: list


@dataclass
class PlanResult:
    character: str
    frame_start: int
    frame_end: int
    pieces: list
    cost: float
    seconds: float
    expansions: int
    strips: list
    stashed_action_track: str = None
    stats: dict = field(default_factory=dict)


def scene_fps(scene):
    return scene.render.fps / scene.render.fps_base


def import_mocap(paths, scale=mocap.CMU_SCALE, armature=None, name=None):
    """Import BVH files as actions on one armature; returns (armature, [actions])."""
    try:
        return mocap.import_bvh(paths, scale, armature, name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def bake_locomotion_patch(scene, armature, straight, turns=(), layer="walk", name=None,
                          cells=8, nodes=8, effort_rate=1.0, mirror_turns=True, progress=None):
    """Bake and store a locomotion patch from a straight action and turn actions."""
    if armature is None or armature.type != "ARMATURE":
        raise MotionPatchesError("choose the armature the clips were imported on")
    if straight is None:
        raise MotionPatchesError("choose a straight locomotion action")
    t0 = time.perf_counter()
    fps = scene_fps(scene)
    try:
        clips = [act_io.clip_from_action(a, armature, fps) for a in (straight,) + tuple(turns)]
        gait = build_gait(layer, clips[0], tuple(clips[1:]), fps=fps, mirror_turns=mirror_turns)
        patch = bake(gait, cells=cells, nodes=nodes, effort_rate=effort_rate, progress=progress)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    if patch.segment_count == 0:
        raise MotionPatchesError("every candidate segment was culled: the turn clips do not "
                                 "turn enough for this patch size")
    name = name or layer
    storage.store_patch(scene, patch, name)
    return BakeResult(name, layer, patch.stats, time.perf_counter() - t0, list(gait.notes))


def tag_object_patch(obj, clips, patch_name=None, scene=None, context=None):
    """Make ``obj`` an object patch carrying ``clips``: [(action, kind, effort, copy_step)]
    with kind 'TRAVERSAL' or 'INTERACTION'. Everything is validated first (footprint, root
    motion of each clip on the patch's skeleton); on error nothing is changed."""
    scene = scene or bpy.context.scene
    context = context or bpy.context
    try:
        patch = storage.load_patch(scene, patch_name)
    except ValueError as exc:
        raise MotionPatchesError(f"bake a locomotion patch before tagging props ({exc})") from None
    if obj is None:
        raise MotionPatchesError("choose a mesh object to tag")
    context.view_layer.update()
    depsgraph = context.evaluated_depsgraph_get()
    for action, kind, effort, step in clips:
        if kind not in props_io.KINDS:
            raise MotionPatchesError(f"clip kind must be TRAVERSAL or INTERACTION, not {kind}")
    try:
        props_io.footprint(obj, depsgraph)
        for action, kind, effort, step in clips:
            if action is None:
                raise ValueError("a clip has no action")
            clip = act_io.clip_from_action(action, None, scene_fps(scene),
                                           skeleton=patch.gait.skeleton)
            object_patch.patch_clip_from(clip, props_io.KINDS[kind], scene_fps(scene), effort)
    except ValueError as exc:
        raise MotionPatchesError(f"cannot tag '{obj.name}': {exc}") from None
    mp = obj.motion_patch
    mp.enabled = True
    mp.clips.clear()
    for action, kind, effort, step in clips:
        item = mp.clips.add()
        item.action, item.kind, item.effort, item.copy_step = action, kind, effort, step
    return obj


def object_patches(scene, depsgraph, patch):
    """Core object patches of every tagged prop in the scene."""
    out = []
    floor = patch.gait.floor()
    for obj in props_io.tagged(scene):
        try:
            out.append(props_io.object_patch(obj, depsgraph, patch.gait.skeleton, patch.gait.fps,
                                             gait_floor=floor))
        except ValueError as exc:
            raise MotionPatchesError(str(exc)) from None
    return out


def _plan_store(obj, data):
    buf = io.BytesIO()
    np.savez_compressed(buf, **{k: v for k, v in data.items() if isinstance(v, np.ndarray)})
    meta = {k: v for k, v in data.items() if not isinstance(v, np.ndarray)}
    obj[PLAN_KEY] = json.dumps({"meta": meta, "arrays": base64.b64encode(buf.getvalue()).decode()})


def load_plan_record(obj):
    """The last plan written on ``obj`` (meta dict, arrays dict)."""
    raw = obj.get(PLAN_KEY)
    if raw is None:
        raise MotionPatchesError(f"'{obj.name}' has no planned motion; plan a path first")
    d = json.loads(raw)
    with np.load(io.BytesIO(base64.b64decode(d["arrays"]))) as z:
        arrays = {k: z[k] for k in z.files}
    return d["meta"], arrays


def plan_path(scene, character, goal, patch_name=None, alpha=1.0, beta=0.5, gamma=0.2,
              radius=0.25, frame_start=None, context=None, stitching="dynamic", start_prop=None):
    """Plan ``character`` to ``goal`` (an object or (x, y, heading)) and write it as NLA.

    Tagged props (object patches) offer their traversal clips; ``stitching`` is
    "dynamic" (lazy, the paper's method) or "static" (everything stitched first). A goal
    that is a tagged prop with a sit-down interaction clip ends the path seated on it; a
    ``start_prop`` with a stand-up clip starts it there (the character's own position is
    then not used)."""
    try:
        patch = storage.load_patch(scene, patch_name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    if abs(patch.gait.fps - scene_fps(scene)) > 1e-3:
        raise MotionPatchesError(f"the patch was baked at {patch.gait.fps:g} fps but the scene "
                                 f"runs at {scene_fps(scene):g} fps; re-bake or change the scene rate")
    skel = patch.gait.skeleton
    # Objects moved by a script have stale matrix_world until the view layer updates.
    (context or bpy.context).view_layer.update()
    try:
        nla.check_rig(character, skel)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    # The character's own meshes (children of the rig) never block it.
    exclude = (character,) + tuple(character.children_recursive)
    if isinstance(goal, bpy.types.Object):
        goal_state = scene_io.ground_state(goal)
        if not goal.motion_patch.enabled:  # a goal prop (sit on it) stays an obstacle
            exclude += (goal,) + tuple(goal.children_recursive)
    else:
        if goal is None or len(goal) != 3:
            raise MotionPatchesError("choose a goal object (its location and facing)")
        goal_state = np.asarray(goal, float)
    depsgraph = (context or bpy.context).evaluated_depsgraph_get()
    env = scene_io.environment(scene, depsgraph, patch, radius, exclude)
    start_state = scene_io.character_state(character, skel)
    props = object_patches(scene, depsgraph, patch)
    by_name = {p.name: p for p in props}
    start_ref = goal_ref = None
    if isinstance(goal, bpy.types.Object) and goal.name in by_name:
        i = props_io.interaction_clip(by_name[goal.name], sitting=True)
        if i is None:
            raise MotionPatchesError(f"the goal '{goal.name}' is a prop without a sit-down "
                                     f"interaction clip: there is nowhere to end the path")
        goal_ref = (by_name[goal.name], i)
    if start_prop is not None:
        if start_prop.name not in by_name:
            raise MotionPatchesError(f"'{start_prop.name}' is not a tagged object patch")
        i = props_io.interaction_clip(by_name[start_prop.name], sitting=False)
        if i is None:
            raise MotionPatchesError(f"'{start_prop.name}' has no stand-up interaction clip")
        start_ref = (by_name[start_prop.name], i)
    s_state, g_state = interaction_states(start_ref, goal_ref)
    start_state = start_state if s_state is None else s_state
    goal_state = goal_state if g_state is None else g_state
    try:
        plan = SegmentPlanner(patch, env, alpha, beta, gamma, props=props,
                              mode=stitching).plan(start_state, goal_state)
    except PlanError as exc:
        raise MotionPatchesError(str(exc)) from None
    plan = with_interactions(plan, start_ref, goal_ref)
    motions = plan_motions(patch, plan)
    world = concatenate(motions)
    frame_start = scene.frame_current if frame_start is None else int(frame_start)
    patch_key = storage.patch_key(scene, patch_name)
    strips, stashed = nla.write_plan(bpy, character, patch, patch_key, plan, motions, world,
                                     frame_start)
    wm = world.world_matrices(skel)
    foot = contacts.foot_joints(skel)
    frame_end = frame_start + world.frames - 1
    _plan_store(character, {
        "ground": world.ground, "root": wm[:, skel.root, :3, 3], "contacts": world.contacts,
        "foot_names": [skel.names[i] for i in foot], "root_name": skel.names[skel.root],
        "frame_start": frame_start, "frame_end": frame_end, "goal": goal_state.tolist(),
        "boundaries": [s["start"] for s in strips[1:]], "radius": radius,
        "facing": nla.facing_angle(skel),
        "traversals": [[s["start"], s["end"]] for s in strips if s["kind"] == "traversal"],
        "interactions": [[s["start"], s["end"]] for s in strips if s["kind"] == "interaction"],
        "obstacles": {o.name: o.polygon.tolist() for o in env.obstacles.values()},
    })
    return PlanResult(character.name, frame_start, frame_end, [p.label for p in plan.pieces],
                      plan.cost, plan.seconds, plan.expansions, strips, stashed, plan.stats)


def analyse(context, character):
    """Figures of the evaluated (depsgraph) motion against the last plan on ``character``."""
    meta, arrays = load_plan_record(character)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    bones = [meta["root_name"]] + list(meta["foot_names"])
    pos, ground, rot, _ = evaluate.sample_armature(context, character, frames, bones)
    fps = scene_fps(context.scene)
    root, feet = pos[:, 0], pos[:, 1:]
    skate = metrics.foot_skate(feet, fps, arrays["contacts"])
    goal = np.array(meta["goal"])
    planned_root = arrays["root"]
    root_err = np.linalg.norm(root[:, :2] - planned_root[:, :2], axis=1)
    path_err = metrics.distance_to_polyline(ground[:, :2], arrays["ground"][:, :2])
    from .motion_patches.environment import Environment, Obstacle
    env = Environment(1.0, 8, 0.0)
    for name, poly in meta["obstacles"].items():
        env.place(Obstacle(name, np.array(poly)))
    inside_mask = env.blocked(root[:, :2]) if meta["obstacles"] else np.zeros(frames.size, bool)
    during = np.zeros(frames.size, bool)
    for a, b in meta.get("traversals", []) + meta.get("interactions", []):
        during[(frames >= a) & (frames <= b)] = True  # clips that touch their prop
    inside = int((inside_mask & ~during).sum())
    boundaries = [b - meta["frame_start"] for b in meta["boundaries"]]
    pops = metrics.boundary_pops(rot, boundaries, fps)
    end_heading = ground[-1, 2] + meta["facing"]
    return {
        "frames": int(frames.size),
        "seconds": float((frames.size - 1) / fps),
        "foot_skate": skate,
        "root_from_plan_cm": {"mean": float(root_err.mean() * 100), "max": float(root_err.max() * 100)},
        "ground_from_path_cm": {"max": float(path_err.max() * 100)},
        "goal_position_error_cm": float(np.linalg.norm(ground[-1, :2] - goal[:2]) * 100),
        "goal_root_position_error_cm": float(np.linalg.norm(root[-1, :2] - goal[:2]) * 100),
        "goal_heading_error_deg": float(abs(np.degrees(metrics.angle_difference(end_heading, goal[2])))),
        "frames_root_inside_obstacle": inside,
        "frames_root_over_prop_in_traversal": int((inside_mask & during).sum()),
        "traversals": len(meta.get("traversals", [])),
        "boundary_pop": pops,
    }
