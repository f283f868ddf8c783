# SPDX-License-Identifier: GPL-3.0-or-later
"""A* over integer node keys with a binary heap of plain tuples.

Graph structure is supplied as a vectorised ``expand(key)`` returning numpy arrays of
successor keys, edge costs and an edge payload, so callers keep segments in arrays and
the search never builds per-node objects. Expansions are cached by the closed set, so a
node's successors (and the occlusion tests behind them) are computed once (Cain 2002);
a node is expanded again only when an edge added late by the observer lowers its cost.
"""

import heapq
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

GOAL = -1  # key of the virtual goal node reached through ``goal_cost``
START = -2
# Entries of the open list that are not nodes: a start connector or a goal link whose cost
# is known only by a lower bound so far (code -3 - 2k: the goal link of node k; -4 - 2k:
# the start connector of node k).
_LAZY = -3


_INF = float("inf")


def _listed(a):
    """A list of the values of a numpy array or sequence."""
    return a.tolist() if hasattr(a, "tolist") else list(a)


@dataclass
class SearchResult:
    found: bool
    cost: float
    path: list  # [(key, payload)] from the first node to GOAL; payload of the edge into key
    expansions: int


def search(
    starts: Iterable[tuple[int, float, object]],
    expand: Callable[[int], tuple],
    heuristic: Callable[[np.ndarray], np.ndarray],
    goal_cost: Callable[[int], tuple[float, object] | None],
    max_expansions: int = 500_000,
    observer: Callable[[float, int], Iterable[tuple]] | None = None,
    lazy_starts: Sequence[tuple[int, float]] = (),
    start_cost: Callable[[int], tuple[float, object] | None] | None = None,
    goal_bound: Callable[[int], float | None] | None = None,
    heuristic_of: Callable[[int], float] | None = None,
) -> SearchResult:
    """Cheapest path from any of ``starts`` [(key, cost, payload)] to the virtual goal.

    ``expand(key) -> (keys, costs, payloads)`` (numpy arrays or lists); ``heuristic(keys)
    -> h`` (admissible, numpy arrays); ``goal_cost(key) -> (cost, payload) or None`` links
    a node to the goal. ``heuristic_of(key) -> float``, when given, is the same heuristic
    of one key (a table look-up, say): the inner loop then relaxes edges one by one in
    plain Python, with no numpy call per expansion (most expansions have a handful of
    successors, for which numpy's call overhead is most of the work).

    Costs that are dear to compute (the planner's connectors: curves sampled and tested)
    may be known by a lower bound first and computed only when the search gets to them
    (lazy edge evaluation): ``lazy_starts`` [(key, bound)] go on the open list with
    f = bound + h, and when one comes off, ``start_cost(key) -> (cost, payload) or None``
    gives its cost and the node goes on the list with it; with ``goal_bound(key) ->
    bound or None``, the goal link of an expanded node goes on the list with f = g +
    bound, and ``goal_cost`` is asked only when it comes off. A bound that is at most the
    cost keeps the result optimal: every entry that could lead to a cheaper path comes off
    before the goal does.

    ``observer(f, key) -> [(from_key, to_key, cost, payload)]`` may add edges (lazy
    stitching). It is called once for every node taken off the open list, just before
    the node is expanded, with its key and f = g + h (stale heap entries of nodes
    already expanded are skipped); with ``key == GOAL`` and f = the best goal cost found
    so far whenever the virtual goal comes off the list; and with ``key == GOAL`` and
    f = inf when the list runs empty without reaching the goal. Added edges are kept
    for the whole search: an edge out of a node not yet expanded joins its expansion;
    one out of an expanded node is relaxed at once, and a node whose cost it lowers is
    reopened and expanded again, so edges may come late. If edges are added at a GOAL
    call, the goal goes back on the list and the search goes on: it ends only when a
    GOAL call adds nothing. The result is then optimal over every edge the observer
    could add provided that, at that last call, it has added every edge lying on a path
    cheaper than f (e.g. every edge whose lower bound of cost + heuristic of the paths
    through it is <= f).
    """
    g: dict[int, float] = {}
    parent: dict[int, tuple[int, object]] = {}  # key -> (parent key, payload of the edge)
    heap: list[tuple[float, int, int]] = []  # (f, tie, key)
    tie = 0
    for key, cost, payload in starts:
        if cost < g.get(key, np.inf):
            g[key] = cost
            parent[key] = (START, payload)
    keys = np.fromiter(g.keys(), dtype=np.int64, count=len(g))
    if keys.size:
        for k, h in zip(keys.tolist(), heuristic(keys).tolist()):
            heapq.heappush(heap, (g[k] + h, tie, k))
            tie += 1
    h_of: dict[int, float] = {}  # heuristic of the nodes of lazy starts
    if len(lazy_starts):
        lazy = np.array([k for k, _ in lazy_starts], np.int64)
        for (k, bound), h in zip(lazy_starts, heuristic(lazy).tolist()):
            h_of[k] = h
            heap.append((bound + h, tie, _LAZY - 1 - 2 * k))
            tie += 1
        heapq.heapify(heap)  # the same order of pops as pushing them one by one
    closed: set[int] = set()
    expansions = 0
    best_goal = np.inf
    # from_key -> [(to_key, cost, payload)] added by the observer
    extra: dict[int, list[tuple[int, float, object]]] = {}
    heappop, push, gget, discard, inf = heapq.heappop, heapq.heappush, g.get, closed.discard, _INF
    while heap or observer is not None:
        if heap:
            f, _, key = heappop(heap)
        else:  # every reachable node expanded: the observer may still open a way
            f, key = np.inf, GOAL
        if key <= _LAZY:  # a connector known by its bound so far: its cost now
            k, is_start = divmod(_LAZY - key, 2)
            if is_start:
                assert start_cost is not None, "lazy_starts need start_cost"
                got = start_cost(k)
                if got is not None and got[0] < g.get(k, np.inf):
                    g[k] = got[0]
                    parent[k] = (START, got[1])
                    closed.discard(k)
                    heapq.heappush(heap, (got[0] + h_of[k], tie, k))
                    tie += 1
            else:
                link = goal_cost(k)
                if link is not None and g[k] + link[0] < best_goal:
                    best_goal = g[k] + link[0]
                    g[GOAL] = best_goal
                    parent[GOAL] = (k, link[1])
                    heapq.heappush(heap, (best_goal, tie, GOAL))
                    tie += 1
            continue
        if key in closed:  # a stale entry: the node was reached more cheaply since
            continue
        added = observer(f, key) if observer is not None else ()
        if added and key == GOAL:  # new edges may still beat the goal found so far
            heapq.heappush(heap, (f, tie, GOAL))
            tie += 1
        for a, b, c, p in added:
            extra.setdefault(a, []).append((b, c, p))
            if a in closed and g[a] + c < g.get(b, np.inf):
                g[b] = g[a] + c
                parent[b] = (a, p)
                closed.discard(b)  # reopen: its successors may get cheaper too
                hb = (
                    heuristic_of(b)
                    if heuristic_of is not None
                    else float(heuristic(np.array([b]))[0])
                )
                heapq.heappush(heap, (g[b] + hb, tie, b))
                tie += 1
        if key == GOAL:
            if not added:
                break
            continue
        closed.add(key)
        expansions += 1
        if expansions > max_expansions:
            break
        gk = g[key]
        if goal_bound is not None:
            link_bound = goal_bound(key)
            if link_bound is not None and gk + link_bound < best_goal:
                heapq.heappush(heap, (gk + link_bound, tie, _LAZY - 2 * key))
                tie += 1
            link = None
        else:
            link = goal_cost(key)
        if link is not None and gk + link[0] < best_goal:
            best_goal = gk + link[0]
            g[GOAL] = best_goal
            parent[GOAL] = (key, link[1])
            heapq.heappush(heap, (best_goal, tie, GOAL))
            tie += 1
        nkeys, ncosts, payloads = expand(key)
        more = extra.get(key)
        if heuristic_of is not None:
            if type(nkeys) is list:
                ks, cs, ps = nkeys, ncosts, payloads
            else:
                ks, cs, ps = _listed(nkeys), _listed(ncosts), _listed(payloads)
            if more:
                ks = ks + [m[0] for m in more]
                cs = cs + [m[1] for m in more]
                ps = ps + [m[2] for m in more]
            for k, c, p in zip(ks, cs, ps):
                c += gk
                if c < gget(k, inf):  # parallel edges: the cheapest wins
                    g[k] = c
                    parent[k] = (key, p)
                    discard(k)  # only after a late edge: with a consistent h, never closed
                    push(heap, (c + heuristic_of(k), tie, k))
                    tie += 1
            continue
        if more:
            nkeys = np.concatenate((nkeys, np.array([m[0] for m in more], np.int64)))
            ncosts = np.concatenate((ncosts, np.array([m[1] for m in more], float)))
            payloads = np.concatenate((payloads, np.array([m[2] for m in more], np.int64)))
        if len(nkeys) == 0:
            continue
        ng = (gk + ncosts).tolist()
        better = [i for i, (k, c) in enumerate(zip(nkeys.tolist(), ng)) if c < g.get(k, np.inf)]
        if not better:
            continue
        if len(better) < len(ng):
            nkeys, payloads = nkeys[better], payloads[better]
            ng = [ng[i] for i in better]
        hs = heuristic(nkeys)
        for k, c, h, p in zip(nkeys.tolist(), ng, hs.tolist(), payloads.tolist()):
            if c >= g.get(k, np.inf):  # parallel edges: keep the cheapest
                continue
            g[k] = c
            parent[k] = (key, p)
            closed.discard(k)  # only after a late edge: with a consistent h, never closed
            heapq.heappush(heap, (c + h, tie, k))
            tie += 1
    if GOAL not in parent:
        return SearchResult(False, np.inf, [], expansions)
    path = []
    k = GOAL
    while k != START:
        prev, payload = parent[k]
        path.append((k, payload))
        k = prev
    path.reverse()
    return SearchResult(True, g[GOAL], path, expansions)
