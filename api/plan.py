# SPDX-License-Identifier: GPL-3.0-or-later
"""Planning one character to its goal (:func:`plan_path`), in one gait layer or several."""

from __future__ import annotations

import bpy

from ..adapter import moving as moving_io
from ..adapter import scene as scene_io
from ..adapter import storage, transaction
from ..motion_patches.patch import layers
from ..motion_patches.planning import body_clearance, transitions
from ..motion_patches.planning.motions import stand_note
from ..motion_patches.planning.planner import PlanError, plan_motions
from ..motion_patches.planning.settings import PlanSettings
from ..motion_patches.props.environment import Obstacle
from ..motion_patches.quality import validate
from .common import (
    _check_character,
    _not_obstacles,
    _patch_for_planning,
    _size,
    object_patches,
    own_goal,
    scene_fps,
)
from .errors import MotionPatchesError, PathNotFound
from .results import PlanResult
from .settings import plan_settings
from .solve import (
    _avoid_moving,
    _body_clear,
    _check_clear,
    _check_ends,
    _endpoints,
    _frame_start,
    _planner,
    _solve,
    _without,
    _writable,
)
from .writing import WRITTEN_KEYS, _placed, _write


def plan_path(
    scene: bpy.types.Scene,
    character: bpy.types.Object,
    goal: bpy.types.Object | tuple | None,
    patch_name: str | None = None,
    alpha: float | None = None,
    beta: float | None = None,
    gamma: float | None = None,
    radius: float | None = None,
    frame_start: int | None = None,
    context: bpy.types.Context | None = None,
    stitching: str | None = None,
    start_prop: bpy.types.Object | None = None,
    foot_lock: bool | None = None,
    goal_facing: str | None = None,
    gait: str | None = None,
    turn_in_place: bool | None = None,
    from_here: bool = False,
) -> PlanResult:
    """Plan ``character`` to ``goal`` (an object or (x, y, heading); None: the character's
    Own Goal, else the scene's goal, as in a crowd: :func:`own_goal`) and write it as NLA.
    Settings left None are the scene's (:func:`planning_settings`).

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
    patch). A character planned before starts again where it stood then, whatever frame
    the timeline shows; ``from_here`` starts it where it is at the current frame instead
    (continue from here). Raises
    :class:`PathNotFound` when the props leave no way, and
    :class:`MotionPatchesError` for bad input; either way the scene is unchanged."""
    settings = plan_settings(
        scene,
        alpha=alpha,
        beta=beta,
        gamma=gamma,
        radius=radius,
        stitching=stitching,
        foot_lock=foot_lock,
        goal_facing=goal_facing,
        turn_in_place=turn_in_place,
    )
    if gait is None:  # the scene's choice (Planning panel); "active": the active patch
        gait = {"ACTIVE": None}.get(scene.motion_patches.gait, scene.motion_patches.gait.lower())
    candidates = _layer_patches(scene, patch_name, gait)
    context = context or bpy.context
    # Objects moved by a script have stale matrix_world until the view layer updates.
    context.view_layer.update()
    if goal is None:
        goal = own_goal(scene, character)
    if goal is None:
        who = getattr(character, "name", character)
        raise MotionPatchesError(
            f"no goal for '{who}': choose a goal object (its location and facing), give "
            "the character its own goal or set the scene's goal"
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
                    settings,
                    frame_start,
                    context,
                    start_prop,
                    from_here,
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
    assert best is not None  # every plan tried has a cost
    layer_keys = None
    if best == len(tried):  # the plan that changes layer: written with the walk's patch
        patch, rig, env, _, _, start_frame, _, name = min(tried, key=lambda t: t[0].effort_rate)
        assert change is not None  # best is past the layers tried only when it exists
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
    placed = _placed(scene, patch, rig, motions, plan)
    _writable(character, start_frame, placed[2].frames)
    with transaction.kept(bpy, scene, [character], WRITTEN_KEYS):
        return _write(
            scene,
            character,
            patch,
            name,
            plan,
            placed,
            start_frame,
            env,
            settings,
            rig,
            layer_keys=layer_keys,
            from_here=from_here,
        )


def _too_low(prop, clip, clears, height, scale=1.0):
    """A sentence: a traversal clip not offered because it does not clear its prop."""
    return (
        f"{clip} clears {clears * scale:.2f} m over '{prop.name}', which is "
        f"{height * scale:.2f} m high: not offered"
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
    settings: PlanSettings,
    frame_start,
    context,
    start_prop,
    from_here=False,
):
    """(patch, rig map, planner world, plan, piece motions, first frame, {planner, ends,
    moving: whether props move}) of one character planned in the layer of ``patch``; its
    props offer only the traversal clips that serve that layer
    (:func:`motion_patches.patch.layers.serves`); ``settings``: the request's."""
    rig = _check_character(character, patch)
    scale = _size(rig)
    depsgraph = context.evaluated_depsgraph_get()
    goal_obj = goal if isinstance(goal, bpy.types.Object) else None
    env = scene_io.environment(
        scene, depsgraph, patch, settings.radius, _not_obstacles((character, goal_obj)), scale
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
        settings.goal_facing,
        scale,
        from_here,
    )
    _check_ends(character, ends, scale)
    tracks = moving_io.tracks(scene, depsgraph, list(env.obstacles), frame_start, scale)
    awake = [t.name for t in tracks if t.awake_at(0.0)]
    for t in tracks:  # where each stands at the first frame (the scene may show another)
        env.remove(t.name)
        env.place(Obstacle(t.name, t.polygon_at(t.pose_at(0.0)[0])))
    with _without(env, awake):  # awake props are avoided locally, after (Sec. 4.4)
        _check_clear(env, character, ends, by_name)
        planner = _planner(patch, env, settings, props)
        plan = _solve(planner, character, ends)
        plan, motions = _body_clear(planner, plan, plan_motions(patch, plan), ends)
    if tracks:
        plan, wait = _avoid_moving(
            planner, patch, plan, tracks, character, frame_start, scene_fps(scene)
        )
        frame_start += int(round(wait * scene_fps(scene)))
        motions = plan_motions(patch, plan)
    plan.stats["glitches"] = validate.count(validate.plan_glitches(patch, plan, motions))
    low = [_too_low(p, n, h, top, scale) for p in props for n, h, top in p.too_low]
    if low:  # why the walk goes round a tagged prop
        plan.stats["traversals_too_low"] = low
    plan.stats["stand"] = stand_note(patch, plan)
    layer = {"planner": planner, "ends": ends, "moving": bool(tracks)}  # for _gait_change
    return patch, rig, env, plan, motions, frame_start, layer
