# SPDX-License-Identifier: GPL-3.0-or-later
"""The conflicts a crowd was written with, kept on the scene so they can be found again:
which characters still come too close (or meet a prop that moves) and on which frame.

A conflict is kept with the fingerprint of each character's plan record as written; one
whose character was planned again since (or is gone) is no longer listed."""

from __future__ import annotations

import json

import bpy

from ..adapter import storage
from .errors import MotionPatchesError

CONFLICTS_KEY = "motion_patches_crowd_conflicts"  # scene custom property: the crowd's conflicts


def _characters(c):
    return [c["a"], c["b"]] if "a" in c else [c["character"]]


def _objects(c):
    """The objects a conflict is between: the pair, or the character and the prop."""
    return [c["a"], c["b"]] if "a" in c else [c["character"], c["prop"]]


def _stored(scene):
    try:
        return list(json.loads(scene.get(CONFLICTS_KEY, "[]")))
    except (TypeError, ValueError):
        return []


def _by_name(scene):
    """{name: object} of ``scene``, read once: a lookup in ``scene.objects`` walks the
    scene (a crowd of 1,000 has as many characters and goals)."""
    return {ob.name: ob for ob in scene.objects}


def _still_true(objects, c):
    """Whether conflict ``c`` holds among ``objects`` (:func:`_by_name`): its objects are
    there and its characters' plans are the ones it was found in."""
    return all(n in objects for n in _objects(c)) and all(
        storage.plan_fingerprint(objects[n]) == c["plans"].get(n) for n in _characters(c)
    )


def remember_conflicts(scene: bpy.types.Scene, conflicts: list, moving: list) -> None:
    """Keep a crowd's ``conflicts`` (pairs) and ``moving`` (walks meeting a moving prop),
    just written, on the scene, with the ones kept before that are still true."""
    new, objects = [], _by_name(scene)
    for c in list(conflicts) + list(moving):
        c = dict(c)
        c["plans"] = {n: storage.plan_fingerprint(objects[n]) for n in _characters(c)}
        new.append(c)
    kept = [c for c in _stored(scene) if _still_true(objects, c)]
    if kept or new:
        scene[CONFLICTS_KEY] = json.dumps(kept + new)
    elif CONFLICTS_KEY in scene:
        del scene[CONFLICTS_KEY]


def has_crowd_conflicts(scene: bpy.types.Scene) -> bool:
    """Whether conflicts were kept (cheap, for a button's poll: not checked still true)."""
    return bool(scene.get(CONFLICTS_KEY))


def crowd_conflicts(scene: bpy.types.Scene) -> list[dict]:
    """The conflicts of the crowds planned on ``scene`` that are still true, by frame:
    {"a", "b", "frame", "first_frame", "frames", "distance_m"} for a pair,
    {"character", "prop", "frame", "distance_m"} for a walk meeting a moving prop."""
    objects = _by_name(scene)
    out = [c for c in _stored(scene) if _still_true(objects, c)]
    for c in out:
        del c["plans"]
    return sorted(out, key=lambda c: (c["frame"], _objects(c)))


def select_crowd_conflicts(
    scene: bpy.types.Scene, view_layer: bpy.types.ViewLayer | None = None
) -> list[dict]:
    """Select the objects of every conflict still true (the pairs' characters, and the
    moving props met) and nothing else, make the first conflict's character active, and go
    to its frame; the conflicts, by frame. :class:`MotionPatchesError` when there are none."""
    conflicts = crowd_conflicts(scene)
    if not conflicts:
        raise MotionPatchesError(
            "no crowd conflicts to select: the crowds planned here keep their spacing "
            "(or their characters were planned again since)"
        )
    view_layer = view_layer or bpy.context.view_layer
    names = {n for c in conflicts for n in _objects(c)}
    for ob in view_layer.objects:
        ob.select_set(ob.name in names)
    view_layer.objects.active = scene.objects[_characters(conflicts[0])[0]]
    scene.frame_set(int(conflicts[0]["frame"]))
    return conflicts
