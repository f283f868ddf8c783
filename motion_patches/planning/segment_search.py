# SPDX-License-Identifier: GPL-3.0-or-later
"""The segment search's graph (paper Sec. 4.2, Eq. 7, 8) and its lazy stitching (Sec. 4.3).

Nodes are tile entry states packed into one integer: tile (i, j) and the local entry id
(edge, slot, heading) of the locomotion patch. Expanding a node looks up the segments of
that entry state, drops those whose cell mask is occluded in the tile (Eq. 8), and maps
each exit to the entry state of the neighbouring tile. The heuristic (Eq. 7 plus an effort
bound) is tabled tile by tile. Traversal clips of object patches join the graph as
stitched edges, lazily, through an observer of the search that bounds each copy by the
nodes it takes off in the copy's tile (:class:`TraversalObserver`).
"""

import heapq
from collections.abc import Callable, Iterable

import numpy as np

from ..patch.locomotion_patch import (
    DIRECTIONS,
    EDGES,
    INWARD,
    LocomotionPatch,
    node_id,
    node_position,
    split_node_id,
)
from ..patch.node_keys import BIAS, LOCAL, NEXT_EDGE, TILE_STEP, pack, unpack
from ..props.environment import PATH_MARGIN, SUB, Environment
from ..props.object_patch import ObjectPatch
from . import astar
from .pieces import PlanError
from .stitching import POSITION_TOLERANCE, part_speed
from .traversal_probability import accessibility, tile_traversal

HEADING_SLACK = 0.02  # radians, for sampling error in precomputed turn sums
_NONE = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64))  # no successors


class SegmentGraph:
    """The lattice of one baked locomotion patch as the segment search sees it: node keys,
    their poses, successors (Eq. 8) and heuristic (Eq. 7), in the environment, region and
    goal the planner sets for each search (plan frame coordinates)."""

    def __init__(
        self,
        patch: LocomotionPatch,
        env: Environment,
        alpha: float,
        beta: float,
        gamma: float,
        props: Iterable[ObjectPatch] = (),
    ) -> None:
        if patch.nodes * DIRECTIONS * EDGES > LOCAL:
            raise PlanError("the patch has more nodes per edge than the planner packs (8)")
        self.props = self.world_props = list(props)
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
        self.corridor: set[tuple[int, int]] | None = None  # tiles of the high-level path's corridor
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
        # Per local entry state: (segments, cell masks, relative keys, costs), None for none.
        self._out: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None]
        self._out = [None] * LOCAL
        for local in range(LOCAL):
            segs = self.order[self.first[local] : self.first[local + 1]]
            if segs.size:
                self._out[local] = (segs, patch.seg_mask[segs], rel[segs], self.costs[segs])
        self._cos, self._sin = np.cos(self.local_heading), np.sin(self.local_heading)
        # edges of a tile -> local ids of their entry states
        self._entry_ids: dict[tuple[int, ...], np.ndarray] = {}
        self._all_local = np.arange(LOCAL, dtype=np.int64)
        # tile id -> heuristic of its LOCAL keys (:meth:`heuristic_of`)
        self._h_tiles: dict[int, list[float]] = {}
        self._lx, self._ly = self.local_pos[:, 0].copy(), self.local_pos[:, 1].copy()
        self._goal: np.ndarray | None = None
        # (i0, j0, i1, j1): the tiles the search may enter
        self.region: tuple[int, int, int, int] | None = None
        self.frame_angle = 0.0  # of the plan frame, for the messages (world degrees)
        self.bin_culled = 0  # traversal copies the last search culled by density bins

    @property
    def goal(self) -> np.ndarray | None:
        """The goal (x, y, heading; NaN heading: any facing) the heuristic aims at; setting
        it drops the heuristic's tables of the goal before."""
        return self._goal

    @goal.setter
    def goal(self, goal: np.ndarray) -> None:
        self._goal = goal
        self._h_tiles = {}

    # -- graph -------------------------------------------------------------------------
    def node_pose(self, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions (n, 2) and headings (n,) of nodes ``keys`` (plan frame)."""
        i, j, local = unpack(np.asarray(keys, np.int64))
        p = self.local_pos[local] + np.stack((i, j), -1) * self.patch.side
        return p, self.local_heading[local]

    def heuristic(self, keys: np.ndarray) -> np.ndarray:
        """Eq. 7 plus an effort bound: alpha |G| + beta angle-to-goal + gamma T_min."""
        keys = np.asarray(keys, np.int64)
        local = keys % LOCAL
        tile = keys // LOCAL
        goal = self.goal
        assert goal is not None, "the planner sets the goal before searching"
        # Goal relative to each node: goal - tile corner - node's place in the tile.
        gx, gy = goal[0] + BIAS * self.patch.side, goal[1] + BIAS * self.patch.side
        dx = (gx - self._lx[local]) - (tile // (2 * BIAS)) * self.patch.side
        dy = (gy - self._ly[local]) - (tile % (2 * BIAS)) * self.patch.side
        dist = np.sqrt(dx * dx + dy * dy)
        return self.per_metre * dist + self.beta * self._turn_to_goal(
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

    def heuristic_of(self, key: int) -> float:
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

    def state_heuristic(self, p: np.ndarray, h: np.ndarray, gap: float = 0.0) -> np.ndarray:
        """:meth:`heuristic` of states: positions (n, 2), headings (n,); ``gap``: the walk
        on may start that far from the state (see :meth:`_turn_to_goal`)."""
        goal = self.goal
        assert goal is not None, "the planner sets the goal before searching"
        d = goal[:2] - p
        dist = np.linalg.norm(d, axis=-1)
        h = np.asarray(h, float)
        to = _turn_bound(h, goal[2]) if np.isfinite(goal[2]) else np.zeros_like(h)
        turn = self._turn_to_goal(d[:, 0], d[:, 1], dist, np.cos(h), np.sin(h), to, gap)
        return self.per_metre * dist + self.beta * turn

    @property
    def per_metre(self) -> float:
        """Heuristic cost per metre to the goal: alpha, and gamma x the effort of walking
        that metre at the gait's fastest (the effort bound)."""
        return self.alpha + self.gamma * self.patch.effort_rate / self.max_speed

    def expand(self, key: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(keys, costs, segments) of the successors of node ``key``: its segments whose
        cells are free in its tile (Eq. 8), or whose own paths keep the radius."""
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

    def in_region(self, i: int, j: int) -> bool:
        """Tile (i, j) is one the search may enter (the corridor's, else the region's)."""
        if self.corridor is not None:
            return (int(i), int(j)) in self.corridor
        r = self.region
        assert r is not None, "the planner sets the region before searching"
        return r[0] <= i <= r[2] and r[1] <= j <= r[3]

    # -- connectors ----------------------------------------------------------------------
    @property
    def gait_name(self) -> str:
        """What the messages call the motion planned: the gait's layer ("walk", "run")."""
        return self.patch.gait.layer or "walk"

    @property
    def way(self) -> str:
        """'walkable way' for a walk, 'way the run can take' for a run (messages)."""
        name = self.gait_name
        return "walkable way" if name == "walk" else f"way the {name} can take"

    # -- nodes -------------------------------------------------------------------------
    def entries(
        self, tiles_edges: Iterable[tuple[tuple[int, int], Iterable[int]]]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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

    def block(self, tile: tuple[int, int]) -> list[tuple[tuple[int, int], list[int]]]:
        """The 3 x 3 tiles around ``tile``, every edge of each (for :meth:`entries`)."""
        every = list(range(EDGES))
        return [((tile[0] + di, tile[1] + dj), every) for di in (-1, 0, 1) for dj in (-1, 0, 1)]

    def node_key(self, p: np.ndarray, h: float) -> int:
        """Key of the lattice node at plan-frame position ``p`` with heading ``h`` (a piece
        boundary inside a plan); PlanError when no node is there."""
        keys, pos, head = self.entries(self.block(self.env.tile_of(np.asarray(p, float))))
        dh = np.abs((head - h + np.pi) % (2 * np.pi) - np.pi)
        hit = np.flatnonzero((np.linalg.norm(pos - p, axis=1) < 1e-6) & (dh < 1e-6))
        if hit.size == 0:
            raise PlanError("a piece boundary of the plan is not on a lattice node")
        return int(keys[hit[0]])

    def tile_tau(self, tile: tuple[int, int]) -> np.ndarray:
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

    def traversal_estimates(self, start: np.ndarray) -> list[tuple]:
        """[(f lower bound, prop, clip copy, tile id, entry x, entry y, entry heading,
        clip cost + heuristic from the exit)] of every traversal copy in the region.

        The bound is alpha |start - entry| (+ effort bound) + clip cost + heuristic from
        the exit: no path through the copy costs less. The tile id (node key // LOCAL) is
        the tile of the copy's entry keyframe, where its stitched edges start; the rest
        is what :meth:`through` bounds the copy by from a node."""
        out = []
        self.bin_culled = 0
        per_metre = self.per_metre
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

    def through(self, copies: list[tuple]) -> Callable[..., np.ndarray]:
        """``through(keys, fs, idx)`` of :class:`TraversalObserver` for ``copies`` of
        :meth:`traversal_estimates`: g of each node (f less its heuristic) + a lower bound
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
    through it (from the start, :meth:`SegmentGraph.traversal_estimates`), and the tile
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

    def __init__(
        self,
        copies: list[tuple],
        stitch_copy: Callable[[int, int], list[tuple]],
        across: list[int],
        up_front: bool = False,
        through: Callable[..., np.ndarray] | None = None,
    ) -> None:
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
        # tile id -> indices of its copies, for tiles not entered yet
        self.unseen: dict[int, list[int]] = {}
        # tile id -> ([keys], [fs]) of the nodes taken off in it
        self.taken: dict[int, tuple[list[int], list[float]]] = {}
        # heap of (estimate, copy index) of copies of entered tiles
        self.waiting: list[tuple[float, int]] = []
        # tile id -> indices of its copies with a bound, not stitched
        self.active: dict[int, np.ndarray] = {}
        self.due: list[tuple[float, int]] = []  # heap of (bound, copy index)
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

    def __call__(self, f: float, key: int) -> list[tuple] | tuple:
        """The stitched edges to add as the search takes node ``key`` off with ``f``."""
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
