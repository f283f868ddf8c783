# SPDX-License-Identifier: GPL-3.0-or-later
"""Python API: the functions behind every operator and every CLI command.

Arguments are plain Blender objects, actions, names and numbers; results are small
dataclasses. Every failure is a :class:`MotionPatchesError` with a message meant for the
user, raised before the scene is changed.
"""

import contextlib
import functools
import inspect
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import bpy
import numpy as np

from .adapter import actions as act_io
from .adapter import compat, evaluate, mocap, nla, props_io, storage, transaction
from .adapter import moving as moving_io
from .adapter import rig as rig_io
from .adapter import scene as scene_io
from .motion_patches.crowd import crowd, held_motion
from .motion_patches.kinematics import contacts, foot_lock, scene_rate
from .motion_patches.kinematics.inplace import root_positions
from .motion_patches.kinematics.motion import Motion, concatenate
from .motion_patches.patch import layers
from .motion_patches.patch.gait import MIN_TURN, build_gait
from .motion_patches.patch.locomotion_patch import bake
from .motion_patches.planning import body_clearance, causes, moving_props, transitions
from .motion_patches.planning.planner import (
    PlanError,
    SegmentPlanner,
    interaction_states,
    plan_motions,
    with_interactions,
)
from .motion_patches.planning.settings import PLANNING as DEFAULTS
from .motion_patches.planning.settings import PlanSettings
from .motion_patches.props import blocking, object_patch
from .motion_patches.props.environment import Obstacle
from .motion_patches.quality import layout_spec, metrics, validate

PLAN_KEY = storage.PLAN_KEY  # the custom property holding a character's plan record
CROWD_RESOLVE_SLACK = 0.05  # metres the crowd is resolved wider than its spacing (see plan_crowd)
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
    armature: str = ""  # the armature the clips play on
    straight: str = ""  # action names baked
    turns: list = field(default_factory=list)
    imported: list = field(default_factory=list)  # actions imported from BVH files


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
    plans: list  # PlanResult per planned character, in the order given
    failed: list  # [(character name, why no path)]
    conflicts: list  # [{"a", "b", "frame", "distance_m"}] closer than two radii
    delays: dict  # character name -> frames it waits at its start
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


def bake_locomotion_patch(
    scene: "bpy.types.Scene",
    armature,
    straight,
    turns=(),
    layer: str = "walk",
    name: str | None = None,
    cells: int = 8,
    nodes: int = 8,
    effort_rate: float | None = None,
    mirror_turns: bool = True,
    progress=None,
    bvh_files=(),
    fps: float | None = None,
) -> BakeResult:
    """Bake and store a locomotion patch from a straight action and turn actions (none
    needed: the straight stride is bent to turns, see ``gait.STRAIGHT_BEND_RADIUS``), make
    it the active patch and remember its clips in the scene's bake settings (what the
    Locomotion Patches panel shows). A patch too sparse to connect is refused, saying what
    to add. Its tile side is two straight cycles, so a run's tiles are larger than a
    walk's; ``effort_rate`` (effort T per second) defaults to the gait's
    (:func:`motion_patches.patch.layers.effort_rate`: 1 for a walk, more for a run) so the costs
    of two layers compare.

    ``bvh_files``: BVH files imported first, onto ``armature`` (an armature object, or the
    name of a new one); ``straight`` and ``turns`` are actions or action names, a name
    matching an imported file's stem meaning that file's action. ``fps`` sets the scene's
    frame rate first (the patch is baked at the scene rate). Everything is checked before
    the first change; when the bake fails anyway, the objects, armatures and actions it
    made and the frame rate are put back."""
    if fps is not None and not (isinstance(fps, (int, float)) and 1 <= fps <= 1000):
        raise MotionPatchesError(f"the frame rate must be between 1 and 1000, not {fps}")
    if not str(layer).strip():
        raise MotionPatchesError("the layer (gait name) must not be empty")
    for what, v in (("cells", cells), ("nodes per edge", nodes)):
        if not (isinstance(v, int) and 2 <= v <= 8):
            raise MotionPatchesError(f"{what} must be a whole number from 2 to 8, not {v!r}")
    files = [Path(f).expanduser() for f in bvh_files]
    armature = _bake_armature(scene, armature, bool(files))
    stems = {f.stem for f in files}
    for f in files:
        if not f.is_file():
            raise MotionPatchesError(f"BVH file not found: {f}")
    if straight is None:
        raise MotionPatchesError("choose a straight locomotion action")
    if any(t is None for t in turns):
        raise MotionPatchesError("a turn clip has no action: choose one or remove the row")
    for clip in (straight, *turns):
        if isinstance(clip, str) and clip not in stems and bpy.data.actions.get(clip) is None:
            raise MotionPatchesError(
                f"no action named '{clip}' (have: {_some_names(bpy.data.actions)}"
                + (f"; imported files give: {', '.join(sorted(stems))}" if stems else "")
                + ")"
            )
    with transaction.made_undone_on_error(bpy, scene):
        if fps is not None:
            scene.render.fps, scene.render.fps_base = int(fps), 1.0
        imported = {}
        if files:
            armature, acts = import_mocap(
                files,
                armature=None if isinstance(armature, str) else armature,
                name=armature if isinstance(armature, str) else None,
            )
            imported = {f.stem: a for f, a in zip(files, acts)}
        straight = _bake_action(straight, imported)
        turns = [_bake_action(t, imported) for t in turns]
        res = _bake(
            scene,
            armature,
            straight,
            turns,
            layer,
            name,
            cells,
            nodes,
            effort_rate,
            mirror_turns,
            progress,
        )
    s = scene.motion_patches  # the clips this patch came from, as the panel shows them
    s.source_armature = armature
    s.straight_action = straight
    s.turn_actions.clear()
    for t in turns:
        s.turn_actions.add().action = t
    storage.make_active(scene, res.name)
    res.armature, res.straight, res.turns = armature.name, straight.name, [t.name for t in turns]
    res.imported = [a.name for a in imported.values()]
    return res


def _bake_armature(scene, armature, importing):
    """The armature to bake on: an object, or a name (of one in the scene; with BVH files
    to import, a name no object has becomes the new armature's)."""
    if isinstance(armature, str):
        ob = scene.objects.get(armature)
        if ob is None and importing:
            return armature
        if ob is None:
            raise MotionPatchesError(
                f"no armature object named '{armature}' for the clips (have: "
                f"{_some_names([o for o in scene.objects if o.type == 'ARMATURE'])})"
            )
        armature = ob
    if armature is None or armature.type != "ARMATURE":
        raise MotionPatchesError(
            "choose the armature the clips were imported on"
            + (f" ('{armature.name}' is a {armature.type.lower()})" if armature is not None else "")
        )
    return armature


def _bake_action(clip, imported):
    if not isinstance(clip, str):
        return clip
    return imported.get(clip) or bpy.data.actions[clip]


def _bake(
    scene, armature, straight, turns, layer, name, cells, nodes, effort_rate, mirror_turns, progress
):
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
                f"or rename its bones"
            )
    try:
        clips = [act_io.clip_from_action(a, armature, fps) for a in (straight,) + tuple(turns)]
        gait = build_gait(layer, clips[0], tuple(clips[1:]), fps=fps, mirror_turns=mirror_turns)
        for action in turns:
            if not any(n.startswith(f"turn: {action.name} ") for n in gait.notes):
                raise ValueError(
                    f"the turn clip '{action.name}' does not turn: none of its gait cycles turns "
                    f"{np.degrees(MIN_TURN):.0f} degrees or more; give a clip that turns, or "
                    f"bake without it (the straight stride is bent to turns)"
                )
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
            out.add(path[len('pose.bones["') : path.index('"]')])
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
            clip = act_io.clip_from_action(
                action, None, scene_fps(scene), skeleton=patch.gait.skeleton
            )
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


def active_patch_name(scene: "bpy.types.Scene") -> str | None:
    """The patch planning uses when none is named (None: no patch is baked)."""
    return storage.active_name(scene)


def export_patch(scene: "bpy.types.Scene", path, patch_name: str | None = None) -> str:
    """Write a baked patch (the active one by default) to a file another scene can import;
    returns the name of the patch written."""
    path = Path(path).expanduser()
    if not path.parent.is_dir():
        raise MotionPatchesError(f"cannot write {path}: folder {path.parent} does not exist")
    try:
        name = patch_name or storage.active_name(scene)
        storage.export_patch(scene, name, path)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    except OSError as exc:
        raise MotionPatchesError(f"cannot write {path}: {exc.strerror or exc}") from None
    return name


def import_patch(scene: "bpy.types.Scene", path, name: str | None = None) -> str:
    """Store a patch file written by :func:`export_patch` in ``scene`` and make it the
    active patch (the one planning uses next); returns its name."""
    path = Path(path).expanduser()
    if not path.is_file():
        raise MotionPatchesError(f"patch file not found: {path}")
    try:
        stored = storage.import_patch(scene, path, name).name
    except OSError as exc:
        raise MotionPatchesError(f"cannot read {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise MotionPatchesError(f"{path}: {exc}") from None
    storage.make_active(scene, stored)
    return stored


def object_patches(scene, depsgraph, patch, scale=1.0):
    """Core object patches of every tagged prop in the scene (``scale``: the character's
    size relative to the patch skeleton, :func:`_size`: props placed in the world the
    planner sees, shrunk by it)."""
    out = []
    floor = patch.gait.floor()
    for obj in props_io.tagged(scene):
        try:
            out.append(
                props_io.object_patch(
                    obj,
                    depsgraph,
                    patch.gait.skeleton,
                    patch.gait.fps,
                    gait_floor=floor,
                    scale=scale,
                )
            )
        except ValueError as exc:
            raise MotionPatchesError(str(exc)) from None
    return out


def load_plan_record(obj: "bpy.types.Object") -> tuple[dict, dict]:
    """The last plan written on ``obj`` (meta dict, arrays dict)."""
    try:
        return storage.load_plan(obj)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def last_analysis(obj: "bpy.types.Object | None") -> dict | None:
    """The figures :func:`analyse` kept on ``obj`` last time, or None."""
    return storage.last_analysis(obj)


def state_dict(state, name=None):
    """(x, y, heading) as JSON-friendly numbers (heading in degrees, -180..180)."""
    h = (float(np.degrees(state[2])) + 180.0) % 360.0 - 180.0
    d = {
        "x": round(float(state[0]), 6),
        "y": round(float(state[1]), 6),
        "heading_deg": round(h, 4) + 0.0,
    }
    if name is not None:
        d["object"] = name
    return d


def path_length(ground):
    """Metres walked by a ground trajectory (frames, >= 2)."""
    return float(np.linalg.norm(np.diff(np.asarray(ground)[:, :2], axis=0), axis=1).sum())


def _patch_for_planning(scene, patch_name):
    """The stored patch to plan with. A scene at another frame rate than the patch's is
    fine: strips play the patch's keys scaled in time
    (:mod:`motion_patches.kinematics.scene_rate`)."""
    try:
        return storage.load_patch(scene, patch_name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def _check_character(character, patch):
    """The :class:`~motion_patches.kinematics.retarget.RigMap` that puts the patch on the character
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
        raise MotionPatchesError(f"armature '{character.name}' has no bones {', '.join(wrong[:6])}")
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
        raise MotionPatchesError(
            "choose a goal object (its location and facing) or give (x, y, heading)"
        ) from None
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
            raise MotionPatchesError(
                f"the goal '{goal.name}' is a prop without a sit-down "
                f"interaction clip: there is nowhere to end the path"
            )
        goal_ref = (by_name[goal.name], i)
    if start_prop is not None:
        if start_prop.name not in by_name:
            raise MotionPatchesError(f"'{start_prop.name}' is not a tagged object patch")
        i = props_io.interaction_clip(by_name[start_prop.name], sitting=False)
        if i is None:
            raise MotionPatchesError(f"'{start_prop.name}' has no stand-up interaction clip")
        start_ref = (by_name[start_prop.name], i)
    s_state, g_state = interaction_states(start_ref, goal_ref)
    return (
        start_state if s_state is None else s_state,
        goal_state if g_state is None else g_state,
        start_ref,
        goal_ref,
    )


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
    for what, state, ref in (
        ("start", endpoints[0], endpoints[2]),
        ("goal", endpoints[1], endpoints[3]),
    ):
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
                f"'{tagged[0]}' a sit-down / stand-up clip and use the prop itself"
            )
        raise MotionPatchesError(
            f"{who} is inside or within {env.radius:.2f} m of "
            f"{', '.join(repr(n) for n in near[:4])}: move it into the open"
        )


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
            raise PathNotFound(
                f"no path for '{character.name}': {_limit_text(causes.SEARCH_LIMIT)}", exc.cause
            ) from None
        raise PathNotFound(
            f"no path for '{character.name}': {exc}", exc.cause, scene_io.owners(exc.props)
        ) from None
    except PlanError as exc:
        raise PathNotFound(f"no path for '{character.name}': {exc}") from None
    return with_interactions(plan, start_ref, goal_ref)


def _body_clear(planner, plan, motions, ends):
    """(plan, its motions) whose hips keep the radius too (:mod:`body_clearance`)."""
    return body_clearance.keep_clear(
        planner,
        plan,
        motions,
        ends[0],
        ends[1],
        lambda p: plan_motions(planner.patch, p),
        lambda p: with_interactions(p, ends[2], ends[3]),
    )


def _writable(character, first=None, frames=None):
    """Refuse, before anything is written, a plan on ``character`` that writing could not
    carry out or that would delete user data (:func:`adapter.transaction.check_writable`);
    ``first``: its first frame, ``frames``: how many."""
    why = transaction.check_writable(
        bpy, character, first, None if first is None else first + frames - 1
    )
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
        raise MotionPatchesError(
            f"the start frame {frame_start} is outside what Blender holds ({lo} to {hi})"
        )
    return int(round(f))


MAX_COORDINATE = 1e5  # metres from the origin a start or goal may lie
MAX_DISTANCE = 2000.0  # metres between start and goal of one plan (plan longer walks in legs)
SAME_PLACE = 0.05  # metres: a goal this near the start, facing the same way, is the start
SAME_FACING = np.radians(2.0)


def _check_weights(alpha, beta, gamma, radius):
    """Refuse weights the search cannot sum (NaN, negative, huge) and a radius that is not
    a body's, naming the value (the ranges of :data:`SETTINGS`)."""
    planning_checked(alpha=alpha, beta=beta, gamma=gamma, radius=radius)


def planning_checked(**values) -> PlanSettings:
    """:meth:`PlanSettings.checked` with :class:`MotionPatchesError` naming a bad value."""
    try:
        return PlanSettings.checked(**values)
    except ValueError as e:
        raise MotionPatchesError(str(e)) from None


def planning_settings(scene: "bpy.types.Scene", **given) -> dict:
    """The planning settings of a request (the names of
    :data:`motion_patches.planning.settings.SETTINGS`):
    each one given (not None) as given, the others the scene's (its Planning panel, which
    starts from those defaults). All are checked: :class:`MotionPatchesError` names a bad one."""
    s = scene.motion_patches
    values = {}
    for key in DEFAULTS:
        v = given.pop(key, None)
        values[key] = getattr(s, key) if v is None else v
    if given:
        raise TypeError(f"not planning settings: {', '.join(sorted(given))}")
    return planning_checked(**values).as_dict()


def _fills_planning_settings(fn):
    """``fn`` with every planning setting its caller left None (or out) filled from the
    scene's and checked (:func:`planning_settings`): one rule for the operators, the CLI
    and scripts."""
    sig = inspect.signature(fn)

    @functools.wraps(fn)
    def run(*args, **kwargs):
        bound = sig.bind(*args, **kwargs)
        bound.apply_defaults()
        a = bound.arguments
        a.update(planning_settings(a["scene"], **{k: a[k] for k in DEFAULTS}))
        return fn(*bound.args, **bound.kwargs)

    return run


def _check_far(start, goal, who, scale=1.0):
    """Refuse a start or goal farther from the origin than ``MAX_COORDINATE`` or start and
    goal farther apart than ``MAX_DISTANCE`` (planner-world states of a character ``scale``
    times the patch's size), and a goal where the start is (same place, same facing)."""
    for what, state in (("start", start), ("goal", goal)):
        far = float(np.abs(np.asarray(state[:2], float)).max()) * scale
        if not far <= MAX_COORDINATE:
            raise MotionPatchesError(
                f"the {what} of {who} lies {far:.3g} m from the origin; "
                f"plans stay within {MAX_COORDINATE:g} m of it"
            )
    d = float(np.hypot(*(np.asarray(goal[:2], float) - np.asarray(start[:2], float)))) * scale
    if d > MAX_DISTANCE:
        raise MotionPatchesError(
            f"the goal of {who} is {d:,.0f} m from its start; one plan "
            f"walks at most {MAX_DISTANCE:,.0f} m: plan the walk in legs"
        )
    turn = abs((float(goal[2]) - float(start[2]) + np.pi) % (2 * np.pi) - np.pi)
    if d < SAME_PLACE and (np.isnan(goal[2]) or turn < SAME_FACING):
        raise MotionPatchesError(
            f"the goal of {who} is where it stands ({d * 100:.0f} cm away, "
            f"facing the same way): there is nothing to plan"
        )


def _check_ends(character, endpoints, scale):
    """:func:`_check_far` of a character's start and goal states (``_endpoints``) unless a
    prop's clip starts or ends the path there."""
    if endpoints[2] is None and endpoints[3] is None:
        _check_far(endpoints[0], endpoints[1], f"'{character.name}'", scale)


def _limit_text(nodes):
    return (
        f"search limit reached after {nodes:,} nodes: the search stopped before finding a "
        f"way, which does not mean the props close it; plan to a nearer goal first and on "
        f"from there"
    )


def _placed(scene, patch, rig, motions):
    """A plan's piece motions (:func:`plan_motions`) put on the character: (its pieces'
    motions on its skeleton, at the patch's rate; the scene frames where the pieces start
    and the last ends, from 0; the whole motion on the scene's frames). ``rig``: the
    character's :class:`~motion_patches.kinematics.retarget.RigMap` (None: the patch skeleton)."""
    if rig is not None:
        motions = [rig.motion(m) for m in motions]
    patch_bounds, bounds = scene_rate.piece_bounds(
        [m.frames for m in motions], scene_fps(scene) / patch.gait.fps
    )
    world = scene_rate.at_scene_rate(concatenate(motions), patch_bounds, bounds)
    return motions, bounds, world


FRAME_RANGE_KEY = "motion_patches_frame_range"  # the scene frame range last set by a plan
BLENDER_DEFAULT_RANGE = (1, 250)  # a new scene's: not a range anyone chose


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
    plans = [storage.plan_range(ob) for ob in scene.objects if storage.has_plan(ob)]
    if plans:
        ours = scene.get(FRAME_RANGE_KEY)
        start, end = fitted_frame_range(
            (scene.frame_start, scene.frame_end), plans, tuple(ours) if ours is not None else None
        )
        scene.frame_start, scene.frame_end = start, end
        scene[FRAME_RANGE_KEY] = [start, end]


def _write(
    scene,
    character,
    patch,
    patch_name,
    plan,
    placed,
    frame_start,
    env,
    radius,
    lock=True,
    rig=None,
    fit=True,
    layer_keys=None,
):
    """NLA strips and the plan record of one planned character (``placed``: its motion,
    :func:`_placed`; ``env``: the planner's world, shrunk by the character's size).
    ``fit``: fit the scene's frame range now (a crowd fits it once, after every write).
    ``layer_keys``: {layer: patch key} of a plan that changes layer (:func:`_gait_change`)."""
    scale = _size(rig)
    goal_state = _shrunk(plan.goal, 1.0 / scale)  # the facing reached when any would do
    skel = rig.target if rig is not None else patch.gait.skeleton
    motions, bounds, world = placed
    # Feet moving fast while labelled planted (through a blend) are not planted: neither
    # pinned nor measured as skating (foot_lock.still_contacts).
    posed = foot_lock.pose_legs(skel, world)
    world = Motion(
        world.ground,
        world.root_local,
        world.rotations,
        foot_lock.still_contacts(skel, world, patch.gait.fps, posed),
    )
    locked = foot_lock.lock_feet(skel, world, posed=posed) if lock else None
    strips, stashed = nla.write_plan(
        bpy,
        character,
        patch,
        storage.patch_key(scene, patch_name),
        plan,
        motions,
        world,
        frame_start,
        locked,
        rig,
        bounds,
        layer_keys,
    )
    root = root_positions(world.ground, world.root_local)  # the hips
    foot = contacts.foot_joints(skel)
    frame_end = frame_start + world.frames - 1
    if rig is not None:
        plan.stats["retarget"] = rig.note()
    if abs(scene_fps(scene) - patch.gait.fps) > 1e-3:
        plan.stats["frame_rate"] = (
            f"patch baked at {patch.gait.fps:g} fps, played at the "
            f"scene's {scene_fps(scene):g} fps (strips scaled)"
        )
    storage.store_plan(
        character,
        {
            "ground": world.ground,
            "root": root,
            "contacts": world.contacts,
            "foot_names": [skel.names[i] for i in foot],
            "root_name": skel.names[skel.root],
            "frame_start": frame_start,
            "frame_end": frame_end,
            "goal": goal_state.tolist(),
            "boundaries": [s["start"] for s in strips[1:]],
            "radius": radius,
            "facing": nla.facing_angle(skel),
            "foot_lock": bool(lock),
            "traversals": [[s["start"], s["end"]] for s in strips if s["kind"] == "traversal"],
            "interactions": [[s["start"], s["end"]] for s in strips if s["kind"] == "interaction"],
            "layers": [
                [s["start"], s["end"], transitions.piece_layer(p, patch.layer)]
                for s, p in zip(strips, plan.pieces)
            ],
            "obstacles": {o.name: (o.polygon * scale).tolist() for o in env.obstacles.values()},
        },
    )
    if fit:
        _fit_frame_range(scene)
    return PlanResult(
        character.name,
        frame_start,
        frame_end,
        [p.label for p in plan.pieces],
        plan.cost,
        plan.seconds,
        plan.expansions,
        strips,
        stashed,
        plan.stats,
        path_length(world.ground),
        tuple(goal_state),
    )


def _avoid_moving(
    planner, patch, plan, tracks, character, frame_start, fps, longest_wait=moving_props.MAX_DELAY_S
):
    """(plan, seconds to wait at the start) clear of the props that move during it
    (:mod:`moving_props`: a wait of at most ``longest_wait`` or a repaired run);
    :class:`PathNotFound` naming the prop and the frame when neither keeps clear of it.
    ``fps``: the scene's rate."""
    scene_fps_ratio = fps / patch.gait.fps
    plan, wait, repairs, left = moving_props.avoid(
        planner,
        patch,
        plan,
        tracks,
        lambda p: plan_motions(patch, p),
        longest_wait=longest_wait,
    )
    if left:
        raise PathNotFound(
            f"no path for '{character.name}' clear of moving props: "
            + "; ".join(c.describe(patch.gait.fps, frame_start, fps) for c in left)
            + " (move the prop's keyframes, or start later with Frame Start)",
            "moving",
            [c.prop for c in left],
        )
    plan.stats["moving_props"] = {
        "props": [t.name for t in tracks],
        "awake_at_start": [t.name for t in tracks if t.awake_at(0.0)],
        "wait_s": wait,
        "repairs": [
            dict(r, frame=frame_start + int(round(r["frame"] * scene_fps_ratio))) for r in repairs
        ],
    }
    return plan, wait


@_fills_planning_settings
def plan_path(
    scene: "bpy.types.Scene",
    character: "bpy.types.Object",
    goal,
    patch_name: str | None = None,
    alpha: float | None = None,
    beta: float | None = None,
    gamma: float | None = None,
    radius: float | None = None,
    frame_start: int | None = None,
    context=None,
    stitching: str | None = None,
    start_prop: "bpy.types.Object | None" = None,
    foot_lock: bool | None = None,
    goal_facing: str | None = None,
    gait: str | None = None,
    turn_in_place: bool | None = None,
) -> PlanResult:
    """Plan ``character`` to ``goal`` (an object or (x, y, heading); None: the scene's goal)
    and write it as NLA. Settings left None are the scene's (:func:`planning_settings`).

    Tagged props (object patches) offer their traversal clips; ``stitching`` is
    "dynamic" (lazy, the paper's method) or "static" (everything stitched first). A goal
    that is a tagged prop with a sit-down interaction clip ends the path seated on it; a
    ``start_prop`` with a stand-up clip starts it there (the character's own position is
    then not used). With ``foot_lock`` planted feet are pinned by leg IK, written as a
    an Add track over the shared segment strips. ``goal_facing="any"`` lets the walk end
    facing whichever way is cheapest (the goal object's facing is then ignored). With
    ``turn_in_place`` a character facing away turns on the spot first (last) instead of
    walking a loop (a turn derived from the gait's sharpest turn loop).
    ``gait`` picks the layer: a layer name ("walk", "run") plans with the stored patch of
    that layer, "auto" plans in every layer stored, and a plan that changes layer (walk,
    run through the run layer's traversals, walk: :func:`_gait_change`), and keeps the
    cheapest Eq. 5 cost of the motion played (``stats["cost_shortened"]``;
    ``stats["layers"]`` gives each one's, "walk+run" the change's), None takes the
    scene's Gait (Planning panel), whose default plans with ``patch_name`` (or the active
    patch). Raises
    :class:`PathNotFound` when the props leave no way, and
    :class:`MotionPatchesError` for bad input; either way the scene is unchanged."""
    if gait is None:  # the scene's choice (Planning panel); "active": the active patch
        gait = {"ACTIVE": None}.get(scene.motion_patches.gait, scene.motion_patches.gait.lower())
    candidates = _layer_patches(scene, patch_name, gait)
    context = context or bpy.context
    # Objects moved by a script have stale matrix_world until the view layer updates.
    context.view_layer.update()
    if goal is None:
        goal = scene.motion_patches.goal
    if goal is None:
        raise MotionPatchesError(
            "no goal: choose a goal object (its location and facing) or set the scene's goal"
        )
    if goal == character:
        raise MotionPatchesError("the goal cannot be the character itself")
    frame_start = _frame_start(scene, frame_start)
    _writable(character)
    tried, failures = [], []
    for name, patch in candidates:
        try:
            tried.append(
                _plan_in_layer(
                    scene,
                    character,
                    goal,
                    patch,
                    alpha,
                    beta,
                    gamma,
                    radius,
                    frame_start,
                    context,
                    stitching,
                    start_prop,
                    goal_facing,
                    turn_in_place,
                )
                + (name,)
            )
        except PathNotFound as exc:
            if len(candidates) == 1:
                raise
            failures.append((patch.layer, exc))
    if not tried:
        first = failures[0][1]
        raise PathNotFound(
            "; ".join(f"{layer}: {exc}" for layer, exc in failures), first.cause, first.props
        )
    costs = [float(t[3].stats.get("cost_shortened", t[3].cost)) for t in tried]
    change, why = _gait_change(tried) if gait == "auto" else (None, None)
    best = layers.choose(costs + ([change[0].cost] if change else []))
    layer_keys = None
    if best == len(tried):  # the plan that changes layer: written with the walk's patch
        patch, rig, env, _, _, start_frame, _, name = min(tried, key=lambda t: t[0].effort_rate)
        plan, motions = change
        layer_keys = {t[0].layer: storage.patch_key(scene, t[7]) for t in tried}
    else:
        patch, rig, env, plan, motions, start_frame, _, name = tried[best]
    if gait is not None:
        plan.stats["layer"] = (
            plan.stats.get("layer") if change and best == len(tried) else patch.layer
        )
        plan.stats["layers"] = {t[0].layer: round(c, 4) for t, c in zip(tried, costs)}
        plan.stats["layers"].update({layer: None for layer, _ in failures})
        if change:
            plan.stats["layers"][change[0].stats["layer"]] = round(change[0].cost, 4)
        elif why:
            plan.stats["gait_change"] = why
    placed = _placed(scene, patch, rig, motions)
    _writable(character, start_frame, placed[2].frames)
    with transaction.kept(bpy, scene, [character], (PLAN_KEY, FRAME_RANGE_KEY)):
        return _write(
            scene,
            character,
            patch,
            name,
            plan,
            placed,
            start_frame,
            env,
            radius,
            foot_lock,
            rig,
            layer_keys=layer_keys,
        )


def _gait_change(tried):
    """((plan, piece motions), None) of the cheapest plan that walks, runs through the run
    layer's traversals and walks again (:func:`motion_patches.planning.transitions.compose`), from
    the layers' plans ``tried`` (:func:`_plan_in_layer`: the layer of least effort walks,
    that of most runs), or (None, why not). Not offered with props that move, with a start
    or goal on a prop's clip (sitting), nor when the plan's hips would come within the
    radius of a prop."""
    if len(tried) < 2:
        return None, None
    walk_t = min(tried, key=lambda t: t[0].effort_rate)
    run_t = max(tried, key=lambda t: t[0].effort_rate)
    if walk_t[0].effort_rate == run_t[0].effort_rate:
        return None, "the layers cost the same effort: none of them is a run"
    walk, run = walk_t[6], run_t[6]
    if walk["moving"] or run["moving"]:
        return None, "not offered with props that move"
    ends = walk["ends"]
    if ends[2] is not None or ends[3] is not None:
        return None, "not offered when the path starts or ends on a prop's clip"
    try:
        plan = transitions.compose(walk["planner"], run["planner"], ends[0], ends[1])
    except PlanError as exc:
        return None, str(exc)
    motions = transitions.plan_layer_motions(plan)
    close = body_clearance.hips_too_close(
        walk_t[0], plan.pieces, motions, walk["planner"].world_env
    )
    if close:
        return None, f"its hips come within the radius of a prop on {len(close)} frames"
    plan.stats["glitches"] = validate.count(transitions.glitches(plan, motions))
    return (plan, motions), None


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
            raise MotionPatchesError(
                f"the patch '{patch_name}' is of layer '{item.layer}', not '{gait}' (have: {have})"
            )
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
        raise MotionPatchesError(
            f"no locomotion patch of layer '{gait}' is baked in this scene "
            f"(have: {have}); bake one with that layer, or plan with "
            f"gait 'auto' or one of the layers there are"
        )
    return [(item.name, _patch_for_planning(scene, item.name)) for item in chosen]


def _plan_in_layer(
    scene,
    character,
    goal,
    patch,
    alpha,
    beta,
    gamma,
    radius,
    frame_start,
    context,
    stitching,
    start_prop,
    goal_facing,
    turn_in_place=DEFAULTS["turn_in_place"],
):
    """(patch, rig map, planner world, plan, piece motions, first frame, {planner, ends,
    moving: whether props move}) of one character planned in the layer of ``patch``; its
    props offer only the traversal clips that serve that layer
    (:func:`motion_patches.patch.layers.serves`)."""
    rig = _check_character(character, patch)
    scale = _size(rig)
    depsgraph = context.evaluated_depsgraph_get()
    goal_obj = goal if isinstance(goal, bpy.types.Object) else None
    env = scene_io.environment(
        scene, depsgraph, patch, radius, _not_obstacles((character, goal_obj)), scale
    )
    props = [
        layers.for_layer(p, patch.layer) for p in object_patches(scene, depsgraph, patch, scale)
    ]
    by_name = {p.name: p for p in props}
    ends = _endpoints(
        character,
        goal,
        start_prop,
        by_name,
        rig.target if rig else patch.gait.skeleton,
        goal_facing,
        scale,
    )
    _check_ends(character, ends, scale)
    tracks = moving_io.tracks(scene, depsgraph, list(env.obstacles), frame_start, scale)
    awake = [t.name for t in tracks if t.awake_at(0.0)]
    for t in tracks:  # where each stands at the first frame (the scene may show another)
        env.remove(t.name)
        env.place(Obstacle(t.name, t.polygon_at(t.pose_at(0.0)[0])))
    with _without(env, awake):  # awake props are avoided locally, after (Sec. 4.4)
        _check_clear(env, character, ends, by_name)
        planner = SegmentPlanner(
            patch,
            env,
            alpha,
            beta,
            gamma,
            props=props,
            mode=stitching,
            turn_in_place=turn_in_place,
        )
        plan = _solve(planner, character, ends)
        plan, motions = _body_clear(planner, plan, plan_motions(patch, plan), ends)
    if tracks:
        plan, wait = _avoid_moving(
            planner, patch, plan, tracks, character, frame_start, scene_fps(scene)
        )
        frame_start += int(round(wait * scene_fps(scene)))
        motions = plan_motions(patch, plan)
    plan.stats["glitches"] = validate.count(validate.plan_glitches(patch, plan, motions))
    layer = {"planner": planner, "ends": ends, "moving": bool(tracks)}  # for _gait_change
    return patch, rig, env, plan, motions, frame_start, layer


def crowd_members(scene: "bpy.types.Scene", characters=None) -> list[tuple]:
    """Who is in a crowd and where each walks: [(armature, goal object)] by name, what
    :func:`plan_crowd` takes. The one rule for the operator, the CLI and scripts.

    ``characters``: the objects chosen (the selection, the CLI's --character); the
    armatures among them are the crowd (a selected body mesh is no character). None:
    every armature of the scene that has its own goal. Each walks to its own goal, else to
    the scene's; a character with neither, or whose goal is itself, is refused by name,
    and so is a choice with no armature in it."""
    scene_goal = scene.motion_patches.goal
    if characters is None:
        chosen = [
            ob
            for ob in scene.objects
            if ob.type == "ARMATURE" and ob.motion_patches_character.goal is not None
        ]
        if not chosen:
            raise MotionPatchesError(
                "no crowd: no armature in the scene has its own goal; "
                "choose the characters, or give each its own goal"
            )
    else:
        chosen = [ob for ob in characters if ob is not None and ob.type == "ARMATURE"]
        if not chosen:
            raise MotionPatchesError("no crowd: none of the chosen objects is an armature")
    pairs = []
    for ob in sorted({ob.name: ob for ob in chosen}.values(), key=lambda o: o.name):
        if scene.objects.get(ob.name) != ob:
            raise MotionPatchesError(f"'{ob.name}' is not in the scene '{scene.name}'")
        goal = ob.motion_patches_character.goal or scene_goal
        if goal is None:
            raise MotionPatchesError(
                f"'{ob.name}' has no goal: give it its own goal or set the scene's goal"
            )
        if goal == ob:
            raise MotionPatchesError(f"the goal of '{ob.name}' is the character itself")
        pairs.append((ob, goal))
    return pairs


@_fills_planning_settings
def plan_crowd(
    scene: "bpy.types.Scene",
    pairs,
    patch_name: str | None = None,
    alpha: float | None = None,
    beta: float | None = None,
    gamma: float | None = None,
    radius: float | None = None,
    frame_start: int | None = None,
    context=None,
    stitching: str | None = None,
    progress=None,
    max_wait_seconds: float = 4.0,
    spacing: float | None = None,
    foot_lock: bool | None = None,
    goal_facing: str | None = None,
    turn_in_place: bool | None = None,
) -> CrowdResult:
    """Plan several characters and write each one's NLA; ``pairs`` = [(armature, goal)] or
    [(armature, goal, options)], a goal being an object or (x, y, heading); ``options``:
    {"start_prop": a tagged prop with a stand-up clip to start seated on, "priority":
    a number, higher planned first}. A goal that is a tagged prop with a sit-down clip
    ends the walk seated on it. Characters that find no path are listed in ``failed``
    with the reason.

    Characters are taken in priority order (the given priority, then the longer distance
    from start to goal first). Each path is planned against the props and the spots where
    the others stand still while it walks: the goals of those before it and the starts of
    those after it (:func:`motion_patches.crowd.crowd.standing_spots`; dropped when they box it
    in). Then each character in turn is checked against a space-time reservation of
    everyone before it and kept ``spacing`` metres (default: two radii) from them by an
    idle hold mid-walk on a double-support frame, else a wait at its start (whole 0.2 s
    steps, each at most ``max_wait_seconds``), else a re-route round where the other walks
    then (:func:`motion_patches.crowd.crowd.resolve`). Closer approaches left are returned as
    ``conflicts`` by pair and frame, checked on the motion as written. Bad input (a
    character twice, two characters sent to one goal, goals closer than ``spacing``: one
    could never be free) raises :class:`MotionPatchesError` before anything is written."""
    t0 = time.perf_counter()
    _check_weights(alpha, beta, gamma, radius)
    patch = _patch_for_planning(scene, patch_name)
    context = context or bpy.context
    context.view_layer.update()
    pairs = [tuple(p) for p in pairs]
    if not pairs:
        raise MotionPatchesError("a crowd needs at least one character with a goal")
    if any(len(p) not in (2, 3) for p in pairs):
        raise MotionPatchesError(
            "each crowd entry is (character, goal) or (character, goal, options)"
        )
    options = [dict(p[2]) if len(p) == 3 and p[2] else {} for p in pairs]
    pairs = [p[:2] for p in pairs]
    spacing = 2 * radius if spacing is None else float(spacing)
    if not (0 <= spacing < np.inf and 0 <= max_wait_seconds < np.inf):
        raise MotionPatchesError("spacing and the longest wait must be numbers >= 0")
    seen, rigs, taken = set(), [], {}
    for (character, goal), opt in zip(pairs, options):
        unknown = set(opt) - {"start_prop", "priority"}
        if unknown:
            raise MotionPatchesError(
                f"unknown crowd option(s) {', '.join(sorted(unknown))} "
                f"for '{getattr(character, 'name', character)}'"
            )
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
        try:
            opt["priority"] = float(opt.get("priority", 0.0))
        except (TypeError, ValueError):
            raise MotionPatchesError(
                f"the priority of '{character.name}' must be a number"
            ) from None
        for what, ob in (("goal", goal), ("start seat", opt.get("start_prop"))):
            if isinstance(ob, bpy.types.Object):
                if ob.name in taken:
                    raise MotionPatchesError(
                        f"'{ob.name}' is the {what} of both '{taken[ob.name]}' and "
                        f"'{character.name}': one spot, one character; give each its own"
                    )
                taken[ob.name] = character.name
    first = _frame_start(scene, frame_start)
    depsgraph = context.evaluated_depsgraph_get()
    # Characters are not obstacles of the scene: they are kept apart in space and time, and
    # where they stand still (goals of earlier ones, starts of later ones) in space. A goal
    # object is no obstacle for its own character only. Characters of another size than the
    # patch skeleton (retargeted rigs) are planned in the world shrunk by their size, one
    # environment and planner per size.
    sizes, worlds = [_size(r) for r in rigs], {}

    def world_of(size):
        if size not in worlds:
            env = scene_io.environment(
                scene, depsgraph, patch, radius, _not_obstacles([c for c, _ in pairs]), size
            )
            props = object_patches(scene, depsgraph, patch, size)
            # props that move (keyframed): where each stands on the first frame; the ones
            # moving then are left out of the global plans and walked round after (Sec. 4.4)
            tracks = moving_io.tracks(scene, depsgraph, list(env.obstacles), first, size)
            for t in tracks:
                env.remove(t.name)
                env.place(Obstacle(t.name, t.polygon_at(t.pose_at(0.0)[0])))
            awake = [t.name for t in tracks if t.awake_at(0.0)]
            worlds[size] = [env, props, {p.name: p for p in props}, None, tracks, awake]
        return worlds[size]

    ends = [
        _endpoints(
            c,
            g,
            opt.get("start_prop"),
            world_of(sz)[2],
            r.target if r else patch.gait.skeleton,
            goal_facing,
            sz,
        )
        for (c, g), opt, r, sz in zip(pairs, options, rigs, sizes)
    ]
    own = [
        [
            o.name
            for o in _not_obstacles([g, opt.get("start_prop")])
            if isinstance(o, bpy.types.Object)
        ]
        for (_, g), opt in zip(pairs, options)
    ]
    for (c, _), e, mine, sz in zip(pairs, ends, own, sizes):
        _check_ends(c, e, sz)
        with _without(world_of(sz)[0], mine):
            _check_clear(world_of(sz)[0], c, e, world_of(sz)[2])
    for w in worlds.values():
        w[3] = SegmentPlanner(
            patch,
            w[0],
            alpha,
            beta,
            gamma,
            props=w[1],
            mode=stitching,
            turn_in_place=turn_in_place,
        )
    world_ends = [(_shrunk(e[0], 1.0 / sz), _shrunk(e[1], 1.0 / sz)) for e, sz in zip(ends, sizes)]
    goals = np.array([g[1][:2] for g in world_ends])
    for i in range(len(pairs)):
        for j in range(i):
            gap = float(np.linalg.norm(goals[i] - goals[j]))
            if gap < spacing:
                raise MotionPatchesError(
                    f"the goals of '{pairs[j][0].name}' and '{pairs[i][0].name}' are {gap:.2f} m "
                    f"apart, closer than the spacing ({spacing:.2f} m): the one arriving second "
                    f"would never find its goal free; move one of them"
                )
    # priority order: the given priority, then the longer way first
    order = sorted(
        range(len(pairs)),
        key=lambda n: (
            -options[n]["priority"],
            -float(np.linalg.norm(world_ends[n][1][:2] - world_ends[n][0][:2])),
        ),
    )
    rank_ends = [world_ends[n] for n in order]

    def solve_one(n, ghosts=()):
        """Plan character n round the standing spots (dropped when they box it in) and,
        when re-routing, round ``ghosts`` (world polygons; PathNotFound if they box it in)."""
        character, e = pairs[n][0], ends[n]
        env, _, _, planner, tracks, awake = world_of(sizes[n])
        spots = [
            Obstacle(f"{CROWD_SPOT}{pairs[order[m]][0].name}", polygon / sizes[n])
            for m, polygon in crowd.standing_spots(rank_ends, order.index(n), spacing, radius)
        ]
        mine = np.array([e[0][:2], e[1][:2]], float)
        extra = [
            Obstacle(f"{CROWD_GHOST}{k}", polygon / sizes[n]) for k, polygon in enumerate(ghosts)
        ]
        extra = [g for g in extra if not g.within(mine, radius).any()]  # not on its own ends
        with _without(env, own[n]):
            for ob in spots + extra:  # where the others stand still while this one walks
                env.place(ob)
            try:
                with _without(env, awake):
                    try:
                        plan = _solve(planner, character, e, explain=not (spots or extra))
                    except PathNotFound:
                        if not spots or extra:
                            raise
                        for spot in spots:  # boxed in by the others: plan past them
                            env.remove(spot.name)
                        spots = []
                        plan = _solve(planner, character, e)
                if tracks:  # round the moving props by re-routing (the crowd times waits)
                    plan, _ = _avoid_moving(
                        planner, patch, plan, tracks, character, first, fps, longest_wait=0.0
                    )
                return plan
            finally:
                for ob in spots + extra:
                    env.remove(ob.name)

    fps = scene_fps(scene)
    rate = fps / patch.gait.fps  # scene frames per patch frame (holds are timed on the scene's)
    ramp = max(2, int(round(CROWD_HOLD_RAMP_SECONDS * fps)) // 2 * 2)

    def synthesised(n, plan):
        """(raw piece motions, placed motion, holdable frames or None) of a plan."""
        raw = plan_motions(patch, plan)
        placed = _placed(scene, patch, rigs[n], raw)
        return raw, placed, _holdable(plan, placed, ramp)

    planned, failed = [], []  # planned: [(n, plan, raw, placed, holdable)] in priority order
    for count, n in enumerate(order):
        try:
            plan = solve_one(n)
            planned.append([n, plan, *synthesised(n, plan)])
        except PathNotFound as exc:
            failed.append((pairs[n][0].name, str(exc)))
        if progress is not None:
            progress(0.8 * (count + 1) / len(pairs))

    versions = [[p] for p in planned]  # every re-plan kept: the crowd may settle on any

    def replan(k, ghosts):
        """Character k of the planned ones re-planned round ``ghosts``: its new track (the
        next version of its plan)."""
        n = planned[k][0]
        try:
            plan = solve_one(n, ghosts)
        except PathNotFound:
            return None
        versions[k].append([n, plan, *synthesised(n, plan)])
        return _root_track(versions[k][-1][3]), versions[k][-1][4]

    # Resolved a little wider than reported: a hold is laid into the written motion by a time
    # warp, which may bring a pair a few millimetres nearer than the track the table saw.
    schedules, _ = crowd.resolve(
        [_root_track(p[3]) for p in planned],
        replan,
        spacing + CROWD_RESOLVE_SLACK,
        radius,
        fps,
        round(max_wait_seconds * fps),
        max(1, round(0.2 * fps)),
        ramp=ramp,
        holdable=[p[4] for p in planned],
    )
    planned = [v[s.version] for v, s in zip(versions, schedules)]
    holds = {}
    for p, s in zip(planned, schedules):
        if s.holds:  # each hold put in the piece it falls in, as its own strip
            at = []
            for k, h in s.holds:
                bounds = scene_rate.piece_bounds([m.frames for m in p[2]], rate)[1]
                p[1], p[2] = _with_hold(p[1], p[2], bounds, k, h, ramp, rate)
                at = [(f + h + ramp if f > k else f, n) for f, n in at] + [(k, h)]
            p[3] = _placed(scene, patch, rigs[p[0]], p[2])
            holds[pairs[p[0]][0].name] = sorted(at)
    # what is reported is checked on the motion written, whatever resolved it
    ranked = sorted(range(len(planned)), key=lambda k: schedules[k].rank)  # order kept
    conflicts = crowd.conflicts_of(
        [_root_track(planned[k][3]) for k in ranked],
        [schedules[k].delay for k in ranked],
        spacing,
    )
    # the props that move, against each walk as scheduled (its wait and holds included)
    moving_left = []
    for p, s in zip(planned, schedules):
        _, _, _, planner_n, tracks, _ = world_of(sizes[p[0]])
        if not tracks:
            continue
        wait = s.delay / fps
        for c in moving_props.conflicts(
            p[2], tracks, planner_n.world_env.radius, patch.gait.fps, wait
        ):
            moving_left.append(
                {
                    "character": pairs[p[0]][0].name,
                    "prop": c.prop,
                    "frame": first + s.delay + int(round(c.frame * fps / patch.gait.fps)),
                    "distance_m": float(c.distance),
                }
            )
    if progress is not None:
        progress(0.9)
    written = {}
    for (n, plan, _, placed, _), s in zip(planned, schedules):
        _writable(pairs[n][0], first + s.delay, placed[2].frames)
    with transaction.kept(
        bpy, scene, [pairs[n][0] for n, *_ in planned], (PLAN_KEY, FRAME_RANGE_KEY)
    ):
        for (n, plan, _, placed, _), s in zip(planned, schedules):
            env = world_of(sizes[n])[0]
            with _without(env, own[n]):  # the plan record lists what it walked around
                written[n] = _write(
                    scene,
                    pairs[n][0],
                    patch,
                    patch_name,
                    plan,
                    placed,
                    first + s.delay,
                    env,
                    radius,
                    foot_lock,
                    rigs[n],
                    fit=False,
                )
        if written:
            _fit_frame_range(scene)  # once: it reads every character's plan record
    if progress is not None:
        progress(1.0)
    names = [pairs[p[0]][0].name for p in planned]
    for c in conflicts:
        c["a"], c["b"] = names[ranked[c["a"]]], names[ranked[c["b"]]]
        c["frame"] += first
        c["first_frame"] += first
    for p in planned:  # holds on the scene's frames (a character that holds starts at once)
        name = pairs[p[0]][0].name
        if name in holds:
            holds[name] = [
                {"frame": written[p[0]].frame_start + f + ramp // 2, "frames": int(n)}
                for f, n in holds[name]
            ]
    return CrowdSchedule(
        [written[n] for n in sorted(written)],
        failed,
        conflicts,
        {nm: s.delay for nm, s in zip(names, schedules)},
        time.perf_counter() - t0,
        [nm for nm, s in zip(names, schedules) if s.rerouted],
        holds,
        [names[k] for k in ranked],
        moving_left,
    )


def analyse(
    context: "bpy.types.Context", character: "bpy.types.Object", keep: bool = False
) -> dict:
    """Figures of the evaluated (depsgraph) motion against the last plan on ``character``;
    ``keep`` stores them on it (:func:`last_analysis`, the Analysis panel)."""
    figures = _analyse(context, character)
    if keep:
        storage.store_analysis(character, figures)
    return figures


def _analyse(context, character):
    meta, arrays = load_plan_record(character)
    frames = np.arange(meta["frame_start"], meta["frame_end"] + 1)
    bones = [meta["root_name"]] + list(meta["foot_names"])
    pos, ground, rot, _ = evaluate.sample_armature(context, character, frames, bones)
    fps = scene_fps(context.scene)
    root, feet = pos[:, 0], pos[:, 1:]
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
    boundaries = [b - meta["frame_start"] for b in meta["boundaries"]]
    pops = metrics.boundary_pops(rot, boundaries, fps)
    end_heading = ground[-1, 2] + meta["facing"]
    return {
        "frames": int(frames.size),
        "seconds": float((frames.size - 1) / fps),
        "foot_skate": skate,
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
        "traversals": len(meta.get("traversals", [])),
        "boundary_pop": pops,
    }


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


def _resolve(scene, place, what, patch):
    """(state, object or None) for the name of an object of ``scene`` or [x, y,
    heading_deg]; a start that is an armature starts where its own skeleton stands (it may
    be retargeted)."""
    if what == "exclude":
        ob = scene.objects.get(place)
        if ob is None:
            raise MotionPatchesError(f"layout spec: no object named '{place}' to exclude")
        return None, ob
    if not isinstance(place, str):
        return np.array([place[0], place[1], math.radians(place[2])]), None
    ob = scene.objects.get(place)
    if ob is None:
        raise MotionPatchesError(
            f"layout spec: no object named '{place}' for a {what} "
            f"(have: {_some_names(scene.objects)})"
        )
    if what == "character" or (what == "start" and ob.type == "ARMATURE"):
        rig = _check_character(ob, patch)  # the rule plan_path applies to its character
        return scene_io.character_state(ob, rig.target if rig else patch.gait.skeleton), ob
    return scene_io.ground_state(ob), ob


def planned_pairs(scene: "bpy.types.Scene", characters=(), goals=()) -> list[dict]:
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


def check_layout(scene: "bpy.types.Scene", spec: dict, context=None) -> list[dict]:
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
    try:
        w = planning_settings(scene, **{k: spec[k] for k in ("alpha", "beta", "gamma", "radius")})
    except MotionPatchesError as exc:
        raise MotionPatchesError(f"layout spec: {exc}") from None
    margin = 3 if spec["margin_tiles"] is None else int(spec["margin_tiles"])
    # Evaluate first: it also brings the objects' world matrices up to date.
    depsgraph = (context or bpy.context).evaluated_depsgraph_get()
    jobs = []
    for p in spec["pairs"]:
        start, sob = _resolve(
            scene, p["start"], "character" if p.get("character") else "start", patch
        )
        goal, gob = _resolve(scene, p["goal"], "goal", patch)
        # A retargeted character plans in the world shrunk by its size (see _size).
        size = (
            _size(_check_character(sob, patch))
            if sob is not None and sob.type == "ARMATURE"
            else 1.0
        )
        # Not obstacles: the start and goal objects with their children (a character's own
        # body mesh) and whatever the spec excludes.
        exclude = {}
        for ob in [sob, gob] + [
            _resolve(scene, n, "exclude", patch)[1] for n in spec["exclude"] + p["exclude"]
        ]:
            if ob is not None:
                for o in (ob, *ob.children_recursive):
                    exclude[o.name] = o
        jobs.append((p, start, sob, goal, gob, exclude, size))
    envs, results, props = {}, [], {}
    for p, start, sob, goal, gob, exclude, size in jobs:
        allow = bool(p["limits"]["allow_traversal"])
        key = (tuple(sorted(exclude)), allow, size)
        if key not in envs:
            env = scene_io.environment(
                scene, depsgraph, patch, w["radius"], tuple(exclude.values()), size
            )
            if size not in props:  # tagged props offer traversals
                props[size] = object_patches(scene, depsgraph, patch, size)
            usable = [pr for pr in props[size] if pr.name not in exclude] if allow else []
            try:
                planner = SegmentPlanner(
                    patch,
                    env,
                    w["alpha"],
                    w["beta"],
                    w["gamma"],
                    props=usable,
                    turn_in_place=w["turn_in_place"],
                )
            except PlanError as exc:
                raise MotionPatchesError(str(exc)) from None
            envs[key] = env, planner
        env, planner = envs[key]
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
            "blocked_reason": None,
            "error": None,
            "limits": p["limits"],
        }
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
            r.update(
                reachable=True,
                frames=int(round(seconds * scene_fps(scene))) + 1,
                seconds=seconds,
                length_m=path_length(world.ground) * size,
                cost=float(plan.cost),
                pieces=len(plan.pieces),
                expansions=int(plan.expansions),
                plan_seconds=float(plan.seconds),
                traversals=sum(pc.kind == "traversal" for pc in plan.pieces),
            )
        r["failures"] = layout_spec.judge(r, p["limits"])
        r["passed"] = not r["failures"]
        results.append(r)
    return results


def _some_names(coll, limit=8):
    names = sorted(x.name for x in coll)
    return (", ".join(names[:limit]) + (", ..." if len(names) > limit else "")) or "none"


# --- crowds: idle holds ----------------------------------------------------------------------

CROWD_HOLD_RAMP_SECONDS = 0.5  # slowing to an idle hold and walking on again, each


@dataclass
class CrowdSchedule(CrowdResult):
    """A :class:`CrowdResult` with how the crowd was kept apart beyond waits."""

    # name -> [{"frame": first scene frame standing still, "frames": how many}]
    holds: dict = field(default_factory=dict)
    order: list = field(default_factory=list)  # planned names in the order they were placed
    # [{"character", "prop", "frame", "distance_m"}]: a walk as scheduled (waits and holds
    # of the crowd included) meeting a prop that moves
    moving_conflicts: list = field(default_factory=list)


_CLIPS = ("traversal", "interaction")


def _piece_holding(plan, bounds, at, ramp):
    """Index of the walking piece whose scene frames ``bounds[i]..bounds[i+1]`` hold frame
    ``at`` with half a ``ramp`` to spare on both sides, or None."""
    half = ramp // 2
    for i, p in enumerate(plan.pieces):
        if p.kind not in _CLIPS and bounds[i] + half <= at <= bounds[i + 1] - half:
            return i
    return None


def _holdable(plan, placed, ramp):
    """Bool per scene frame of a placed plan (:func:`_placed`): frames a crowd may hold on,
    double support (a planted joint on each foot) inside a walking piece with room for the
    slow-down and speed-up in that piece."""
    _, bounds, world = placed
    c = world.contacts
    ok = c[:, :2].any(axis=1) & c[:, 2:].any(axis=1)
    inside = np.zeros_like(ok)
    half = ramp // 2
    for i, p in enumerate(plan.pieces):
        if p.kind not in _CLIPS:
            inside[bounds[i] + half : bounds[i + 1] - half + 1] = True
    return ok & inside


def _with_hold(plan, raw, bounds, at, hold, ramp, rate=1.0):
    """(plan, raw piece motions) with an idle hold of ``hold`` frames on scene frame ``at``
    (``bounds``: the pieces' scene frames, ``rate`` scene frames per patch frame): the piece
    it falls in is time-warped (:func:`motion_patches.kinematics.retime.held`; at another rate
    :func:`motion_patches.crowd.held_motion.held_piece`) and becomes a piece of kind "hold",
    so it is written as its own action, not the shared segment action."""
    import dataclasses

    from .motion_patches.kinematics import retime

    i = _piece_holding(plan, bounds, at, ramp)
    if i is None:
        raise MotionPatchesError(f"internal: frame {at} is in no walking piece to hold in")
    raw = list(raw)
    if abs(rate - 1.0) < 1e-9:
        raw[i] = retime.held(raw[i], at - bounds[i], hold, ramp)
    else:
        span = int(bounds[i + 1] - bounds[i])
        raw[i] = held_motion.held_piece(raw[i], at - bounds[i], hold, ramp, span, rate)
    pieces = list(plan.pieces)
    pieces[i] = dataclasses.replace(pieces[i], kind="hold")
    return dataclasses.replace(plan, pieces=pieces), raw


def _root_track(placed):
    """(frames, 2) ground position of the root joint of a placed motion (:func:`_placed`):
    what a crowd keeps apart (the hips sway a few centimetres about the ground track)."""
    world = placed[2]
    return root_positions(world.ground, world.root_local)[:, :2]


# --- crowds: duplicating a source armature ---------------------------------------------------

CROWD_COLLECTION = "MP Crowd"


def duplicate_crowd(
    scene,
    source,
    count,
    region,
    goal_region,
    seed=0,
    radius=0.25,
    spacing=None,
    patch_name=None,
    context=None,
):
    """[(character, goal empty)]: ``count`` copies of the armature ``source`` sharing its
    armature data (linked, as Alt+D makes them), scattered over ``region`` ((x0, y0), (x1,
    y1)) and each sent to a goal empty scattered over ``goal_region``, facing the way it
    walks; all in a new collection. Starts and goals keep ``spacing`` (default: two radii)
    plus a radius from one another and stay clear of the props. Everything is checked and
    every spot drawn before anything is made: a source the patch cannot play, or regions
    too small to hold the crowd, raise :class:`MotionPatchesError` with the scene unchanged."""
    context = context or bpy.context
    patch = _patch_for_planning(scene, patch_name)
    if source is None or source.type != "ARMATURE":
        raise MotionPatchesError("choose the source armature to duplicate")
    rig = _check_character(source, patch)
    try:
        count = int(count)
        region = np.asarray(region, float).reshape(2, 2)
        goal_region = np.asarray(goal_region, float).reshape(2, 2)
    except (TypeError, ValueError):
        raise MotionPatchesError(
            "a crowd needs a count and two regions ((x0, y0), (x1, y1))"
        ) from None
    if count < 1:
        raise MotionPatchesError("a crowd needs at least one character")
    for what, r in (("region", region), ("goal region", goal_region)):
        if not np.isfinite(r).all() or (r[1] <= r[0]).any():
            raise MotionPatchesError(
                f"the {what} must have its second corner above and right of its first"
            )
    spacing = 2 * radius if spacing is None else float(spacing)
    context.view_layer.update()
    depsgraph = context.evaluated_depsgraph_get()
    env = scene_io.environment(scene, depsgraph, patch, radius, _not_obstacles([source]), 1.0)
    rng = np.random.default_rng(seed)
    gap = spacing + radius

    def scatter(r, what):
        pts = np.empty((0, 2))
        for _ in range(200 * count):
            p = rng.uniform(r[0], r[1])
            if env.near(p) or (len(pts) and np.linalg.norm(pts - p, axis=1).min() < gap):
                continue
            pts = np.vstack((pts, p))
            if len(pts) == count:
                return pts
        raise MotionPatchesError(
            f"the {what} holds only {len(pts)} of {count} characters {gap:.2f} m apart and "
            f"clear of the props: make it larger or the crowd smaller"
        )

    starts, goals = scatter(region, "region"), scatter(goal_region, "goal region")
    rng.shuffle(goals)
    skel = rig.target if rig is not None else patch.gait.skeleton
    facing = nla.facing_angle(skel)
    coll = bpy.data.collections.new(CROWD_COLLECTION)
    scene.collection.children.link(coll)
    pairs = []
    for k, (s, g) in enumerate(zip(starts, goals)):
        heading = float(np.arctan2(g[1] - s[1], g[0] - s[0]))
        ob = source.copy()  # object copy, armature data shared
        ob.name = f"{source.name}.crowd{k:03d}"
        ob.animation_data_clear()
        for key in (PLAN_KEY, nla.TRACKS_KEY):
            if key in ob:
                del ob[key]
        coll.objects.link(ob)
        ob.location = (s[0], s[1], source.location[2])
        ob.rotation_mode = "XYZ"
        ob.rotation_euler = (0.0, 0.0, heading - facing)
        goal = bpy.data.objects.new(f"{ob.name} goal", None)
        coll.objects.link(goal)
        goal.location = (g[0], g[1], 0.0)
        goal.rotation_euler = (0.0, 0.0, heading + np.pi / 2)  # its -Y along the heading
        ob.motion_patches_character.goal = goal
        pairs.append((ob, goal))
    context.view_layer.update()
    return pairs


def remove_crowd(pairs):
    """Remove what :func:`duplicate_crowd` made (the copies, their goals, their collection
    when it is left empty, the actions planning made for them); the source is untouched."""
    colls = set()
    for ob, goal in pairs:
        for o in (ob, goal):
            colls.update(c for c in o.users_collection if c.name.startswith(CROWD_COLLECTION))
        names = {ob.name}
        if ob.animation_data is not None:
            ob.animation_data_clear()
        bpy.data.objects.remove(ob)
        bpy.data.objects.remove(goal)
        for a in list(bpy.data.actions):
            if a.get(nla.CHARACTER_KEY) in names and a.users == 0:
                bpy.data.actions.remove(a)
    for c in colls:
        if not c.objects and not c.children:
            bpy.data.collections.remove(c)
