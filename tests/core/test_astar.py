# SPDX-License-Identifier: GPL-3.0-or-later
import heapq
import itertools

import numpy as np
import pytest

from motion_patches.planning import astar


def random_graph(rng, n, p):
    pos = rng.uniform(0, 10, size=(n, 2))
    edges = {}
    for a, b in itertools.permutations(range(n), 2):
        if rng.random() < p:
            edges.setdefault(a, []).append((b, np.linalg.norm(pos[a] - pos[b]) * rng.uniform(1, 2)))
    return pos, edges


def brute_force(starts, edges, goals, n):
    """Cheapest cost over every simple path (exhaustive enumeration)."""
    best = np.inf

    def walk(node, cost, seen):
        nonlocal best
        if cost >= best:
            return
        if node in goals:
            best = min(best, cost + goals[node])
        for b, c in edges.get(node, ()):
            if b not in seen:
                walk(b, cost + c, seen | {b})

    for s, c in starts:
        walk(s, c, {s})
    return best


def one_by_one(heuristic):
    """The per-key form of a vectorised heuristic (``astar.search``'s ``heuristic_of``)."""
    return lambda k: float(heuristic(np.array([k]))[0])


def expander(edges):
    """A search's successor function over ``edges`` {key: [(next key, cost)]}: (keys,
    costs, payloads), the payload being the next key."""

    def expand(k):
        out = edges.get(k, [])
        return (
            np.array([b for b, _ in out], np.int64),
            np.array([c for _, c in out]),
            np.array([b for b, _ in out], np.int64),
        )

    return expand


@pytest.mark.parametrize("per_key", (False, True))
@pytest.mark.parametrize("seed", range(25))
def test_astar_finds_the_brute_force_optimum(seed, per_key):
    rng = np.random.default_rng(seed)
    n = 9
    pos, edges = random_graph(rng, n, 0.3)
    goal_xy = pos[n - 1]
    goals = {n - 1: 0.0, n - 2: float(rng.uniform(0, 3))}
    starts = [(0, 0.0), (1, float(rng.uniform(0, 2)))]

    expand = expander(edges)

    def heuristic(keys):
        # Admissible: every edge costs at least its straight-line length; node n-2's link
        # to the goal may be cheaper than its distance, so use the smaller of both.
        d = np.linalg.norm(pos[keys] - goal_xy, axis=1)
        return np.minimum(d, np.linalg.norm(pos[keys] - pos[n - 2], axis=1))

    def goal_cost(k):
        return (goals[k], -1) if k in goals else None

    res = astar.search(
        [(s, c, -1) for s, c in starts],
        expand,
        heuristic,
        goal_cost,
        heuristic_of=one_by_one(heuristic) if per_key else None,
    )
    expected = brute_force(starts, edges, goals, n)
    if np.isinf(expected):
        assert not res.found
    else:
        assert res.found and np.isclose(res.cost, expected)
        # The returned path's edges add up to the reported cost.
        keys = [k for k, _ in res.path]
        start_cost = dict(starts)[keys[0]]
        total = start_cost + sum(dict(edges[a])[b] for a, b in zip(keys[:-2], keys[1:-1]))
        assert np.isclose(total + goals[keys[-2]], res.cost)


def test_astar_reports_no_path_when_goal_is_disconnected():
    def expand(k):
        return np.array([], np.int64), np.array([]), np.array([], np.int64)

    res = astar.search([(0, 0.0, -1)], expand, lambda k: np.zeros(len(k)), lambda k: None)
    assert not res.found and res.expansions == 1


# -- the observer: lazily added edges --------------------------------------------------
# Nodes are packed like the planner's: key = tile * LOCAL + local, three nodes per tile;
# a node with local 0 also lies in the next tile (like a node on a tile edge).

from motion_patches.patch.node_keys import LOCAL
from motion_patches.planning.planner import TraversalObserver

ACROSS = [1] + [0] * (LOCAL - 1)


def key_of(node):
    return (node // 3) * LOCAL + node % 3


def node_of(keys):
    keys = np.asarray(keys)
    return (keys // LOCAL) * 3 + keys % LOCAL


def dijkstra(starts, edges, n):
    dist = np.full(n, np.inf)
    heap = []
    for s, c in starts:
        if c < dist[s]:
            dist[s] = c
            heapq.heappush(heap, (c, s))
    while heap:
        d, a = heapq.heappop(heap)
        if d > dist[a]:
            continue
        for b, c in edges.get(a, ()):
            if d + c < dist[b]:
                dist[b] = d + c
                heapq.heappush(heap, (d + c, b))
    return dist


def lazy_problem(seed, n=12):
    """A random graph, some of its edges hidden (to be added by an observer), each with a
    tight estimate: the exact cost + heuristic of the best path through it."""
    rng = np.random.default_rng(seed)
    pos, edges = random_graph(rng, n, 0.25)
    goal_xy = pos[n - 1]
    goals = {n - 1: 0.0}
    starts = [(0, 0.0)]
    visible, hidden = {}, []
    for a, out in edges.items():
        for b, c in out:
            if rng.random() < 0.35:
                hidden.append((a, b, c))
            else:
                visible.setdefault(a, []).append((b, c))
    h = np.linalg.norm(pos - goal_xy, axis=1)  # consistent: edges cost >= their length
    g_full = dijkstra(starts, edges, n)
    estimates = [g_full[a] + c + h[b] for a, b, c in hidden]

    def expand(k):
        out = visible.get(int(node_of(k)), [])
        return (
            np.array([key_of(b) for b, _ in out], np.int64),
            np.array([c for _, c in out]),
            np.array([b for b, _ in out], np.int64),
        )

    def heuristic(keys):
        return h[node_of(keys)]

    def goal_cost(k):
        node = int(node_of(k))
        return (goals[node], -1) if node in goals else None

    problem = dict(
        starts=[(key_of(s), c, -1) for s, c in starts],
        expand=expand,
        heuristic=heuristic,
        goal_cost=goal_cost,
    )
    return (
        problem,
        hidden,
        estimates,
        brute_force(starts, edges, goals, n),
        brute_force(starts, visible, goals, n),
    )


def hidden_edges(hidden, which):
    return [(key_of(a), key_of(b), c, 1000 + e) for e, (a, b, c) in enumerate(hidden) if e in which]


def per_tile_observer(hidden, estimates, h=None):
    """The planner's observer over the hidden edges. With ``h`` (the heuristic per node)
    each edge's estimate is halved (still a lower bound, but a loose one, as the
    planner's straight-line estimates from the start are) and the observer is given the
    exact bound through the node an edge leaves (g + cost + h of its end; none through
    the other nodes of the tile), as the planner's bound through a node is."""
    copies = [
        (est if h is None else 0.5 * est, 0, e, key_of(a) // LOCAL)
        for e, ((a, _, _), est) in enumerate(zip(hidden, estimates))
    ]
    through = None
    if h is not None:
        src, dst, cost = (np.array(col) for col in zip(*hidden))

        def through(keys, fs, idx, below=None):
            nodes = node_of(keys)[:, None]
            g = np.asarray(fs)[:, None] - h[nodes]
            return np.where(src[idx] == nodes, g + cost[idx] + h[dst[idx]], np.inf)

    return TraversalObserver(
        copies, lambda _, e: hidden_edges(hidden, {e}), ACROSS, through=through
    )


def late_observer(hidden):
    """Adds every hidden edge when the goal first comes off: edges out of expanded nodes
    into expanded nodes, which only reopening can use."""
    done = []

    def observer(f, key):
        if key == astar.GOAL and not done:
            done.append(True)
            return hidden_edges(hidden, range(len(hidden)))
        return ()

    return observer


SEEDS = range(40)


@pytest.mark.parametrize("per_key", (False, True))
@pytest.mark.parametrize("seed", SEEDS)
def test_edges_added_by_observers_reach_the_brute_force_optimum(seed, per_key):
    problem, hidden, estimates, full, visible_only = lazy_problem(seed)
    if per_key:
        problem["heuristic_of"] = one_by_one(problem["heuristic"])
    h = problem["heuristic"](key_of(np.arange(12)))
    for observer in (
        per_tile_observer(hidden, estimates),
        per_tile_observer(hidden, estimates, h),
        late_observer(hidden),
    ):
        res = astar.search(observer=observer, **problem)
        if np.isinf(full):
            assert not res.found
        else:
            assert res.found and np.isclose(res.cost, full), (res.cost, full, visible_only)


def test_lazy_edges_matter_and_the_bound_through_a_node_adds_fewer():
    """Guards the test above from passing vacuously: hidden edges often make the optimum
    cheaper; and with the bound through the node an edge leaves, the observer adds fewer
    edges than with the (loose) estimates alone, never more."""
    cheaper = fewer = 0
    for seed in SEEDS:
        problem, hidden, estimates, full, visible_only = lazy_problem(seed)
        cheaper += full < visible_only - 1e-9
        h = problem["heuristic"](key_of(np.arange(12)))
        added = []
        for through in (None, h):
            loose = [0.5 * e for e in estimates]
            observer = per_tile_observer(hidden, loose if through is None else estimates, through)
            astar.search(observer=observer, **problem)
            added.append(observer.by_tile + observer.at_goal)
        assert added[1] <= added[0], seed
        fewer += added[1] < added[0]
    assert cheaper >= 10 and fewer >= 10, (cheaper, fewer)


def test_the_goal_backstop_adds_an_edge_no_node_reaches(monkeypatch):
    """A hidden edge whose bound lies between the last node taken off and the goal (the
    goal link costs more than its node's heuristic, as the planner's goal connectors
    do): only the backstop at the goal adds it; without it the search ends on the
    dearer path."""
    visible = {0: [(1, 10.0)]}
    problem = dict(
        starts=[(0, 0.0, -1)],
        expand=expander(visible),
        heuristic=lambda keys: np.zeros(len(keys)),
        goal_cost=lambda k: (2.0, -1) if k == 1 else None,
    )
    hidden = [(0, 1, 9.0)]

    def observer():
        copies = [(11.0, 0, 0, 0)]  # the exact cost through the hidden edge
        return TraversalObserver(copies, lambda _, e: hidden_edges(hidden, {e}), ACROSS)

    res = astar.search(observer=observer(), **problem)
    assert np.isclose(res.cost, 11.0)
    monkeypatch.setattr(TraversalObserver, "_backstop", lambda self, f: [])
    assert np.isclose(astar.search(observer=observer(), **problem).cost, 12.0)


@pytest.mark.parametrize("seed", range(10))
def test_observer_sees_each_expanded_node_once_with_its_f_then_the_goal(seed):
    rng = np.random.default_rng(seed)
    n = 10
    pos, edges = random_graph(rng, n, 0.35)
    h = np.linalg.norm(pos - pos[n - 1], axis=1)
    calls = []

    def observer(f, key):
        calls.append((f, key))
        return ()

    expand = expander(edges)

    res = astar.search(
        [(0, 0.0, -1)],
        expand,
        lambda k: h[k],
        lambda k: (0.0, -1) if k == n - 1 else None,
        observer=observer,
    )
    g = dijkstra([(0, 0.0)], edges, n)
    nodes = [k for _, k in calls if k != astar.GOAL]
    assert len(nodes) == len(set(nodes)) == res.expansions  # no stale entries reported
    for f, k in calls:
        if k != astar.GOAL:
            assert np.isclose(f, g[k] + h[k])
    fs = [f for f, _ in calls]
    assert all(a <= b + 1e-9 for a, b in zip(fs, fs[1:]))  # consistent h: f never drops
    if res.found:
        assert calls[-1] == (res.cost, astar.GOAL)
    else:  # out of nodes: the observer is still asked once, with f = inf, to open a way
        assert calls[-1] == (np.inf, astar.GOAL)


@pytest.mark.parametrize("seed", range(10))
def test_per_key_heuristic_searches_exactly_as_the_vectorised_one(seed):
    """Same expansions in the same order, same path: the one-by-one relaxation of
    ``heuristic_of`` is only a faster way of doing the same search."""
    rng = np.random.default_rng(100 + seed)
    n = 14
    pos, edges = random_graph(rng, n, 0.3)
    h = np.linalg.norm(pos - pos[n - 1], axis=1)

    expand = expander(edges)

    runs = []
    for per_key in (False, True):
        seen = []

        def observer(f, key, seen=seen):
            seen.append((round(f, 9), key))
            return ()

        res = astar.search(
            [(0, 0.0, -1)],
            expand,
            lambda k: h[k],
            lambda k: (0.0, -1) if k == n - 1 else None,
            observer=observer,
            heuristic_of=(lambda k: float(h[k])) if per_key else None,
        )
        runs.append((seen, res.path, res.cost, res.expansions))
    assert runs[0] == runs[1]
