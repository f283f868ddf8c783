# SPDX-License-Identifier: GPL-3.0-or-later
"""Segment-level path planning across tiles (paper Sec. 4.2, Eq. 5, 7, 8).

:class:`SegmentPlanner` plans one character's path: it frames the search (the plan frame,
:mod:`.plan_frame`), runs the A* segment search (:mod:`.astar`) over the node graph of
:mod:`.segment_search`, joined to the start and goal by the connectors of
:mod:`.connectors`, with traversal clips stitched lazily (:class:`TraversalObserver`);
then shortens the path (:mod:`.shortcut`) and turns on the spot where a person would
(:mod:`.turn_in_place`). A plan's motions are made by :mod:`.motions`. The names other
code imports from here (the planner, the pieces and refusals, the motions) stay
importable from here.
"""

import contextlib
import time
from collections.abc import Iterable, Iterator

import numpy as np

from ..patch.locomotion_patch import LocomotionPatch
from ..patch.node_keys import unpack
from ..props.environment import Environment, Obstacle
from ..props.object_patch import ObjectPatch
from . import astar, shortcut
from .connectors import ConnectedGraph
from .high_level import TilePlanner
from .motions import (
    hips_to,
    interaction_states,
    piece_motion,
    plan_motions,
    turn_motion,
    with_interactions,
)
from .pieces import (
    FacingRefused,
    InsideObstacle,
    Piece,
    Plan,
    PlanError,
    SearchLimit,
    Unreachable,
)
from .plan_frame import (
    local_environment,
    local_prop,
    plan_region,
    to_local,
)
from .segment_search import TraversalObserver
from .settings import PlanSettings
from .stitching import Connection, Stitch, stitch_table
from .turn_in_place import can_turn, plan_turning

__all__ = [
    "FacingRefused",
    "Piece",
    "Plan",
    "PlanError",
    "SearchLimit",
    "SegmentPlanner",
    "TraversalObserver",
    "Unreachable",
    "hips_to",
    "interaction_states",
    "piece_motion",
    "plan_motions",
    "turn_motion",
    "with_interactions",
]

CORRIDOR_TILES = 2  # tiles either side of the high-level path the corridor holds
STITCH_PAYLOAD = -10  # payloads at or below this are stitched edges: -10 - index
_DEFAULTS = PlanSettings()  # the settings a planner is made with when not given


class SegmentPlanner(ConnectedGraph):
    """Plans one character's path on an environment with a baked locomotion patch: the
    graph and its connectors (:class:`~.connectors.ConnectedGraph`) framed, searched,
    shortened and turned on the spot."""

    def __init__(
        self,
        patch: LocomotionPatch,
        env: Environment,
        alpha: float = _DEFAULTS.alpha,
        beta: float = _DEFAULTS.beta,
        gamma: float = _DEFAULTS.gamma,
        props: Iterable[ObjectPatch] = (),
        mode: str = _DEFAULTS.stitching,
        turn_in_place: bool = _DEFAULTS.turn_in_place,
    ) -> None:
        self.turn_in_place = bool(turn_in_place)  # plan() turns on the spot where it helps
        if mode not in ("dynamic", "static"):
            raise PlanError(f"unknown stitching mode '{mode}' (dynamic or static)")
        self.mode = mode
        super().__init__(patch, env, alpha, beta, gamma, props)

    def plan(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        margin_tiles: int = 3,
        max_expansions: int = 400_000,
        use_corridor: bool = False,
        shorten: bool = True,
        turn_in_place: bool | None = None,
    ) -> Plan:
        """Cheapest path from ``start`` to ``goal`` (x, y, heading); raises PlanError.

        The search runs in the plan frame (:mod:`.plan_frame`): the lattice anchored at the
        start and turned to the goal; the obstacles and props near the way are moved into
        it, and every piece of the result carries the frame back to the world.

        With ``turn_in_place`` (None: the planner's own setting) the walk turns on the spot
        (:mod:`.turn_in_place`) where a person would: at the start when the goal lies more
        than ``LOOP_TURN`` off its facing, at the goal when the goal's heading is that far off
        the way in; and when a walk planned without still loops near an end (or cannot leave
        or arrive facing its way at all), one with a turn there is planned too and the
        cheaper by Eq. 5 kept.
        """
        t0 = time.perf_counter()
        args = (margin_tiles, max_expansions, use_corridor, shorten)
        start, goal = np.asarray(start, float), np.asarray(goal, float)
        if turn_in_place is None:
            turn_in_place = self.turn_in_place
        if not (turn_in_place and self.can_turn_in_place):
            return self._plan_once(start, goal, *args)
        made = []  # every walk searched, for the plan's time and counts

        def once(s, g):
            made.append(self._plan_once(s, g, *args))
            return made[-1]

        best = plan_turning(self, start, goal, once)
        # The plan's time is the whole call's, every search made counted.
        best.seconds = time.perf_counter() - t0
        best.stats["shortening_seconds"] = sum(p.stats["shortening_seconds"] for p in made)
        best.stats["walks_searched"] = len(made)
        return best

    @property
    def can_turn_in_place(self) -> bool:
        """The gait can turn on the spot within the patch's curvature range."""
        got = self.__dict__.get("_can_turn_in_place")
        if got is None:
            got = self._can_turn_in_place = can_turn(self.patch.gait, self.kmin, self.kmax)
        return got

    def _plan_once(self, start, goal, margin_tiles, max_expansions, use_corridor, shorten):
        t0 = time.perf_counter()
        start, goal = np.asarray(start, float), np.asarray(goal, float)
        for what, pt in (("start", start), ("goal", goal)):
            if not np.isfinite(pt[:2]).all():
                raise PlanError(f"the {what} position must be finite numbers")
            if self.world_env.blocked(pt[None, :2])[0]:
                raise InsideObstacle(what, pt, self.world_env.radius)
        with self.framed(start, goal, margin_tiles) as (ls, lg, frame):
            plan = self.plan_local(ls, lg, margin_tiles, max_expansions, use_corridor)
            searched = len(plan.pieces)
            t_short = time.perf_counter()
            if shorten:
                plan.pieces = shortcut.shorten(self, plan.pieces, ls, lg)
                plan.pieces = shortcut.pull_tail(self, plan.pieces, lg)
            plan.stats["shortening_seconds"] = time.perf_counter() - t_short
            plan.pieces = shortcut.long_last_piece(self, plan.pieces)
        plan.stats["pieces_searched"] = searched
        plan.stats["cost_shortened"] = float(sum(p.cost for p in plan.pieces))
        for piece in plan.pieces:
            piece.frame = frame
        goal_reached = np.array(goal)
        if np.isnan(goal[2]):
            goal_reached[2] = plan.goal[2] + frame[2]
        plan.start, plan.goal = tuple(start), tuple(goal_reached)
        plan.seconds = time.perf_counter() - t0
        plan.stats["frame"] = frame
        return plan

    def replan_run(
        self,
        plan: Plan,
        first: int,
        last: int,
        extra: Iterable[Obstacle] = (),
        margin_tiles: int = 3,
        max_expansions: int = 400_000,
    ) -> Plan:
        """``plan`` with its pieces ``first`` to ``last`` (inclusive, locomotion only)
        searched again with the obstacles ``extra`` (world footprints) added: from the node
        where piece ``first`` begins (the plan's start when it is the first piece) to the
        node where piece ``last`` ends (the goal when it is the last), in the plan's own
        frame, so every other piece is kept as it was and joins the new run on its node.
        Used when a prop moves into a planned path (Sec. 4.4: only the occluded segments
        are replaced). The run is shortened like a plan. Raises PlanError."""
        pieces = plan.pieces
        if not (0 <= first <= last < len(pieces)):
            raise PlanError(f"no run {first}-{last} in a plan of {len(pieces)} pieces")
        if any(p.kind not in shortcut.LOCOMOTION for p in pieces[first : last + 1]):
            raise PlanError("a run holding a traversal or interaction clip is not re-planned")
        start, goal = np.asarray(plan.start, float), np.asarray(plan.goal, float)
        t0 = time.perf_counter()
        with self.framed(start, goal, margin_tiles) as (ls, lg, frame):
            for ob in extra:
                self.env.place(Obstacle(ob.name, to_local(frame, ob.polygon)))
            begin = end = None
            if first > 0 and pieces[first].kind != "start":
                p, h = shortcut.entry_state(self, pieces[first])
                begin = self.node_key(p, h)
                ls = np.array([p[0], p[1], h])
            if last < len(pieces) - 1 and pieces[last].kind != "goal":
                p, h = shortcut.exit_state(self, pieces[last])
                end = self.node_key(p, h)
                lg = np.array([p[0], p[1], h])
            run = self.plan_local(
                ls, lg, margin_tiles, max_expansions, False, start_key=begin, goal_key=end
            )
            new = shortcut.shorten(self, run.pieces, ls, lg)
            if end is None:
                new = shortcut.pull_tail(self, new, lg)
            out = list(pieces[:first]) + new + list(pieces[last + 1 :])
            if end is None:
                out = shortcut.long_last_piece(self, out)
        for piece in out:
            piece.frame = frame
        stats = dict(
            plan.stats,
            repaired=plan.stats.get("repaired", 0) + 1,
            kept_pieces=len(pieces) - (last + 1 - first),
        )
        return Plan(
            out,
            plan.cost - sum(p.cost for p in pieces[first : last + 1]) + run.cost,
            plan.expansions + run.expansions,
            plan.seconds + time.perf_counter() - t0,
            plan.start,
            plan.goal,
            stats,
        )

    @contextlib.contextmanager
    def framed(
        self, start: np.ndarray, goal: np.ndarray, margin_tiles: int = 3
    ) -> Iterator[tuple[np.ndarray, np.ndarray, tuple[float, float, float]]]:
        """Within the block the planner's ``env``, ``props`` and ``goal`` are those of the
        plan frame of ``start`` -> ``goal``; yields (local start, local goal, frame)."""
        side = self.patch.side
        frame, ls, lg, region = plan_region(
            start, goal, side, self.patch.nodes, margin_tiles, self.world_env.side
        )
        self.env = local_environment(
            self.world_env,
            frame,
            (region[0] * side, region[1] * side),
            ((region[2] + 1) * side, (region[3] + 1) * side),
        )
        self.props = [local_prop(p, frame) for p in self.world_props]
        self.goal, self.region = lg, region
        self.frame_angle = frame[2]
        try:
            yield ls, lg, frame
        finally:
            self.env, self.props = self.world_env, self.world_props

    def plan_local(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        margin_tiles: int,
        max_expansions: int,
        use_corridor: bool,
        start_key: int | None = None,
        goal_key: int | None = None,
    ) -> Plan:
        """The search of :meth:`plan`, in plan-frame coordinates.

        With ``start_key`` (``goal_key``) the search begins (ends) on that node instead of
        a start (goal) connector: ``start`` (``goal``) is then the node's state, and the
        pieces begin (end) there (a run of a plan re-planned, :meth:`replan_run`).

        With ``use_corridor`` the segment search runs inside the corridor of the
        high-level tile path (the tiles within ``CORRIDOR_TILES`` of it) and falls back to
        the whole region when the corridor holds no path (tile probabilities are
        estimates). It is off by default: on bench_speed's 20 pillar fields the corridor
        of the path's tiles and their edge neighbours found paths up to 69 % costlier (a
        way round the other side), and with two tiles either side the same costs but
        27 % more time (the tile search costs more than the segment search it spares).
        """
        t0 = time.perf_counter()
        self.goal = goal
        ts, tg = self.env.tile_of(start[:2]), self.env.tile_of(goal[:2])
        self.region = (
            min(ts[0], tg[0]) - margin_tiles,
            min(ts[1], tg[1]) - margin_tiles,
            max(ts[0], tg[0]) + margin_tiles,
            max(ts[1], tg[1]) + margin_tiles,
        )
        for what, state, key in (("start", start, start_key), ("goal", goal, goal_key)):
            if key is None:
                self.check_turning_room(what, state)
        t_conn = time.perf_counter()
        self.reset_start_links()
        starts = self.start_connectors(start) if start_key is None else []
        if goal_key is None:
            goals = self.goal_connectors(goal)
        else:
            goals = self.goal_on_node(goal_key)

        def no_start():
            return start_key is None and not any(self.start_link(k) is not None for k, _ in starts)

        if not goals:
            if no_start():
                raise self.refused("start", start, f"no {self.way} out of the start: ")
            raise PlanError(f"no {self.way} into the goal: every node around it is too close")
        payloads = {}
        self.corridor = None
        tiles = None
        if use_corridor:
            tiles = TilePlanner(self.patch, self.env, traversal=self.tile_tau).plan(
                start[:2], goal[:2], self.region
            )
            if tiles is not None:
                w = range(-CORRIDOR_TILES, CORRIDOR_TILES + 1)
                self.corridor = {(t[0] + di, t[1] + dj) for t in tiles for di in w for dj in w}

        stitched: dict[tuple[int, int], list[tuple[int, int, float, int]]] = {}  # copy -> edges
        stitches: list[tuple[int, int, Connection, Connection, float, int, int]] = []
        counters = {"stitch_seconds": 0.0}

        def stitch_copy(pi, ci):
            """The edges of one traversal copy (stitched once per plan, kept for a retry)."""
            if (pi, ci) not in stitched:
                t_s = time.perf_counter()
                edges = []
                table = stitch_table(
                    self.patch, self.env, self.props[pi], ci, self.alpha, self.beta, self.gamma
                )
                if table is not None:
                    ins, outs, from_keys, to_keys, clip_cost = table
                    for a, from_key in zip(ins, from_keys):
                        for b, to_key in zip(outs, to_keys):
                            cost = a.cost + clip_cost + b.cost
                            edges.append((from_key, to_key, cost, STITCH_PAYLOAD - len(stitches)))
                            stitches.append((pi, ci, a, b, cost, from_key, to_key))
                stitched[(pi, ci)] = edges
                counters["stitch_seconds"] += time.perf_counter() - t_s
            return stitched[(pi, ci)]

        def goal_cost(key):
            if key not in goals:
                return None
            if goal_key is not None:  # the end node itself: nothing more to walk
                payloads[key] = None
                return 0.0, -1
            link = self.goal_link(key)
            if link is None:
                return None
            payloads[key] = link[1]
            return link[0], -1

        def start_cost(key):
            link = self.start_link(key)
            return None if link is None else (link[0], -1)

        def search():
            copies = self.traversal_estimates(start)
            observer = TraversalObserver(
                copies,
                stitch_copy,
                self.across,
                up_front=self.mode == "static",
                through=self.through(copies) if copies and self.mode == "dynamic" else None,
            )
            first = [] if start_key is None else [(int(start_key), 0.0, -1)]
            bound = (
                self.goal_bound if goal_key is None else (lambda k: 0.0 if k == goal_key else None)
            )
            result = astar.search(
                first,
                self.expand,
                self.heuristic,
                goal_cost,
                max_expansions,
                observer if copies else None,
                lazy_starts=starts,
                start_cost=start_cost,
                goal_bound=bound,
                heuristic_of=self.heuristic_of,
            )
            return result, observer

        connector_seconds = time.perf_counter() - t_conn
        t_search = time.perf_counter()
        result, observer = search()
        corridor_fallback = False
        if not result.found and self.corridor is not None:
            self.corridor, corridor_fallback = None, True
            result, observer = search()
        if not result.found and no_start():
            raise self.refused("start", start, f"no {self.way} out of the start: ")
        if (
            not result.found
            and goal_key is None
            and not any(self.goal_link(k) is not None for k in goals)
        ):
            raise self.refused("goal", goal, f"no {self.way} into the goal: ")
        if not result.found:
            raise (SearchLimit if result.expansions >= max_expansions else Unreachable)(
                "the goal is unreachable: obstacles "
                f"close every path within {margin_tiles} tiles of start and goal "
                f"({result.expansions} nodes searched)"
            )
        pieces = []
        keys = [k for k, _ in result.path]
        first = keys[0]
        if start_key is None:
            link = self.start_link(first)
            assert link is not None, "the path begins on a start connector the search took"
            pieces.append(link[1]())
        for (k, payload), prev in zip(result.path[1:], keys[:-1]):
            if k == astar.GOAL:
                if payloads[prev] is not None:
                    pieces.append(payloads[prev]())
            elif payload <= STITCH_PAYLOAD:
                pi, ci, a, b, cost, from_key, to_key = stitches[STITCH_PAYLOAD - payload]
                prop = self.props[pi]
                st = Stitch(prop.name, ci, a, b, cost, from_key, to_key)
                a, b = st.entry, st.exit
                pieces += [
                    Piece("part", segment=a.segment, tile=a.tile, frames=(0, a.frame), cost=a.cost),
                    Piece(
                        "traversal",
                        prop=prop,
                        clip_index=st.clip_index,
                        cost=st.cost - a.cost - b.cost,
                    ),
                    Piece(
                        "part",
                        segment=b.segment,
                        tile=b.tile,
                        frames=(
                            b.frame,
                            int(self.patch.seg_cycles[b.segment]) * self.patch.gait.frames,
                        ),
                        cost=b.cost,
                    ),
                ]
            else:
                i, j, _ = unpack(prev)
                pieces.append(
                    Piece(
                        "segment",
                        segment=int(payload),
                        tile=(int(i), int(j)),
                        cycles=int(self.patch.seg_cycles[payload]),
                        cost=float(self.costs[payload]),
                    )
                )
        seconds = time.perf_counter() - t0
        if np.isnan(goal[2]):  # any facing: the plan ends facing along its last connector
            last = pieces[-1].curve
            assert last is not None, "a plan to a goal of any facing ends on its goal connector"
            goal = np.array([goal[0], goal[1], last.heading[-1]])
        return Plan(
            pieces,
            float(result.cost),
            result.expansions,
            seconds,
            tuple(start),
            tuple(goal),
            {
                "start_connectors": self.start_links_valid,
                "start_nodes_tested": self.start_nodes_tested,
                "goal_connectors": len(goals),
                "goal_links_tested": self.goal_links_tested,
                "connector_seconds": connector_seconds,
                "search_seconds": time.perf_counter() - t_search,
                "occlusion_computations": self.env.occlusion_computations,
                "high_level_tiles": len(tiles) if tiles else 0,
                "corridor_fallback": corridor_fallback,
                "mode": self.mode,
                "copies_stitched": len(stitched),
                "copies_stitched_by_tile": observer.by_tile,
                "copies_stitched_at_goal": observer.at_goal,
                "copies_culled_by_bins": self.bin_culled,
                "stitch_edges": len(stitches),
                "stitch_seconds": counters["stitch_seconds"],
                "traversals_used": sum(p.kind == "traversal" for p in pieces),
            },
        )


def planner_for(
    patch: LocomotionPatch,
    env: Environment,
    settings: PlanSettings,
    props: Iterable[ObjectPatch] = (),
) -> SegmentPlanner:
    """The planner of a request's settings (weights, stitching, turns on the spot) in
    ``env`` with the object patches ``props``: one mapping for every door and the crowd."""
    return SegmentPlanner(
        patch,
        env,
        settings.alpha,
        settings.beta,
        settings.gamma,
        props=props,
        mode=settings.stitching,
        turn_in_place=settings.turn_in_place,
    )
