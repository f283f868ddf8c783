# SPDX-License-Identifier: GPL-3.0-or-later
"""Shared by every use case: the scene's frame rate, the stored patch and plan records, the
character's size against the patch, a start or goal's checks."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..adapter import compat, nla, props_io, storage
from .errors import MotionPatchesError

if TYPE_CHECKING:
    import bpy

    from ..motion_patches.patch.locomotion_patch import LocomotionPatch
    from ..motion_patches.props.object_patch import ObjectPatch


PLAN_KEY = storage.PLAN_KEY  # the custom property holding a character's plan record
ANALYSIS_KEY = storage.ANALYSIS_KEY  # ... and the figures of its last analysis


def scene_fps(scene: bpy.types.Scene) -> float:
    """Frames per second of ``scene`` (its rate over its base)."""
    return scene.render.fps / scene.render.fps_base


def active_patch_name(scene: bpy.types.Scene) -> str | None:
    """The patch planning uses when none is named (None: no patch is baked)."""
    return storage.active_name(scene)


def object_patches(
    scene: bpy.types.Scene,
    depsgraph: bpy.types.Depsgraph,
    patch: LocomotionPatch,
    scale: float = 1.0,
) -> list[ObjectPatch]:
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


def load_plan_record(obj: bpy.types.Object) -> tuple[dict, dict]:
    """The last plan written on ``obj`` (meta dict, arrays dict)."""
    try:
        return storage.load_plan(obj)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None


def last_analysis(obj: bpy.types.Object | None) -> dict | None:
    """The figures :func:`analyse` kept on ``obj`` last time, or None."""
    return storage.last_analysis(obj)


def state_dict(state: Sequence[float], name: str | None = None) -> dict:
    """(x, y, heading) as JSON-friendly numbers (heading in degrees, -180..180)."""
    h = (float(np.degrees(state[2])) + 180.0) % 360.0 - 180.0
    d: dict[str, float | str] = {
        "x": round(float(state[0]), 6),
        "y": round(float(state[1]), 6),
        "heading_deg": round(h, 4) + 0.0,
    }
    if name is not None:
        d["object"] = name
    return d


def path_length(ground: np.ndarray) -> float:
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


def _size(rig):
    """How much larger the character is than the patch's skeleton (its hip-height ratio).
    The planner works in the world divided by it, where the patch's steps are the
    character's; its motion is scaled back by :meth:`RigMap.motion`."""
    return 1.0 if rig is None else float(rig.scale)


def _skeleton(rig, patch):
    """The skeleton a character plays the patch on: its rig map's target, else (no map)
    the patch's own."""
    return rig.target if rig is not None else patch.gait.skeleton


def _shrunk(state, scale):
    """A world (x, y, heading) in the planner's world of a character ``scale`` times the
    patch skeleton's size (and back with ``1 / scale``)."""
    state = np.array(state, float)
    state[:2] /= scale
    return state


def _children_map():
    """{object: its children} of the file, in one pass: ``children_recursive`` looks at every
    object of the file each time (1.6 ms an object among 20,000; a crowd of 10,000 asks it of
    each character and each goal)."""
    import bpy

    out = {}
    for ob in bpy.data.objects:
        if ob.parent is not None:
            out.setdefault(ob.parent, []).append(ob)
    return out


def _descendants(ob, children):
    """``ob``'s children, theirs, ... from :func:`_children_map`'s ``children``."""
    out, todo = [], list(children.get(ob, ()))
    while todo:
        child = todo.pop()
        out.append(child)
        todo.extend(children.get(child, ()))
    return out


def _not_obstacles(objects, children=None):
    """Objects that never block: the given ones with their children (a character's own
    body mesh), except tagged props (a goal prop to sit on stays an obstacle).
    ``children``: :func:`_children_map` of the file, when asked for many objects."""
    out = []
    for ob in objects:
        if ob is not None and not props_io.is_tagged(ob):
            kids = ob.children_recursive if children is None else _descendants(ob, children)
            out += [ob, *kids]
    return tuple(out)


MAX_COORDINATE = 1e5  # metres from the origin a start or goal may lie
MAX_DISTANCE = 2000.0  # metres between start and goal of one plan (plan longer walks in legs)
SAME_PLACE = 0.05  # metres: a goal this near the start, facing the same way, is the start
SAME_FACING = np.radians(2.0)


def _check_far(start, goal, who, scale=1.0, same_place=True):
    """Refuse a start or goal farther from the origin than ``MAX_COORDINATE`` or start and
    goal farther apart than ``MAX_DISTANCE`` (planner-world states of a character ``scale``
    times the patch's size), and (``same_place``) a goal where the start is (same place,
    same facing)."""
    for what, state in (("start", start), ("goal", goal)):
        xy = np.asarray(state[:2], float)
        if not np.isfinite(xy).all() or not np.isfinite(state[2]) and what == "start":
            raise MotionPatchesError(
                f"the {what} of {who} has a coordinate or facing that is not a number "
                f"({', '.join(f'{v:g}' for v in np.asarray(state, float))}): check its transform"
            )
        far = float(np.abs(xy).max()) * scale
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
    refused = _same_place(start, goal, who, scale) if same_place else None
    if refused:
        raise MotionPatchesError(refused)


def _same_place(start, goal, who, scale=1.0):
    """Why a goal where the start is (same place, same facing) is refused, or None (states
    as :func:`_check_far` takes them)."""
    d = float(np.hypot(*(np.asarray(goal[:2], float) - np.asarray(start[:2], float)))) * scale
    turn = abs((float(goal[2]) - float(start[2]) + np.pi) % (2 * np.pi) - np.pi)
    if d < SAME_PLACE and (np.isnan(goal[2]) or turn < SAME_FACING):
        return (
            f"the goal of {who} is where it stands ({d * 100:.0f} cm away, "
            f"facing the same way): there is nothing to plan"
        )
    return None


def _limit_text(nodes):
    return (
        f"search limit reached after {nodes:,} nodes: the search stopped before finding a "
        f"way, which does not mean the props close it; plan to a nearer goal first and on "
        f"from there"
    )


def _some_names(coll, limit=8):
    names = sorted(x.name for x in coll)
    return (", ".join(names[:limit]) + (", ..." if len(names) > limit else "")) or "none"


def own_goal(scene: bpy.types.Scene, character: bpy.types.Object) -> bpy.types.Object | None:
    """Where ``character`` walks when no goal is given: its Own Goal, else the scene's
    goal (None: neither), the one rule for Plan Path, the ``plan`` command and crowds."""
    return character_goal(character) or scene.motion_patches.goal


def character_goal(character: bpy.types.Object) -> bpy.types.Object | None:
    """``character``'s Own Goal (Planning panel), or None: :func:`_character_setting`."""
    return _character_setting(character, "goal")


def character_start_prop(character: bpy.types.Object) -> bpy.types.Object | None:
    """``character``'s Start Prop (Planning panel), or None: :func:`_character_setting`."""
    return _character_setting(character, "start_prop")


def _character_setting(character, name):
    """A setting of ``character`` (``MOTION_PATCHES_PG_character``), None where never set,
    read without changing it (a plan that fails must leave it as it was:
    :func:`compat.stored_settings`); no object gives None, refused by name where it is
    checked."""
    settings = compat.stored_settings(character, "motion_patches_character")
    return None if settings is None else getattr(settings, name)
