# SPDX-License-Identifier: GPL-3.0-or-later
"""A crowd made from one armature: linked copies scattered over a region, each with a goal."""

from __future__ import annotations

from collections.abc import Sequence

import bpy
import numpy as np

from ..adapter import copies, nla
from ..adapter import scene as scene_io
from .bodies import add_bodies, has_body, remove_bodies
from .common import _check_character, _not_obstacles, _patch_for_planning, _skeleton
from .errors import MotionPatchesError

CROWD_COLLECTION = "MP Crowd"


MAX_COPIES = 10_000  # copies one Duplicate Crowd makes (each an object and a goal)


def duplicate_crowd(
    scene: bpy.types.Scene,
    source: bpy.types.Object,
    count: int,
    region: Sequence[Sequence[float]],
    goal_region: Sequence[Sequence[float]],
    seed: int = 0,
    radius: float = 0.25,
    spacing: float | None = None,
    patch_name: str | None = None,
    context: bpy.types.Context | None = None,
) -> list[tuple]:
    """[(character, goal empty)]: ``count`` copies of the armature ``source`` sharing its
    armature data (linked, as Alt+D makes them), scattered over ``region`` ((x0, y0), (x1,
    y1)) and each sent to a goal empty scattered over ``goal_region``, facing the way it
    walks; all in a new collection. A source with a proxy body (:func:`.bodies.add_bodies`)
    gives its copies bodies too, of the same meshes, each in its own colour. Starts and
    goals keep ``spacing`` (default: two radii) plus a radius from one another and stay
    clear of the props. Everything is checked and every spot drawn before anything is
    made: a source the patch cannot play, or regions too small to hold the crowd, raise
    :class:`MotionPatchesError` with the scene unchanged."""
    context = context or bpy.context
    patch = _patch_for_planning(scene, patch_name)
    if source is None or source.type != "ARMATURE":
        raise MotionPatchesError("choose the source armature to duplicate")
    rig = _check_character(source, patch)
    try:
        count = int(count)
        corners = np.asarray(region, float).reshape(2, 2)
        goal_corners = np.asarray(goal_region, float).reshape(2, 2)
    except (TypeError, ValueError):
        raise MotionPatchesError(
            "a crowd needs a count and two regions ((x0, y0), (x1, y1))"
        ) from None
    if count < 1:
        raise MotionPatchesError("a crowd needs at least one character")
    if count > MAX_COPIES:
        raise MotionPatchesError(
            f"a crowd of {count:,} copies is more than Duplicate Crowd makes at once "
            f"({MAX_COPIES:,}): duplicate it in parts"
        )
    spacing = 2 * radius if spacing is None else float(spacing)
    for what, r in (("region", corners), ("goal region", goal_corners)):
        if not np.isfinite(r).all():
            raise MotionPatchesError(f"the {what}'s corners must be numbers, not {r.tolist()}")
        if (r[1] <= r[0]).any():
            raise MotionPatchesError(
                f"the {what} must have its second corner above and right of its first"
            )
        # Discs of diameter `spacing + radius` packed as tightly as discs go (hexagonal):
        # a region smaller than that cannot hold the crowd, however long it is tried.
        holds = np.prod(r[1] - r[0] + spacing + radius) / (0.866 * (spacing + radius) ** 2)
        if holds < count:
            raise MotionPatchesError(
                f"the {what} ({(r[1] - r[0])[0]:g} x {(r[1] - r[0])[1]:g} m) cannot hold "
                f"{count:,} characters {spacing + radius:.2f} m apart (at most about "
                f"{int(holds):,}): make it larger or the crowd smaller"
            )
    context.view_layer.update()
    depsgraph = context.evaluated_depsgraph_get()
    env = scene_io.environment(scene, depsgraph, patch, radius, _not_obstacles([source]), 1.0)
    rng = np.random.default_rng(seed)
    gap = spacing + radius

    def scatter(r, what):
        pts, n = np.empty((count, 2)), 0
        for _ in range(200 * count):
            p = rng.uniform(r[0], r[1])
            if env.near(p) or (n and np.linalg.norm(pts[:n] - p, axis=1).min() < gap):
                continue
            pts[n], n = p, n + 1
            if n == count:
                return pts
        raise MotionPatchesError(
            f"the {what} holds only {n} of {count} characters {gap:.2f} m apart and "
            f"clear of the props: make it larger or the crowd smaller"
        )

    starts, goals = scatter(corners, "region"), scatter(goal_corners, "goal region")
    rng.shuffle(goals)
    skel = _skeleton(rig, patch)
    facing = nla.facing_angle(skel)
    pairs = copies.make_copies(scene, source, starts, goals, facing, CROWD_COLLECTION)
    if has_body(source):
        add_bodies([ob for ob, _ in pairs])
    context.view_layer.update()
    return pairs


def remove_crowd(pairs: list[tuple]) -> None:
    """Remove what :func:`duplicate_crowd` made (the copies, their goals, their collection
    when it is left empty, the actions planning made for them, their bodies); the source
    is untouched."""
    remove_bodies([ob for ob, _ in pairs])
    copies.remove_copies(pairs, CROWD_COLLECTION)
