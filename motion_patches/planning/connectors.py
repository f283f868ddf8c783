# SPDX-License-Identifier: GPL-3.0-or-later
"""Start and goal connectors: the character's start and goal joined to the node graph
(paper Sec. 4.2).

The joins are Dubins paths (:mod:`.dubins`) at a share of the gait's sharpest turn, then
at that turn itself, known to the search by a lower bound of their Eq. 5 cost and sampled
and tested only when it gets to them: the start ones played from the phase that makes
them end on the node pose, the goal ones ending on the exact goal position and heading.
The same words, measures and tests serve shortening (:mod:`.shortcut`).
"""

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from ..patch import curves
from ..patch.locomotion_patch import LocomotionPatch
from ..patch.synthesis import cycles_along, cycles_along_many
from ..props.environment import PATH_MARGIN, Environment
from ..props.object_patch import ObjectPatch
from . import dubins
from .pieces import FacingRefused, Piece, PlanError
from .segment_search import SegmentGraph

ANY_FACING = np.radians(np.arange(0, 360, 45))  # goal headings tried when any facing will do
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


class ConnectedGraph(SegmentGraph):
    """The segment graph with the start and goal joined to it by connectors, and the
    measures and tests of the curves walked off the lattice (connectors, shortcuts)."""

    def __init__(
        self,
        patch: LocomotionPatch,
        env: Environment,
        alpha: float,
        beta: float,
        gamma: float,
        props: Iterable[ObjectPatch] = (),
    ) -> None:
        super().__init__(patch, env, alpha, beta, gamma, props)
        # The search's start and goal connectors so far (:meth:`start_connectors`,
        # :meth:`goal_connectors`): tables of arrays, counts and caches by name.
        self._start_table: dict[str, Any] = {"valid": 0, "done": 0}
        self._goal_table: dict[str, Any] | None = None
        self._goal_links: dict[int, tuple[float, Callable[[], Piece]] | None] = {}
        self._goal_asked: list[int] = []

    # -- curves ------------------------------------------------------------------------
    def curve_cost(self, curve: curves.Curve, cycles_count: float) -> float:
        """Eq. 5 cost of following ``curve`` in ``cycles_count`` gait cycles."""
        frames = cycles_count * self.patch.gait.frames
        effort = self.patch.effort_rate * frames / self.patch.gait.fps
        return self.alpha * curve.length + self.beta * curve.total_turn() + self.gamma * effort

    def bends_within(self, curve: curves.Curve) -> bool:
        """The curve bends within the gait's curvature limits, between samples too."""
        # A curve turning at exactly the sharpest limit (a Dubins arc of that radius) reads
        # a hair over it in floating point: allow for rounding, not for more.
        tol = KAPPA_ROUNDING * max(-self.kmin, self.kmax)
        if curve.kappa.min() < self.kmin - tol or curve.kappa.max() > self.kmax + tol:
            return False
        return bool(
            curves.follows_turn_limits(curve.pos, curves.unit(curve.heading), self.kmin, self.kmax)
        )

    def valid(self, curve: curves.Curve) -> bool:
        """The curve bends within the gait's limits and keeps the radius from every
        footprint (every sample tested)."""
        return self.bends_within(curve) and not self.env.path_blocked(curve.pos[None])[0]

    def segment_curve(self, piece: Piece) -> curves.Curve:
        """A segment piece's curve in plan-frame coordinates."""
        c = self.patch.curve(piece.segment)
        return curves.Curve(
            c.s, c.pos + np.array(piece.tile, float) * self.patch.side, c.heading, c.kappa
        )

    def cycles(self, curve: curves.Curve) -> float:
        """Gait cycles (fractional) that following ``curve`` takes."""
        return float(cycles_along(self.patch.gait, curve.pos[None], *_derivs(curve))[0])

    def measure(self, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray) -> np.ndarray:
        """Gait cycles along sampled curves (the measure :func:`.curves.tabulate` fits)."""
        return cycles_along(self.patch.gait, pos, vel, acc)

    # -- connectors ----------------------------------------------------------------------
    def reset_start_links(self) -> None:
        """Forget the start links of the search before (a search beginning on a node asks
        for none)."""
        self._start_table = {"valid": 0, "done": 0}

    def goal_on_node(self, key: int) -> dict[int, int]:
        """The goal links of a search ending on node ``key`` instead of a goal connector:
        that node alone, with nothing more to walk."""
        self._goal_links = {}
        return {int(key): 0}

    @property
    def start_links_valid(self) -> int:
        """Valid start connectors the last search found."""
        return self._start_table["valid"]

    @property
    def start_nodes_tested(self) -> int:
        """Start nodes whose connectors the last search tested."""
        return self._start_table["done"]

    @property
    def goal_links_tested(self) -> int:
        """Nodes whose goal links the last search tested."""
        return len(self._goal_links)

    def start_connectors(self, start: np.ndarray) -> list[tuple[int, float]]:
        """[(key, bound)]: the entry nodes of the 3 x 3 tiles around the start a start
        connector may join, in the order the search takes them (bound + heuristic), each
        with a lower bound of its connector's Eq. 5 cost (its cheapest Dubins word's,
        :meth:`dubins_table`). The connectors themselves (:meth:`start_link`) are sampled
        and tested only when the search gets to them."""
        keys, p, h = self.entries(self.block(self.env.tile_of(start[:2])))
        table = self.dubins_table(
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

    def start_link(self, key: int) -> tuple[float, Callable[[], Piece]] | None:
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
            found = self.first_valids(
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

    def goal_connectors(self, goal: np.ndarray) -> dict[int, int]:
        """Goal links of the entry nodes of the 3 x 3 tiles around the goal: for each node
        the Dubins words into the goal, cheapest first (over ``ANY_FACING`` goal headings
        when the goal heading is NaN). Nothing is computed here: the words of a tile's
        nodes are tabled when the search first asks for the bound of one of them
        (:meth:`goal_bound`; a short plan asks for a few of the nine tiles), and only the
        links of the nodes it expands are sampled and tested (:meth:`goal_link`)."""
        keys, p, h = self.entries(self.block(self.env.tile_of(goal[:2])))
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
            cost, lens, radii, words, _ = self.dubins_table(
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

    def goal_bound(self, key: int) -> float | None:
        """A lower bound of the cost of node ``key``'s goal link (its cheapest Dubins word's
        Eq. 5 cost, :meth:`dubins_table`), or None for a node with no link."""
        t = self._goal_table
        assert t is not None, "goal_connectors tables the goal first"
        m = t["index"].get(key)
        if m is None:
            return None
        if not t["tiled"][m // t["per_tile"]]:
            self._goal_tiles([m])
        self._goal_asked.append(key)
        return float(t["bound"][m])

    def goal_link(self, key: int) -> tuple[float, Callable[[], Piece]] | None:
        """(cost, Piece maker) of the cheapest valid connector from node ``key`` into the
        goal, or None (tested once per node and cached). The links of up to
        ``GOAL_BATCH - 1`` other nodes the search has expanded are tested with it (they
        are likely asked for next)."""
        if key in self._goal_links:
            return self._goal_links[key]
        t = self._goal_table
        assert t is not None, "goal_connectors tables the goal first"
        if key not in t["index"]:
            return None
        batch = [key]
        while self._goal_asked and len(batch) < GOAL_BATCH:
            k = self._goal_asked.pop()
            if k not in self._goal_links and k not in batch:
                batch.append(k)
        m = np.array([t["index"][k] for k in batch])
        self._goal_tiles(m)
        found = self.first_valids(t["p"][m], t["h"][m], tuple(t["table"]), m)
        for k, got in zip(batch, found):
            link = None
            if got is not None:
                link = (
                    got[0],
                    lambda cost=got[0], make=got[2]: Piece("goal", curve=make(), cost=cost),
                )
            self._goal_links[k] = link
        return self._goal_links[key]

    def check_turning_room(self, what: str, state: np.ndarray) -> None:
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
            f"no {self.gait_name} can {way} {np.degrees(state[2] + self.frame_angle):.0f} "
            f"degrees: {names} stand(s) in the way within {APPROACH:.2f} m and the "
            f"{self.gait_name} cannot turn tighter than {1 / max(self.kmax, -self.kmin):.2f} m; "
            f"turn the {what} or move {'it' if len(hit) <= 1 else 'them'}"
            + (" (or plan with goal facing 'any')" if what == "goal" else "")
        )

    def refused(self, what: str, state: np.ndarray, said: str) -> PlanError:
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
            else f" facing {np.degrees(state[2] + self.frame_angle):.0f} degrees"
        )
        who = ", ".join(repr(n) for n in names[:4]) if names else "nothing near"
        return (
            f"the {self.gait_name} cannot {way}{facing} (it turns no tighter than "
            f"{1 / max(self.kmax, -self.kmin):.2f} m and keeps {self.env.radius:.2f} m from "
            f"props; within {reach:.1f} m: {who}); move or turn the {what}, or move those props"
            + (", or plan with goal facing 'any'" if what == "goal" else "")
        )

    @property
    def turn_radii(self) -> tuple[float, float]:
        """Radii of the Dubins arcs, in the order they are tried: a share of the sharpest
        turn the gait follows, then that sharpest turn itself (only where nothing wider
        fits: the tighter the turn, the more the planted feet slide)."""
        tight = 1.0 / min(-self.kmin, self.kmax)
        return (tight / DUBINS_CURVATURE_SHARE, tight)

    def dubins_table(
        self,
        p0: np.ndarray,
        h0: np.ndarray,
        p1: np.ndarray,
        h1: np.ndarray,
        max_length: float | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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

    def first_valid(
        self, p0: np.ndarray, h0: float, table: tuple, m: int, min_length: float = 0.0
    ) -> tuple[curves.Curve, float, float] | None:
        """(curve, Eq. 5 cost, gait cycles) of the first valid Dubins word of column ``m``
        of a :meth:`dubins_table` from state (p0, h0), or None."""
        found = self.first_valids(
            np.asarray(p0, float)[None], np.atleast_1d(h0), table, np.array([m]), min_length
        )[0]
        return None if found is None else (found[2](), found[0], found[1])

    def first_valids(
        self,
        p0: np.ndarray,
        h0: np.ndarray,
        table: tuple,
        columns: np.ndarray,
        min_length: float = 0.0,
        tries: int = DUBINS_TRIES,
        limit: int | None = None,
    ) -> list[tuple[float, float, Callable[[], curves.Curve]] | None]:
        """:meth:`first_valid` of many columns at once (start states ``p0`` (n, 2),
        ``h0`` (n,)): per column (Eq. 5 cost, gait cycles, a function making its curve) or
        None. The words of every column are tried in their order, ``tries`` per column at
        a time, their samples tested against the footprints together (as
        ``Environment.path_blocked`` does); the first clear word of a column must bend
        within the gait's limits (:meth:`bends_within`; a word at the wider radius does by
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
                clear[k] = ~self.samples_blocked(pos, first)
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
                    if wide_l[j] or self.bends_within(_dubins_curve(samples)):
                        chosen[i] = samples
                        break
                else:
                    if b0 - a0 == tries:  # more words down its order
                        rank[i] += tries
                        more.append(i)
            todo = more
        found: list[tuple[float, float, Callable[[], curves.Curve]] | None]
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
                # mypy cannot type a lambda with a default argument (the loop's part bound)
                found[i] = (c, n, lambda part=part: _dubins_curve(part))  # type: ignore[misc]
        return found

    def samples_blocked(self, pos: np.ndarray, first: np.ndarray) -> np.ndarray:
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


def _dubins_curve(
    samples: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> curves.Curve:
    """A :class:`~.curves.Curve` of a Dubins word from its samples (arc length, positions,
    headings, curvatures; :func:`.dubins.samples`), the curvature smoothed for blending."""
    arc, pos, heading, kappa = samples
    return curves.Curve(arc, pos, heading, dubins.smoothed(arc, kappa))


def _derivs(curve):
    """Finite-difference derivatives of a dense curve in its own sampling (for measures)."""
    vel = np.gradient(curve.pos, axis=0)
    acc = np.gradient(vel, axis=0)
    return vel[None], acc[None]
