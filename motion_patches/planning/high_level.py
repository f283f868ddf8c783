# SPDX-License-Identifier: GPL-3.0-or-later
"""High-level planning over tiles (paper Sec. 4.1, Eq. 1 and 4).

A state is a tile and the edge it was entered by. Crossing the tile from edge j to edge k
costs ``lambda * max(upsilon_jk, tau_jk) ** -omega``: the tile's length, growing as the
tile gets less likely to be passable. The avoidance probability upsilon_jk is estimated
from an evenly spaced sample of the patch's j->k segments tested against the tile's
free-cell bitfield (not every segment); it and the traversal probability tau_jk (supplied
by object patches) are computed lazily, the first time a tile is expanded.
"""

import heapq
from collections.abc import Callable

import numpy as np

from ..patch.locomotion_patch import LocomotionPatch, split_node_id
from ..props.environment import Environment

STEP = {0: (0, -1), 1: (1, 0), 2: (0, 1), 3: (-1, 0)}  # exit edge -> neighbour offset
OPPOSITE = {0: 2, 1: 3, 2: 0, 3: 1}
_State = tuple[tuple[int, int], int]  # (tile, edge it was entered by; -1: the start's)
SAMPLES = 16  # segments sampled per (entry edge, exit edge) for upsilon


def edge_samples(
    patch: LocomotionPatch, samples: int = SAMPLES
) -> dict[tuple[int, int], np.ndarray]:
    """{(j, k): segment indices}, an evenly spaced sample of the segments from j to k."""
    e0, _, _ = split_node_id(patch.seg_entry, patch.nodes)
    e1, _, _ = split_node_id(patch.seg_exit, patch.nodes)
    out = {}
    for j in range(4):
        for k in range(4):
            idx = np.flatnonzero((e0 == j) & (e1 == k))
            if idx.size:
                take = np.unique(
                    np.linspace(0, idx.size - 1, min(samples, idx.size)).round().astype(int)
                )
                out[(j, k)] = idx[take]
    return out


class TilePlanner:
    """A* over tiles with lazily computed avoidance (and traversal) probabilities."""

    def __init__(
        self,
        patch: LocomotionPatch,
        env: Environment,
        omega: float = 1.0,
        traversal: Callable[[tuple[int, int]], np.ndarray] | None = None,
    ) -> None:
        self.patch, self.env, self.omega = patch, env, float(omega)
        self.samples = edge_samples(patch)
        self.traversal = traversal  # callable(tile) -> (4, 4) tau, or None
        self._upsilon: dict[tuple[int, int], np.ndarray] = {}  # tile -> upsilon, computed once
        self.tiles_evaluated = 0

    def upsilon(self, tile: tuple[int, int]) -> np.ndarray:
        """(4, 4) avoidance probabilities of a tile, computed on first use."""
        u = self._upsilon.get(tile)
        if u is None:
            self.tiles_evaluated += 1
            free = self.env.free_cells(tile)
            u = np.zeros((4, 4))
            for (j, k), segs in self.samples.items():
                m = self.patch.seg_mask[segs]
                u[j, k] = np.mean((m & free) == m)
            self._upsilon[tile] = u
        return u

    def passability(self, tile: tuple[int, int]) -> np.ndarray:
        """(4, 4) max(upsilon, tau) of a tile: the likelier way through it, j to k."""
        u = self.upsilon(tile)
        if self.traversal is not None:
            u = np.maximum(u, self.traversal(tile))
        return u

    def edge_cost(self, tile: tuple[int, int], j: int | None, k: int) -> float:
        """Eq. 4; infinite when neither avoidance nor traversal can pass (``j`` None: the
        start's tile, entered by no edge)."""
        p = self.passability(tile)
        pjk = p[j, k] if j is not None else p[:, k].max()
        if pjk <= 0:
            return np.inf
        return self.patch.side * pjk ** (-self.omega)

    def plan(
        self,
        start_xy: np.ndarray,
        goal_xy: np.ndarray,
        region: tuple[int, int, int, int] | None = None,
        max_expansions: int = 100_000,
    ) -> list[tuple[int, int]] | None:
        """Tiles from the start's tile to the goal's tile, or None when none is passable."""
        side = self.patch.side
        goal = np.asarray(goal_xy, float)
        ts, tg = self.env.tile_of(start_xy), self.env.tile_of(goal_xy)

        def h(tile):  # Eq. 1
            centre = (np.asarray(tile) + 0.5) * side
            return float(np.linalg.norm(goal - centre))

        start: _State = (ts, -1)
        g = {start: 0.0}
        parent: dict[_State, _State | None] = {start: None}
        heap = [(h(ts), 0, start)]
        tie = 1
        closed: set[_State] = set()
        while heap and len(closed) < max_expansions:
            _, _, state = heapq.heappop(heap)
            if state in closed:
                continue
            closed.add(state)
            tile, j = state
            if tile == tg:
                path = []
                at: _State | None = state
                while at is not None:
                    path.append(at[0])
                    at = parent[at]
                return path[::-1]
            for k in range(4):
                if k == j:
                    continue
                cost = self.edge_cost(tile, None if j < 0 else j, k)
                if not np.isfinite(cost):
                    continue
                nt = (tile[0] + STEP[k][0], tile[1] + STEP[k][1])
                if region is not None and not (
                    region[0] <= nt[0] <= region[2] and region[1] <= nt[1] <= region[3]
                ):
                    continue
                ns = (nt, OPPOSITE[k])
                c = g[state] + cost
                if c < g.get(ns, np.inf):
                    g[ns] = c
                    parent[ns] = state
                    heapq.heappush(heap, (c + h(nt), tie, ns))
                    tie += 1
        return None
