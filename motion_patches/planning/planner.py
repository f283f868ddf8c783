# SPDX-License-Identifier: GPL-3.0-or-later
"""Segment-level path planning across tiles (paper Sec. 4.2, Eq. 5, 7, 8).

Nodes are tile entry states packed into one integer: tile (i, j) and the local entry id
(edge, slot, heading) of the locomotion patch. Expanding a node looks up the segments of
that entry state, drops those whose cell mask is occluded in the tile (Eq. 8), and maps
each exit to the entry state of the neighbouring tile. The character's start and goal are
joined to the node graph by Dubins connectors (:mod:`.dubins`), known to the search by a
lower bound of their cost and sampled and tested only when it gets to them (the start
ones played from the phase that makes them end on the node pose, the goal ones ending
on the exact goal position and heading). Traversal clips of object patches join the
graph as stitched edges, lazily, through an observer of the search that bounds each copy
by the nodes it takes off in the copy's tile (:class:`TraversalObserver`).
"""

import contextlib
import heapq
import time

import numpy as np

from ..kinematics import retime
from ..kinematics.motion import Motion, ease_to, sliced
from ..patch import curves
from ..patch.locomotion_patch import (
    DIRECTIONS,
    EDGES,
    INWARD,
    node_id,
    node_position,
    split_node_id,
)
from ..patch.node_keys import BIAS, LOCAL, NEXT_EDGE, TILE_STEP, pack, unpack
from ..patch.synthesis import cycles_along, cycles_along_many, follow
from ..props.environment import PATH_MARGIN, SUB, Obstacle
from . import astar, dubins, shortcut, turn_in_place
from .high_level import TilePlanner
from .pieces import (
    FacingRefused,
    Piece,
    Plan,
    PlanError,
    SearchLimit,
    Unreachable,
)
from .plan_frame import (
    IDENTITY,
    lattice_frame,
    local_environment,
    local_prop,
    state_to_local,
    to_local,
)
from .settings import PLANNING as DEFAULTS
from .stitching import BLEND_FRAMES, POSITION_TOLERANCE, Stitch, part_speed, stitch_table
from .traversal_probability import accessibility, tile_traversal

ANY_FACING = np.radians(np.arange(0, 360, 45))  # goal headings tried when any facing will do
HEADING_SLACK = 0.02  # radians, for sampling error in precomputed turn sums
DUBINS_CURVATURE_SHARE = 0.8  # connectors turn at this share of the gait's sharpest turn
MAX_CONNECTOR_TILES = 2.0  # longest start / goal connector, in tile sides
MIN_CONNECTOR_CYCLES = 0.5  # shortest start connector (room to ease in from standing)
KAPPA_ROUNDING = 1e-9  # relative slack on the curvature limits (floating point only)
START_CONNECTORS = 48  # valid start connectors offered to the search (best f first)
APPROACH = 0.35  # metres of the way into the goal (out of the start) checked first
DUBINS_TRIES = 3  # Dubins words of a node sampled and tested together
START_BATCH = 24  # start nodes whose connectors are tested together
GOAL_BATCH = 8  # goal links tested together
COARSE = 4  # every COARSE-th sample of a connector is tested first (most blocked ones stop)
CORRIDOR_TILES = 2  # tiles either side of the high-level path the corridor holds
LOOP_TURN = np.radians(90.0)  # a walk turning more than this near its start (goal) may loop
LOOP_REACH = 2.0  # gait cycles of way from either end where such a loop is looked for
MIN_TURN_IN_PLACE = np.radians(20.0)  # a start this close to facing the goal walks off


STITCH_PAYLOAD = -10  # payloads at or below this are stitched edges: -10 - index
_NONE = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64))  # no successors


class SegmentPlanner:
    """Plans one character's path on an environment with a baked locomotion patch."""

    def __init__(
        self,
        patch,
        env,
        alpha=DEFAULTS["alpha"],
        beta=DEFAULTS["beta"],
        gamma=DEFAULTS["gamma"],
        props=(),
        mode=DEFAULTS["stitching"],
        turn_in_place=DEFAULTS["turn_in_place"],
    ):
        self.turn_in_place = bool(turn_in_place)  # plan() turns on the spot where it helps
        if mode not in ("dynamic", "static"):
            raise PlanError(f"unknown stitching mode '{mode}' (dynamic or static)")
        self.props, self.mode = list(props), mode
        self.world_props = self.props
        if patch.nodes * DIRECTIONS * EDGES > LOCAL:
            raise PlanError("the patch has more nodes per edge than the planner packs (8)")
        self.patch, self.env = patch, env
        self.world_env = env
        self.alpha, self.beta, self.gamma = float(alpha), float(beta), float(gamma)
        self.costs = patch.costs(alpha, beta, gamma)
        self.order, self.first = patch.by_entry()
        e1, k1, h1 = split_node_id(patch.seg_exit, patch.nodes)
        self.step = TILE_STEP[e1]
        self.next_local = node_id(NEXT_EDGE[e1], k1, h1, patch.nodes)
        e, k, h = split_node_id(np.arange(LOCAL), patch.nodes)
        self.local_pos = node_position(e % EDGES, k, patch.side, patch.nodes)
        self.local_heading = h * np.pi / 4
        loops = patch.gait.loops
        self.max_speed = max(lp.cycle_distance for lp in loops) * patch.gait.fps / patch.gait.frames
        self.kmin, self.kmax = patch.stats.get("curvature_limits", patch.gait.kappa_limits)
        self.corridor = None
        e, _, _ = split_node_id(np.arange(LOCAL), patch.nodes)
        step = TILE_STEP[e % EDGES]
        # Tile ids are node keys // LOCAL; a node on edge e of its tile also lies in the
        # tile across that edge, whose id differs by this much.
        self.across = (step[:, 0] * (2 * BIAS) + step[:, 1]).tolist()
        # Per local entry state: its segments, their cell masks, costs, and the key of the
        # node each leads to relative to the key of the entry's tile (keys are linear in
        # the tile coordinates), so an expansion is a few array operations.
        rel = ((self.step[:, 0] * (2 * BIAS) + self.step[:, 1]) * LOCAL + self.next_local).astype(
            np.int64
        )
        self._out = [None] * LOCAL
        for local in range(LOCAL):
            segs = self.order[self.first[local] : self.first[local + 1]]
            if segs.size:
                self._out[local] = (segs, patch.seg_mask[segs], rel[segs], self.costs[segs])
        self._cos, self._sin = np.cos(self.local_heading), np.sin(self.local_heading)
        self._entry_ids = {}  # edges of a tile -> local ids of their entry states
        self._all_local = np.arange(LOCAL, dtype=np.int64)
        self._h_tiles = {}  # tile id -> heuristic of its LOCAL keys (:meth:`heuristic_of`)
        self._lx, self._ly = self.local_pos[:, 0].copy(), self.local_pos[:, 1].copy()

    # -- graph -------------------------------------------------------------------------
    def node_pose(self, keys):
        i, j, local = unpack(np.asarray(keys, np.int64))
        p = self.local_pos[local] + np.stack((i, j), -1) * self.patch.side
        return p, self.local_heading[local]

    def heuristic(self, keys):
        """Eq. 7 plus an effort bound: alpha |G| + beta angle-to-goal + gamma T_min."""
        keys = np.asarray(keys, np.int64)
        local = keys % LOCAL
        tile = keys // LOCAL
        # Goal relative to each node: goal - tile corner - node's place in the tile.
        gx, gy = self.goal[0] + BIAS * self.patch.side, self.goal[1] + BIAS * self.patch.side
        dx = (gx - self._lx[local]) - (tile // (2 * BIAS)) * self.patch.side
        dy = (gy - self._ly[local]) - (tile % (2 * BIAS)) * self.patch.side
        dist = np.sqrt(dx * dx + dy * dy)
        return self._per_metre * dist + self.beta * self._turn_to_goal(
            dx, dy, dist, self._cos[local], self._sin[local], self._goal_turn()[local]
        )

    def _turn_to_goal(self, dx, dy, dist, cos_h, sin_h, to_heading, gap=0.0):
        """A lower bound of the radians a walk turns from states of heading (cos_h,
        sin_h) at (-dx, -dy) from the goal into the goal: the headings a walk takes span
        (when they span less than half a turn) its start heading, its end heading and the
        direction of its chord, so it turns at least the largest angle between two of
        them: start heading to chord, start heading to goal heading (``to_heading``, the
        angle already), chord to goal heading (none of the last two when any facing will
        do). Less ``HEADING_SLACK`` each, for sampled headings; no chord term where the
        state is on the goal. With ``gap`` the walk may start up to that far from the
        state (a stitch's position gap): the chord's direction is then known only within
        the angle the gap subtends, which the chord terms lose (all of them nearer than
        twice the gap)."""
        on = dist > max(1e-6, 2.0 * gap)
        inv = np.where(on, 1.0 / np.maximum(dist, 1e-9), 0.0)
        ux, uy = dx * inv, dy * inv
        slack = HEADING_SLACK + (np.arcsin(np.minimum(gap * inv, 1.0)) if gap > 0 else 0.0)
        ang = np.arccos(np.clip(ux * cos_h + uy * sin_h, -1.0, 1.0)) - slack
        hg = float(self.goal[2])
        if np.isfinite(hg):
            arrive = np.arccos(np.clip(ux * np.cos(hg) + uy * np.sin(hg), -1.0, 1.0))
            ang = np.maximum(ang, arrive - slack)
        return np.maximum(np.where(on, ang, 0.0), to_heading)

    def heuristic_of(self, key):
        """:meth:`heuristic` of one key, looked up in a table of its tile's entry states
        (each tile's table computed once per search, all 256 at once)."""
        t = key // LOCAL
        row = self._h_tiles.get(t)
        if row is None:
            row = self._h_tiles[t] = self.heuristic(t * LOCAL + self._all_local).tolist()
        return row[key - t * LOCAL]

    def _goal_turn(self):
        """(LOCAL,) a lower bound of the radians a walk from each local entry state turns
        to end facing the goal heading (zeros when any facing will do): a path turns at
        least both to face the goal and to end with its heading, so the heuristic's turn
        term is the larger of the two (still admissible)."""
        hg = float(self.goal[2])
        got = self.__dict__.get("_goal_turn_table")
        if got is None or not (got[0] == hg or (np.isnan(hg) and np.isnan(got[0]))):
            if np.isnan(hg):
                table = np.zeros(LOCAL)
            else:
                table = _turn_bound(self.local_heading, hg)
            got = self._goal_turn_table = (hg, table)
        return got[1]

    def state_heuristic(self, p, h, gap=0.0):
        """:meth:`heuristic` of states: positions (n, 2), headings (n,); ``gap``: the walk
        on may start that far from the state (see :meth:`_turn_to_goal`)."""
        d = self.goal[:2] - p
        dist = np.linalg.norm(d, axis=-1)
        h = np.asarray(h, float)
        to = _turn_bound(h, self.goal[2]) if np.isfinite(self.goal[2]) else np.zeros_like(h)
        turn = self._turn_to_goal(d[:, 0], d[:, 1], dist, np.cos(h), np.sin(h), to, gap)
        return self._per_metre * dist + self.beta * turn

    @property
    def _per_metre(self):
        """Heuristic cost per metre to the goal: alpha, and gamma x the effort of walking
        that metre at the gait's fastest (the effort bound)."""
        return self.alpha + self.gamma * self.patch.effort_rate / self.max_speed

    def expand(self, key):
        local = key % LOCAL
        out = self._out[local]
        if out is None:
            return _NONE
        t = key // LOCAL
        tile = (t // (2 * BIAS) - BIAS, t % (2 * BIAS) - BIAS)
        if not self.in_region(*tile):
            return _NONE
        segs, mask, rel, costs = out
        free, solid = self.env.cell_states(tile)
        clear = (mask & free) == mask  # Eq. 8
        if not clear.all():
            # Cells only partly occluded: the segment's own path decides (a gap the
            # character fits through stays open however the cells fall on it), first by
            # the sub-cells its samples lie in, then, where those are partly occluded too,
            # sample by sample.
            unsure = np.flatnonzero(~clear & ((mask & solid) == 0))
            if unsure.size:
                sub = self._sub_masks()[segs[unsure]]
                sfree, ssolid = self.env.sub_states(tile, self.env.radius + PATH_MARGIN)
                ok = ((sub & sfree) == sub).all(axis=1)
                test = ~ok & ((sub & ssolid) == 0).all(axis=1)
                clear[unsure[ok]] = True
                if test.any():
                    clear[unsure[test]] = self._path_clear(tile, segs[unsure[test]])
            return (key - local) + rel[clear], costs[clear], segs[clear]
        return (key - local) + rel, costs, segs

    def _sub_masks(self):
        """(S, W) sub-cell bitmasks of the segments' sampled paths."""
        env = self.env
        return _patch_cache(
            self.patch, ("sub", env.cells, SUB), lambda: env.sub_mask(self.patch.path_points())
        )

    def _path_clear(self, tile, segs):
        """(n,) True where the paths of segments walked in ``tile`` keep the radius from
        every footprint: each sample of their curves tested through the tile's clearance
        raster, exactly where the raster cannot tell (``Environment.tile_paths_blocked``)."""
        pts = self.patch.path_points()[segs] + np.array(tile, float) * self.patch.side
        index, ox, oy = self._path_raster()
        return ~self.env.tile_paths_blocked(tile, pts, index[segs], ox[segs], oy[segs])

    def _path_raster(self):
        """(S, PATH_SAMPLES) raster index of every segment sample within its tile, and its
        offset x, y from that raster cell's centre (S, PATH_SAMPLES each)."""
        g, h = self.env.fine, self.env.fine_size

        def make():
            pts = self.patch.path_points()
            f = np.clip(np.floor(pts / h), 0, g - 1)
            off = pts - (f + 0.5) * h
            f = f.astype(np.int32)
            return f[..., 1] * g + f[..., 0], off[..., 0].copy(), off[..., 1].copy()

        return _patch_cache(self.patch, ("raster", g, h), make)

    def in_region(self, i, j):
        if self.corridor is not None:
            return (int(i), int(j)) in self.corridor
        r = self.region
        return r[0] <= i <= r[2] and r[1] <= j <= r[3]

    # -- connectors ----------------------------------------------------------------------
    def _entries(self, tiles_edges):
        """Keys, positions and headings of the entry states on given (tile, edges)."""
        n = self.patch.nodes
        keys = []
        for tile, edges in tiles_edges:
            edges = tuple(edges)
            local = self._entry_ids.get(edges)
            if local is None:
                e, k, dd = np.meshgrid(edges, np.arange(n), (-1, 0, 1), indexing="ij")
                e, k, dd = e.ravel(), k.ravel(), dd.ravel()
                local = self._entry_ids[edges] = node_id(e, k, (INWARD[e] + dd) % DIRECTIONS, n)
            keys.append(pack(tile[0], tile[1], 0) + local)
        keys = np.concatenate(keys)
        p, h = self.node_pose(keys)
        return keys, p, h

    def _block(self, tile):
        every = list(range(EDGES))
        return [((tile[0] + di, tile[1] + dj), every) for di in (-1, 0, 1) for dj in (-1, 0, 1)]

    def _curve_cost(self, curve, cycles_count):
        frames = cycles_count * self.patch.gait.frames
        effort = self.patch.effort_rate * frames / self.patch.gait.fps
        return self.alpha * curve.length + self.beta * curve.total_turn() + self.gamma * effort

    def _bends_within(self, curve):
        """The curve bends within the gait's curvature limits, between samples too."""
        # A curve turning at exactly the sharpest limit (a Dubins arc of that radius) reads
        # a hair over it in floating point: allow for rounding, not for more.
        tol = KAPPA_ROUNDING * max(-self.kmin, self.kmax)
        if curve.kappa.min() < self.kmin - tol or curve.kappa.max() > self.kmax + tol:
            return False
        return bool(
            curves.follows_turn_limits(curve.pos, curves.unit(curve.heading), self.kmin, self.kmax)
        )

    def _valid(self, curve):
        """The curve bends within the gait's limits and keeps the radius from every
        footprint (every sample tested)."""
        return self._bends_within(curve) and not self.env.path_blocked(curve.pos[None])[0]

    def _long_last_piece(self, pieces):
        """The pieces with a goal connector shorter than a gait cycle merged with the
        walking pieces before it into one goal piece (one curve followed the same way), so
        the stop (:mod:`.retime`) has a cycle to slow down over."""
        out = list(pieces)
        need = self.patch.gait.cycle_distance
        while (
            len(out) > 1
            and out[-1].kind == "goal"
            and out[-1].curve.length < need
            and out[-2].kind in ("segment", "shortcut", "start")
        ):
            before = out[-2]
            c = before.curve if before.curve is not None else self._segment_curve(before)
            merged = curves.joined(c, out[-1].curve)
            out[-2:] = [Piece("goal", curve=merged, cost=before.cost + out[-1].cost)]
        return out

    def _segment_curve(self, piece):
        """A segment piece's curve in plan-frame coordinates."""
        c = self.patch.curve(piece.segment)
        return curves.Curve(
            c.s, c.pos + np.array(piece.tile, float) * self.patch.side, c.heading, c.kappa
        )

    def _cycles(self, curve):
        """Gait cycles (fractional) that following ``curve`` takes."""
        return float(cycles_along(self.patch.gait, curve.pos[None], *_derivs(curve))[0])

    def _measure(self, pos, vel, acc):
        return cycles_along(self.patch.gait, pos, vel, acc)

    def start_connectors(self, start):
        """[(key, bound)]: the entry nodes of the 3 x 3 tiles around the start a start
        connector may join, in the order the search takes them (bound + heuristic), each
        with a lower bound of its connector's Eq. 5 cost (its cheapest Dubins word's,
        :meth:`_dubins_table`). The connectors themselves (:meth:`start_link`) are sampled
        and tested only when the search gets to them."""
        keys, p, h = self._entries(self._block(self.env.tile_of(start[:2])))
        table = self._dubins_table(
            np.tile(start[:2], (keys.size, 1)), np.full(keys.size, start[2]), p, h
        )
        bound = table[0].min(axis=0)
        f = bound + self.heuristic(keys)
        ranked = np.argsort(f, kind="stable")
        ranked = ranked[np.isfinite(f[ranked])]
        self._start_table = {
            "start": start,
            "table": table,
            "keys": keys,
            "ranked": ranked,
            "rank": dict(zip(keys[ranked].tolist(), range(ranked.size))),
            "done": 0,
            "valid": 0,
            "links": {},
            "shortest": MIN_CONNECTOR_CYCLES * self.patch.gait.cycle_distance,
        }
        return list(zip(keys[ranked].tolist(), bound[ranked].tolist()))

    def start_link(self, key):
        """(cost, Piece maker) of the start connector joining node ``key``: the Dubins path
        from the start, its cheapest valid word, the motion along it starting at the gait
        phase that makes it end on the node pose; None when no word is valid or the node
        is not among the first ``START_CONNECTORS`` valid ones in the search's order (the
        rest would rarely be taken). Nodes are tested in that order, ``START_BATCH`` at a
        time, and cached."""
        t = self._start_table
        r = t["rank"].get(key)
        if r is None:
            return None
        start, keys = t["start"], t["keys"]
        shortest = t["shortest"]
        while t["done"] <= r:
            if t["valid"] >= START_CONNECTORS:
                return None
            batch = t["ranked"][t["done"] : t["done"] + START_BATCH]
            n = batch.size
            found = self._first_valids(
                np.tile(start[:2], (n, 1)),
                np.full(n, start[2]),
                t["table"],
                batch,
                shortest,
                limit=START_CONNECTORS - t["valid"],
            )
            for m, got in zip(batch.tolist(), found):
                link = None
                if got is not None:
                    cost, cycles, make = got
                    link = (
                        cost,
                        lambda make=make, cost=cost, cycles=cycles: Piece(
                            "start", curve=make(), cycles=cycles, cost=cost
                        ),
                    )
                    t["valid"] += 1
                t["links"][int(keys[m])] = link
            t["done"] += n
        return t["links"].get(key)

    def goal_connectors(self, goal):
        """Goal links of the entry nodes of the 3 x 3 tiles around the goal: for each node
        the Dubins words into the goal, cheapest first (over ``ANY_FACING`` goal headings
        when the goal heading is NaN). Nothing is computed here: the words of a tile's
        nodes are tabled when the search first asks for the bound of one of them
        (:meth:`goal_bound`; a short plan asks for a few of the nine tiles), and only the
        links of the nodes it expands are sampled and tested (:meth:`goal_link`)."""
        keys, p, h = self._entries(self._block(self.env.tile_of(goal[:2])))
        headings = ANY_FACING if np.isnan(goal[2]) else np.array([goal[2]])
        n, rows = keys.size, len(self.turn_radii) * len(dubins.WORDS) * headings.size
        too_close = np.linalg.norm(p - goal[:2], axis=1) < 0.2 * self.patch.gait.cycle_distance
        self._goal_table = {
            "index": dict(zip(keys[~too_close].tolist(), np.flatnonzero(~too_close).tolist())),
            "p": p,
            "h": h,
            "goal": np.array(goal[:2], float),
            "headings": headings,
            "per_tile": n // 9,
            "tiled": np.zeros(9, bool),
            # Filled tile by tile (_goal_tiles); columns of tiles not tabled yet unused.
            "table": [
                np.full((rows, n), np.inf),
                np.zeros((rows, n, 3)),
                None,
                None,
                np.zeros((rows, n), np.int64),
            ],
            "bound": np.full(n, np.inf),
        }
        self._goal_links = {}
        self._goal_asked = []  # nodes whose bound the search asked for (it expanded them)
        return self._goal_table["index"]

    def _goal_tiles(self, columns):
        """Table the Dubins words into the goal of every node of the tiles holding nodes
        ``columns`` (indices into the goal block's nodes) not tabled yet: per node its words
        at every radius and goal heading (rows heading by heading, wider turns first
        throughout), their order and its bound."""
        t = self._goal_table
        per = t["per_tile"]
        for b in np.unique(np.asarray(columns) // per).tolist():
            if t["tiled"][b]:
                continue
            t["tiled"][b] = True
            cols = slice(b * per, (b + 1) * per)
            p, h, headings = t["p"][cols], t["h"][cols], t["headings"]
            n, nh = per, headings.size
            cost, lens, radii, words, _ = self._dubins_table(
                np.tile(p, (nh, 1)),
                np.tile(h, nh),
                np.tile(t["goal"], (nh * n, 1)),
                np.repeat(headings, n),
            )
            rows = cost.shape[0]
            cost = cost.reshape(rows, nh, n).transpose(1, 0, 2).reshape(nh * rows, n)
            lens = lens.reshape(rows, nh, n, 3).transpose(1, 0, 2, 3).reshape(nh * rows, n, 3)
            radii, words = np.tile(radii, nh), np.tile(words, nh)
            rank = np.where(np.isfinite(cost), cost + 1e6 * (radii < radii.max())[:, None], np.inf)
            table = t["table"]
            table[0][:, cols], table[1][:, cols] = cost, lens
            table[2], table[3] = radii, words
            table[4][:, cols] = np.argsort(rank, axis=0, kind="stable")
            t["bound"][cols] = cost.min(axis=0)

    def goal_bound(self, key):
        """A lower bound of the cost of node ``key``'s goal link (its cheapest Dubins word's
        Eq. 5 cost, :meth:`_dubins_table`), or None for a node with no link."""
        m = self._goal_table["index"].get(key)
        if m is None:
            return None
        if not self._goal_table["tiled"][m // self._goal_table["per_tile"]]:
            self._goal_tiles([m])
        self._goal_asked.append(key)
        return float(self._goal_table["bound"][m])

    def goal_link(self, key):
        """(cost, Piece maker) of the cheapest valid connector from node ``key`` into the
        goal, or None (tested once per node and cached). The links of up to
        ``GOAL_BATCH - 1`` other nodes the search has expanded are tested with it (they
        are likely asked for next)."""
        if key in self._goal_links:
            return self._goal_links[key]
        t = self._goal_table
        if key not in t["index"]:
            return None
        batch = [key]
        while self._goal_asked and len(batch) < GOAL_BATCH:
            k = self._goal_asked.pop()
            if k not in self._goal_links and k not in batch:
                batch.append(k)
        m = np.array([t["index"][k] for k in batch])
        self._goal_tiles(m)
        found = self._first_valids(t["p"][m], t["h"][m], tuple(t["table"]), m)
        for k, got in zip(batch, found):
            link = None
            if got is not None:
                link = (
                    got[0],
                    lambda cost=got[0], make=got[2]: Piece("goal", curve=make(), cost=cost),
                )
            self._goal_links[k] = link
        return self._goal_links[key]

    def _check_turning_room(self, what, state):
        """Refuse at once a start (goal) where no walk can leave (arrive) facing the given
        way: every way out of the start (into the goal) runs, over its first (last)
        ``APPROACH`` metres, between the sharpest left and right arcs the gait can turn;
        when the straight way and both arcs meet props there, none can. A NaN heading
        (any facing) always has room."""
        if np.isnan(state[2]):
            return
        sign = 1.0 if what == "start" else -1.0
        s = np.linspace(0.0, APPROACH, 12)
        hit = set()
        for k in (0.0, self.kmax, self.kmin):
            pos, _ = curves.arc_frame(state[:2], state[2] + (np.pi if sign < 0 else 0.0), k, s)
            blocked = self.env.blocked(pos[1:])
            if not blocked.any():
                return
            for p in pos[1:][blocked]:
                hit.update(self.env.near(p))
        names = ", ".join(repr(n) for n in sorted(hit)[:4]) or "an obstacle"
        way = "leave the start facing" if what == "start" else "arrive at the goal facing"
        raise FacingRefused(
            f"no {self._gait_name} can {way} {np.degrees(state[2] + self._frame_angle):.0f} "
            f"degrees: {names} stand(s) in the way within {APPROACH:.2f} m and the "
            f"{self._gait_name} cannot turn tighter than {1 / max(self.kmax, -self.kmin):.2f} m; "
            f"turn the {what} or move {'it' if len(hit) <= 1 else 'them'}"
            + (" (or plan with goal facing 'any')" if what == "goal" else "")
        )

    def _refused(self, what, state, said):
        """The error for no connector out of the start (into the goal): ``said`` and why
        (:meth:`_boxed_in`); a :class:`FacingRefused` when the state has a heading to face."""
        cls = PlanError if np.isnan(state[2]) else FacingRefused
        return cls(said + self._boxed_in(what, state))

    def _boxed_in(self, what, state):
        """Why no connector leaves the start (enters the goal), naming the props around."""
        reach = 2.0 / min(-self.kmin, self.kmax) + self.env.radius
        p = np.asarray(state[:2], float)
        names = [
            n
            for n in self.env.names_in_box(p - reach, p + reach)
            if self.env.obstacles[n].within(p[None], reach)[0]
        ]
        way = "turn out of it" if what == "start" else "turn into it"
        facing = (
            ""
            if np.isnan(state[2])
            else f" facing {np.degrees(state[2] + self._frame_angle):.0f} degrees"
        )
        who = ", ".join(repr(n) for n in names[:4]) if names else "nothing near"
        return (
            f"the {self._gait_name} cannot {way}{facing} (it turns no tighter than "
            f"{1 / max(self.kmax, -self.kmin):.2f} m and keeps {self.env.radius:.2f} m from "
            f"props; within {reach:.1f} m: {who}); move or turn the {what}, or move those props"
            + (", or plan with goal facing 'any'" if what == "goal" else "")
        )

    @property
    def turn_radii(self):
        """Radii of the Dubins arcs, in the order they are tried: a share of the sharpest
        turn the gait follows, then that sharpest turn itself (only where nothing wider
        fits: the tighter the turn, the more the planted feet slide)."""
        tight = 1.0 / min(-self.kmin, self.kmax)
        return (tight / DUBINS_CURVATURE_SHARE, tight)

    def _dubins_table(self, p0, h0, p1, h1, max_length=None):
        """Approximate Eq. 5 cost (R*6, M), lengths (R*6, M, 3), radius (R*6,), word (R*6,)
        and the order to try them (R*6, M) of the Dubins words between state pairs at each
        radius; too-long and missing words cost inf. Wider turns are tried first."""
        p0, p1 = np.atleast_2d(p0), np.atleast_2d(p1)
        n, w, r = p0.shape[0], len(dubins.WORDS), np.array(self.turn_radii)
        # Every radius in one call: pairs repeated radius by radius.
        radius = np.repeat(r, n)
        lengths = dubins.words(
            np.tile(p0, (r.size, 1)),
            np.tile(h0, r.size),
            np.tile(p1, (r.size, 1)),
            np.tile(h1, r.size),
            radius,
        )
        total = lengths.sum(axis=-1)
        turn = dubins.turns(lengths, radius)
        effort = self.patch.effort_rate * total / self.max_speed
        cost = self.alpha * total + self.beta * turn + self.gamma * effort
        longest = MAX_CONNECTOR_TILES * self.patch.side if max_length is None else max_length
        cost = np.where(np.isfinite(total) & (total <= longest), cost, np.inf)
        # Rows radius by radius, word by word; columns the pairs.
        cost = cost.reshape(w, r.size, n).transpose(1, 0, 2).reshape(r.size * w, n)
        lens = lengths.reshape(w, r.size, n, 3).transpose(1, 0, 2, 3).reshape(r.size * w, n, 3)
        rank = np.repeat(np.arange(r.size), w)[:, None]
        key = np.where(np.isfinite(cost), cost + 1e6 * rank, np.inf)
        return (
            cost,
            lens,
            np.repeat(r, w),
            np.tile(np.arange(w), r.size),
            np.argsort(key, axis=0, kind="stable"),
        )

    def _first_valid(self, p0, h0, table, m, min_length=0.0):
        """(curve, Eq. 5 cost, gait cycles) of the first valid Dubins word of column ``m``
        of a :meth:`_dubins_table` from state (p0, h0), or None."""
        found = self._first_valids(
            np.asarray(p0, float)[None], np.atleast_1d(h0), table, np.array([m]), min_length
        )[0]
        return None if found is None else (found[2](), found[0], found[1])

    def _first_valids(self, p0, h0, table, columns, min_length=0.0, tries=DUBINS_TRIES, limit=None):
        """:meth:`_first_valid` of many columns at once (start states ``p0`` (n, 2),
        ``h0`` (n,)): per column (Eq. 5 cost, gait cycles, a function making its curve) or
        None. The words of every column are tried in their order, ``tries`` per column at
        a time, their samples tested against the footprints together (as
        ``Environment.path_blocked`` does); the first clear word of a column must bend
        within the gait's limits (:meth:`_bends_within`; a word at the wider radius does by
        construction, one at the sharpest turn is checked). With ``limit`` only the first
        ``limit`` columns that have a valid word get it (the rest None)."""
        cost, lengths, radii, words, order = table
        wide = radii.max()
        chosen = {}  # column position -> (arc, pos, heading, kappa)
        rank = np.zeros(len(columns), int)  # how far down its order each column has got
        todo = list(range(len(columns)))
        columns = np.asarray(columns)
        step = np.arange(tries)
        while todo:
            # The next ``tries`` words down each column's order (fewer at its end), the
            # finite ones, column by column in ``todo`` order.
            at_col = np.array(todo)
            m = columns[at_col][:, None]
            idx = rank[at_col][:, None] + step
            inside = idx < order.shape[0]
            r = order[np.minimum(idx, order.shape[0] - 1), m]
            keep = inside & np.isfinite(cost[r, m])
            rows, who = r[keep], np.repeat(at_col, keep.sum(axis=1))
            if rows.size == 0:
                break
            lens = lengths[rows, columns[who]]
            clear = lens.sum(axis=1) >= min_length
            k = np.flatnonzero(clear)
            at = np.full(rows.size, -1)
            if k.size:
                arc, pos, heading, kappa, first = dubins.samples(
                    p0[who[k]], h0[who[k]], words[rows[k]], lens[k], radii[rows[k]]
                )
                clear[k] = ~self._samples_blocked(pos, first)
                at[k] = np.arange(k.size)
            more = []
            lo = np.searchsorted(who, at_col, side="left").tolist()
            hi = np.searchsorted(who, at_col, side="right").tolist()
            clear_l, wide_l, at_l = clear.tolist(), (radii[rows] == wide).tolist(), at.tolist()
            for i, a0, b0 in zip(todo, lo, hi):  # each column's words, in its order
                for j in range(a0, b0):
                    if not clear_l[j]:
                        continue
                    a, b = first[at_l[j]], first[at_l[j] + 1]
                    samples = (arc[a:b], pos[a:b], heading[a:b], kappa[a:b])
                    if wide_l[j] or self._bends_within(_dubins_curve(samples)):
                        chosen[i] = samples
                        break
                else:
                    if b0 - a0 == tries:  # more words down its order
                        rank[i] += tries
                        more.append(i)
            todo = more
        found = [None] * len(columns)
        use = sorted(chosen)[:limit]
        if use:
            parts = [chosen[i] for i in use]
            first = np.concatenate(([0], np.cumsum([p[0].size for p in parts])))
            cycles = cycles_along_many(
                self.patch.gait, np.concatenate([p[1] for p in parts]), first
            )
            for i, part, n in zip(use, parts, cycles.tolist()):
                turn = float(np.sum(np.abs(np.diff(part[2]))))
                frames = n * self.patch.gait.frames
                effort = self.patch.effort_rate * frames / self.patch.gait.fps
                c = self.alpha * float(part[0][-1]) + self.beta * turn + self.gamma * effort
                found[i] = (c, n, lambda part=part: _dubins_curve(part))
        return found

    def _samples_blocked(self, pos, first):
        """(C,) True where path c (samples ``pos[first[c]:first[c + 1]]``) has a sample
        within the radius (+ ``PATH_MARGIN``) of a footprint. Every ``COARSE``-th sample
        is tested first: a path hit there is blocked, and only the other samples of the
        paths still clear are tested (the same answer as testing every sample)."""
        radius = self.env.radius + PATH_MARGIN
        n = first[1:] - first[:-1]
        owner = np.repeat(np.arange(n.size), n)
        coarse = (np.arange(pos.shape[0]) - first[owner]) % COARSE == 0
        hit = np.zeros(pos.shape[0], bool)
        hit[coarse] = self.env.blocked(pos[coarse], radius=radius)
        out = np.logical_or.reduceat(hit, first[:-1])
        rest = np.flatnonzero(~coarse & ~out[owner])
        if rest.size:
            hit[rest] = self.env.blocked(pos[rest], radius=radius)
            out = np.logical_or.reduceat(hit, first[:-1])
        return out

    # -- search ---------------------------------------------------------------------------
    def plan(
        self,
        start,
        goal,
        margin_tiles=3,
        max_expansions=400_000,
        use_corridor=False,
        shorten=True,
        turn_in_place=None,
    ):
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

        best = self._plan_turning(start, goal, once)
        # The plan's time is the whole call's, every search made counted.
        best.seconds = time.perf_counter() - t0
        best.stats["shortening_seconds"] = sum(p.stats["shortening_seconds"] for p in made)
        best.stats["walks_searched"] = len(made)
        return best

    def _plan_turning(self, start, goal, once):
        """:meth:`plan` with turns on the spot; ``once(start, goal)`` searches one walk."""
        # The goal behind the character (or its heading against the way in): turn on the
        # spot first (last), as a person does, and plan the walk once.
        bearing = float(np.arctan2(goal[1] - start[1], goal[0] - start[0]))
        ends = (
            abs(_wrap(bearing - start[2])) > LOOP_TURN,
            not np.isnan(goal[2]) and abs(_wrap(goal[2] - bearing)) > LOOP_TURN,
        )
        if any(ends):
            found = self._turned(start, goal, bearing, ends, once)
            if found is not None:
                return found
        try:
            exact, error = once(start, goal), None
        except PlanError as e:
            exact, error = None, e
            if not isinstance(e, (FacingRefused, Unreachable)):
                raise  # a search limit, a goal inside a prop: no turn on the spot helps
        # A walk that still loops near an end (props in the way): the turn on the spot
        # there is tried too and the cheaper by Eq. 5 kept.
        loops = (True, True) if exact is None else self._loops(exact)
        loops = (loops[0] and not ends[0], loops[1] and not ends[1])
        best = exact
        if any(loops):
            found = self._turned(start, goal, bearing, loops, once)
            if found is not None and (best is None or _final_cost(found) < _final_cost(best)):
                best = found
                best.stats["exact_facing_cost"] = None if exact is None else _final_cost(exact)
        if best is None:
            raise error
        return best

    def _turned(self, start, goal, bearing, ends, once):
        """The plan with a turn on the spot at the start (towards the goal) and / or at the
        goal (to its heading, the walk arriving facing any way) where ``ends`` says, or
        None when that walk finds no path (or no turn is needed after all)."""
        turn_to = (
            bearing if ends[0] and abs(_wrap(bearing - start[2])) >= MIN_TURN_IN_PLACE else None
        )
        free = ends[1] and not np.isnan(goal[2])
        if turn_to is None and not free:
            return None
        s = start if turn_to is None else np.array([start[0], start[1], turn_to])
        g = np.array([goal[0], goal[1], np.nan]) if free else goal
        try:
            found = once(s, g)
        except PlanError:
            return None
        return self._with_turns(
            found, start if turn_to is not None else None, goal if free else None
        )

    @property
    def _gait_name(self):
        """What the messages call the motion planned: the gait's layer ("walk", "run")."""
        return self.patch.gait.layer or "walk"

    @property
    def _way(self):
        """'walkable way' for a walk, 'way the run can take' for a run (messages)."""
        name = self._gait_name
        return "walkable way" if name == "walk" else f"way the {name} can take"

    @property
    def can_turn_in_place(self):
        """The gait can turn on the spot within the patch's curvature range."""
        got = self.__dict__.get("_can_turn_in_place")
        if got is None:
            got = self._can_turn_in_place = turn_in_place.can_turn(
                self.patch.gait, self.kmin, self.kmax
            )
        return got

    def _loops(self, plan):
        """(start, goal): the walk turns more than ``LOOP_TURN`` within its first (last)
        ``LOOP_REACH`` gait cycles of way: it may loop out of the start's heading (into
        the goal's), where a turn on the spot would do."""
        reach = LOOP_REACH * self.patch.gait.cycle_distance
        out = []
        for piece, end in ((plan.pieces[0], 0), (plan.pieces[-1], -1)):
            if piece.kind in ("traversal", "interaction", "turn"):
                out.append(False)
                continue
            c = piece.curve if piece.curve is not None else self._segment_curve(piece)
            near = c.s <= c.s[0] + reach if end == 0 else c.s >= c.s[-1] - reach
            h = np.unwrap(c.heading[near])
            out.append(bool(h.size > 1 and np.sum(np.abs(np.diff(h))) > LOOP_TURN))
        return tuple(out)

    def _turn_piece(self, x, y, heading, to_heading):
        """A turn on the spot at (x, y) from ``heading`` to ``to_heading`` (the shorter
        way), costed by Eq. 5: its turn and its time, eased in and out."""
        gait, delta = self.patch.gait, _wrap(to_heading - heading)
        frames = turn_in_place.frames_needed(gait, delta)
        frames = retime.warp_phases(frames, True, True, gait.frames).size
        cost = self.beta * abs(delta) + self.gamma * self.patch.effort_rate * frames / gait.fps
        return Piece("turn", cost=cost, turn=(float(x), float(y), float(heading), delta))

    def _with_turns(self, plan, start=None, goal=None):
        """``plan`` with a turn on the spot from ``start``'s heading before it and / or
        one to ``goal``'s heading after it (the plan then starts facing its first piece's
        way, ends facing any way); Eq. 5 costs count each turn and its time."""
        before = [] if start is None else [self._turn_piece(*start[:3], plan.start[2])]
        after = [] if goal is None else [self._turn_piece(*goal[:2], plan.goal[2], goal[2])]
        added = sum(p.cost for p in before + after)
        stats = dict(
            plan.stats,
            turn_in_place_deg=[float(np.degrees(p.turn[3])) for p in before + after],
            cost_shortened=_final_cost(plan) + added,
        )
        return Plan(
            before + list(plan.pieces) + after,
            plan.cost + added,
            plan.expansions,
            plan.seconds,
            tuple(start) if start is not None else plan.start,
            tuple(goal) if goal is not None else plan.goal,
            stats,
        )

    def _plan_once(self, start, goal, margin_tiles, max_expansions, use_corridor, shorten):
        t0 = time.perf_counter()
        start, goal = np.asarray(start, float), np.asarray(goal, float)
        for what, pt in (("start", start), ("goal", goal)):
            if not np.isfinite(pt[:2]).all():
                raise PlanError(f"the {what} position must be finite numbers")
            if self.world_env.blocked(pt[None, :2])[0]:
                raise PlanError(
                    f"the {what} ({pt[0]:.2f}, {pt[1]:.2f}) is inside or within "
                    f"{self.world_env.radius:.2f} m of an obstacle"
                )
        with self.framed(start, goal, margin_tiles) as (ls, lg, frame):
            plan = self._plan_local(ls, lg, margin_tiles, max_expansions, use_corridor)
            searched = len(plan.pieces)
            t_short = time.perf_counter()
            if shorten:
                plan.pieces = shortcut.shorten(self, plan.pieces, ls, lg)
                plan.pieces = shortcut.pull_tail(self, plan.pieces, lg)
            plan.stats["shortening_seconds"] = time.perf_counter() - t_short
            plan.pieces = self._long_last_piece(plan.pieces)
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

    def replan_run(self, plan, first, last, extra=(), margin_tiles=3, max_expansions=400_000):
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
                begin = self._node_key(p, h)
                ls = np.array([p[0], p[1], h])
            if last < len(pieces) - 1 and pieces[last].kind != "goal":
                p, h = shortcut.exit_state(self, pieces[last])
                end = self._node_key(p, h)
                lg = np.array([p[0], p[1], h])
            run = self._plan_local(
                ls, lg, margin_tiles, max_expansions, False, start_key=begin, goal_key=end
            )
            new = shortcut.shorten(self, run.pieces, ls, lg)
            if end is None:
                new = shortcut.pull_tail(self, new, lg)
            out = list(pieces[:first]) + new + list(pieces[last + 1 :])
            if end is None:
                out = self._long_last_piece(out)
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

    def _node_key(self, p, h):
        """Key of the lattice node at plan-frame position ``p`` with heading ``h`` (a piece
        boundary inside a plan); PlanError when no node is there."""
        keys, pos, head = self._entries(self._block(self.env.tile_of(np.asarray(p, float))))
        dh = np.abs((head - h + np.pi) % (2 * np.pi) - np.pi)
        hit = np.flatnonzero((np.linalg.norm(pos - p, axis=1) < 1e-6) & (dh < 1e-6))
        if hit.size == 0:
            raise PlanError("a piece boundary of the plan is not on a lattice node")
        return int(keys[hit[0]])

    @contextlib.contextmanager
    def framed(self, start, goal, margin_tiles=3):
        """Within the block the planner's ``env``, ``props`` and ``goal`` are those of the
        plan frame of ``start`` -> ``goal``; yields (local start, local goal, frame)."""
        side = self.patch.side
        frame = lattice_frame(start, goal, side, self.patch.nodes)
        ls, lg = state_to_local(frame, start), state_to_local(frame, goal)
        ts, tg = self.world_env.tile_of(ls[:2]), self.world_env.tile_of(lg[:2])
        region = (
            min(ts[0], tg[0]) - margin_tiles,
            min(ts[1], tg[1]) - margin_tiles,
            max(ts[0], tg[0]) + margin_tiles,
            max(ts[1], tg[1]) + margin_tiles,
        )
        self.env = local_environment(
            self.world_env,
            frame,
            (region[0] * side, region[1] * side),
            ((region[2] + 1) * side, (region[3] + 1) * side),
        )
        self.props = [local_prop(p, frame) for p in self.world_props]
        self.goal, self.region = lg, region
        self._frame_angle = frame[2]
        try:
            yield ls, lg, frame
        finally:
            self.env, self.props = self.world_env, self.world_props

    def _plan_local(
        self, start, goal, margin_tiles, max_expansions, use_corridor, start_key=None, goal_key=None
    ):
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
        self._h_tiles = {}  # the heuristic's tables are the goal's
        ts, tg = self.env.tile_of(start[:2]), self.env.tile_of(goal[:2])
        self.region = (
            min(ts[0], tg[0]) - margin_tiles,
            min(ts[1], tg[1]) - margin_tiles,
            max(ts[0], tg[0]) + margin_tiles,
            max(ts[1], tg[1]) + margin_tiles,
        )
        for what, state, key in (("start", start, start_key), ("goal", goal, goal_key)):
            if key is None:
                self._check_turning_room(what, state)
        t_conn = time.perf_counter()
        self._start_table = {"valid": 0, "done": 0}
        starts = self.start_connectors(start) if start_key is None else []
        if goal_key is None:
            goals = self.goal_connectors(goal)
        else:
            goals, self._goal_links = {int(goal_key): 0}, {}

        def no_start():
            return start_key is None and not any(self.start_link(k) is not None for k, _ in starts)

        if not goals:
            if no_start():
                raise self._refused("start", start, f"no {self._way} out of the start: ")
            raise PlanError(f"no {self._way} into the goal: every node around it is too close")
        payloads = {}
        self.corridor = None
        tiles = None
        if use_corridor:
            tiles = TilePlanner(self.patch, self.env, traversal=self._tile_traversal).plan(
                start[:2], goal[:2], self.region
            )
            if tiles is not None:
                w = range(-CORRIDOR_TILES, CORRIDOR_TILES + 1)
                self.corridor = {(t[0] + di, t[1] + dj) for t in tiles for di in w for dj in w}

        stitched, stitches = {}, []
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
            copies = self._traversal_estimates(start)
            observer = TraversalObserver(
                copies,
                stitch_copy,
                self.across,
                up_front=self.mode == "static",
                through=self._through(copies) if copies and self.mode == "dynamic" else None,
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
            raise self._refused("start", start, f"no {self._way} out of the start: ")
        if (
            not result.found
            and goal_key is None
            and not any(self.goal_link(k) is not None for k in goals)
        ):
            raise self._refused("goal", goal, f"no {self._way} into the goal: ")
        if not result.found:
            raise (SearchLimit if result.expansions >= max_expansions else Unreachable)(
                f"goal ({goal[0]:.2f}, {goal[1]:.2f}) is unreachable: obstacles "
                f"close every path within {margin_tiles} tiles of start and goal "
                f"({result.expansions} nodes searched)"
            )
        pieces = []
        keys = [k for k, _ in result.path]
        first = keys[0]
        if start_key is None:
            pieces.append(self.start_link(first)[1]())
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
            goal = np.array([goal[0], goal[1], pieces[-1].curve.heading[-1]])
        return Plan(
            pieces,
            float(result.cost),
            result.expansions,
            seconds,
            tuple(start),
            tuple(goal),
            {
                "start_connectors": self._start_table["valid"],
                "start_nodes_tested": self._start_table["done"],
                "goal_connectors": len(goals),
                "goal_links_tested": len(self._goal_links),
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

    def _tile_traversal(self, tile):
        """tau (Eq. 3) of a tile, from the traversable props overlapping it (lazy)."""
        names = self.env.members(tile)
        props = [p for p in self.props if p.name in names and p.traversals()]
        return tile_traversal(
            self.patch,
            self.env,
            props,
            tile,
            lambda p: accessibility(
                self.patch, p, self.env.radius, weights=(self.alpha, self.beta, self.gamma)
            ),
        )

    def _traversal_estimates(self, start):
        """[(f lower bound, prop, clip copy, tile id, entry x, entry y, entry heading,
        clip cost + heuristic from the exit)] of every traversal copy in the region.

        The bound is alpha |start - entry| (+ effort bound) + clip cost + heuristic from
        the exit: no path through the copy costs less. The tile id (node key // LOCAL) is
        the tile of the copy's entry keyframe, where its stitched edges start; the rest
        is what :meth:`_through` bounds the copy by from a node."""
        out = []
        self.bin_culled = 0
        per_metre = self._per_metre
        for pi, prop in enumerate(self.props):
            x, y, heading = prop.pose
            if not self.in_region(*self.env.tile_of((x, y))):
                continue
            which = np.array(
                [ci for ci, clip in enumerate(prop.clips) if clip.kind == "traversal"], int
            )
            if which.size == 0:
                continue
            # Density bins: another prop there culls the copies starting or ending in them.
            lo, hi = prop.extended_bounds()
            box = prop.to_world(
                np.array([[lo[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]], [hi[0], lo[1]]])
            )
            near = [
                self.env.obstacles[n]
                for n in self.env.names_in_box(box.min(axis=0), box.max(axis=0))
            ]
            occluded = prop.occluded_bins(near)
            _, clip_bins = prop.density_bins()
            keep = ~occluded[clip_bins[which]].any(axis=1)
            self.bin_culled += int(np.count_nonzero(~keep))
            which = which[keep]
            if which.size == 0:
                continue
            c, s = np.cos(heading), np.sin(heading)
            ends = np.array([(prop.clips[ci].entry, prop.clips[ci].exit) for ci in which.tolist()])
            wx = c * ends[..., 0] - s * ends[..., 1] + x  # as ObjectPatch.world_clip moves them
            wy = s * ends[..., 0] + c * ends[..., 1] + y
            wh = ends[..., 2] + heading
            # Walking to the entry turns from the start's heading to the keyframe's (the
            # stitch pays the heading gap), and walking on from the exit turns to the
            # goal's: beta x each turn bounds those costs from below too.
            cx, cy = wx[:, 0] - start[0], wy[:, 0] - start[1]
            far = np.hypot(cx, cy)
            approach = per_metre * far + self.beta * _approach_turn(start[2], wh[:, 0], cx, cy)
            cost = np.array(
                [
                    self.alpha * prop.clips[ci].length()
                    + self.beta * prop.clips[ci].turn()
                    + self.gamma * prop.clips[ci].effort
                    for ci in which.tolist()
                ]
            )
            # The walk on joins a segment frame up to POSITION_TOLERANCE from the exit.
            h = self.state_heuristic(
                np.column_stack((wx[:, 1], wy[:, 1])), wh[:, 1], gap=POSITION_TOLERANCE
            )
            # The tile stitching indexes for the entry, as a node key's tile id.
            ti = np.floor(wx[:, 0] / self.env.side).astype(np.int64)
            tj = np.floor(wy[:, 0] / self.env.side).astype(np.int64)
            tiles = pack(ti, tj, 0) // LOCAL
            out += list(
                zip(
                    (approach + cost + h).tolist(),
                    [pi] * which.size,
                    which.tolist(),
                    tiles.tolist(),
                    wx[:, 0].tolist(),
                    wy[:, 0].tolist(),
                    wh[:, 0].tolist(),
                    (cost + h).tolist(),
                )
            )
        return out

    def _through(self, copies):
        """``through(keys, fs, idx)`` of :class:`TraversalObserver` for ``copies`` of
        :meth:`_traversal_estimates`: g of each node (f less its heuristic) + a lower bound
        of the entry part walked from it (its segment starts on the node) into the copy's
        entry keyframe + the clip + the heuristic from the exit.

        The entry part costs alpha x (its length + the position gap, at least the
        distance d) + gamma x its effort (its length, at least d less the gap, walked
        no faster than the fastest part of any segment) + beta x (its turn + the heading
        gap, :func:`_approach_turn` from the node's heading)."""
        ex, ey, eh, rest = (np.array([c[k] for c in copies], float) for k in (4, 5, 6, 7))
        side, lx, ly, heading = self.patch.side, self._lx, self._ly, self.local_heading
        walk = self.alpha
        effort = self.gamma * self.patch.effort_rate / part_speed(self.patch)
        beta, h_of, slack = self.beta, self.heuristic_of, 1e-9

        def to_entry(keys, idx):
            """Local ids of nodes ``keys`` and the way (x, y, length) from each to the
            entry keyframes of copies ``idx``."""
            t = keys // LOCAL
            local = keys - t * LOCAL
            cx = ex[idx] - (lx[local] + (t // (2 * BIAS) - BIAS) * side)
            cy = ey[idx] - (ly[local] + (t % (2 * BIAS) - BIAS) * side)
            return local, cx, cy, np.hypot(cx, cy)

        def walk_in(d):
            """The entry part's distance and effort terms over a way ``d`` long."""
            return walk * d + effort * np.maximum(d - POSITION_TOLERANCE, 0.0)

        def through(keys, fs, idx, below=None):
            if below is not None:
                return one(keys[0], fs[0], idx, below)
            keys = np.asarray(keys, np.int64)[:, None]
            local, cx, cy, d = to_entry(keys, idx)
            # f - h is g up to rounding: the slack keeps the bound below the true one
            g = np.array([f - h_of(int(k)) for k, f in zip(keys[:, 0].tolist(), fs)])
            out = (g * (1.0 - slack) - slack)[:, None] + rest[idx]
            out += walk_in(d)
            return out + beta * _approach_turn(heading[local], eh[idx], cx, cy)

        def one(key, f, idx, below):
            """One node: nothing when even g + the cheapest rest is not under ``below``
            anywhere; else the turn only where the rest of the bound is under it."""
            g = (f - h_of(key)) * (1.0 - slack) - slack
            r = rest[idx]
            if g + r.min() >= below.max():
                return below[None]
            local, cx, cy, d = to_entry(key, idx)
            out = g + r
            out += walk_in(d)
            need = np.flatnonzero(out < below)
            if need.size:
                h1 = eh[idx[need]]
                out[need] += beta * _approach_turn(heading[local], h1, cx[need], cy[need])
            return out[None]

        return through


class TraversalObserver:
    """High-level observer of the segment search (paper Sec. 4.3): lazy stitching.

    Each traversal copy has an estimate, a lower bound of cost + heuristic of any path
    through it (from the start, :meth:`SegmentPlanner._traversal_estimates`), and the tile
    of its entry keyframe, whose nodes its stitched edges leave from. Tiles are node keys
    // LOCAL; a node on a tile edge lies in both tiles sharing the edge.

    When the search takes a node of tile t off its open list, the pending copies of t
    get a bound through that node: at least the estimate, and, with ``through``, g of
    the node + a lower bound of walking from it into the copy's entry keyframe + the
    clip + the heuristic from the exit (any path through the copy whose stitched edge
    leaves this node costs that much). A copy is stitched, and its edges join the graph,
    once the search takes off a node whose f is at least the copy's lowest bound (A*
    takes nodes by increasing f; edges out of nodes expanded earlier are relaxed by astar
    at once). Without ``through`` a copy's bound is its estimate from the moment the
    search enters its tile. The paper's observer records the cost and heuristic of the
    path through each tile and stitches a traversal once they exceed its estimate; here
    the cost recorded (g of the nodes taken off in the tile) also sharpens the estimate,
    so copies off the way the search goes (dearer to reach than a straight line from the
    start says) wait, often for good (``bench/bench_speed.py --sections table1``: 23.9
    copies stitched per path instead of 62.1 with the start's estimate alone, the same
    costs).

    Backstop, for optimality: when the goal comes off with f (the cheapest path found so
    far; inf when the search ran out of nodes), every pending copy with a bound <= f is
    stitched, and astar puts the goal back and goes on. Without it copies may be missed:
    a copy whose bound lies between the f of the last node taken off and the goal's (a
    goal link dearer than its node's heuristic; test_astar shows one) is never reached
    by the rule. Copies never bounded can be skipped: take a path cheaper than f whose
    first copy not yet stitched is X, entered from node n; the part before X uses only
    edges already in the graph, so with an admissible heuristic each of its nodes, n
    included, has f below the goal's and was taken off (last) with g at most its cost
    along the path before the goal came off; then X's bound through n is at most the
    path's cost, below f. So when the goal comes off and nothing is added, no copy left
    could give a cheaper path: dynamic stitching finds the cost static stitching (every
    copy stitched before the search) finds, with ``copies_stitched_by_tile`` (at nodes)
    + ``copies_stitched_at_goal`` copies stitched.
    """

    def __init__(self, copies, stitch_copy, across, up_front=False, through=None):
        """``copies`` [(estimate, prop, copy, tile id, ...)]; ``stitch_copy(prop, copy) ->
        edges``; ``across[local]``: tile id offset of the other tile of a node;
        ``through(keys, fs, idx, below=None) -> (len(keys), len(idx))``: lower bounds of
        the cost + heuristic of paths through copies ``idx`` (indices into ``copies``)
        whose stitched edge leaves node ``keys[k]``, taken off with ``fs[k]`` (with
        ``below``, for one node, those not under ``below`` may be left lower, for speed);
        with ``up_front`` (static mode) every copy is stitched now and added at the first
        call.

        A copy's bound matters only once the search takes off a node with f at least its
        estimate (the bound is never lower), so the nodes taken off in its tile are kept
        and the bound is computed over them then, and lowered by each node after."""
        self.stitch_copy, self.across, self.through = stitch_copy, across, through
        self.by_tile = self.at_goal = 0
        self.ready = []
        self.unseen = {}  # tile id -> indices of its copies, for tiles not entered yet
        self.taken = {}  # tile id -> ([keys], [fs]) of the nodes taken off in it
        self.waiting = []  # heap of (estimate, copy index) of copies of entered tiles
        self.active = {}  # tile id -> indices of its copies with a bound, not stitched
        self.due = []  # heap of (bound, copy index)
        if up_front:
            for _, pi, ci, *_ in copies:
                self.ready += stitch_copy(pi, ci)
            return
        self.which = [(pi, ci) for _, pi, ci, *_ in copies]
        self.estimate = np.array([c[0] for c in copies], float)
        self.tile = [c[3] for c in copies]
        self.bound = np.full(len(copies), np.inf)  # lowest bound so far per copy
        self.done = np.zeros(len(copies), bool)
        for i, t in enumerate(self.tile):
            self.unseen.setdefault(t, []).append(i)

    def __call__(self, f, key):
        if self.ready:
            ready, self.ready = self.ready, []
            return ready
        if key == astar.GOAL:
            return self._backstop(f)
        tile = key // LOCAL
        for t in (tile, tile + self.across[key - tile * LOCAL]):
            taken = self.taken.get(t)
            if taken is not None:
                taken[0].append(key)
                taken[1].append(f)
                idx = self.active.get(t)
                if idx is not None:
                    self._lower(t, idx, key, f)
            elif t in self.unseen:  # the search enters the tile
                self.taken[t] = ([key], [f])
                for i in self.unseen.pop(t):
                    heapq.heappush(self.waiting, (self.estimate[i], i))
        self._wake(f)
        due = self.due
        if not due or due[0][0] > f:
            return ()
        edges, n = self._stitch(f)
        self.by_tile += n
        return edges

    def _wake(self, f):
        """Bound the copies of entered tiles whose estimates are <= f, over the nodes
        taken off in their tiles so far."""
        waiting = self.waiting
        if not waiting or waiting[0][0] > f:
            return
        woken = {}
        while waiting and waiting[0][0] <= f:
            _, i = heapq.heappop(waiting)
            woken.setdefault(self.tile[i], []).append(i)
        for t, idx in woken.items():
            idx = np.array(idx, np.int64)
            new = self.estimate[idx]
            if self.through is not None:
                keys, fs = self.taken[t]
                new = np.maximum(new, self.through(keys, fs, idx).min(axis=0))
            self.bound[idx] = new
            for b, i in zip(new.tolist(), idx.tolist()):
                heapq.heappush(self.due, (b, i))
            have = self.active.get(t)
            self.active[t] = idx if have is None else np.concatenate((have, idx))

    def _lower(self, tile, idx, key, f):
        """Lower the bounds of the bounded copies ``idx`` of ``tile`` by node ``key``."""
        idx = idx[~self.done[idx]]
        if idx.size == 0:
            del self.active[tile]
            return
        self.active[tile] = idx
        if self.through is None:  # the bound is the estimate
            return
        new = self.through([key], [f], idx, below=self.bound[idx])[0]
        lower = new < self.bound[idx]
        if lower.any():
            idx, new = idx[lower], new[lower]
            self.bound[idx] = new
            push, due = heapq.heappush, self.due
            for b, i in zip(new.tolist(), idx.tolist()):
                push(due, (b, i))

    def _stitch(self, f):
        """Stitch the copies whose bounds are <= f: (edges, copies)."""
        due, edges, n = self.due, [], 0
        while due and due[0][0] <= f:
            _, i = heapq.heappop(due)
            if self.done[i]:
                continue  # a higher bound of a copy stitched already
            self.done[i] = True
            edges += self.stitch_copy(*self.which[i])
            n += 1
        return edges, n

    def _backstop(self, f):
        self._wake(f)
        edges, n = self._stitch(f)
        self.at_goal += n
        return edges


def _turn_bound(a, b):
    """A lower bound of the radians any walk turns from heading ``a`` to heading ``b``:
    their angle, less ``HEADING_SLACK`` for sampled headings (the turn a piece pays is
    the sum of its samples' heading steps, at least the angle between its ends)."""
    gap = np.abs((np.asarray(b, float) - a + np.pi) % (2 * np.pi) - np.pi)
    return np.maximum(gap - HEADING_SLACK, 0.0)


def _approach_turn(h0, h1, cx, cy):
    """A lower bound of the radians a walk turns from heading ``h0`` to a traversal's
    entry keyframe of heading ``h1`` at (cx, cy) from its start (the stitch pays the
    heading gap to the keyframe): the angle between the two headings, and between each
    and the chord, whose end (the segment frame the stitch joins) may lie up to
    ``stitching.POSITION_TOLERANCE`` from the keyframe: its direction is known only
    within the angle that distance subtends (none near the start)."""
    turn = _turn_bound(h0, h1)
    far = np.hypot(cx, cy)
    with np.errstate(divide="ignore", invalid="ignore"):
        spread = np.arcsin(np.clip(POSITION_TOLERANCE / far, 0.0, 1.0))
    chord = np.arctan2(cy, cx)
    known = far > 2.0 * POSITION_TOLERANCE
    for h in (h0, h1):
        by_chord = np.maximum(_turn_bound(h, chord) - spread, 0.0)
        turn = np.maximum(turn, np.where(known, by_chord, 0.0))
    return turn


def _patch_cache(patch, key, make):
    """What ``make()`` returns, computed once per patch (and key): arrays the planner
    derives from a baked patch, kept with the patch's own caches."""
    cache = patch.__dict__.setdefault("_planner_cache", {})
    got = cache.get(key)
    if got is None:
        got = cache[key] = make()
    return got


def _wrap(a):
    return float((a + np.pi) % (2 * np.pi) - np.pi)


def _final_cost(plan):
    """Eq. 5 cost of a plan's pieces as they will be walked (after shortening)."""
    return float(plan.stats.get("cost_shortened", plan.cost))


def _dubins_curve(samples):
    """A :class:`~.curves.Curve` of a Dubins word from its samples (arc length, positions,
    headings, curvatures; :func:`.dubins.samples`), the curvature smoothed for blending."""
    arc, pos, heading, kappa = samples
    return curves.Curve(arc, pos, heading, dubins.smoothed(arc, kappa))


def _derivs(curve):
    """Finite-difference derivatives of a dense curve in its own sampling (for measures)."""
    vel = np.gradient(curve.pos, axis=0)
    acc = np.gradient(vel, axis=0)
    return vel[None], acc[None]


def plan_motions(patch, plan, standing=True):
    """World-space motion of every piece, eased across stitches into and out of clips;
    with ``standing`` a plan that starts (ends) walking starts from (ends in) standing:
    its first (last) piece is time-warped (:mod:`.retime`), ramps one gait cycle long. A
    turn on the spot continues from the pose the walk before it stopped in; the walk
    slows to a stop at the goal and the turn eases in and out."""
    ms = []
    for i, p in enumerate(plan.pieces):
        if p.kind == "turn":
            ms.append(turn_motion(patch, p, ms[-1] if ms else None))
        else:
            ms.append(piece_motion(patch, p))
    clips = ("traversal", "interaction")
    kinds = [p.kind for p in plan.pieces]
    if standing:
        ramp, n = patch.gait.frames, len(ms)
        for i, kind in enumerate(kinds):
            if kind in clips:
                continue
            ease_in = i == 0 or kind == "turn" or kinds[i - 1] == "turn"
            ease_out = i == n - 1 or kind == "turn" or kinds[i + 1] == "turn"
            ms[i] = retime.eased(ms[i], ease_in, ease_out, ramp)
        if kinds[-1] not in clips and np.isfinite(np.asarray(plan.goal[:2], float)).all():
            ms[-1] = hips_to(ms[-1], plan.goal[:2], 2 * patch.gait.frames)
    for i, kind in enumerate(kinds):
        if kind in clips:
            continue
        if i + 1 < len(ms) and kinds[i + 1] in clips:
            ms[i] = ease_to(ms[i], ms[i + 1], BLEND_FRAMES, at_end=True)
        if i > 0 and (kinds[i - 1] in clips or "turn" in (kind, kinds[i - 1])):
            ms[i] = ease_to(ms[i], ms[i - 1], BLEND_FRAMES, at_end=False)
    return ms


def turn_motion(patch, piece, previous=None):
    """World-space motion of a turn on the spot (kind "turn"), continuing ``previous``."""
    x, y, heading, delta = piece.turn
    return turn_in_place.turn_motion(patch.gait, (x, y), heading, delta, previous)


def hips_to(motion, xy, window):
    """The motion with its root (the hips) brought onto the ground point ``xy`` on its last
    frame: a walk stops wherever its stride ends, so the hips would stand a few centimetres
    beside the ground path's end. Over the last ``window`` frames (a smoothstep) the root's
    horizontal offset from the ground frame is blended from the stride's own sway to the
    offset that puts it on ``xy`` (none when the ground path ends there, as a plan's
    does): the body settles over the goal as a stopping walker does, never swaying farther
    from the path than the stride itself, and the ground path (the object) is unchanged.
    Planted feet move with the body by at most the sway; foot locking pins them."""
    n = motion.frames
    if n < 2:
        return motion
    g = motion.ground
    c, s = np.cos(g[-1, 2]), np.sin(g[-1, 2])
    d = np.asarray(xy, float) - g[-1, :2]
    target = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])  # in the last ground frame
    k = int(min(max(window, 2), n))
    t = np.linspace(0.0, 1.0, k)
    w = np.zeros(n)
    w[-k:] = t * t * (3.0 - 2.0 * t)
    root = motion.root_local.copy()
    root[:, :2] += w[:, None] * (target[None] - root[:, :2])
    return Motion(g, root, motion.rotations, motion.contacts)


def with_interactions(plan, start=None, goal=None):
    """The plan with an interaction clip before it (stand up) and/or after it (sit down):
    ``start`` / ``goal`` are (ObjectPatch, clip index); the plan must run from the start
    clip's last frame to the goal clip's first frame (see :func:`interaction_states`)."""

    def piece(ref):
        prop, ci = ref
        return Piece("interaction", prop=prop, clip_index=ci, cost=prop.clips[ci].effort)

    pieces = (
        ([piece(start)] if start is not None else [])
        + list(plan.pieces)
        + ([piece(goal)] if goal is not None else [])
    )
    return Plan(
        pieces,
        plan.cost,
        plan.expansions,
        plan.seconds,
        plan.start,
        plan.goal,
        dict(plan.stats, interactions=[p.label for p in pieces if p.kind == "interaction"]),
    )


def interaction_states(start=None, goal=None):
    """World (x, y, heading) where walking must start after a stand-up clip and end before
    a sit-down clip: the clips' last and first ground frames."""
    s = g = None
    if start is not None:
        prop, ci = start
        s = prop.world_clip(prop.clips[ci]).ground[-1]
    if goal is not None:
        prop, ci = goal
        g = prop.world_clip(prop.clips[ci]).ground[0]
    return s, g


def piece_motion(patch, piece):
    """World-space motion of one planned piece (not eased; see :func:`plan_motions`)."""
    if piece.kind == "turn":
        return turn_motion(patch, piece)
    m = _local_piece_motion(patch, piece)
    return m if piece.frame == IDENTITY else m.transformed(*piece.frame)


def _local_piece_motion(patch, piece):
    if piece.kind in ("segment", "part"):
        m = patch.motion(piece.segment)
        if piece.kind == "part":
            m = sliced(m, *piece.frames)
        return m.transformed(piece.tile[0] * patch.side, piece.tile[1] * patch.side)
    if piece.kind in ("traversal", "interaction"):
        return piece.prop.world_clip(piece.prop.clips[piece.clip_index])
    if piece.kind == "start":
        return follow(patch.gait, piece.curve, cycles="to node")
    if piece.kind == "shortcut":
        return follow(patch.gait, piece.curve, cycles=piece.cycles)
    return follow(patch.gait, piece.curve, cycles=None, eased=(True, False))
