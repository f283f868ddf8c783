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

from . import curves

MIN_GAIN = 1e-3  # a replacement must save at least this much Eq. 5 cost


def shorten(planner, pieces, start, goal):
    """``pieces`` with runs of locomotion pieces replaced by cheaper single curves (plan
    frame coordinates; the planner's environment is that of the plan frame)."""
    from .planner import Piece
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
            run = out[i:j + 1]
            a = _entry_state(planner, run[0])
            b = _exit_state(planner, run[-1])
            to_goal = run[-1].kind == "goal"
            old_cost = sum(p.cost for p in run)
            free_length = to_goal or run[0].kind == "start"
            found = (_dubins(planner, a, b, old_cost) if free_length
                     else _fit(planner, a, b, old_cost))
            if found is not None:
                curve, cycles, cost = found
                kind = "goal" if to_goal else ("start" if run[0].kind == "start" else "shortcut")
                piece = Piece(kind, curve=curve, cycles=cycles, cost=cost)
                out[i:j + 1] = [piece]
                break
        i += 1
    return out


def _locomotion(piece):
    return piece.kind in ("start", "segment", "goal", "shortcut")


def _entry_state(planner, piece):
    if piece.curve is not None:
        return piece.curve.pos[0], float(piece.curve.heading[0])
    p0, d0, _, _ = planner.patch.endpoints(np.array([piece.segment]))
    return p0[0] + np.array(piece.tile, float) * planner.patch.side, float(np.arctan2(d0[0, 1], d0[0, 0]))


def _exit_state(planner, piece):
    if piece.curve is not None:
        return piece.curve.pos[-1], float(piece.curve.heading[-1])
    _, _, p1, d1 = planner.patch.endpoints(np.array([piece.segment]))
    return p1[0] + np.array(piece.tile, float) * planner.patch.side, float(np.arctan2(d1[0, 1], d1[0, 0]))


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
    table = planner._dubins_table(pa[None], np.array([ha]), pb[None], np.array([hb]))
    found = planner._first_valid(pa, ha, table, 0)
    if found is None or found[1] >= old_cost - MIN_GAIN:
        return None
    return found[0], planner._cycles(found[0]), found[1]


def _fit(planner, a, b, old_cost):
    """(curve, cycles, cost) of the cheapest valid Hermite curve of a whole number of gait
    cycles from node state ``a`` to node state ``b`` costing less than ``old_cost``."""
    (pa, ha), (pb, hb) = a, b
    if not _worth_trying(planner, pa, pb, old_cost):
        return None
    p0, d0 = pa[None], curves.unit(ha)[None]
    p1, d1 = pb[None], curves.unit(hb)[None]
    from .planner import CONNECTOR_SCALES
    table = curves.tabulate(p0, d0, p1, d1, planner._measure, CONNECTOR_SCALES, samples=48)
    least = int(np.argmin(table[1][0]))
    centre = table[0][0, least]
    best = None
    for n in sorted({int(np.floor(centre)), int(np.ceil(centre))} - {0},
                    key=lambda n: abs(n - centre)):
        sc = curves.fit_scale(p0, d0, p1, d1, float(n), planner._measure, CONNECTOR_SCALES,
                              samples=48, table=table)[0]
        if np.isnan(sc):
            continue
        c = curves.hermite_curve(pa, curves.unit(ha), pb, curves.unit(hb), sc)
        if not planner._valid(c, exact=True):
            continue
        cost = planner._curve_cost(c, n)
        if cost < old_cost - MIN_GAIN and (best is None or cost < best[2]):
            best = (c, n, cost)
    return best
