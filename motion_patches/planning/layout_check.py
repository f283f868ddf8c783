# SPDX-License-Identifier: GPL-3.0-or-later
"""The planning of a layout check's pairs: from the patch and the footprints alone.

A layout check (``api.check_layout``) resolves its spec in Blender, then each pair is a
pure task: plan from a start to a goal in one :class:`World` (the obstacles, the radius,
the weights, the props that offer traversals) and report what a level designer reads. A
batch of checks can then plan on Dask workers (:mod:`..cluster`) and get what it would here.

A world's planner (its environment's lazy tile bitfields and rasters, the graph's tables) is
kept in the process under the world's key, a digest of everything it is built from: a check
of an unchanged scene, and every pair of one check in the same world, reuse it. So are the
figures of the pairs planned in it: planning is deterministic, so a pair asked again in an
unchanged world is answered without planning (``reused`` True, its figures those of the
plan that was made, ``plan_seconds`` included).

Never imports bpy.
"""

import hashlib
from collections import OrderedDict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ..kinematics.motion import concatenate
from ..patch.locomotion_patch import LocomotionPatch
from ..props.blocking import blocking_props
from ..props.environment import Environment, Obstacle
from ..props.object_patch import ObjectPatch
from . import causes
from .motions import plan_motions
from .pieces import InsideObstacle, PlanError
from .planner import SegmentPlanner

KEPT = 8  # planners kept in a process (one per world: a check's excludes and sizes)


@dataclass(frozen=True)
class World:
    """What a pair plans in. ``key`` (:func:`world`) names it: equal keys, equal planners."""

    key: str
    obstacles: tuple[Obstacle, ...]
    radius: float
    alpha: float
    beta: float
    gamma: float
    turn_in_place: bool
    props: tuple[ObjectPatch, ...] = ()


def world(
    obstacles: Iterable[Obstacle],
    radius: float,
    alpha: float,
    beta: float,
    gamma: float,
    turn_in_place: bool,
    props: Sequence[ObjectPatch] = (),
) -> World:
    """A :class:`World` with its key: a digest of the obstacles' names and footprints, the
    radius and weights, and the props (each one's name, pose, footprint and clips: names,
    kinds, efforts, layers, angles and every frame of their motion)."""
    obstacles = tuple(obstacles)
    h = hashlib.blake2b(digest_size=20)
    for ob in obstacles:
        h.update(ob.name.encode() + b"\0")
        h.update(np.ascontiguousarray(ob.polygon, float).tobytes())
    h.update(np.array([radius, alpha, beta, gamma, float(turn_in_place)], float).tobytes())
    for pr in props:
        h.update(f"prop {pr.name}\0".encode())
        h.update(np.array([*pr.pose], float).tobytes())
        h.update(np.ascontiguousarray(pr.footprint, float).tobytes())
        for c in pr.clips:
            h.update(f"{c.name}\0{c.kind}\0{c.layer_in}\0{c.layer_out}\0".encode())
            h.update(np.array([c.effort, c.angle], float).tobytes())
            m = c.motion
            for a in (m.ground, m.root_local, m.rotations, m.contacts):
                h.update(np.ascontiguousarray(a).tobytes())
    return World(
        h.hexdigest(),
        obstacles,
        float(radius),
        float(alpha),
        float(beta),
        float(gamma),
        bool(turn_in_place),
        tuple(props),
    )


_kept: OrderedDict = OrderedDict()  # (id(patch), world key) -> (patch, env, planner, figures)


def planner_in(patch: LocomotionPatch, w: World) -> tuple[Environment, SegmentPlanner, dict]:
    """(environment, planner, figures of the pairs planned so far) of ``w`` for ``patch``:
    kept from an earlier call when one was made for the same patch and world; PlanError
    when no planner can be made."""
    k = (id(patch), w.key)
    hit = _kept.get(k)
    if hit is not None and hit[0] is patch:  # the patch itself: an id is reused once freed
        _kept.move_to_end(k)
        return hit[1], hit[2], hit[3]
    env = Environment(patch.side, patch.cells, w.radius)
    for ob in w.obstacles:
        env.place(ob)
    planner = SegmentPlanner(
        patch, env, w.alpha, w.beta, w.gamma, props=list(w.props), turn_in_place=w.turn_in_place
    )
    _kept[k] = (patch, env, planner, {})
    while len(_kept) > KEPT:
        _kept.popitem(last=False)
    return env, planner, _kept[k][3]


def forget(planners: bool = True) -> None:
    """Drop every kept planner (tests; a process that wants its memory back); with
    ``planners`` False only the figures kept in them, so pairs asked again are planned
    again by warm planners (a benchmark's plan of an unchanged scene)."""
    if planners:
        _kept.clear()
    for hit in _kept.values():
        hit[3].clear()


def plan_pair(task: dict, patch: LocomotionPatch, worlds: dict[str, World]) -> dict:
    """Plan one pair: ``task`` holds "world" (a key of ``worlds``), "start" and "goal"
    (x, y, heading in the world the planner sees; a NaN heading: any facing) and "margin"
    (tiles), and "scale" (the character's size: the planner's world is the scene's divided
    by it; 1 when absent). Returns the figures of the pair: "reachable"; when reached "seconds",
    "length_m" (in the planner's world), "cost", "pieces", "traversals", "expansions",
    "plan_seconds" and "goal" (the state reached); when not, "error", "blocked" (obstacle
    names) and "blocked_reason" ("search limit" when the search stopped at its limit);
    "reused" when the pair was answered from an earlier plan in the same world.
    "planner_error" instead of all these when no planner could be made."""
    try:
        env, planner, figures = planner_in(patch, worlds[task["world"]])
    except PlanError as exc:
        return {"planner_error": str(exc)}
    start = np.asarray(task["start"], float)
    goal = np.asarray(task["goal"], float)
    margin = int(task["margin"])
    key = np.concatenate((start, goal, [margin, task.get("scale", 1.0)])).tobytes()
    if key in figures:
        return dict(figures[key], reused=True)
    out = _planned(patch, env, planner, start, goal, margin, float(task.get("scale", 1.0)))
    figures[key] = out
    return dict(out)


def _planned(patch, env, planner, start, goal, margin, scale=1.0):
    out: dict = {
        "reachable": False,
        "blocked": [],
        "blocked_reason": None,
        "error": None,
        "reused": False,
    }
    try:
        with causes.counted(planner) as expanded:
            plan = planner.plan(start, goal, margin_tiles=margin)
    except PlanError as exc:
        if expanded[0] >= causes.SEARCH_LIMIT:
            out["error"], out["blocked_reason"] = None, "search limit"
            out["expanded"] = int(expanded[0])
        else:
            # said in the scene's coordinates (``scale``: the character's size)
            out["error"] = exc.text(scale) if isinstance(exc, InsideObstacle) else str(exc)
            out["blocked"], out["blocked_reason"] = blocking_props(env, start, goal, margin)
        return out
    motion = concatenate(plan_motions(patch, plan, poses=False))
    ground = motion.ground[:, :2]
    out.update(
        reachable=True,
        seconds=(motion.frames - 1) / patch.gait.fps,
        length_m=float(np.linalg.norm(np.diff(ground, axis=0), axis=1).sum()),
        cost=float(plan.cost),
        pieces=len(plan.pieces),
        expansions=int(plan.expansions),
        plan_seconds=float(plan.seconds),
        traversals=sum(pc.kind == "traversal" for pc in plan.pieces),
        goal=[float(v) for v in plan.goal],
    )
    return out
