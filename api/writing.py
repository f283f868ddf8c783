# SPDX-License-Identifier: GPL-3.0-or-later
"""Writing a plan: its motion placed on the character at the scene's rate, the NLA strips,
the plan record and the scene's frame range."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import bpy
import numpy as np

from ..adapter import actions as act_io
from ..adapter import nla, storage
from ..motion_patches.kinematics import contacts, loop_strips, rig_keys, scene_rate
from ..motion_patches.kinematics.inplace import root_positions
from ..motion_patches.planning import transitions
from ..motion_patches.planning.settings import PlanSettings
from .common import _shrunk, _size, _skeleton, path_length, scene_fps
from .results import PlanResult
from .solve import _start_matrix


def _placed(scene, patch, rig, motions, plan):
    """A plan's piece motions (:func:`plan_motions`) put on the character: (its pieces'
    motions on its skeleton, at the patch's rate; the scene frames where the pieces start
    and the last ends, from 0; the whole motion on the scene's frames, as its strips play
    it: :func:`~motion_patches.kinematics.scene_rate.placed`). ``rig``: the character's
    :class:`~motion_patches.kinematics.retarget.RigMap` (None: the patch skeleton)."""
    own = rig_keys.own_pieces(plan)
    return scene_rate.placed(patch, rig, motions, scene_fps(scene), own)


FRAME_RANGE_KEY = "motion_patches_frame_range"  # the scene frame range last set by a plan
# the custom properties writing a plan may change (a character's, the scene's), put back
# with its animation when a write fails or is cancelled (adapter.transaction.kept)
WRITTEN_KEYS = (storage.PLAN_KEY, storage.PLAN_ID_KEY, storage.ANALYSIS_KEY, FRAME_RANGE_KEY)
BLENDER_DEFAULT_RANGE = (1, 250)  # a new scene's: not a range anyone chose


def fitted_frame_range(
    current: Sequence[int], plans: Iterable[Sequence[int]], ours: Sequence[int] | None = None
) -> tuple[int, int]:
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


def _prepared_args(character, skel, placed, settings: PlanSettings, fps, plan) -> tuple:
    """The arguments of :func:`~motion_patches.kinematics.rig_keys.prepare` for one
    character (what writing its plan computes before it touches Blender): Blender's data
    it needs (rotation modes, scale, height, tilt) and the storage tolerance, read here,
    so the rest can run anywhere (a crowd fits its characters' keys on its workers)."""
    units, root_units = nla.write_units(character, skel), nla.root_units(character)
    return (skel, placed, bool(settings.foot_lock), fps, plan, units, root_units, act_io.COMPACT)


def _walked_round(env, ground, scale, margin):
    """{name: footprint in the scene's metres} of the props of ``env`` (the planner's world,
    ``scale`` times smaller) whose bounds come within ``margin`` of the bounds of the path
    ``ground`` (F, 2+): those the plan walked round, which the overlay draws (with the
    lattice round the path) and the analysis checks the root against. Listing every prop
    of a large scene in every character's record would grow a crowd's file with the crowd
    times the props."""
    if not env.obstacles:
        return {}
    xy = np.asarray(ground, float)[:, :2]
    # looked up by tile, not prop by prop: a crowd in a plaza of 360 props spent 5 ms a
    # character here
    near = set(
        env.names_in_box((xy.min(axis=0) - margin) / scale, (xy.max(axis=0) + margin) / scale)
    )
    return {n: (ob.polygon * scale).tolist() for n, ob in env.obstacles.items() if n in near}


def _write(
    scene,
    character,
    patch,
    patch_name,
    plan,
    placed,
    frame_start,
    env,
    settings: PlanSettings,
    rig=None,
    fit=True,
    layer_keys=None,
    from_here=False,
    segments=None,
    prepared=None,
    reads=None,
):
    """NLA strips and the plan record of one planned character (``placed``: its motion,
    :func:`_placed`; ``env``: the planner's world, shrunk by the character's size; ``settings``: the
    request's, whose radius and foot lock it records and applies).
    ``fit``: fit the scene's frame range now (a crowd fits it once, after every write).
    ``layer_keys``: {layer: patch key} of a plan that changes layer (:func:`_gait_change`).
    ``from_here``: the plan started where the character is now, not where it stood.
    ``segments``: the file's shared segment actions (:func:`nla.segment_index`) when several
    characters are written in a row (a crowd): found once, not once per character.
    ``prepared``: :func:`~motion_patches.kinematics.rig_keys.prepare` of this character
    and plan, made already. ``reads``: what the foot lock has read of the shared actions
    so far, kept for the next characters of a crowd (:func:`nla.write_plan`)."""
    stood = _start_matrix(character, from_here)  # read before the record is replaced
    scale = _size(rig)
    goal_state = _shrunk(plan.goal, 1.0 / scale)  # the facing reached when any would do
    skel = _skeleton(rig, patch)
    motions, bounds, _ = placed
    if prepared is None:
        prepared = rig_keys.prepare(
            *_prepared_args(character, skel, placed, settings, scene_fps(scene), plan),
            loop=loop_strips.straight_loop(patch.gait, rig),
        )
    world, locked, body, root = prepared
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
        segments,
        body,
        root,
        reads,
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
            "stood": stood.tolist(),
            "boundaries": [s["start"] for s in strips[1:]],
            # every strip's start but the first (a piece's loop stretches start strips too):
            # where the analysis looks for a pop
            "joins": sorted(p for s in strips for p in s["parts"])[1:],
            "radius": settings.radius,
            "facing": nla.facing_angle(skel),
            "foot_lock": bool(settings.foot_lock),
            "traversals": [[s["start"], s["end"]] for s in strips if s["kind"] == "traversal"],
            "interactions": [[s["start"], s["end"]] for s in strips if s["kind"] == "interaction"],
            "layers": [
                [s["start"], s["end"], transitions.piece_layer(p, patch.layer)]
                for s, p in zip(strips, plan.pieces)
            ],
            # the overlay's lattice reaches two tiles past the path's bounds, turned
            "obstacles": _walked_round(
                env, world.ground, scale, settings.radius + 3.0 * patch.side * scale
            ),
        },
    )
    storage.forget_analysis(character)  # the Analysis panel must not show the last plan's
    if fit:
        _fit_frame_range(scene)
    result = PlanResult(
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
    return result
