# SPDX-License-Identifier: GPL-3.0-or-later
"""Shortening a found path: runs of pieces replaced by one followed space curve.

The segment search (Sec. 4.2) finds the cheapest path through the lattice, but the lattice
only offers node positions on tile edges and 45-degree headings, so a path round a pillar
or through a gap zig-zags between them. After the search, a run of consecutive
locomotion pieces (start connector, segments, goal connector) is replaced by a single
cubic Hermite curve from the state where the run begins to the state where it ends, when
that curve bends within the gait's curvature limits, keeps the radius from every
footprint (its own samples tested exactly), and costs less by Eq. 5. The curve is followed
by space-curve following (paper Sec. 6) like any segment: a run ending on a node takes a
whole number of gait cycles (it ends on the node pose, so the next piece joins without a
pop); a run ending at the goal ends where the goal connector did. Traversal and
interaction clips and the segment parts that stitch them are never changed.
"""

import numpy as np

from ..patch import curves
from .connectors import ConnectedGraph
from .pieces import CONNECTOR_SCALES, Piece

MIN_GAIN = 1e-3  # a replacement must save at least this much Eq. 5 cost


def shorten(
    planner: ConnectedGraph, pieces: list[Piece], start: np.ndarray, goal: np.ndarray
) -> list[Piece]:
    """``pieces`` with runs of locomotion pieces replaced by cheaper single curves (plan
    frame coordinates; the planner's environment is that of the plan frame)."""
    out = list(pieces)
    i = 0
    while i < len(out) - 1:
        if not _locomotion(out[i]):
            i += 1
            continue
        end = i
        while end + 1 < len(out) and _locomotion(out[end + 1]):
            end += 1
        for j in range(end, i, -1):  # the longest run first
            run = out[i : j + 1]
            a = entry_state(planner, run[0])
            b = exit_state(planner, run[-1])
            to_goal = run[-1].kind == "goal"
            old_cost = sum(p.cost for p in run)
            free_length = to_goal or run[0].kind == "start"
            found = (
                _dubins(planner, a, b, old_cost) if free_length else _fit(planner, a, b, old_cost)
            )
            if found is not None:
                curve, cycles, cost = found
                kind = "goal" if to_goal else ("start" if run[0].kind == "start" else "shortcut")
                piece = Piece(kind, curve=curve, cycles=cycles, cost=cost)
                out[i : j + 1] = [piece]
                break
        i += 1
    return out


LOCOMOTION = ("start", "segment", "goal", "shortcut")  # pieces that walk (no clip)


def _locomotion(piece):
    return piece.kind in LOCOMOTION


def entry_state(planner: ConnectedGraph, piece: Piece) -> tuple[np.ndarray, float]:
    """(position, heading) where a piece begins (plan frame)."""
    if piece.curve is not None:
        return piece.curve.pos[0], float(piece.curve.heading[0])
    p0, d0, _, _ = planner.patch.endpoints(np.array([piece.segment]))
    return p0[0] + np.array(piece.tile, float) * planner.patch.side, float(
        np.arctan2(d0[0, 1], d0[0, 0])
    )


def exit_state(planner: ConnectedGraph, piece: Piece) -> tuple[np.ndarray, float]:
    """(position, heading) where a piece ends (plan frame)."""
    if piece.curve is not None:
        return piece.curve.pos[-1], float(piece.curve.heading[-1])
    _, _, p1, d1 = planner.patch.endpoints(np.array([piece.segment]))
    return p1[0] + np.array(piece.tile, float) * planner.patch.side, float(
        np.arctan2(d1[0, 1], d1[0, 0])
    )


def _chord_clear(planner, a, b):
    """The straight line between two states keeps the radius: a cheap first filter (a
    shortcut curve bends little off its chord, and one that cannot pass its chord rarely
    passes at all)."""
    n = max(2, int(np.ceil(np.linalg.norm(b - a) / 0.05)) + 1)
    t = np.linspace(0.0, 1.0, n)[:, None]
    return not planner.env.blocked(a[None] + t * (b - a)[None]).any()


def _worth_trying(planner, pa, pb, old_cost):
    d = np.linalg.norm(pb - pa)
    if d < 0.2 * planner.patch.gait.cycle_distance:
        return False
    bound = planner.alpha * d + planner.gamma * planner.patch.effort_rate * d / planner.max_speed
    return bound < old_cost - MIN_GAIN and _chord_clear(planner, pa, pb)


def _dubins(planner, a, b, old_cost):
    """(curve, cycles, cost) of the cheapest valid Dubins path from state ``a`` to state
    ``b`` costing less than ``old_cost`` (a start or goal run: any length will do)."""
    (pa, ha), (pb, hb) = a, b
    if not _worth_trying(planner, pa, pb, old_cost):
        return None
    table = planner.dubins_table(pa[None], np.array([ha]), pb[None], np.array([hb]))
    found = planner.first_valid(pa, ha, table, 0)
    if found is None or found[1] >= old_cost - MIN_GAIN:
        return None
    return found[0], found[2], found[1]


def _fit(planner, a, b, old_cost):
    """(curve, cycles, cost) of the cheapest valid Hermite curve of a whole number of gait
    cycles from node state ``a`` to node state ``b`` costing less than ``old_cost``."""
    (pa, ha), (pb, hb) = a, b
    if not _worth_trying(planner, pa, pb, old_cost):
        return None
    p0, d0 = pa[None], curves.unit(ha)[None]
    p1, d1 = pb[None], curves.unit(hb)[None]
    table = curves.tabulate(p0, d0, p1, d1, planner.measure, CONNECTOR_SCALES, samples=48)
    least = int(np.argmin(table[1][0]))
    centre = table[0][0, least]
    best = None
    for n in sorted(
        {int(np.floor(centre)), int(np.ceil(centre))} - {0}, key=lambda n: abs(n - centre)
    ):
        sc = curves.fit_scale(
            p0, d0, p1, d1, float(n), planner.measure, CONNECTOR_SCALES, samples=48, table=table
        )[0]
        if np.isnan(sc):
            continue
        c = curves.hermite_curve(pa, curves.unit(ha), pb, curves.unit(hb), sc)
        if not planner.valid(c):
            continue
        cost = planner.curve_cost(c, n)
        if cost < old_cost - MIN_GAIN and (best is None or cost < best[2]):
            best = (c, n, cost)
    return best


def long_last_piece(planner: ConnectedGraph, pieces: list[Piece]) -> list[Piece]:
    """The pieces with a goal connector shorter than a gait cycle merged with the
    walking pieces before it into one goal piece (one curve followed the same way), so
    the stop (:mod:`.retime`) has a cycle to slow down over."""
    out = list(pieces)
    need = planner.patch.gait.cycle_distance
    while len(out) > 1 and out[-1].kind == "goal":
        last = out[-1].curve
        assert last is not None, "a goal piece is a connector: it has its curve"
        if not (last.length < need and out[-2].kind in ("segment", "shortcut", "start")):
            break
        before = out[-2]
        c = before.curve if before.curve is not None else planner.segment_curve(before)
        merged = curves.joined(c, last)
        out[-2:] = [Piece("goal", curve=merged, cost=before.cost + out[-1].cost)]
    return out


PULL_SPACING = 0.2  # metres between the path points string pulling looks at
PULL_CLEARANCE = 0.05  # metres kept beyond the radius by pulled chords (room for the turns)
PULL_ENDS = 3  # where pulling may end: the goal, or the start of one of the last pieces


def pull_tail(planner: ConnectedGraph, pieces: list[Piece], goal: np.ndarray) -> list[Piece]:
    """``pieces`` with the walk after the last clip re-laid as one goal piece when that is
    cheaper: the found path's ground points are string-pulled (the farthest point whose
    chord keeps the radius and a margin, and so on) and the corners joined by Dubins paths
    through each corner along the bisector of its legs (or along a leg), every part tested
    exactly (:func:`_chain`). It ends at the goal, or where one of the last pieces begins
    (those are kept, followed on as the same curve); it begins where the walk begins, or
    where one of the first pieces ends (a start that turns round keeps its turn). The
    pulled path stays in the found path's corridor: the search chose the way round the
    props, pulling only straightens it. Plan frame coordinates."""
    first = len(pieces)
    while first > 0 and _locomotion(pieces[first - 1]):
        first -= 1
    run = pieces[first:]
    if len(run) < 2 or run[-1].kind != "goal":
        return pieces
    for begin in range(0, min(PULL_ENDS, len(run) - 1)):
        # Pull from the start of the run, else from where one of its first pieces ends
        # (those are kept: a start that must turn round keeps its turn).
        found = _pull(planner, run[begin:], goal)
        if found is not None:
            return pieces[: first + begin] + [found]
    return pieces


def _pull(planner, run, goal):
    """One goal piece re-laying ``run`` (see :func:`pull_tail`), or None."""
    old_cost = sum(p.cost for p in run)
    for q in range(len(run), max(len(run) - PULL_ENDS, 1) - 1, -1):
        # Pull to the goal itself, else to where one of the last pieces begins (that piece
        # and the ones after it are kept, followed on as the same curve).
        if q == len(run):
            pts, end_heading, tail = _resampled(planner, run, goal[:2]), float(goal[2]), []
        else:
            p_end, end_heading = entry_state(planner, run[q])
            pts, tail = _resampled(planner, run[:q], p_end), run[q:]
        corners = pts[_string_pull(planner.env, pts, planner.env.radius + PULL_CLEARANCE)]
        parts = _chain(planner, corners, entry_state(planner, run[0]), end_heading)
        if parts is None:
            continue
        parts += [p.curve if p.curve is not None else planner.segment_curve(p) for p in tail]
        curve = parts[0]
        for c in parts[1:]:
            curve = curves.joined(curve, c)
        cost = planner.curve_cost(curve, planner.cycles(curve))
        if cost < old_cost - MIN_GAIN:
            return Piece("goal", curve=curve, cost=cost)
    return None


def _resampled(planner, run, end):
    """Ground points of the pieces of ``run`` every ``PULL_SPACING`` metres, then ``end``."""
    pts = np.concatenate([_ground_points(planner, p) for p in run])
    s = np.concatenate(([0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))))
    if s[-1] > PULL_SPACING:
        at = np.arange(0.0, s[-1], PULL_SPACING)
        pts = np.column_stack((np.interp(at, s, pts[:, 0]), np.interp(at, s, pts[:, 1])))
    return np.vstack((pts, np.asarray(end, float)[None]))


def _chain(planner, corners, first, goal_heading, budget=60):
    """Dubins parts from state ``first`` through ``corners[1:]`` (the last is the goal, met
    facing ``goal_heading``), each corner passed along the bisector of its legs, or along
    either leg where that does not fit (a depth-first search over those choices, at most
    ``budget`` parts tried); None when no choice fits. The rest of a chain depends only on
    the corner and the heading it is passed at: one found not to fit is not tried again
    from the other ways into that corner."""
    tries = [0]
    dead = set()  # (corner, heading) from which no choice fits the rest

    def options(j):
        if j == len(corners) - 1:
            return [goal_heading]
        d_in, d_out = corners[j] - corners[j - 1], corners[j + 1] - corners[j]
        a_in, a_out = np.arctan2(d_in[1], d_in[0]), np.arctan2(d_out[1], d_out[0])
        turn = (a_out - a_in + np.pi) % (2 * np.pi) - np.pi
        return [float(a_in + turn / 2), float(a_out), float(a_in)]

    def solve(j, pa, ha):
        if j == len(corners):
            return []
        heads = [h for h in options(j) if (j + 1, h) not in dead][: max(budget - tries[0], 0)]
        if not heads:
            return None
        # The options of a corner are sampled and tested together, tried in order.
        n, pb = len(heads), corners[j]
        table = planner.dubins_table(
            np.tile(pa, (n, 1)),
            np.full(n, ha),
            np.tile(pb, (n, 1)),
            np.array(heads),
            max_length=np.inf,
        )
        found = planner.first_valids(np.tile(pa, (n, 1)), np.full(n, ha), table, np.arange(n))
        for hb, got in zip(heads, found):
            tries[0] += 1
            if got is None:
                continue
            rest = solve(j + 1, pb, hb)
            if rest is not None:
                return [got[2]()] + rest
            if tries[0] >= budget:
                return None
            dead.add((j + 1, hb))  # searched to the end (not cut short by the budget)
        return None

    return solve(1, first[0], first[1])


def _ground_points(planner, piece):
    if piece.curve is not None:
        return piece.curve.pos
    return (
        planner.patch.path_points()[piece.segment]
        + np.array(piece.tile, float) * planner.patch.side
    )


def _string_pull(env, pts, clearance, chunk=16):
    """Indices of the corners of the string-pulled polyline through ``pts`` (N, 2): from
    each corner the farthest point whose chord keeps ``clearance`` from every footprint
    (candidates tested farthest first, ``chunk`` chords at a time)."""
    corners, k, n = [0], 0, len(pts)
    while k < n - 1:
        nxt = k + 1
        for hi in range(n - 1, k, -chunk):
            m = np.arange(max(hi - chunk + 1, k + 1), hi + 1)
            length = np.linalg.norm(pts[m] - pts[k], axis=1)
            samples = max(int(np.ceil(length.max() / 0.05)) + 1, 2)
            t = np.linspace(0.0, 1.0, samples)[None, :, None]
            chords = pts[k][None, None] + t * (pts[m] - pts[k])[:, None]
            hit = (
                env.blocked(chords.reshape(-1, 2), radius=clearance).reshape(m.size, -1).any(axis=1)
            )
            clear = np.flatnonzero(~hit)
            if clear.size:
                nxt = int(m[clear.max()])
                break
        k = nxt
        corners.append(k)
    return corners
