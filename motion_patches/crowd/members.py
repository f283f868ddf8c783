# SPDX-License-Identifier: GPL-3.0-or-later
"""A crowd member's own work: its path planned round the props and the spots where the others
stand still, its motion synthesised and put on its rig at the scene's rate, and the frames on
which it may hold.

This work does not depend on the other members' plans, only on their ends, so the members of
a crowd can be planned anywhere, in any order (:mod:`motion_patches.cluster`): a task is a
:class:`MemberTask` and the world it plans in a :class:`MemberWorld`, both plain data that
pickle; the answer is a :class:`Member` or a :class:`NoPlan` (exceptions of the planner are
turned into data, so nothing has to be raised across a process boundary).
"""

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..kinematics import loop_strips, rig_keys
from ..kinematics.inplace import root_positions
from ..kinematics.motion import Motion
from ..kinematics.retarget import RigMap
from ..kinematics.scene_rate import placed
from ..planning import body_clearance, causes, moving_props, plan_frame
from ..planning.pieces import Plan, PlanError
from ..planning.planner import SegmentPlanner, plan_motions, planner_for, with_interactions
from ..planning.settings import PlanSettings
from ..props.environment import Environment, Obstacle
from .crowd import SPOT_MARGIN, standing_spots

HOLD_RAMP_SECONDS = 0.5  # slowing to an idle hold and walking on again, each
CLIPS = ("traversal", "interaction")
GHOST = "\x00crowd ghost "  # obstacle names of where another member walks when two would meet


def hold_ramp(fps: float) -> int:
    """Scene frames of a hold's slow-down and speed-up together (even, at least 2)."""
    return max(2, int(round(HOLD_RAMP_SECONDS * fps)) // 2 * 2)


@dataclass
class MemberWorld:
    """What the members of one character size share: the patch, the props as the planner sees
    them (``env``, the object patches ``props``), the settings, the props that move
    (``tracks``; ``awake``: obstacle names of those moving on the first frame), the scene's
    first frame and rate, and every member's (start, goal) in priority order (``rank_ends``,
    in the world of size 1) with the names its standing spots take (``spot_names``) and the
    ``spacing`` they keep. Its planner is made where it is first used, once per process."""

    patch: Any
    env: Environment
    props: list
    settings: PlanSettings
    tracks: list = field(default_factory=list)
    awake: tuple = ()
    first: int = 1
    scene_fps: float = 30.0
    rank_ends: Sequence = ()
    spot_names: Sequence = ()
    spacing: float = 0.0
    _planner: SegmentPlanner | None = field(default=None, repr=False, compare=False)
    _rank_xy: tuple | None = field(default=None, repr=False, compare=False)
    _spots: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def planner(self) -> SegmentPlanner:
        if self._planner is None:
            self._planner = planner_for(self.patch, self.env, self.settings, self.props)
        return self._planner

    @property
    def rank_xy(self) -> np.ndarray:
        """(members, start / goal, 2) of ``rank_ends``: made once, not per member (a crowd of
        10,000 spent a third of a member's plan rebuilding it)."""
        if self._rank_xy is None or self._rank_xy[0] is not self.rank_ends:
            xy = np.array([[s[:2], g[:2]] for s, g in self.rank_ends], float).reshape(-1, 2, 2)
            self._rank_xy = (self.rank_ends, xy)
        return self._rank_xy[1]

    def spot_obstacles(self) -> dict:
        """{(spot index, size): obstacle} of the standing spots made so far: a spot is the
        same obstacle for every member of a size (a crowd of 10,000 made each member's
        few hundred anew). Dropped when the ranks, names, spacing or radius change."""
        key = (self.rank_ends, self.spot_names, self.spacing, self.settings.radius)
        got = self._spots
        if (
            got is None
            or any(a is not b for a, b in zip(got[0][:2], key[:2]))
            or (got[0][2:] != key[2:])
        ):
            got = self._spots = (key, {})
        return got[1]

    @property
    def ramp(self) -> int:
        """Frames of a hold's slow-down and speed-up together (even)."""
        return hold_ramp(self.scene_fps)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_planner"] = state["_rank_xy"] = state["_spots"] = None  # made where used
        return state


@dataclass
class MemberTask:
    """One member to plan: ``ends`` = (start, goal, start clip, goal clip) in its world (of
    ``size``: the world is shrunk by a rig's size); ``own``: obstacle names that are no
    obstacle for it (its goal, its seat); ``rank``: its place in the world's ``rank_ends``,
    whose others' standing spots it walks round (None: none); ``ghosts``: polygons of where
    others walk when it meets them (re-routing); ``rig``: its rig map or None. The spots are
    found where it is planned (:func:`spots_of`): a few numbers travel, not a polygon for
    everyone else in the crowd."""

    entry: int
    ends: tuple
    own: tuple = ()
    rank: int | None = None
    ghosts: Sequence = ()
    rig: RigMap | None = None
    size: float = 1.0


@dataclass
class NoPlan:
    """Why a member has no plan: ``kind`` "limit" (the search's node limit), "cause" (no
    path, ``cause`` and ``props`` say why), "plan" (a refusal of the planner, ``text``) or
    "moving" (props keyframed across every way; ``text`` describes each, ``props`` names
    them)."""

    entry: int
    kind: str
    text: str
    cause: str | None = None
    props: list = field(default_factory=list)


@dataclass
class Member:
    """A member planned: its plan, the plan's piece motions at the patch's rate (``raw``),
    the scene frames where the pieces start and the last ends (``bounds``), its root's ground
    track on the scene's frames and the scene frames it may hold on. The motion on its rig
    at the scene's rate is :func:`placed` again from ``raw`` where it is written: cheap to
    redo, and half of what would travel back from a worker."""

    entry: int
    plan: Plan
    raw: list
    bounds: np.ndarray
    root_track: np.ndarray
    holdable: np.ndarray


def no_plan_of(entry: int, exc: PlanError) -> NoPlan:
    """A refusal of the planner (:class:`causes.NoPath` or any :class:`PlanError`) as data."""
    if isinstance(exc, causes.NoPath):
        kind = "limit" if exc.cause == "search limit" else "cause"
        return NoPlan(entry, kind, str(exc), exc.cause, list(exc.props))
    return NoPlan(entry, "plan", str(exc))


def planned_path(planner: SegmentPlanner, ends: tuple, explain: bool = True) -> Plan:
    """The plan from ``ends[0]`` to ``ends[1]`` with the clips that start and end it;
    ``explain``: on failure find its cause (:func:`causes.plan_explained`)."""
    start, goal, start_ref, goal_ref = ends
    if explain:
        plan = causes.plan_explained(planner, start, goal)
    else:
        plan = planner.plan(start, goal)
    return with_interactions(plan, start_ref, goal_ref)


def around_moving(
    planner: SegmentPlanner,
    patch: Any,
    plan: Plan,
    tracks: list,
    frame_start: int,
    fps: float,
    longest_wait: float = moving_props.MAX_DELAY_S,
) -> tuple[Plan, float, list]:
    """(plan, seconds to wait at the start, conflicts left) clear of the props that move
    during it (:func:`moving_props.avoid`); the plan's stats say what was done. ``fps``:
    the scene's rate, ``frame_start`` its first frame (for the frames the stats name)."""
    ratio = fps / patch.gait.fps
    plan, wait, repairs, left = moving_props.avoid(
        planner, patch, plan, tracks, lambda p: plan_motions(patch, p), longest_wait=longest_wait
    )
    if not left:
        plan.stats["moving_props"] = {
            "props": [t.name for t in tracks],
            "awake_at_start": [t.name for t in tracks if t.awake_at(0.0)],
            "wait_s": wait,
            "repairs": [
                dict(r, frame=frame_start + int(round(r["frame"] * ratio))) for r in repairs
            ],
        }
    return plan, wait, left


def moving_text(left: list, patch: Any, frame_start: int, fps: float) -> str:
    """What a walk that cannot keep clear of moving props meets: each prop and frame."""
    return "; ".join(c.describe(patch.gait.fps, frame_start, fps) for c in left)


def holdable(plan: Plan, bounds: np.ndarray, world: Motion, ramp: int) -> np.ndarray:
    """Bool per scene frame: frames a member may hold on, double support (a planted joint on
    each foot) inside a walking piece with room for the slow-down and speed-up in it."""
    c = world.contacts
    ok = c[:, :2].any(axis=1) & c[:, 2:].any(axis=1)
    inside = np.zeros_like(ok)
    half = ramp // 2
    for i, p in enumerate(plan.pieces):
        if p.kind not in CLIPS:
            inside[bounds[i] + half : bounds[i + 1] - half + 1] = True
    return ok & inside


def root_track(world: Motion) -> np.ndarray:
    """(frames, 2) ground position of the root joint: what a crowd keeps apart (the hips
    sway a few centimetres about the ground track)."""
    return root_positions(world.ground, world.root_local)[:, :2]


@contextlib.contextmanager
def without(env: Environment, names: Sequence[str]) -> Iterator[Environment]:
    """``env`` with the obstacles ``names`` taken out for the block (put back after)."""
    # by name (reading every obstacle cost a member 0.6 ms among 5,000 props)
    saved = [env.obstacles[n] for n in dict.fromkeys(names) if n in env.obstacles]
    for ob in saved:
        env.remove(ob.name)
    try:
        yield env
    finally:
        for ob in saved:
            env.place(ob)


def synthesised(task: MemberTask, world: MemberWorld, plan: Plan) -> Member:
    """The member's motion for ``plan``: synthesised, on its rig, at the scene's rate."""
    raw = plan_motions(world.patch, plan)
    _, bounds, whole = placed(
        world.patch, task.rig, raw, world.scene_fps, rig_keys.own_pieces(plan)
    )
    hold = holdable(plan, bounds, whole, world.ramp)  # holds are timed on the scene's frames
    return Member(task.entry, plan, packed(raw), bounds, root_track(whole), hold)


def packed(motions: list) -> list:
    """Piece motions kept with single-precision rotations (the precision Blender keys them
    in): a member's motions travel back from a worker and wait with every other member's
    until the crowd is written, and rotations are nearly all of them (10,000 members: about
    3.7 GB in double precision). :func:`unpacked` gives them back in double precision."""
    return [
        Motion(m.ground, m.root_local, np.asarray(m.rotations, np.float32), m.contacts)
        for m in motions
    ]


def unpacked(motions: list) -> list:
    """:func:`packed` motions in double precision again, as the rest of the core takes them."""
    return [
        Motion(m.ground, m.root_local, np.asarray(m.rotations, float), m.contacts) for m in motions
    ]


def prepared_keys(jobs: Sequence[tuple], fps: float, patch: Any) -> list[tuple]:
    """What writing members computes before it touches Blender
    (:func:`~..kinematics.rig_keys.prepare_packed`), from each one's (:func:`packed` piece
    motions, rig map or None, :func:`~..kinematics.rig_keys.prepare`'s arguments with the
    placed motion, the second, left None) in ``jobs``: each motion placed on its rig at
    the scene's rate ``fps`` here, so a worker is sent a quarter of the bytes."""
    out, loops = [], {}
    for raw, rig, args in jobs:
        sig = None if rig is None else rig.signature()
        if sig not in loops:  # the same for every character of one rig
            loops[sig] = loop_strips.straight_loop(patch.gait, rig)
        own = rig_keys.own_pieces(args[4])
        where = placed(patch, rig, unpacked(raw), fps, own, loops[sig])
        out.append(rig_keys.prepare_packed(args[0], where, *args[2:], loop=loops[sig]))
    return out


def spots_of(task: MemberTask, world: MemberWorld, every: bool = True) -> list[Obstacle]:
    """Where the others stand still (:func:`~.crowd.standing_spots` of its rank: with
    ``every``, every other's start and goal, else those it walks by if the crowd walks in
    priority order), as obstacles in its world."""
    if task.rank is None or not world.rank_ends:
        return []
    radius = world.settings.radius
    box = plan_box(task.ends[0], task.ends[1], world.planner)
    if box is not None:
        box = (box[0] * task.size, box[1] * task.size)  # in the world of size 1
    # the hips' sway about the path (a path round another's start grown by 1 cm still
    # passed 0.499 m from it, where 0.5 was asked, among 10,000): the crowd keeps hips apart
    gait = world.patch.gait
    margin = SPOT_MARGIN + body_clearance.sway(gait, [gait.straight]) * task.size
    found = standing_spots(world.rank_xy, task.rank, world.spacing, radius, box, every, margin)
    made, out = world.spot_obstacles(), []
    for k, poly in found:
        ob = made.get((k, task.size))
        if ob is None:
            name = f"{world.spot_names[k // 2]} {('start', 'goal')[k % 2]}"
            ob = made[(k, task.size)] = Obstacle(name, poly / task.size)
        out.append(ob)
    return out


def plan_box(
    start: np.ndarray, goal: np.ndarray, planner: SegmentPlanner
) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi): a world box holding every footprint a plan of ``start`` -> ``goal`` can
    meet: the box its search region's obstacles are looked up in (:meth:`SegmentPlanner.
    framed`, the planner's margin), a tile wider. None when the ends coincide (the plan
    frame then turns with the start's heading)."""
    if np.hypot(*(np.asarray(goal[:2], float) - np.asarray(start[:2], float))) <= 1e-6:
        return None
    side, env = planner.patch.side, planner.world_env
    frame, _, _, region = plan_frame.plan_region(
        np.asarray(start, float),
        np.asarray(goal, float),
        side,
        planner.patch.nodes,
        causes.MARGIN_TILES,
        env.side,
    )
    lo, hi = (region[0] * side, region[1] * side), ((region[2] + 1) * side, (region[3] + 1) * side)
    return plan_frame.region_box(frame, lo, hi, env.radius + env.side)


def plan_member(task: MemberTask, world: MemberWorld) -> Member | NoPlan:
    """Plan one member round the standing spots and, when re-routing, round its ghosts (no
    plan when they box it in); then round the props that move by re-routing (the crowd
    times the waits); then its motion."""
    env, planner = world.env, world.planner
    radius = world.settings.radius
    mine = np.array([task.ends[0][:2], task.ends[1][:2]], float)
    extra = [Obstacle(f"{GHOST}{k}", np.asarray(p, float)) for k, p in enumerate(task.ghosts)]
    extra = [g for g in extra if not g.within(mine, radius).any()]  # not on its own ends
    try:
        with without(env, task.own):
            for ob in extra:  # where others walk when it would meet them
                env.place(ob)
            try:
                with without(env, world.awake):
                    plan = round_spots(task, world, bool(extra))
                if world.tracks:
                    plan, _, left = around_moving(
                        planner,
                        world.patch,
                        plan,
                        world.tracks,
                        world.first,
                        world.scene_fps,
                        longest_wait=0.0,
                    )
                    if left:
                        text = moving_text(left, world.patch, world.first, world.scene_fps)
                        return NoPlan(task.entry, "moving", text, "moving", [x.prop for x in left])
            finally:
                for ob in extra:
                    env.remove(ob.name)
    except PlanError as exc:
        return no_plan_of(task.entry, exc)
    return synthesised(task, world, plan)


def round_spots(task: MemberTask, world: MemberWorld, ghosts: bool) -> Plan:
    """The member's plan round where the others stand still (:func:`spots_of`): round every
    other's start and goal; boxed in by them, round those it walks by if the crowd walks in
    priority order; boxed in again, past them all, but not when re-routing round ``ghosts``
    (it raises then: no way round where the others walk)."""
    env, planner = world.env, world.planner

    def planned(spots):
        for ob in spots:
            env.place(ob)
        try:
            return planned_path(planner, task.ends, explain=not (spots or ghosts))
        finally:
            for ob in spots:
                env.remove(ob.name)

    def tries():
        """The spots of each try in turn: the fewer ones are only looked up when the plan
        round every spot fails (it rarely does)."""
        every = spots_of(task, world, every=True)
        yield every
        if every:
            fewer = spots_of(task, world, every=False)
            last = every
            if len(fewer) < len(every):
                yield fewer
                last = fewer
            if last and not ghosts:
                yield []

    refused = None
    for spots in tries():
        try:
            return planned(spots)
        except PlanError as exc:
            refused = exc
    assert refused is not None, "the first try is always made"
    raise refused


def plan_sized(task: MemberTask, worlds: dict) -> Member | NoPlan:
    """:func:`plan_member` in the world of the task's size (``worlds``: {size: world}, sent
    to a worker once for every re-plan of a crowd)."""
    return plan_member(task, worlds[task.size])


def plan_members(tasks: Sequence[MemberTask], world: MemberWorld) -> list:
    """:func:`plan_member` of each task, in order."""
    return [plan_member(t, world) for t in tasks]
