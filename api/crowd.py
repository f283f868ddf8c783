# SPDX-License-Identifier: GPL-3.0-or-later
"""Planning a crowd (:func:`plan_crowd`): who is in it, each one's path round the others'
standing spots, then kept apart in time by holds, waits and re-routes."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import bpy
import numpy as np

from ..adapter import moving as moving_io
from ..adapter import nla, transaction
from ..adapter import scene as scene_io
from ..motion_patches import cluster
from ..motion_patches.crowd import crowd, members
from ..motion_patches.kinematics import rig_keys, scene_rate
from ..motion_patches.planning import moving_props
from ..motion_patches.planning.settings import PlanSettings
from ..motion_patches.props.environment import Obstacle
from . import crowd_keys
from .common import (
    _check_character,
    _children_map,
    _not_obstacles,
    _patch_for_planning,
    _shrunk,
    _size,
    _skeleton,
    character_goal,
    character_start_prop,
    object_patches,
    own_goal,
    scene_fps,
)
from .crowd_conflicts import remember_conflicts
from .crowd_holds import _root_track, _with_hold
from .errors import MotionPatchesError, check_cancelled, cluster_kept
from .results import CrowdResult, CrowdSchedule
from .settings import plan_settings
from .solve import (
    _check_clear,
    _check_ends,
    _endpoints,
    _frame_start,
    _goal,
    _not_found,
    _obstacle_names,
    _without,
    _writable,
)
from .writing import WRITTEN_KEYS, _fit_frame_range, _placed, _write

CROWD_RESOLVE_SLACK = 0.02  # metres the crowd is resolved wider than its spacing (see _resolve)
CROWD_SPOT = "\x00crowd spot "  # obstacle names of other characters' standing spots
CROWD_GHOST = members.GHOST  # where another character walks when two would meet
CANCELLED = "planning the crowd"  # what Cancelled names


def cluster_executor(
    workers: int | None = None, scheduler: str | None = None
) -> cluster.InProcess | cluster.DaskCluster:
    """Where a crowd's members (or a batch's items) are planned: in this process (neither
    given), on a new Dask ``LocalCluster`` of ``workers`` processes, or on the running Dask
    scheduler at ``scheduler`` ("tcp://host:8786"). Close it (or use it as a context
    manager) when done. :class:`MotionPatchesError` when Dask is missing or the scheduler
    cannot be reached."""
    if workers is not None and (
        isinstance(workers, bool) or int(workers) != workers or workers < 1
    ):
        raise MotionPatchesError(f"workers must be a whole number of at least 1, not {workers!r}")
    try:
        return cluster.executor(workers, scheduler)
    except ImportError as exc:
        raise MotionPatchesError(
            f"a Dask cluster needs the dask and distributed packages ({exc}); "
            "pip install dask distributed into Blender's Python, or plan in process"
        ) from None
    except OSError as exc:
        raise MotionPatchesError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from None


def crowd_members(
    scene: bpy.types.Scene, characters: Iterable[bpy.types.Object] | None = None
) -> list[tuple]:
    """Who is in a crowd and where each walks: [(armature, goal object, options)] by name,
    what :func:`plan_crowd` takes (:func:`crowd_member` of each). The one rule for the
    operator, the CLI and scripts.

    ``characters``: the objects chosen (the selection, the CLI's --character); the
    armatures among them are the crowd (a selected body mesh is no character). None:
    every armature of the scene that has its own goal. Each walks to its own goal, else to
    the scene's; a character with neither, or whose goal is itself, is refused by name,
    and so is a choice with no armature in it."""
    if characters is None:
        chosen = [
            ob for ob in scene.objects if ob.type == "ARMATURE" and character_goal(ob) is not None
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
    here = set(scene.objects)  # a lookup in scene.objects walks the scene: read it once
    for ob in sorted({ob.name: ob for ob in chosen}.values(), key=lambda o: o.name):
        if ob not in here:
            raise MotionPatchesError(f"'{ob.name}' is not in the scene '{scene.name}'")
        goal = own_goal(scene, ob)
        if goal is None:
            raise MotionPatchesError(
                f"'{ob.name}' has no goal: give it its own goal or set the scene's goal"
            )
        if goal == ob:
            raise MotionPatchesError(f"the goal of '{ob.name}' is the character itself")
        pairs.append(crowd_member(ob, goal))
    return pairs


def crowd_member(character: bpy.types.Object, goal: Any) -> tuple:
    """``character``'s entry of a crowd walking to ``goal``: (character, goal, options), the
    options its own settings give (``{"start_prop": its Start Prop}`` where it has one: it
    starts seated there, as Plan Path starts it)."""
    seat = character_start_prop(character)
    return character, goal, ({"start_prop": seat} if seat is not None else {})


def plan_crowd(
    scene: bpy.types.Scene,
    pairs: list[tuple],
    patch_name: str | None = None,
    alpha: float | None = None,
    beta: float | None = None,
    gamma: float | None = None,
    radius: float | None = None,
    frame_start: int | None = None,
    context: bpy.types.Context | None = None,
    stitching: str | None = None,
    progress: Callable[[float], None] | None = None,
    max_wait_seconds: float = 4.0,
    spacing: float | None = None,
    foot_lock: bool | None = None,
    goal_facing: str | None = None,
    turn_in_place: bool | None = None,
    executor: cluster.InProcess | cluster.DaskCluster | None = None,
    cancelled: Callable[[], bool] | None = None,
) -> CrowdResult:
    """Plan several characters and write each one's NLA; ``pairs`` = [(armature, goal)] or
    [(armature, goal, options)], a goal being an object or (x, y, heading); ``options``:
    {"start_prop": a tagged prop with a stand-up clip to start seated on, "priority":
    a number, higher planned first}. A goal that is a tagged prop with a sit-down clip
    ends the walk seated on it. Characters that find no path are listed in ``failed``
    with the reason.

    Characters are taken in priority order (the given priority, then the longer distance
    from start to goal first). Each path is planned against the props and the spots where
    the others stand still: their starts and goals (:func:`motion_patches.crowd.crowd.
    standing_spots`; when they box it in, the goals of those before it and the starts of
    those after it; when those do too, none). Then each character in turn is checked
    against a space-time reservation of everyone before it and kept ``spacing`` metres
    (default: two radii) from them by an idle hold mid-walk on a double-support frame, else
    a wait at its start (whole 0.2 s steps, each at most ``max_wait_seconds``), else a
    re-route round where the other walks then (:func:`motion_patches.crowd.crowd.resolve`;
    a counter-flow through a narrow way is split into lanes). Closer approaches left are returned as
    ``conflicts`` by pair and frame, checked on the motion as written. Bad input (a
    character twice, two characters sent to one goal, goals closer than ``spacing``: one
    could never be free) raises :class:`MotionPatchesError` before anything is written.

    ``executor``: where the members' paths are planned (:func:`cluster_executor`: a Dask
    cluster, or in this process, the default); the plans are the same wherever.

    ``cancelled``: asked after each member is planned or re-planned and each character is
    written; when it answers True, :class:`~.errors.Cancelled` is raised and whatever was
    written is put back (Esc in Blender, Ctrl-C in the CLI)."""
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
    t0 = time.perf_counter()
    c = _request(
        scene, pairs, patch_name, settings, frame_start, context, max_wait_seconds, spacing
    )
    if executor is not None:
        c.executor = executor
    c.cancelled = cancelled
    _place_ends(c)
    check_cancelled(cancelled, CANCELLED)
    with cluster_kept():
        planned, failed = _plan_each(c, progress)
    pool = c.executor.pool()  # the re-plans' and the writing's, from the resolution on
    try:
        with cluster_kept():
            keys = crowd_keys.Keys(c, pool, planned)
            planned, schedules = _resolve(c, planned, pool, keys)
        written, conflicts, ranked, holds, moving_left = _settled(
            c, planned, schedules, keys, progress
        )
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    names = [c.pairs[p[0]][0].name for p in planned]
    if progress is not None:
        progress(1.0)
    for x in conflicts:
        x["a"], x["b"] = names[ranked[x["a"]]], names[ranked[x["b"]]]
        x["frame"] += c.first
        x["first_frame"] += c.first
    for p in planned:  # holds on the scene's frames (a character that holds starts at once)
        name = c.pairs[p[0]][0].name
        if name in holds:
            holds[name] = [
                {"frame": written[p[0]].frame_start + f + c.ramp // 2, "frames": int(n)}
                for f, n in holds[name]
            ]
    remember_conflicts(c.scene, conflicts, moving_left)
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


def _settled(c, planned, schedules, keys, progress):
    """The resolved crowd's holds laid in, what is left checked, and every character
    written: (written, conflicts, ranks, holds, props' conflicts)."""
    holds = _lay_holds(c, planned, schedules)
    # what is reported is checked on the motion written, whatever resolved it
    ranked = sorted(range(len(planned)), key=lambda k: schedules[k].rank)  # order kept
    conflicts = crowd.conflicts_of(
        [planned[k][3] for k in ranked],
        [schedules[k].delay for k in ranked],
        c.spacing,
    )
    moving_left = _moving_conflicts(c, planned, schedules)
    if progress is not None:
        progress(0.9)
    check_cancelled(c.cancelled, CANCELLED)
    with cluster_kept():  # what was written is put back first
        written = _write_all(c, planned, schedules, keys, progress)
    return written, conflicts, ranked, holds, moving_left


@dataclass
class _World:
    """The planner's world of the characters of one size (retargeted rigs are planned in
    the world shrunk by their size): its environment, props, planner, and the props that
    move (``tracks``; ``awake``: those moving on the first frame), as the core's
    :class:`~motion_patches.crowd.members.MemberWorld` its members are planned in."""

    members: members.MemberWorld
    by_name: dict
    awake: list

    @property
    def env(self):
        return self.members.env

    @property
    def props(self):
        return self.members.props

    @property
    def tracks(self):
        return self.members.tracks

    @property
    def planner(self):
        return self.members.planner


@dataclass
class _Crowd:
    """A crowd request, checked: its characters (``pairs``, ``options``, ``rigs``,
    ``sizes`` by entry), its settings, and what the steps of :func:`plan_crowd` find."""

    scene: object
    patch: Any
    patch_name: str | None
    settings: PlanSettings
    pairs: list
    options: list
    rigs: list
    sizes: list
    first: int  # the scene frame the crowd starts on
    spacing: float
    max_wait_seconds: float
    depsgraph: object
    fps: float
    worlds: dict = field(default_factory=dict)  # size -> _World
    ends: list = field(default_factory=list)  # _endpoints per entry, in its world
    own: list = field(default_factory=list)  # names no obstacle for each (its goal, seat)
    order: list = field(default_factory=list)  # entries in priority order
    rank_ends: list = field(default_factory=list)  # (start, goal) in the world, by rank
    rank: dict = field(default_factory=dict)  # entry -> its place in ``order``
    executor: object = field(default_factory=cluster.InProcess)  # where members are planned
    cancelled: object = None  # () -> bool: the user asked to stop (plan_crowd's argument)
    children: dict | None = None  # _children_map of the file, read once

    @property
    def ramp(self) -> int:
        return members.hold_ramp(self.fps)

    def not_obstacles(self, objects):
        """:func:`_not_obstacles` of ``objects``, the file's children read once a crowd."""
        if self.children is None:
            self.children = _children_map()
        return _not_obstacles(objects, self.children)


def _request(scene, pairs, patch_name, settings, frame_start, context, max_wait_seconds, spacing):
    """The crowd request checked (:class:`MotionPatchesError` before anything is written):
    each entry (character, goal[, options]) and the spacing."""
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
    spacing = 2 * settings.radius if spacing is None else float(spacing)
    if not (0 <= spacing < np.inf and 0 <= max_wait_seconds < np.inf):
        raise MotionPatchesError("spacing and the longest wait must be numbers >= 0")
    rigs = _checked_entries(pairs, options, patch)
    first = _frame_start(scene, frame_start)
    return _Crowd(
        scene,
        patch,
        patch_name,
        settings,
        pairs,
        options,
        rigs,
        [_size(r) for r in rigs],
        first,
        spacing,
        max_wait_seconds,
        context.evaluated_depsgraph_get(),
        scene_fps(scene),
    )


def _checked_entries(pairs, options, patch):
    """The rig map of each entry's character; :class:`MotionPatchesError` for an unknown
    option, a character twice, a goal missing or its own, a priority that is no number, or
    a goal / start seat shared by two characters."""
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
    return rigs


def _world_of(c, size):
    """The :class:`_World` of characters of ``size``, made on first use.

    Characters are not obstacles of the scene: they are kept apart in space and time, and
    where they stand still (goals of earlier ones, starts of later ones) in space. A goal
    object is no obstacle for its own character only."""
    if size not in c.worlds:
        env = scene_io.environment(
            c.scene,
            c.depsgraph,
            c.patch,
            c.settings.radius,
            c.not_obstacles([ch for ch, _ in c.pairs]),
            size,
        )
        props = object_patches(c.scene, c.depsgraph, c.patch, size)
        # props that move (keyframed): where each stands on the first frame; the ones
        # moving then are left out of the global plans and walked round after (Sec. 4.4)
        tracks = moving_io.tracks(c.scene, c.depsgraph, list(env.obstacles), c.first, size)
        for t in tracks:
            env.remove(t.name)
            env.place(Obstacle(t.name, t.polygon_at(t.pose_at(0.0)[0])))
        awake = [t.name for t in tracks if t.awake_at(0.0)]
        mw = members.MemberWorld(
            c.patch,
            env,
            props,
            c.settings,
            tracks,
            tuple(_obstacle_names(env, awake)),
            c.first,
            c.fps,
        )
        c.worlds[size] = _World(mw, {p.name: p for p in props}, awake)
    return c.worlds[size]


def _place_ends(c):
    """Each entry's start and goal (checked clear, and goals ``spacing`` apart), one
    planner per world, and the priority order: the given priority, then the longer way
    first."""
    skel = c.patch.gait.skeleton
    c.ends = []
    for (ch, g), opt, r, sz in zip(c.pairs, c.options, c.rigs, c.sizes):
        try:
            c.ends.append(
                _endpoints(
                    ch,
                    g,
                    opt.get("start_prop"),
                    _world_of(c, sz).by_name,
                    r.target if r else skel,
                    c.settings.goal_facing,
                    sz,
                )
            )
        except MotionPatchesError as exc:  # in a crowd, say whose start or goal it is
            if f"'{ch.name}'" in str(exc) or type(exc) is not MotionPatchesError:
                raise
            raise MotionPatchesError(f"'{ch.name}': {exc}") from None
    c.own = [
        [
            o.name
            for o in c.not_obstacles([g, opt.get("start_prop")])
            if isinstance(o, bpy.types.Object)
        ]
        for (_, g), opt in zip(c.pairs, c.options)
    ]
    for (ch, _), e, mine, sz in zip(c.pairs, c.ends, c.own, c.sizes):
        _check_ends(ch, e, sz)
        with _without(_world_of(c, sz).env, mine):
            _check_clear(_world_of(c, sz).env, ch, e, _world_of(c, sz).by_name)
    for w in c.worlds.values():
        w.members.planner  # made here, before any standing spot is placed
    world_ends = [
        (_shrunk(e[0], 1.0 / sz), _shrunk(e[1], 1.0 / sz)) for e, sz in zip(c.ends, c.sizes)
    ]
    goals = np.array([g[1][:2] for g in world_ends]).reshape(-1, 2)
    for lo in range(0, len(goals), 512):  # the first pair (i, then j < i) too close
        d = np.linalg.norm(goals[lo : lo + 512, None] - goals[None], axis=2)
        close = (d < c.spacing) & (
            np.arange(len(goals))[None] < np.arange(lo, lo + len(d))[:, None]
        )
        if close.any():
            i = int(np.nonzero(close.any(axis=1))[0][0])
            j = int(np.nonzero(close[i])[0][0])
            gap, i = float(d[i, j]), lo + i
            raise MotionPatchesError(
                f"the goals of '{c.pairs[j][0].name}' and '{c.pairs[i][0].name}' are "
                f"{gap:.2f} m apart, closer than the spacing ({c.spacing:.2f} m): the one "
                f"arriving second would never find its goal free; move one of them"
            )
    c.order = sorted(
        range(len(c.pairs)),
        key=lambda n: (
            -c.options[n]["priority"],
            -float(np.linalg.norm(world_ends[n][1][:2] - world_ends[n][0][:2])),
        ),
    )
    c.rank_ends = [world_ends[n] for n in c.order]
    c.rank = {n: i for i, n in enumerate(c.order)}
    names = [f"{CROWD_SPOT}{c.pairs[n][0].name}" for n in c.order]
    for w in c.worlds.values():  # where each stands still, found where each is planned
        w.members.rank_ends, w.members.spot_names = c.rank_ends, names
        w.members.spacing = c.spacing + CROWD_RESOLVE_SLACK  # kept as the crowd is resolved


def _task(c, n, ghosts=()):
    """Entry n as the core plans it: its ends, what is no obstacle for it, where the others
    stand still while it walks (:func:`motion_patches.crowd.crowd.standing_spots`) and,
    when re-routing, ``ghosts`` (world polygons) in its world."""
    size = c.sizes[n]
    own = _obstacle_names(_world_of(c, size).env, c.own[n])
    return members.MemberTask(
        n, c.ends[n], tuple(own), c.rank[n], [p / size for p in ghosts], c.rigs[n], size
    )


def _entry(c, member):
    """[n, plan, piece motions (:func:`members.packed`), root track, holdable frames] of a
    member: the root track (:func:`_root_track` of its placed motion) is all the crowd's
    resolution reads; the motion is placed on the character again when written
    (:func:`_write_all`), so a crowd of 1,000 does not hold every member's placed motion
    (~0.8 MB each) until then."""
    m = member
    raw = members.unpacked(m.raw)
    track = _root_track(_placed(c.scene, c.patch, c.rigs[m.entry], raw, m.plan))
    return [m.entry, m.plan, m.raw, track, m.holdable]


def _plan_each(c, progress):
    """(planned: [[n, plan, raw, root track, holdable]] in priority order, failed: [(name,
    why)]): each entry planned round the others' standing spots, on ``c.executor``."""
    tasks = [_task(c, n) for n in c.order]
    answers = {}

    def step(f):  # after each member (each part, on a cluster): progress, then may stop
        if progress is not None:
            progress(0.8 * f)
        check_cancelled(c.cancelled, CANCELLED)

    for size in dict.fromkeys(c.sizes[n] for n in c.order):
        mine = [t for t in tasks if c.sizes[t.entry] == size]
        world = _world_of(c, size).members
        done = c.executor.map(
            members.plan_member,
            mine,
            world=world,
            progress=None if progress is None and c.cancelled is None else step,
        )
        answers.update((t.entry, a) for t, a in zip(mine, done))
    planned, failed = [], []
    for n in c.order:
        a = answers[n]
        if isinstance(a, members.NoPlan):
            failed.append((c.pairs[n][0].name, str(_not_found(c.pairs[n][0].name, a))))
        else:
            planned.append(_entry(c, a))
    return planned, failed


def _replan(c, versions, k, ghosts):
    """Planned character k re-planned round ``ghosts``: its new track and holdable frames
    (the next version of its plan, kept in ``versions[k]``), or None."""
    check_cancelled(c.cancelled, CANCELLED)
    n = versions[k][0][0]
    a = members.plan_member(_task(c, n, ghosts), _world_of(c, c.sizes[n]).members)
    return _replanned(c, versions, k, a)


def _replanned(c, versions, k, a):
    """:func:`_replan`'s answer from member ``a``, its new version kept."""
    if isinstance(a, members.NoPlan):
        return None
    versions[k].append(_entry(c, a))
    return versions[k][-1][3], versions[k][-1][4]


class _Replanning:
    """A re-plan worked out on a worker (:func:`_replan_later`); ``result()`` is
    :func:`_replan`'s answer, taken when the crowd's resolution comes to it."""

    def __init__(self, c, versions, k, answer):
        self.c, self.versions, self.k, self.answer = c, versions, k, answer

    def result(self):
        return _replanned(self.c, self.versions, self.k, self.answer.result())


def _replan_later(c, pool, sent, versions, k, ghosts):
    """:func:`_replan` asked of ``pool``'s workers at once, its answer taken later. Every
    size's member world is sent to them with the first re-plan (kept in ``sent``): a crowd
    nobody is re-routed in sends none."""
    check_cancelled(c.cancelled, CANCELLED)
    if not sent:
        sent["worlds"] = pool.share(worlds={size: w.members for size, w in c.worlds.items()})
    task = _task(c, versions[k][0][0], ghosts)
    # before any keys asked early (:func:`_resolve`): the resolution may be waiting for it
    answer = pool.submit(members.plan_sized, task, shared=sent["worlds"], priority=1)
    return _Replanning(c, versions, k, answer)


def _resolve(c, planned, pool, keys):
    """(the version of each planned character the crowd settled on, its schedules):
    :func:`motion_patches.crowd.crowd.resolve` with every re-plan kept. On a cluster
    (``pool``, ``c.executor``'s) the re-plans are worked out on its workers while the
    resolution places the characters that keep clear of them (in process each is worked
    out when its answer is taken, in the same order: the crowd comes out the same), and the
    keys of each character placed as it was planned are asked of them then (``keys``,
    :meth:`~.crowd_keys.Keys.early`), behind the re-plans."""
    versions = [[p] for p in planned]  # every re-plan kept: the crowd may settle on any
    later = settled = None
    if c.executor.workers:
        later = partial(_replan_later, c, pool, {}, versions)

        def settled(i, s):  # placed as it was planned: its keys asked for now
            if s.version == 0 and not s.holds:
                keys.early(i, planned[i][1], planned[i][2])

    # Resolved a little wider than reported: a hold is laid into the written motion by a
    # time warp, which may bring a pair nearer than the track the table saw (on the plaza
    # of 1,000: by 0.2 mm at most; the slack is a hundred times that).
    schedules, _ = crowd.resolve(
        [p[3] for p in planned],
        partial(_replan, c, versions),
        c.spacing + CROWD_RESOLVE_SLACK,
        c.settings.radius,
        c.fps,
        round(c.max_wait_seconds * c.fps),
        max(1, round(0.2 * c.fps)),
        ramp=c.ramp,
        holdable=[p[4] for p in planned],
        replan_later=later,
        settled=settled,
    )
    return [v[s.version] for v, s in zip(versions, schedules)], schedules


def _held(c, p, holds):
    """(plan, piece motions, root track, [(frame from its start, frames held)]) of the
    planned character ``p`` ([n, plan, piece motions, root track, holdable]) with its
    schedule's ``holds`` put in the pieces they fall in, each as its own strip; ``p`` is
    left as it is."""
    plan, raw, at = p[1], members.unpacked(p[2]), []
    rate = c.fps / c.patch.gait.fps  # scene frames per patch frame
    for k, h in holds:
        bounds = scene_rate.piece_bounds([m.frames for m in raw], rate)[1]
        plan, raw = _with_hold(plan, raw, bounds, k, h, c.ramp, rate)
        at = [(f + h + c.ramp if f > k else f, n) for f, n in at] + [(k, h)]
    track = _root_track(_placed(c.scene, c.patch, c.rigs[p[0]], raw, plan))
    return plan, raw, track, sorted(at)


def _lay_holds(c, planned, schedules):
    """Each schedule's holds laid in (:func:`_held`, ``planned`` updated); {name: [(frame
    from its start, frames held)]}."""
    holds = {}
    for p, s in zip(planned, schedules):
        if s.holds:
            p[1], p[2], p[3], holds[c.pairs[p[0]][0].name] = _held(c, p, s.holds)
    return holds


def _moving_conflicts(c, planned, schedules):
    """The props that move, against each walk as scheduled (its wait and holds included):
    [{"character", "prop", "frame", "distance_m"}]."""
    out = []
    for p, s in zip(planned, schedules):
        w = _world_of(c, c.sizes[p[0]])
        if not w.tracks:
            continue
        wait = s.delay / c.fps
        for x in moving_props.conflicts(
            members.unpacked(p[2]), w.tracks, w.planner.world_env.radius, c.patch.gait.fps, wait
        ):
            out.append(
                {
                    "character": c.pairs[p[0]][0].name,
                    "prop": x.prop,
                    "frame": c.first + s.delay + int(round(x.frame * c.fps / c.patch.gait.fps)),
                    "distance_m": float(x.distance),
                }
            )
    return out


def _write_all(c, planned, schedules, keys, progress=None):
    """{entry: PlanResult} of every planned character written (all refused before the
    first is written when one cannot be), the frame range fitted once after; cancelled
    between two characters, those written are put back.

    What a write computes before it touches Blender (the foot lock, the body and root
    actions' keys) comes from ``keys`` (:class:`~.crowd_keys.Keys`: asked of
    ``c.executor``'s workers early, or ahead of the character written; in process, in a
    thread, one at a time). Blender's data is only touched here, in order."""
    written = {}
    for (n, _, _, track, _), s in zip(planned, schedules):
        _writable(c.pairs[n][0], c.first + s.delay, len(track))
    with transaction.kept(
        bpy,
        c.scene,
        [c.pairs[n][0] for n, *_ in planned],
        WRITTEN_KEYS,
    ):
        segments = nla.segment_index(bpy)  # the shared segment actions, found once
        reads: dict = {}  # their curves, read once for every character's foot lock
        keys.writing(planned)
        for k, ((n, plan, raw, *_), s) in enumerate(zip(planned, schedules)):
            check_cancelled(c.cancelled, CANCELLED)
            packed = keys.take(k)
            skel = _skeleton(c.rigs[n], c.patch)
            placed = _placed(c.scene, c.patch, c.rigs[n], members.unpacked(raw), plan)
            prepared = rig_keys.unpack(packed, skel, placed[2])
            env = _world_of(c, c.sizes[n]).env
            with _without(env, c.own[n]):  # the plan record lists what it walked around
                written[n] = _write(
                    c.scene,
                    c.pairs[n][0],
                    c.patch,
                    c.patch_name,
                    plan,
                    placed,
                    c.first + s.delay,
                    env,
                    c.settings,
                    c.rigs[n],
                    fit=False,
                    segments=segments,
                    prepared=prepared,
                    reads=reads,
                )
            # written: its motions are let go, not held to the end beside the actions
            # Blender makes of them
            planned[k][2] = placed = prepared = packed = None
            if progress is not None:
                progress(0.9 + 0.1 * (k + 1) / len(planned))
        if written:
            _fit_frame_range(c.scene)  # once: it reads every character's plan record
    return written
