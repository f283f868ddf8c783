"""A* over integer node keys with a binary heap of plain tuples.

Graph structure is supplied as a vectorised ``expand(key)`` returning numpy arrays of
successor keys, edge costs and an edge payload, so callers keep segments in arrays and
the search never builds per-node objects. Expansions are cached by the closed set, so a
node's successors (and the occlusion tests behind them) are computed once (Cain 2002).
"""

import heapq
from dataclasses import dataclass

import numpy as np

GOAL = -1  # key of the virtual goal node reached through ``goal_cost``
START = -2


@dataclass
class SearchResult:
    found: bool
    cost: float
    path: list          # [(key, payload)] from the first node to GOAL; payload of the edge into key
    expansions: int


def search(starts, expand, heuristic, goal_cost, max_expansions=500_000, observer=None):
    """Cheapest path from any of ``starts`` [(key, cost, payload)] to the virtual goal.

    ``expand(key) -> (keys, costs, payloads)``; ``heuristic(keys) -> h`` (admissible);
    ``goal_cost(key) -> (cost, payload) or None`` links a node to the goal.
    ``observer(f) -> [(from_key, to_key, cost, payload)]`` is called with the f of every
    popped node and may add edges (lazy stitching). It must add an edge before any node
    on a path through it could be popped, i.e. once ``f`` reaches a lower bound of such
    paths; edges out of nodes already expanded are relaxed at once.
    """
    g = {}
    parent = {}
    heap = []
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
    closed = set()
    expansions = 0
    best_goal = np.inf
    extra = {}
    while heap:
        f, _, key = heapq.heappop(heap)
        added = observer(f) if observer is not None else ()
        if added and key == GOAL:  # new edges may still beat the goal found so far
            heapq.heappush(heap, (f, tie, GOAL))
            tie += 1
        for a, b, c, p in added:
            if a not in closed:
                extra.setdefault(a, []).append((b, c, p))
            elif g[a] + c < g.get(b, np.inf) and b not in closed:
                g[b] = g[a] + c
                parent[b] = (a, p)
                heapq.heappush(heap, (g[b] + float(heuristic(np.array([b]))[0]), tie, b))
                tie += 1
        if key == GOAL and not added:
            break
        if key == GOAL or key in closed:
            continue
        closed.add(key)
        expansions += 1
        if expansions > max_expansions:
            break
        gk = g[key]
        link = goal_cost(key)
        if link is not None and gk + link[0] < best_goal:
            best_goal = gk + link[0]
            g[GOAL] = best_goal
            parent[GOAL] = (key, link[1])
            heapq.heappush(heap, (best_goal, tie, GOAL))
            tie += 1
        nkeys, ncosts, payloads = expand(key)
        if key in extra:
            more = extra.pop(key)
            nkeys = np.concatenate((nkeys, np.array([m[0] for m in more], np.int64)))
            ncosts = np.concatenate((ncosts, np.array([m[1] for m in more], float)))
            payloads = np.concatenate((payloads, np.array([m[2] for m in more], np.int64)))
        if len(nkeys) == 0:
            continue
        ng = gk + ncosts
        better = np.array([c < g.get(k, np.inf) for k, c in zip(nkeys.tolist(), ng.tolist())], bool)
        if not better.any():
            continue
        nkeys, ng, payloads = nkeys[better], ng[better], payloads[better]
        hs = heuristic(nkeys)
        for k, c, h, p in zip(nkeys.tolist(), ng.tolist(), hs.tolist(), payloads.tolist()):
            if k in closed or c >= g.get(k, np.inf):  # parallel edges: keep the cheapest
                continue
            g[k] = c
            parent[k] = (key, p)
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
