import heapq
import itertools

import numpy as np
import pytest

from motion_patches import astar


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


@pytest.mark.parametrize("seed", range(25))
def test_astar_finds_the_brute_force_optimum(seed):
    rng = np.random.default_rng(seed)
    n = 9
    pos, edges = random_graph(rng, n, 0.3)
    goal_xy = pos[n - 1]
    goals = {n - 1: 0.0, n - 2: float(rng.uniform(0, 3))}
    starts = [(0, 0.0), (1, float(rng.uniform(0, 2)))]

    def expand(k):
        out = edges.get(k, [])
        return (np.array([b for b, _ in out], np.int64), np.array([c for _, c in out]),
                np.array([b for b, _ in out], np.int64))

    def heuristic(keys):
        # Admissible: every edge costs at least its straight-line length; node n-2's link
        # to the goal may be cheaper than its distance, so use the smaller of both.
        d = np.linalg.norm(pos[keys] - goal_xy, axis=1)
        return np.minimum(d, np.linalg.norm(pos[keys] - pos[n - 2], axis=1))

    def goal_cost(k):
        return (goals[k], -1) if k in goals else None

    res = astar.search([(s, c, -1) for s, c in starts], expand, heuristic, goal_cost)
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
