# SPDX-License-Identifier: GPL-3.0-or-later
"""One character's path, shared by :func:`plan_path` and :func:`plan_crowd`: its start and
goal states, the checks before searching, the search and its refusals."""

from __future__ import annotations

import math

import bpy
import numpy as np

from ..adapter import nla, props_io, storage, transaction
from ..adapter import scene as scene_io
from ..motion_patches.crowd import members
from ..motion_patches.planning import body_clearance, causes, moving_props
from ..motion_patches.planning.planner import (
    PlanError,
    SegmentPlanner,
    interaction_states,
    plan_motions,
    planner_for,
    with_interactions,
)
from ..motion_patches.planning.settings import PlanSettings
from .common import _check_far, _limit_text, _shrunk
from .errors import MotionPatchesError, PathNotFound


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


def _start_matrix(character, from_here=False):
    """The world matrix a plan of ``character`` starts from. While the add-on's root track
    places it, where it stood before it was planned (kept in its plan record), whatever
    frame the timeline shows: re-planning from frame 200 must not start mid-walk. Its place
    at the current frame when ``from_here`` (continue from here) or when nothing of the
    add-on animates it."""
    if not from_here and nla.drives_root(character):
        m = storage.stood(character)
        if m is not None:
            return m
    return np.array(character.matrix_world)


def _endpoints(
    character,
    goal,
    start_prop,
    by_name,
    skel,
    goal_facing="exact",
    scale=1.0,
    from_here=False,
):
    """Start and goal states with the interaction clips that begin / end the path there;
    ``goal_facing`` "any" leaves the goal heading free (NaN) unless a clip fixes it.
    ``skel``: the character's own skeleton; the states are in the planner's world of a
    character ``scale`` times the patch's size (:func:`_size`). ``from_here``: start where
    the character is at the current frame (:func:`_start_matrix`)."""
    if goal_facing not in ("exact", "any"):
        raise MotionPatchesError(f"goal facing must be 'exact' or 'any', not {goal_facing!r}")
    matrix = _start_matrix(character, from_here)
    start_state = _shrunk(scene_io.character_state(character, skel, matrix), scale)
    goal_state = _shrunk(_goal(goal), scale)
    if goal_facing == "exact" and isinstance(goal, bpy.types.Object):
        if np.linalg.norm(np.array(goal.matrix_world)[:2, 1]) < 1e-9:
            raise MotionPatchesError(
                f"the goal '{goal.name}' has no facing (its -Y axis is flattened by a zero "
                "scale or a tilt): give it a scale, or plan with goal facing 'any'"
            )
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


def _obstacle_names(env, names):
    """Names of ``env``'s obstacles that are, or are parts of
    (:func:`adapter.scene.part_name`: "name (part k)", k from 1 up), the objects ``names``,
    object by object. Looked up by name, not by reading every obstacle: a crowd asks this
    about three times a character (5,000 props: 0.9 ms a call)."""
    out = []
    for name in dict.fromkeys(names):
        if name in env.obstacles:
            out.append(name)
        k = 0  # parts of an object of more than one part, numbered from 1 without gaps
        while (part := scene_io.part_name(name, k, k + 2)) in env.obstacles:
            out.append(part)
            k += 1
    return out


def _without(env, names):
    """``env`` with the named objects' obstacles taken out for the block (put back after)."""
    return members.without(env, _obstacle_names(env, names))


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


def _planner(patch, env, settings: PlanSettings, props) -> SegmentPlanner:
    """The core planner of one world, its keyword arguments taken from the request's
    settings (:func:`motion_patches.planning.planner.planner_for`)."""
    return planner_for(patch, env, settings, props)


def _solve(planner, character, endpoints, explain=True):
    """The plan of one character; :class:`PathNotFound` naming the cause when there is none
    (``explain=False`` skips finding the cause: a crowd retries such a failure without
    the others' standing spots)."""
    try:
        return members.planned_path(planner, endpoints, explain)
    except PlanError as exc:
        raise _not_found(character.name, members.no_plan_of(-1, exc)) from None


def _not_found(name: str, why: members.NoPlan) -> PathNotFound:
    """The :class:`PathNotFound` of a refusal of the core (:class:`members.NoPlan`)."""
    if why.kind == "limit":
        return PathNotFound(f"no path for '{name}': {_limit_text(causes.SEARCH_LIMIT)}", why.cause)
    if why.kind == "cause":
        return PathNotFound(
            f"no path for '{name}': {why.text}", why.cause, scene_io.owners(why.props)
        )
    if why.kind == "moving":
        return PathNotFound(
            f"no path for '{name}' clear of moving props: {why.text}"
            " (move the prop's keyframes, or start later with Frame Start)",
            "moving",
            why.props,
        )
    return PathNotFound(f"no path for '{name}': {why.text}")


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
    if isinstance(frame_start, bool) or (math.isfinite(f) and f != round(f)):
        raise MotionPatchesError(f"the start frame must be a whole number, not {frame_start!r}")
    if not (math.isfinite(f) and lo <= f <= hi):
        raise MotionPatchesError(
            f"the start frame {frame_start} is outside what Blender holds ({lo} to {hi})"
        )
    return int(round(f))


def _check_ends(character, endpoints, scale):
    """:func:`_check_far` of a character's start and goal states (``_endpoints``) unless a
    prop's clip starts or ends the path there."""
    if endpoints[2] is None and endpoints[3] is None:
        _check_far(endpoints[0], endpoints[1], f"'{character.name}'", scale)


def _avoid_moving(
    planner, patch, plan, tracks, character, frame_start, fps, longest_wait=moving_props.MAX_DELAY_S
):
    """(plan, seconds to wait at the start) clear of the props that move during it
    (:mod:`moving_props`: a wait of at most ``longest_wait`` or a repaired run);
    :class:`PathNotFound` naming the prop and the frame when neither keeps clear of it.
    ``fps``: the scene's rate."""
    plan, wait, left = members.around_moving(
        planner, patch, plan, tracks, frame_start, fps, longest_wait
    )
    if left:
        text = members.moving_text(left, patch, frame_start, fps)
        raise _not_found(
            character.name, members.NoPlan(-1, "moving", text, "moving", [x.prop for x in left])
        )
    return plan, wait
