"""Python API: the functions behind every operator and every CLI command.

Arguments are plain Blender objects, actions, names and numbers; results are small
dataclasses. Every failure is a :class:`MotionPatchesError` with a message meant for the
user, raised before the scene is changed.
"""

import base64
import contextlib
import io
import json
import math
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from .adapter import actions as act_io
from .adapter import evaluate, mocap, nla, props_io, scene as scene_io, storage
from .adapter import compat
from .adapter import moving as moving_io
from .adapter import rig as rig_io
from .adapter import transaction
from .motion_patches import (blocking, body_clearance, causes, contacts, crowd, foot_lock,
                             layout_spec, metrics, moving_props, object_patch, validate)
from .motion_patches import layers, scene_rate
from .motion_patches.environment import Obstacle
from .motion_patches.gait import MIN_TURN, build_gait
from .motion_patches.locomotion_patch import bake
from .motion_patches.motion import concatenate
from .motion_patches.planner import (PlanError, SegmentPlanner, interaction_states,
                                     plan_motions, with_interactions)

PLAN_KEY = "motion_patches_plan"
CROWD_SPOT = "\x00crowd spot "  # obstacle names of other characters' standing spots
CROWD_GHOST = "\x00crowd ghost "  # where another character walks when two would meet


class MotionPatchesError(ValueError):
    """A request the add-on cannot carry out; the message says why and what to do."""


class PathNotFound(MotionPatchesError):
    """The request was fine but no path was found; the message ends with the cause, also
    given as ``cause``: "props" (named in ``props``), "patch" (its walks turn too wide or
    connect too sparsely for this start and goal, even on open ground), "search limit" or
    "moving" (props keyframed across the path, named in ``props``)."""

    def __init__(self, message, cause=None, props=()):
        super().__init__(message)
        self.cause, self.props = cause, list(props)


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
    length_m: float = 0.0
    goal: tuple = None  # (x, y, heading) reached: the facing chosen when any would do


@dataclass
class CrowdResult:
    plans: list        # PlanResult per planned character, in the order given
    failed: list       # [(character name, why no path)]
    conflicts: list    # [{"a", "b", "frame", "distance_m"}] closer than two radii
    delays: dict       # character name -> frames it waits at its start
    seconds: float
    rerouted: list = field(default_factory=list)  # names re-planned round others' stretches


def scene_fps(scene):
    return scene.render.fps / scene.render.fps_base


def import_mocap(paths, scale=mocap.CMU_SCALE, armature=None, name=None):
    """Import BVH files as actions on one armature; returns (armature, [actions])."""
    try:
        return mocap.import_bvh(paths, scale, armature, name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def bake_locomotion_patch(scene, armature, straight, turns=(), layer="walk", name=None,
                          cells=8, nodes=8, effort_rate=None, mirror_turns=True, progress=None):
    """Bake and store a locomotion patch from a straight action and turn actions (none
    needed: the straight stride is bent to turns, see ``gait.STRAIGHT_BEND_RADIUS``).
    Its tile side is two straight cycles, so a run's tiles are larger than a walk's.
    ``effort_rate`` (effort T per second) defaults to the gait's
    (:func:`motion_patches.layers.effort_rate`: 1 for a walk, more for a run) so the
    costs of two layers compare. A patch too sparse to connect is refused, saying what
    to add."""
    if armature is None or armature.type != "ARMATURE":
        raise MotionPatchesError("choose the armature the clips were imported on")
    if straight is None:
        raise MotionPatchesError("choose a straight locomotion action")
    t0 = time.perf_counter()
    fps = scene_fps(scene)
    bones = {b.name for b in armature.data.bones}
    for action in (straight,) + tuple(turns):
        unknown = sorted(_animated_bones(action) - bones)
        if unknown:
            raise MotionPatchesError(
                f"the action '{action.name}' animates bones the armature '{armature.name}' does "
                f"not have ({', '.join(unknown[:6])}{', ...' if len(unknown) > 6 else ''}): its "
                f"bone names differ; import its BVH onto this armature (it is then retargeted) "
                f"or rename its bones")
    try:
        clips = [act_io.clip_from_action(a, armature, fps) for a in (straight,) + tuple(turns)]
        gait = build_gait(layer, clips[0], tuple(clips[1:]), fps=fps, mirror_turns=mirror_turns)
        for action in turns:
            if not any(n.startswith(f"turn: {action.name} ") for n in gait.notes):
                raise ValueError(
                    f"the turn clip '{action.name}' does not turn: none of its gait cycles turns "
                    f"{np.degrees(MIN_TURN):.0f} degrees or more; give a clip that turns, or "
                    f"bake without it (the straight stride is bent to turns)")
        if effort_rate is None:
            effort_rate = layers.effort_rate(gait)
        patch = bake(gait, cells=cells, nodes=nodes, effort_rate=effort_rate, progress=progress)
    except ValueError as exc:  # SparsePatch included
        raise MotionPatchesError(str(exc)) from None
    name = name or layer
    storage.store_patch(scene, patch, name)
    return BakeResult(name, layer, patch.stats, time.perf_counter() - t0, list(gait.notes))


def _animated_bones(action):
    """Names of the bones an action's F-curves animate (``pose.bones["name"]...`` paths)."""
    out = set()
    for fc in compat.fcurves(action):
        path = fc.data_path
        if path.startswith('pose.bones["'):
            out.add(path[len('pose.bones["'):path.index('"]')])
    return out


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


def export_patch(scene, path, patch_name=None):
    """Write a baked patch (the active one by default) to a file another scene can import."""
    try:
        storage.export_patch(scene, patch_name, path)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    except OSError as exc:
        raise MotionPatchesError(f"cannot write {path}: {exc.strerror or exc}") from None


def import_patch(scene, path, name=None):
    """Store a patch file written by :func:`export_patch` in ``scene``; returns its name."""
    try:
        return storage.import_patch(scene, path, name).name
    except OSError as exc:
        raise MotionPatchesError(f"cannot read {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise MotionPatchesError(f"{path}: {exc}") from None


def object_patches(scene, depsgraph, patch, scale=1.0):
    """Core object patches of every tagged prop in the scene (``scale``: the character's
    size relative to the patch skeleton, :func:`_size`: props placed in the world the
    planner sees, shrunk by it)."""
    out = []
    floor = patch.gait.floor()
    for obj in props_io.tagged(scene):
        try:
            out.append(props_io.object_patch(obj, depsgraph, patch.gait.skeleton, patch.gait.fps,
                                             gait_floor=floor, scale=scale))
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


def state_dict(state, name=None):
    """(x, y, heading) as JSON-friendly numbers (heading in degrees, -180..180)."""
    h = (float(np.degrees(state[2])) + 180.0) % 360.0 - 180.0
    d = {"x": round(float(state[0]), 6), "y": round(float(state[1]), 6),
         "heading_deg": round(h, 4) + 0.0}
    if name is not None:
        d["object"] = name
    return d


def path_length(ground):
    """Metres walked by a ground trajectory (frames, >= 2)."""
    return float(np.linalg.norm(np.diff(np.asarray(ground)[:, :2], axis=0), axis=1).sum())


def _patch_for_planning(scene, patch_name):
    """The stored patch to plan with. A scene at another frame rate than the patch's is
    fine: strips play the patch's keys scaled in time (:mod:`motion_patches.scene_rate`)."""
    try:
        return storage.load_patch(scene, patch_name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def _check_character(character, patch):
    """The :class:`~motion_patches.retarget.RigMap` that puts the patch on the character
    (None: it is the patch's own skeleton); :class:`MotionPatchesError` naming the patch
    bones its armature cannot play."""
    try:
        return nla.check_rig(character, patch.gait.skeleton, patch.gait.floor())
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def bone_map(scene, character, patch_name=None):
    """{patch bone: bone of ``character`` that plays it ('' = none)}: what planning the
    character with the patch uses (its stored bone map over the names' pairing).
    :class:`MotionPatchesError` naming the patch bones that cannot be mapped."""
    patch = _patch_for_planning(scene, patch_name)
    rig = _check_character(character, patch)
    names = patch.gait.skeleton.names
    mapping = {n: n for n in names} if rig is None else rig.mapping
    return {n: mapping.get(n, "") for n in names}


def fill_bone_map(scene, character, patch_name=None):
    """Store on ``character``'s armature a bone map listing every patch bone with the rig
    bone the names give ('' where none), for an animator to correct; returns it. Works
    even when the names leave the legs unmapped (that is what the map is for)."""
    patch = _patch_for_planning(scene, patch_name)
    if character is None or character.type != "ARMATURE":
        raise MotionPatchesError("choose an armature")
    try:
        mapping = rig_io.guessed_map(character, patch.gait.skeleton)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    rig_io.set_bone_map(character, mapping)
    return mapping


def set_bone_map(character, mapping):
    """Store ``mapping`` ({patch bone: rig bone, '' = left out}) as the bone map of the
    armature of ``character`` (shared by every object using that armature); an empty
    mapping clears it (bones are then paired by their names)."""
    if character is None or character.type != "ARMATURE":
        raise MotionPatchesError("choose an armature")
    bones = {b.name for b in character.data.bones}
    wrong = [r for r in mapping.values() if r and r not in bones]
    if wrong:
        raise MotionPatchesError(f"armature '{character.name}' has no bones "
                                 f"{', '.join(wrong[:6])}")
    rig_io.set_bone_map(character, dict(mapping))


def _size(rig):
    """How much larger the character is than the patch's skeleton (its hip-height ratio).
    The planner works in the world divided by it, where the patch's steps are the
    character's; its motion is scaled back by :meth:`RigMap.motion`."""
    return 1.0 if rig is None else float(rig.scale)


def _shrunk(state, scale):
    """A world (x, y, heading) in the planner's world of a character ``scale`` times the
    patch skeleton's size (and back with ``1 / scale``)."""
    state = np.array(state, float)
    state[:2] /= scale
    return state


def _not_obstacles(objects):
    """Objects that never block: the given ones with their children (a character's own
    body mesh), except tagged props (a goal prop to sit on stays an obstacle)."""
    out = []
    for ob in objects:
        if ob is not None and not (ob.type == "MESH" and ob.motion_patch.enabled):
            out += [ob, *ob.children_recursive]
    return tuple(out)


def _goal(goal):
    if isinstance(goal, bpy.types.Object):
        return scene_io.ground_state(goal)
    try:
        state = np.asarray(goal, float).reshape(3)
    except (TypeError, ValueError):
        raise MotionPatchesError("choose a goal object (its location and facing) or give "
                                 "(x, y, heading)") from None
    if not np.isfinite(state).all():
        raise MotionPatchesError("the goal (x, y, heading) must be finite numbers")
    return state


def _endpoints(character, goal, start_prop, by_name, skel, goal_facing="exact", scale=1.0):
    """Start and goal states with the interaction clips that begin / end the path there;
    ``goal_facing`` "any" leaves the goal heading free (NaN) unless a clip fixes it.
    ``skel``: the character's own skeleton; the states are in the planner's world of a
    character ``scale`` times the patch's size (:func:`_size`)."""
    if goal_facing not in ("exact", "any"):
        raise MotionPatchesError(f"goal facing must be 'exact' or 'any', not {goal_facing!r}")
    start_state = _shrunk(scene_io.character_state(character, skel), scale)
    goal_state = _shrunk(_goal(goal), scale)
    if goal_facing == "any":
        goal_state = np.array([goal_state[0], goal_state[1], np.nan])
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
    return (start_state if s_state is None else s_state,
            goal_state if g_state is None else g_state, start_ref, goal_ref)


@contextlib.contextmanager
def _without(env, names):
    """``env`` with the named obstacles (and their parts, :func:`adapter.scene.part_name`)
    taken out for the block (put back after)."""
    names = set(names)
    saved = [ob for n, ob in env.obstacles.items() if n in names or scene_io.owner(n) in names]
    for ob in saved:
        env.remove(ob.name)
    try:
        yield env
    finally:
        for ob in saved:
            env.place(ob)


def _check_clear(env, character, endpoints, by_name):
    """Refuse a start or goal the character cannot stand on, naming the prop in the way."""
    for what, state, ref in (("start", endpoints[0], endpoints[2]),
                             ("goal", endpoints[1], endpoints[3])):
        if ref is not None:  # sitting down / standing up: the clip's own end, beside the prop
            continue
        near = scene_io.owners(env.near(state))
        if not near:
            continue
        who = f"the {what} of '{character.name}'"
        tagged = [n for n in near if n in by_name]
        if tagged:
            raise MotionPatchesError(
                f"{who} is inside the object patch '{tagged[0]}', which has no interaction "
                f"clip that starts or ends there: move the {what} out, or give "
                f"'{tagged[0]}' a sit-down / stand-up clip and use the prop itself")
        raise MotionPatchesError(f"{who} is inside or within {env.radius:.2f} m of "
                                 f"{', '.join(repr(n) for n in near[:4])}: move it into the open")


def _solve(planner, character, endpoints, explain=True):
    """The plan of one character; :class:`PathNotFound` naming the cause when there is none
    (``explain=False`` skips finding the cause: a crowd retries such a failure without
    the others' standing spots)."""
    start_state, goal_state, start_ref, goal_ref = endpoints
    try:
        if explain:
            plan = causes.plan_explained(planner, start_state, goal_state)
        else:
            plan = planner.plan(start_state, goal_state)
    except causes.NoPath as exc:
        if exc.cause == "search limit":
            raise PathNotFound(f"no path for '{character.name}': "
                               f"{_limit_text(causes.SEARCH_LIMIT)}", exc.cause) from None
        raise PathNotFound(f"no path for '{character.name}': {exc}", exc.cause,
                           scene_io.owners(exc.props)) from None
    except PlanError as exc:
        raise PathNotFound(f"no path for '{character.name}': {exc}") from None
    return with_interactions(plan, start_ref, goal_ref)


def _body_clear(planner, plan, motions, ends):
    """(plan, its motions) whose hips keep the radius too (:mod:`body_clearance`)."""
    return body_clearance.keep_clear(planner, plan, motions, ends[0], ends[1],
                                     lambda p: plan_motions(planner.patch, p),
                                     lambda p: with_interactions(p, ends[2], ends[3]))


def _writable(character, first=None, frames=None):
    """Refuse, before anything is written, a plan on ``character`` that writing could not
    carry out or that would delete user data (:func:`adapter.transaction.check_writable`);
    ``first``: its first frame, ``frames``: how many."""
    why = transaction.check_writable(bpy, character, first,
                                     None if first is None else first + frames - 1)
    if why:
        raise MotionPatchesError(why)


def _frame_start(scene, frame_start):
    """The first frame of a plan: the scene's current frame, or ``frame_start`` (a whole
    number Blender can hold)."""
    if frame_start is None:
        return scene.frame_current
    lo, hi = transaction.frame_limits(bpy)
    try:
        f = float(frame_start)
    except (TypeError, ValueError):
        raise MotionPatchesError(f"the start frame must be a number, not {frame_start!r}") from None
    if not (math.isfinite(f) and lo <= f <= hi):
        raise MotionPatchesError(f"the start frame {frame_start} is outside what Blender holds "
                                 f"({lo} to {hi})")
    return int(round(f))


MAX_WEIGHT = 1e6      # alpha, beta, gamma above this overflow the search's costs
MAX_RADIUS = 10.0     # metres: a character's radius
MAX_COORDINATE = 1e5  # metres from the origin a start or goal may lie
MAX_DISTANCE = 2000.0  # metres between start and goal of one plan (plan longer walks in legs)
SAME_PLACE = 0.05     # metres: a goal this near the start, facing the same way, is the start
SAME_FACING = np.radians(2.0)


def _check_weights(alpha, beta, gamma, radius, where=""):
    """Refuse weights the search cannot sum (NaN, negative, huge) and a radius that is not
    a body's, naming the value."""
    for name, v in (("alpha", alpha), ("beta", beta), ("gamma", gamma)):
        try:
            ok = math.isfinite(float(v)) and 0.0 <= float(v) <= MAX_WEIGHT
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise MotionPatchesError(f"{where}{name} must be a number from 0 to {MAX_WEIGHT:g}, "
                                     f"not {v!r}")
    try:
        ok = math.isfinite(float(radius)) and 0.0 < float(radius) <= MAX_RADIUS
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise MotionPatchesError(f"{where}radius must be a number of metres above 0 and at most "
                                 f"{MAX_RADIUS:g}, not {radius!r}")


def _check_far(start, goal, who, scale=1.0):
    """Refuse a start or goal farther from the origin than ``MAX_COORDINATE`` or start and
    goal farther apart than ``MAX_DISTANCE`` (planner-world states of a character ``scale``
    times the patch's size), and a goal where the start is (same place, same facing)."""
    for what, state in (("start", start), ("goal", goal)):
        far = float(np.abs(np.asarray(state[:2], float)).max()) * scale
        if not far <= MAX_COORDINATE:
            raise MotionPatchesError(f"the {what} of {who} lies {far:.3g} m from the origin; "
                                     f"plans stay within {MAX_COORDINATE:g} m of it")
    d = float(np.hypot(*(np.asarray(goal[:2], float) - np.asarray(start[:2], float)))) * scale
    if d > MAX_DISTANCE:
        raise MotionPatchesError(f"the goal of {who} is {d:,.0f} m from its start; one plan "
                                 f"walks at most {MAX_DISTANCE:,.0f} m: plan the walk in legs")
    turn = abs((float(goal[2]) - float(start[2]) + np.pi) % (2 * np.pi) - np.pi)
    if d < SAME_PLACE and (np.isnan(goal[2]) or turn < SAME_FACING):
        raise MotionPatchesError(f"the goal of {who} is where it stands ({d * 100:.0f} cm away, "
                                 f"facing the same way): there is nothing to plan")


def _check_ends(character, endpoints, scale):
    """:func:`_check_far` of a character's start and goal states (``_endpoints``) unless a
    prop's clip starts or ends the path there."""
    if endpoints[2] is None and endpoints[3] is None:
        _check_far(endpoints[0], endpoints[1], f"'{character.name}'", scale)


def _limit_text(nodes):
    return (f"search limit reached after {nodes:,} nodes: the search stopped before finding a "
            f"way, which does not mean the props close it; plan to a nearer goal first and on "
            f"from there")


def _placed(scene, patch, rig, motions):
    """A plan's piece motions (:func:`plan_motions`) put on the character: (its pieces'
    motions on its skeleton, at the patch's rate; the scene frames where the pieces start
    and the last ends, from 0; the whole motion on the scene's frames). ``rig``: the
    character's :class:`~motion_patches.retarget.RigMap` (None: the patch skeleton)."""
    if rig is not None:
        motions = [rig.motion(m) for m in motions]
    patch_bounds, bounds = scene_rate.piece_bounds([m.frames for m in motions],
                                                   scene_fps(scene) / patch.gait.fps)
    world = scene_rate.at_scene_rate(concatenate(motions), patch_bounds, bounds)
    return motions, bounds, world


FRAME_RANGE_KEY = "motion_patches_frame_range"  # the scene frame range last set by a plan
BLENDER_DEFAULT_RANGE = (1, 250)                 # a new scene's: not a range anyone chose


def fitted_frame_range(current, plans, ours=None):
    """The scene's frame range after planning: the span of ``plans`` ((start, end) of every
    planned character), unless ``current`` is a range the user chose (neither Blender's
    default 1-250 nor ``ours``, the range planning set last), which is only extended to
    cover the plans, never shortened."""
    lo, hi = min(p[0] for p in plans), max(p[1] for p in plans)
    current = tuple(int(f) for f in current)
    if current == BLENDER_DEFAULT_RANGE or (ours is not None and current == tuple(ours)):
        return lo, hi
    return min(current[0], lo), max(current[1], hi)


def _fit_frame_range(scene):
    """Apply :func:`fitted_frame_range` to ``scene`` when its Fit Frame Range is on."""
    if not getattr(scene.motion_patches, "fit_frame_range", True):
        return
    plans = [(m["frame_start"], m["frame_end"]) for m in
             (json.loads(ob[PLAN_KEY])["meta"] for ob in scene.objects if PLAN_KEY in ob)]
    if plans:
        ours = scene.get(FRAME_RANGE_KEY)
        start, end = fitted_frame_range((scene.frame_start, scene.frame_end), plans,
                                        tuple(ours) if ours is not None else None)
        scene.frame_start, scene.frame_end = start, end
        scene[FRAME_RANGE_KEY] = [start, end]


def _write(scene, character, patch, patch_name, plan, placed, frame_start, env, radius,
           lock=True, rig=None, fit=True):
    """NLA strips and the plan record of one planned character (``placed``: its motion,
    :func:`_placed`; ``env``: the planner's world, shrunk by the character's size).
    ``fit``: fit the scene's frame range now (a crowd fits it once, after every write)."""
    scale = _size(rig)
    goal_state = _shrunk(plan.goal, 1.0 / scale)  # the facing reached when any would do
    skel = rig.target if rig is not None else patch.gait.skeleton
    motions, bounds, world = placed
    locked = foot_lock.lock_feet(skel, world) if lock else None
    strips, stashed = nla.write_plan(bpy, character, patch, storage.patch_key(scene, patch_name),
                                     plan, motions, world, frame_start, locked, rig, bounds)
    wm = world.world_matrices(skel)
    foot = contacts.foot_joints(skel)
    frame_end = frame_start + world.frames - 1
    if rig is not None:
        plan.stats["retarget"] = rig.note()
    if abs(scene_fps(scene) - patch.gait.fps) > 1e-3:
        plan.stats["frame_rate"] = (f"patch baked at {patch.gait.fps:g} fps, played at the "
                                    f"scene's {scene_fps(scene):g} fps (strips scaled)")
    _plan_store(character, {
        "ground": world.ground, "root": wm[:, skel.root, :3, 3], "contacts": world.contacts,
        "foot_names": [skel.names[i] for i in foot], "root_name": skel.names[skel.root],
        "frame_start": frame_start, "frame_end": frame_end, "goal": goal_state.tolist(),
        "boundaries": [s["start"] for s in strips[1:]], "radius": radius,
        "facing": nla.facing_angle(skel), "foot_lock": bool(lock),
        "traversals": [[s["start"], s["end"]] for s in strips if s["kind"] == "traversal"],
        "interactions": [[s["start"], s["end"]] for s in strips if s["kind"] == "interaction"],
        "obstacles": {o.name: (o.polygon * scale).tolist() for o in env.obstacles.values()},
    })
    if fit:
        _fit_frame_range(scene)
    return PlanResult(character.name, frame_start, frame_end, [p.label for p in plan.pieces],
                      plan.cost, plan.seconds, plan.expansions, strips, stashed, plan.stats,
                      path_length(world.ground), tuple(goal_state))


def _avoid_moving(planner, patch, plan, tracks, character, frame_start, fps):
    """(plan, seconds to wait at the start) clear of the props that move during it
    (:mod:`moving_props`: a wait or a repaired run); :class:`PathNotFound` naming the prop
    and the frame when neither keeps clear of it. ``fps``: the scene's rate."""
    scene_fps_ratio = fps / patch.gait.fps
    plan, wait, repairs, left = moving_props.avoid(planner, patch, plan, tracks,
                                                   lambda p: plan_motions(patch, p))
    if left:
        raise PathNotFound(f"no path for '{character.name}' clear of moving props: "
                           + "; ".join(c.describe(patch.gait.fps, frame_start, fps) for c in left)
                           + " (move the prop's keyframes, or start later with Frame Start)",
                           "moving", [c.prop for c in left])
    plan.stats["moving_props"] = {
        "props": [t.name for t in tracks],
        "awake_at_start": [t.name for t in tracks if t.awake_at(0.0)],
        "wait_s": wait,
        "repairs": [dict(r, frame=frame_start + int(round(r["frame"] * scene_fps_ratio)))
                    for r in repairs]}
    return plan, wait


def plan_path(scene, character, goal, patch_name=None, alpha=1.0, beta=0.5, gamma=0.2,
              radius=0.25, frame_start=None, context=None, stitching="dynamic", start_prop=None,
              foot_lock=True, goal_facing="exact", gait=None):
    """Plan ``character`` to ``goal`` (an object or (x, y, heading)) and write it as NLA.

    Tagged props (object patches) offer their traversal clips; ``stitching`` is
    "dynamic" (lazy, the paper's method) or "static" (everything stitched first). A goal
    that is a tagged prop with a sit-down interaction clip ends the path seated on it; a
    ``start_prop`` with a stand-up clip starts it there (the character's own position is
    then not used). With ``foot_lock`` planted feet are pinned by leg IK, written as a
    an Add track over the shared segment strips. ``goal_facing="any"`` lets the walk end
    facing whichever way is cheapest (the goal object's facing is then ignored).
    ``gait`` picks the layer: a layer name ("walk", "run") plans with the stored patch of
    that layer, "auto" plans in every layer stored and keeps the cheapest Eq. 5 cost
    (:mod:`motion_patches.layers`; ``stats["layers"]`` gives each layer's cost), None
    plans with ``patch_name`` (or the active patch). Raises
    :class:`PathNotFound` when the props leave no way, and
    :class:`MotionPatchesError` for bad input; either way the scene is unchanged."""
    _check_weights(alpha, beta, gamma, radius)
    candidates = _layer_patches(scene, patch_name, gait)
    context = context or bpy.context
    # Objects moved by a script have stale matrix_world until the view layer updates.
    context.view_layer.update()
    if goal is None:
        raise MotionPatchesError("choose a goal object (its location and facing)")
    if goal == character:
        raise MotionPatchesError("the goal cannot be the character itself")
    frame_start = _frame_start(scene, frame_start)
    _writable(character)
    tried, failures = [], []
    for name, patch in candidates:
        try:
            tried.append(_plan_in_layer(scene, character, goal, patch, alpha, beta, gamma,
                                        radius, frame_start, context, stitching, start_prop,
                                        goal_facing) + (name,))
        except PathNotFound as exc:
            if len(candidates) == 1:
                raise
            failures.append((patch.layer, exc))
    if not tried:
        first = failures[0][1]
        raise PathNotFound("; ".join(f"{layer}: {exc}" for layer, exc in failures),
                           first.cause, first.props)
    best = layers.choose([t[3].cost for t in tried])
    patch, rig, env, plan, motions, start_frame, name = tried[best]
    if gait is not None:
        plan.stats["layer"] = patch.layer
        plan.stats["layers"] = {t[0].layer: round(float(t[3].cost), 4) for t in tried}
        plan.stats["layers"].update({layer: None for layer, _ in failures})
    placed = _placed(scene, patch, rig, motions)
    _writable(character, start_frame, placed[2].frames)
    with transaction.kept(bpy, scene, [character], (PLAN_KEY, FRAME_RANGE_KEY)):
        return _write(scene, character, patch, name, plan, placed, start_frame, env,
                      radius, foot_lock, rig)


def _layer_patches(scene, patch_name, gait):
    """[(stored name, patch)] to plan with: the named (or active) patch when ``gait`` is
    None; the patch of layer ``gait`` (the named one, else the active one when it is of
    that layer, else the first); for "auto" one patch per layer stored."""
    if gait is None:
        return [(patch_name, _patch_for_planning(scene, patch_name))]
    try:
        gait = layers.check_gait(gait)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    items = list(storage.patch_items(scene))
    if not items:
        _patch_for_planning(scene, None)  # raises: nothing baked
    have = ", ".join(f"'{i.name}' ({i.layer})" for i in items)
    if patch_name:
        item = next((i for i in items if i.name == patch_name), None)
        if item is None:
            _patch_for_planning(scene, patch_name)  # raises naming the patches there are
        if gait != "auto" and item.layer != gait:
            raise MotionPatchesError(f"the patch '{patch_name}' is of layer '{item.layer}', not "
                                     f"'{gait}' (have: {have})")
        if gait != "auto":
            return [(item.name, _patch_for_planning(scene, item.name))]
    active = scene.motion_patches.active_patch_index
    active = items[active] if 0 <= active < len(items) else None
    by_layer = {}
    for item in items:
        if item.layer not in by_layer or item == active:
            by_layer[item.layer] = item
    if gait == "auto":
        chosen = list(by_layer.values())
    elif gait in by_layer:
        chosen = [by_layer[gait]]
    else:
        raise MotionPatchesError(f"no locomotion patch of layer '{gait}' is baked in this scene "
                                 f"(have: {have}); bake one with that layer, or plan with "
                                 f"gait 'auto' or one of the layers there are")
    return [(item.name, _patch_for_planning(scene, item.name)) for item in chosen]


def _plan_in_layer(scene, character, goal, patch, alpha, beta, gamma, radius, frame_start,
                   context, stitching, start_prop, goal_facing):
    """(patch, rig map, planner world, plan, piece motions, first frame) of one character
    planned in the layer of ``patch``; its props offer only the traversal clips that
    serve that layer (:func:`motion_patches.layers.serves`)."""
    rig = _check_character(character, patch)
    scale = _size(rig)
    depsgraph = context.evaluated_depsgraph_get()
    goal_obj = goal if isinstance(goal, bpy.types.Object) else None
    env = scene_io.environment(scene, depsgraph, patch, radius,
                               _not_obstacles((character, goal_obj)), scale)
    props = [layers.for_layer(p, patch.layer)
             for p in object_patches(scene, depsgraph, patch, scale)]
    by_name = {p.name: p for p in props}
    ends = _endpoints(character, goal, start_prop, by_name,
                      rig.target if rig else patch.gait.skeleton, goal_facing, scale)
    _check_ends(character, ends, scale)
    tracks = moving_io.tracks(scene, depsgraph, list(env.obstacles), frame_start, scale)
    awake = [t.name for t in tracks if t.awake_at(0.0)]
    for t in tracks:  # where each stands at the first frame (the scene may show another)
        env.remove(t.name)
        env.place(Obstacle(t.name, t.polygon_at(t.pose_at(0.0)[0])))
    with _without(env, awake):  # awake props are avoided locally, after (Sec. 4.4)
        _check_clear(env, character, ends, by_name)
        planner = SegmentPlanner(patch, env, alpha, beta, gamma, props=props, mode=stitching)
        plan = _solve(planner, character, ends)
        plan, motions = _body_clear(planner, plan, plan_motions(patch, plan), ends)
    if tracks:
        plan, wait = _avoid_moving(planner, patch, plan, tracks, character, frame_start,
                                   scene_fps(scene))
        frame_start += int(round(wait * scene_fps(scene)))
        motions = plan_motions(patch, plan)
    plan.stats["glitches"] = validate.count(validate.plan_glitches(patch, plan, motions))
    return patch, rig, env, plan, motions, frame_start


def plan_crowd(scene, pairs, patch_name=None, alpha=1.0, beta=0.5, gamma=0.2, radius=0.25,
               frame_start=None, context=None, stitching="dynamic", progress=None,
               max_wait_seconds=4.0, spacing=None, foot_lock=True, goal_facing="exact"):
    """Plan several characters, ``pairs`` = [(armature, goal object or (x, y, heading))],
    and write each one's NLA; characters that find no path are listed in ``failed``.

    Each path is planned against the props and the spots where the others stand still
    while it walks: the goals of the characters before it and the starts of those after it
    (:func:`motion_patches.crowd.standing_spots`; dropped when they box it in). Then, in
    the given order, each character waits at its start (whole 0.2 s steps, at
    most ``max_wait_seconds``) until it keeps ``spacing`` metres (default: two radii)
    from everyone before it at every frame, standing at the goal afterwards included
    (:func:`motion_patches.crowd.stagger`). Where no wait clears two characters, the later
    one is re-planned round the stretch the earlier one walks around that frame (its
    reserved stretch as obstacles, :func:`motion_patches.crowd.keep_apart`) and the crowd
    is staggered again (at most three rounds); those are listed in ``rerouted``. Closer
    approaches left are returned as ``conflicts``. Bad input raises
    :class:`MotionPatchesError` before anything is planned or written."""
    t0 = time.perf_counter()
    _check_weights(alpha, beta, gamma, radius)
    patch = _patch_for_planning(scene, patch_name)
    context = context or bpy.context
    context.view_layer.update()
    pairs = list(pairs)
    if not pairs:
        raise MotionPatchesError("a crowd needs at least one character with a goal")
    spacing = 2 * radius if spacing is None else float(spacing)
    if not (0 <= spacing < np.inf and 0 <= max_wait_seconds < np.inf):
        raise MotionPatchesError("spacing and the longest wait must be numbers >= 0")
    seen, rigs = set(), []
    for character, goal in pairs:
        rigs.append(_check_character(character, patch))
        if character.name in seen:
            raise MotionPatchesError(f"'{character.name}' appears twice in the crowd")
        seen.add(character.name)
        if goal is None:
            raise MotionPatchesError(f"'{character.name}' has no goal")
        if goal == character:
            raise MotionPatchesError(f"the goal of '{character.name}' is the character itself")
        _goal(goal)
        _writable(character)
    first = _frame_start(scene, frame_start)
    depsgraph = context.evaluated_depsgraph_get()
    # Characters are not obstacles of the scene: they are kept apart in time, and only where
    # they stand still (goals of earlier ones, starts of later ones) in space. A goal object
    # is no obstacle for its own character only. Characters of another size than the patch
    # skeleton (retargeted rigs) are planned in the world shrunk by their size, one
    # environment and planner per size.
    sizes, worlds = [_size(r) for r in rigs], {}

    def world_of(size):
        if size not in worlds:
            env = scene_io.environment(scene, depsgraph, patch, radius,
                                       _not_obstacles([c for c, _ in pairs]), size)
            props = object_patches(scene, depsgraph, patch, size)
            worlds[size] = [env, props, {p.name: p for p in props}, None]
        return worlds[size]
    ends = [_endpoints(c, g, None, world_of(sz)[2], r.target if r else patch.gait.skeleton,
                       goal_facing, sz) for (c, g), r, sz in zip(pairs, rigs, sizes)]
    own_goal = [[o.name for o in _not_obstacles([g])] if isinstance(g, bpy.types.Object) else []
                for _, g in pairs]
    for (c, _), e, mine, sz in zip(pairs, ends, own_goal, sizes):
        _check_ends(c, e, sz)
        with _without(world_of(sz)[0], mine):
            _check_clear(world_of(sz)[0], c, e, world_of(sz)[2])
    for w in worlds.values():
        w[3] = SegmentPlanner(patch, w[0], alpha, beta, gamma, props=w[1], mode=stitching)
    world_ends = [(_shrunk(e[0], 1.0 / sz), _shrunk(e[1], 1.0 / sz)) for e, sz in zip(ends, sizes)]
    def solve_one(n, ghosts=()):
        """Plan character n round the standing spots (dropped when they box it in) and,
        when re-routing, round ``ghosts`` (world polygons; PathNotFound if they box it in)."""
        character, e = pairs[n][0], ends[n]
        env, _, _, planner = world_of(sizes[n])
        spots = [Obstacle(f"{CROWD_SPOT}{pairs[m][0].name}", polygon / sizes[n]) for m, polygon
                 in crowd.standing_spots(world_ends, n, spacing, radius)]
        own = np.array([e[0][:2], e[1][:2]], float)
        extra = [Obstacle(f"{CROWD_GHOST}{k}", polygon / sizes[n]) for k, polygon in
                 enumerate(ghosts)]
        extra = [g for g in extra if not g.within(own, radius).any()]  # not on its own ends
        with _without(env, own_goal[n]):
            for ob in spots + extra:  # where the others stand still while this one walks
                env.place(ob)
            try:
                try:
                    return _solve(planner, character, e, explain=not (spots or extra))
                except PathNotFound:
                    if not spots or extra:
                        raise
                    for spot in spots:  # boxed in by the others: plan past them
                        env.remove(spot.name)
                    spots = []
                    return _solve(planner, character, e)
            finally:
                for ob in spots + extra:
                    env.remove(ob.name)

    planned, failed = [], []
    for n, (character, _) in enumerate(pairs):
        try:
            planned.append((n, solve_one(n)))
        except PathNotFound as exc:
            failed.append((character.name, str(exc)))
        if progress is not None:
            progress(0.8 * (n + 1) / len(pairs))
    fps = scene_fps(scene)
    placed = [_placed(scene, patch, rigs[n], plan_motions(patch, plan))  # synthesised once
              for n, plan in planned]
    tracks = [p[2].ground[:, :2] for p in placed]  # on the scene's frames

    def replan(k, ghosts):
        """Character k of the planned ones re-planned round ``ghosts``; its new track."""
        n = planned[k][0]
        try:
            plan = solve_one(n, ghosts)
        except PathNotFound:
            return None
        planned[k] = (n, plan)
        placed[k] = _placed(scene, patch, rigs[n], plan_motions(patch, plan))
        return placed[k][2].ground[:, :2]

    delays, conflicts, rerouted = crowd.keep_apart(
        tracks, replan, spacing, radius, fps, round(max_wait_seconds * fps),
        max(1, round(0.2 * fps)))
    if progress is not None:
        progress(0.9)
    plans = []
    for (n, plan), p, d in zip(planned, placed, delays):
        _writable(pairs[n][0], first + d, p[2].frames)
    with transaction.kept(bpy, scene, [pairs[n][0] for n, _ in planned],
                          (PLAN_KEY, FRAME_RANGE_KEY)):
        for (n, plan), p, d in zip(planned, placed, delays):
            env = world_of(sizes[n])[0]
            with _without(env, own_goal[n]):  # the plan record lists what it walked around
                plans.append(_write(scene, pairs[n][0], patch, patch_name, plan, p, first + d,
                                    env, radius, foot_lock, rigs[n], fit=False))
        if plans:
            _fit_frame_range(scene)  # once: it reads every character's plan record
    if progress is not None:
        progress(1.0)
    names = [pairs[n][0].name for n, _ in planned]
    for c in conflicts:
        c["a"], c["b"], c["frame"] = names[c["a"]], names[c["b"]], first + c["frame"]
    return CrowdResult(plans, failed, conflicts, dict(zip(names, delays)),
                       time.perf_counter() - t0, [names[k] for k in rerouted])


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


def _resolve(place, what, patch):
    """(state, object or None) for an object name or [x, y, heading_deg]; a start that is
    an armature starts where its own skeleton stands (it may be retargeted)."""
    if what == "exclude":
        ob = bpy.data.objects.get(place)
        if ob is None:
            raise MotionPatchesError(f"layout spec: no object named '{place}' to exclude")
        return None, ob
    if not isinstance(place, str):
        return np.array([place[0], place[1], math.radians(place[2])]), None
    ob = bpy.data.objects.get(place)
    if ob is None:
        raise MotionPatchesError(f"layout spec: no object named '{place}' for a {what} "
                                 f"(have: {_some_names(bpy.data.objects)})")
    if what == "character" or (what == "start" and ob.type == "ARMATURE"):
        rig = _check_character(ob, patch)  # the rule plan_path applies to its character
        return scene_io.character_state(ob, rig.target if rig else patch.gait.skeleton), ob
    return scene_io.ground_state(ob), ob


def check_layout(scene, spec, context=None):
    """Plan every start/goal pair of a layout ``spec`` WITHOUT writing to the scene.

    Returns one dict per pair: reachable, seconds of motion, length, cost, the props
    blocking it when it is not reachable, and whether it passed its limits. Raises
    :class:`MotionPatchesError` for a bad spec (unknown object or patch), before planning.
    """
    try:
        spec = layout_spec.normalise(spec)
    except layout_spec.SpecError as exc:
        raise MotionPatchesError(str(exc)) from None
    try:
        patch = storage.load_patch(scene, spec["patch"])
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    s = scene.motion_patches
    w = {k: float(getattr(s, k) if spec[k] is None else spec[k])
         for k in ("alpha", "beta", "gamma", "radius")}
    _check_weights(w["alpha"], w["beta"], w["gamma"], w["radius"], "layout spec: ")
    margin = 3 if spec["margin_tiles"] is None else int(spec["margin_tiles"])
    # Evaluate first: it also brings the objects' world matrices up to date.
    depsgraph = (context or bpy.context).evaluated_depsgraph_get()
    jobs = []
    for p in spec["pairs"]:
        start, sob = _resolve(p["start"], "character" if p.get("character") else "start", patch)
        goal, gob = _resolve(p["goal"], "goal", patch)
        # A retargeted character plans in the world shrunk by its size (see _size).
        size = (_size(_check_character(sob, patch))
                if sob is not None and sob.type == "ARMATURE" else 1.0)
        # Not obstacles: the start and goal objects with their children (a character's own
        # body mesh) and whatever the spec excludes.
        exclude = {}
        for ob in [sob, gob] + [_resolve(n, "exclude", patch)[1]
                                for n in spec["exclude"] + p["exclude"]]:
            if ob is not None:
                for o in (ob, *ob.children_recursive):
                    exclude[o.name] = o
        jobs.append((p, start, sob, goal, gob, exclude, size))
    envs, results, props = {}, [], {}
    for p, start, sob, goal, gob, exclude, size in jobs:
        allow = bool(p["limits"]["allow_traversal"])
        key = (tuple(sorted(exclude)), allow, size)
        if key not in envs:
            env = scene_io.environment(scene, depsgraph, patch, w["radius"],
                                       tuple(exclude.values()), size)
            if size not in props:  # tagged props offer traversals
                props[size] = object_patches(scene, depsgraph, patch, size)
            usable = [pr for pr in props[size] if pr.name not in exclude] if allow else []
            try:
                planner = SegmentPlanner(patch, env, w["alpha"], w["beta"], w["gamma"],
                                         props=usable)
            except PlanError as exc:
                raise MotionPatchesError(str(exc)) from None
            envs[key] = env, planner
        env, planner = envs[key]
        r = {"name": p["name"], "start": state_dict(start, sob and sob.name),
             "goal": state_dict(goal, gob and gob.name), "reachable": False,
             "seconds": None, "frames": None, "length_m": None, "cost": None, "pieces": None,
             "traversals": 0, "expansions": None, "plan_seconds": None, "blocked_by": [],
             "blocked_reason": None, "error": None, "limits": p["limits"]}
        r["goal_facing"] = p["goal_facing"]
        if p["goal_facing"] == "any":
            goal = np.array([goal[0], goal[1], np.nan])
        start, goal = _shrunk(start, size), _shrunk(goal, size)
        try:
            _check_far(start, goal, "start", size)
            with causes.counted(planner) as expanded:
                plan = planner.plan(start, goal, margin_tiles=margin)
        except MotionPatchesError as exc:
            r["error"], r["blocked_reason"] = str(exc), "refused"
        except PlanError as exc:
            if expanded[0] >= causes.SEARCH_LIMIT:
                r["error"], r["blocked_reason"] = _limit_text(expanded[0]), "search limit"
            else:
                r["error"] = str(exc)
                names, r["blocked_reason"] = blocking.blocking_props(env, start, goal, margin)
                r["blocked_by"] = scene_io.owners(names)
        else:
            world = concatenate(plan_motions(patch, plan))
            r["goal"] = state_dict(_shrunk(plan.goal, 1.0 / size), gob and gob.name)
            seconds = (world.frames - 1) / patch.gait.fps
            r.update(reachable=True, frames=int(round(seconds * scene_fps(scene))) + 1,
                     seconds=seconds,
                     length_m=path_length(world.ground) * size, cost=float(plan.cost),
                     pieces=len(plan.pieces), expansions=int(plan.expansions),
                     plan_seconds=float(plan.seconds),
                     traversals=sum(pc.kind == "traversal" for pc in plan.pieces))
        r["failures"] = layout_spec.judge(r, p["limits"])
        r["passed"] = not r["failures"]
        results.append(r)
    return results


def _some_names(coll, limit=8):
    names = sorted(x.name for x in coll)
    return (", ".join(names[:limit]) + (", ..." if len(names) > limit else "")) or "none"
