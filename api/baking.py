# SPDX-License-Identifier: GPL-3.0-or-later
"""Baking a locomotion patch from mocap actions (or BVH files imported first)."""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import bpy
import numpy as np

from ..adapter import actions as act_io
from ..adapter import compat, mocap, storage, transaction
from ..motion_patches.kinematics.clip import straightest
from ..motion_patches.patch import layers, serialize
from ..motion_patches.patch.gait import MIN_TURN, build_gait
from ..motion_patches.patch.locomotion_patch import bake
from ..motion_patches.patch.timing import timing_warnings
from .common import _some_names, scene_fps
from .errors import Cancelled, MotionPatchesError, check_cancelled
from .results import BakeResult


def import_mocap(
    paths: Iterable[str | os.PathLike],
    scale: float = mocap.CMU_SCALE,
    armature: bpy.types.Object | None = None,
    name: str | None = None,
    scene: bpy.types.Scene | None = None,
) -> tuple[bpy.types.Object, list[bpy.types.Action]]:
    """Import BVH files as actions on one armature; returns (armature, [actions]). A new
    armature is named ``name``, else after the files' subject (:func:`subject_name`).
    ``scene``: the clips are for its bake: the armature becomes its source armature, and
    the clip that walks furthest in a straight line (:func:`straight_clip`) its straight
    clip."""
    paths = list(paths)
    if armature is None and not name:
        name = subject_name(paths)
    try:
        arm, acts = mocap.import_bvh(paths, scale, armature, name)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    if scene is not None:
        s = scene.motion_patches
        s.source_armature = arm
        straight = straight_clip(arm, acts)
        if straight is not None:
            s.straight_action = straight
    return arm, acts


def subject_name(paths: Iterable[str | os.PathLike]) -> str:
    """The name of an armature imported from BVH files: what their names share before an
    underscore or dash, "Subject 16" for a number (CMU's 16_15.bvh, 16_18.bvh); else the
    one file's name; else "Mocap"."""
    stems = [Path(p).stem for p in paths]
    parts = [re.split(r"[_\-]", s, maxsplit=1) for s in stems]
    heads = {p[0] for p in parts}
    if all(len(p) == 2 for p in parts) and len(heads) == 1 and (head := heads.pop()):
        return f"Subject {head}" if head.isdigit() else head
    return stems[0] if len(stems) == 1 else "Mocap"


def straight_clip(
    armature: bpy.types.Object, actions: Iterable[bpy.types.Action]
) -> bpy.types.Action | None:
    """The action among ``actions`` on ``armature`` that walks furthest in a straight line
    (:func:`motion_patches.kinematics.clip.straightest`), or None."""
    acts, clips = [], []
    for a in actions:
        try:
            clips.append(act_io.clip_from_action(a, armature, 30.0))
        except ValueError:  # no root motion: not a walk
            continue
        acts.append(a)
    i = straightest(clips)
    return None if i is None else acts[i]


def bake_locomotion_patch(
    scene: bpy.types.Scene,
    armature: bpy.types.Object | str,
    straight: bpy.types.Action | str,
    turns: Iterable[bpy.types.Action | str] = (),
    layer: str = "walk",
    name: str | None = None,
    cells: int = 8,
    nodes: int = 8,
    effort_rate: float | None = None,
    mirror_turns: bool = True,
    progress: Callable[[float], None] | None = None,
    bvh_files: Iterable[str | os.PathLike] = (),
    fps: float | None = None,
    cancelled: Callable[[], bool] | None = None,
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
    made and the frame rate are put back, and so they are when ``cancelled()`` (asked at
    each progress report) answers True: :class:`~.errors.Cancelled`. What looks wrong but is
    baked anyway (clips whose timing is not a person's:
    :func:`motion_patches.patch.timing.timing_warnings`) is in the result's ``warnings``."""
    if fps is not None and not (isinstance(fps, (int, float)) and 1 <= fps <= 1000):
        raise MotionPatchesError(f"the frame rate must be between 1 and 1000, not {fps}")
    if not str(layer).strip():
        raise MotionPatchesError("the layer (gait name) must not be empty")
    for what, v in (("cells", cells), ("nodes per edge", nodes)):
        if not (isinstance(v, int) and 2 <= v <= 8):
            raise MotionPatchesError(f"{what} must be a whole number from 2 to 8, not {v!r}")
    top = serialize.MAX_EFFORT_RATE
    if effort_rate is not None and not (
        isinstance(effort_rate, (int, float))
        and not isinstance(effort_rate, bool)
        and 0.0 <= effort_rate <= top
    ):
        raise MotionPatchesError(
            f"the effort rate (effort T per second of motion) must be a number from 0 to "
            f"{top:g}, not {effort_rate!r}"
        )
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
            cancelled,
        )
    storage.remember_bake_clips(scene, armature, straight, turns)
    storage.make_active(scene, res.name)
    assert not isinstance(armature, str)  # a name only stands for an armature to import onto
    res.armature = armature.name
    # actions by now (_bake_action found each one named); mypy keeps the parameters' types
    res.straight, res.turns = straight.name, [t.name for t in turns]  # type: ignore[union-attr]
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


def _bake_action(clip, imported) -> bpy.types.Action:
    """The action of a bake's clip given as an action or by name (an imported file's stem
    first)."""
    if not isinstance(clip, str):
        return clip
    return imported.get(clip) or bpy.data.actions[clip]


def _bake(
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
    cancelled=None,
):
    t0 = time.perf_counter()

    def step(f):  # the core's progress report: shown, then the bake may stop there
        if progress is not None:
            progress(f)
        check_cancelled(cancelled, "the bake")

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
        warnings = timing_warnings(clips[0], clips[1:])
        if effort_rate is None:
            effort_rate = layers.effort_rate(gait)
        patch = bake(gait, cells=cells, nodes=nodes, effort_rate=effort_rate, progress=step)
    except Cancelled:
        raise
    except ValueError as exc:  # SparsePatch included
        raise MotionPatchesError(str(exc)) from None
    name = name or layer
    storage.store_patch(scene, patch, name)
    return BakeResult(
        name, layer, patch.stats, time.perf_counter() - t0, list(gait.notes), warnings=warnings
    )


def _animated_bones(action):
    """Names of the bones an action's F-curves animate (``pose.bones["name"]...`` paths)."""
    out = set()
    for fc in compat.fcurves(action):
        path = fc.data_path
        if path.startswith('pose.bones["'):
            out.add(path[len('pose.bones["') : path.index('"]')])
    return out
