# SPDX-License-Identifier: GPL-3.0-or-later
"""Gait changes inside one plan (paper Sec. 5): walk, blend into a run, run, blend back.

The paper plans each layer on its own lattice and joins the layers through the blend
table. A plan that changes layer is composed here of per-layer legs joined at
transitions::

    walk leg (start -> walk node A) + blend walk->run (A -> B)
    + run leg (B -> run node C) + blend run->walk (C -> D) + walk leg (D -> goal)

Each blend is the blend table's entry from the node pose (:func:`.blend_table.from_node`:
segments end on that pose, so a leg ending on a node can be blended from), placed by
concatenating the state where it begins with the entry's relative root transform. The
leg after a blend is searched on a lattice of its layer laid so that the blend's end is
one of its nodes (the plan frame is free, :mod:`.plan_frame`): the transition lands on a
node of the target layer in that layer's node pose, and the leg's segments start there.

Candidate switch points come from the run plan: its run nodes before its first traversal
(where a run would have to start) and, on each run leg, the run nodes after its last
traversal (where it may stop, :func:`_stops`); a blend into the run starts on the walk
node nearest the point the blend must start from to reach that run node. Every
composition is scored by the sum of the Eq. 5 costs of its legs and blends (a blend costs
alpha x its length + gamma x its seconds x the mean of the two layers' effort rates: it
goes straight); legs are searched best first by a lower bound of that sum, and the
cheapest composition competes with the walk-only and run-only plans (the caller's
choice). Only walk -> run -> walk is composed: a plan starting or ending in the run is
the run-only plan.
"""

import contextlib
import heapq
import time
from collections.abc import Iterator
from dataclasses import dataclass, fields

import numpy as np

from ..kinematics import retime
from ..kinematics.motion import Motion
from ..patch.blend_table import Transition, from_node
from ..patch.locomotion_patch import LocomotionPatch
from ..patch.node_keys import unpack
from ..quality import validate
from . import shortcut
from .motions import hips_to, plan_motions
from .pieces import Piece, Plan, PlanError
from .plan_frame import state_to_local, to_world
from .planner import SegmentPlanner

SWITCH_CANDIDATES = 3  # run nodes tried on each side of the run plan's traversals
WALK_NODES_PER_SWITCH = 2  # walk nodes tried for each run node the blend must reach
CLIPS = ("traversal", "interaction")


@dataclass
class LayerPiece(Piece):
    """A piece of a plan that changes layer: it knows the locomotion patch it walks in
    (segment indices are per patch); a "transition" piece carries its blend table entry
    and is placed by ``frame``, the world state where the blend begins."""

    patch: LocomotionPatch | None = None
    transition: Transition | None = None

    @property
    def label(self) -> str:
        if self.kind == "transition":
            assert self.transition is not None, "a transition piece has its blend"
            return f"{self.transition.source} -> {self.transition.target}"
        base = super().label
        if self.kind in CLIPS:
            return base
        assert self.patch is not None, "a layer piece has its patch"
        return f"{self.patch.layer} {base}"


def piece_layer(piece: Piece, layer: str) -> str:
    """What a piece plays, for reports: its layer (``layer`` for a piece of a one-layer
    plan), "walk -> run" for a blend, "clip" for a traversal or interaction clip."""
    if piece.kind in CLIPS:
        return "clip"
    if piece.kind == "transition":
        return piece.label
    own = getattr(piece, "patch", None)
    return own.layer if own is not None else layer


def layered(piece: Piece, patch: LocomotionPatch) -> LayerPiece:
    """``piece`` as a :class:`LayerPiece` of ``patch``'s layer."""
    return LayerPiece(**{f.name: getattr(piece, f.name) for f in fields(Piece)}, patch=patch)


def transition_cost(t: Transition, planner_a: SegmentPlanner, planner_b: SegmentPlanner) -> float:
    """Eq. 5 cost of a blend table entry ``t`` from ``planner_a``'s layer into
    ``planner_b``'s (weights of ``planner_a``): it goes straight (no turn); its effort is its
    seconds x the mean effort rate of the two layers (the blend weight's mean is one half)."""
    g = t.motion.ground
    length = float(np.linalg.norm(np.diff(g[:, :2], axis=0), axis=1).sum())
    seconds = (t.frames - 1) / planner_a.patch.gait.fps
    rate = 0.5 * (planner_a.patch.effort_rate + planner_b.patch.effort_rate)
    return planner_a.alpha * length + planner_a.gamma * rate * seconds


def after(state: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The world state reached from ``state`` (x, y, heading) by a relative transform."""
    x, y, h = (float(v) for v in state)
    c, s = np.cos(h), np.sin(h)
    return np.array(
        [x + c * offset[0] - s * offset[1], y + s * offset[0] + c * offset[1], h + offset[2]]
    )


def before(state: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The world state from which the relative transform ``offset`` reaches ``state``."""
    h = float(state[2]) - float(offset[2])
    c, s = np.cos(h), np.sin(h)
    return np.array(
        [
            state[0] - (c * offset[0] - s * offset[1]),
            state[1] - (s * offset[0] + c * offset[1]),
            h,
        ]
    )


def _world(frame, p, h):
    return np.array([*to_world(frame, np.asarray(p, float)), float(h) + frame[2]])


def _distance(a, b):
    return float(np.hypot(b[0] - a[0], b[1] - a[1]))


def _wrap(a):
    return (np.asarray(a, float) + np.pi) % (2 * np.pi) - np.pi


@contextlib.contextmanager
def on_node(
    planner: SegmentPlanner, state: np.ndarray, goal: np.ndarray, margin_tiles: int = 3
) -> Iterator[tuple[np.ndarray, int, np.ndarray, tuple[float, float, float]]]:
    """The planner framed (:meth:`~.planner.SegmentPlanner.framed`) so that world
    ``state`` is a node of its lattice: the middle node of tile (0, 0)'s west edge, heading
    along +x. Yields (local state, its node key, local goal, frame); the frame holds the
    props within reach of ``goal`` too."""
    side = planner.patch.side
    h = float(state[2])
    u = np.array([np.cos(h), np.sin(h)])
    reach = float(np.linalg.norm(np.asarray(goal[:2], float) - np.asarray(state[:2], float)))
    # lattice_frame puts its start in the middle of tile (0, 0), half a side from the west
    # edge, and turns +x to its goal: start half a side ahead, goal straight on.
    s2 = np.asarray(state[:2], float) + 0.5 * side * u
    g2 = s2 + max(reach, side) * u
    extra = int(np.ceil(reach / side)) + 1
    with planner.framed(np.r_[s2, h], np.r_[g2, h], margin_tiles + extra) as (_, _, frame):
        local = state_to_local(frame, state)
        local[2] = float(_wrap(local[2]))
        key = planner.node_key(local[:2], local[2])
        yield local, key, state_to_local(frame, goal), frame


def _entries_before(planner, plan):
    """World states of the run nodes where the pieces before ``plan``'s first traversal
    begin (segments, and the part of a segment walked into a clip)."""
    out = []
    for p in plan.pieces:
        if p.kind == "traversal":
            break
        if p.kind == "segment" or (p.kind == "part" and p.frames[0] == 0):
            pos, h = shortcut.entry_state(planner, p)
            out.append(_world(p.frame, pos, h))
    return out


def _stops(planner, pieces):
    """Candidate runs up to a node where the run may blend back into the walk, after the
    last traversal of ``pieces`` (a run leg, unshortened, in the planner's frame): the
    pieces up to each segment after it, up to the segment part leaving the clip when it
    holds a whole run cycle, and up to each of the ``SWITCH_CANDIDATES`` cheapest run
    segments (cost + heuristic) out of that part's end node. A part shorter than a cycle
    is all ease off the clip's landing (a standing jump lands on both feet), not a run's
    stride: blended from at once, foot locking pins the landing feet into the blend (a 31
    degree knee step after 16_06's 8-frame landing part)."""
    last = max(i for i, p in enumerate(pieces) if p.kind == "traversal")
    out = []
    for i in range(last + 1, len(pieces)):
        p = pieces[i]
        if p.kind == "segment":
            out.append(list(pieces[: i + 1]))
        elif p.kind == "part" and p.frames[0] > 0:
            if p.frames[1] - p.frames[0] >= planner.patch.gait.frames:
                out.append(list(pieces[: i + 1]))
            key = planner.node_key(*shortcut.exit_state(planner, p))
            nxt, costs, segs = planner.expand(key)
            rank = np.argsort(costs + planner.heuristic(nxt), kind="stable")[:SWITCH_CANDIDATES]
            ti, tj, _ = unpack(key)
            for m in rank.tolist():
                seg = int(segs[m])
                step = Piece(
                    "segment",
                    segment=seg,
                    tile=(int(ti), int(tj)),
                    cycles=int(planner.patch.seg_cycles[seg]),
                    cost=float(costs[m]),
                )
                out.append([*pieces[: i + 1], step])
    return out[: 2 * SWITCH_CANDIDATES]


def _nearest_nodes(planner, local, count):
    """[(key, position, heading)] of the ``count`` nodes of the planner's (framed) lattice
    nearest the local state ``local`` with its heading."""
    keys, pos, head = planner.entries(planner.block(planner.env.tile_of(local[:2])))
    d = np.linalg.norm(pos - local[:2], axis=1)
    d[np.abs(_wrap(head - local[2])) > 1e-6] = np.inf
    order = [m for m in np.argsort(d, kind="stable")[:count] if np.isfinite(d[m])]
    return [(int(keys[m]), pos[m], float(head[m])) for m in order]


def _blend_clear(planner, t, state):
    """The ground path of blend ``t`` begun at world ``state`` keeps the radius."""
    g = t.motion.transformed(*state).ground[:, :2]
    return not planner.world_env.path_blocked(g[None])[0]


def compose(
    walk: SegmentPlanner,
    run: SegmentPlanner,
    start: np.ndarray,
    goal: np.ndarray,
    margin_tiles: int = 3,
    max_expansions: int = 400_000,
) -> Plan:
    """The cheapest plan from ``start`` to ``goal`` (world x, y, heading) that walks, blends
    into a run, runs (taking the run layer's traversals), and blends back to walk before
    the goal; ``walk`` and ``run`` are :class:`~.planner.SegmentPlanner` of the two layers
    on the same props (each with its own tiles). Its pieces are :class:`LayerPiece`;
    ``stats`` names the legs and transitions. Raises PlanError when no composition is
    found (the run plan takes no traversal, no blend fits, ...), saying why."""
    t0 = time.perf_counter()
    start, goal = np.asarray(start, float), np.asarray(goal, float)
    wg, rg = walk.patch.gait, run.patch.gait
    if wg.skeleton.names != rg.skeleton.names or abs(wg.fps - rg.fps) > 1e-6:
        raise PlanError(
            f"layers '{walk.patch.layer}' and '{run.patch.layer}' differ in skeleton or frame "
            f"rate: no blend between them"
        )
    if not any(p.traversals() for p in run.world_props):
        raise PlanError(
            f"no prop offers a {run.patch.layer} traversal clip: nothing to change gait for"
        )
    wr, rw = from_node(walk.patch, run.patch), from_node(run.patch, walk.patch)
    c_wr, c_rw = transition_cost(wr, walk, run), transition_cost(rw, run, walk)
    ref = run.plan(start, goal, margin_tiles, max_expansions, shorten=False, turn_in_place=False)
    expansions = ref.expansions
    switches = _entries_before(run, ref)[-SWITCH_CANDIDATES:]
    if not any(p.kind == "traversal" for p in ref.pieces) or not switches:
        raise PlanError(
            f"the {run.patch.layer} plan takes no traversal clip with a "
            f"{run.patch.layer} node before it: nothing to change gait for"
        )
    # 1. Walk legs into the blends: from the start to a walk node from which the blend
    #    reaches (about) a run node of the run plan.
    firsts = []
    with walk.framed(start, goal, margin_tiles) as (ls, _, fw):
        tried: dict[int, tuple[np.ndarray, float]] = {}  # node -> its position, heading
        for b in switches:
            a = state_to_local(fw, before(b, wr.offset))
            for key, p, h in _nearest_nodes(walk, a, WALK_NODES_PER_SWITCH):
                tried.setdefault(key, (p, h))
        for key, (p, h) in tried.items():
            a_local = np.r_[p, h]
            a_world = _world(fw, p, h)
            if not _blend_clear(walk, wr, a_world):
                continue
            leg = _search(walk, ls, a_local, margin_tiles, max_expansions, goal_key=key)
            if leg is None:
                continue
            expansions += leg.expansions
            pieces = shortcut.shorten(walk, leg.pieces, ls, a_local)
            for pc in pieces:
                pc.frame = fw
            firsts.append((float(sum(pc.cost for pc in pieces)), a_world, pieces))
    # 2. Run legs from each blend's end (a run node by construction) on to the goal, and
    # 3. the ways back: from run nodes after the run leg's last traversal, a blend into
    #    the walk and a walk leg from its end (a walk node by construction) to the goal.
    #    Best first: run legs and ways back are searched in the order of a lower bound of
    #    the total they can give (the legs known so far, both blends, and a heuristic cost
    #    per metre for the rest of the way), until the next bound reaches the best total.
    per_metre = min(walk.per_metre, run.per_metre)
    queue: list[tuple[float, int, tuple[float, list[Piece], tuple] | None]] = [
        (cost1 + c_wr + c_rw + per_metre * _distance(after(a_world, wr.offset), goal), n, None)
        for n, (cost1, _, _) in enumerate(firsts)
    ]
    heapq.heapify(queue)
    best, tried_count, run_legs, bounded, count = None, 0, 0, 0, len(queue)
    while queue:
        bound, n, stop = heapq.heappop(queue)
        if best is not None and bound >= best[0]:
            break
        if stop is None:  # a run leg to search: its ways back join the queue
            cost1, a_world, pieces1 = firsts[n]
            b_world = after(a_world, wr.offset)
            if run.world_env.blocked(b_world[None, :2])[0]:
                continue
            with on_node(run, b_world, goal, margin_tiles) as (bl, bkey, gl, fb):
                leg = _search(run, bl, gl, margin_tiles, max_expansions, start_key=bkey)
                if leg is None:
                    continue
                expansions += leg.expansions
                run_legs += 1
                if not any(p.kind == "traversal" for p in leg.pieces):
                    continue
                run.goal = gl  # the heuristic's goal (on_node framed towards a point ahead)
                for prefix in _stops(run, leg.pieces):
                    cp, ch = shortcut.exit_state(run, prefix[-1])
                    prefix = shortcut.shorten(run, prefix, bl, np.r_[cp, ch])
                    c_world = _world(fb, cp, ch)
                    d_world = after(c_world, rw.offset)
                    if (
                        not _blend_clear(run, rw, c_world)
                        or walk.world_env.blocked(d_world[None, :2])[0]
                    ):
                        continue
                    partial = cost1 + c_wr + sum(p.cost for p in prefix) + c_rw
                    head = [
                        *(layered(p, walk.patch) for p in pieces1),
                        _transition(wr, run.patch, a_world, c_wr),
                        *(_framed(layered(p, run.patch), fb) for p in prefix),
                        _transition(rw, walk.patch, c_world, c_rw),
                    ]
                    count += 1
                    bounded += 1
                    heapq.heappush(
                        queue,
                        (
                            partial + walk.per_metre * _distance(d_world, goal),
                            count,
                            (partial, head, (a_world, b_world, c_world, d_world)),
                        ),
                    )
            continue
        partial, head, ends = stop
        with on_node(walk, ends[3], goal, margin_tiles) as (dl, dkey, gl2, fd):
            back = _search(walk, dl, gl2, margin_tiles, max_expansions, start_key=dkey)
            if back is None:
                continue
            expansions += back.expansions
            tail = shortcut.shorten(walk, back.pieces, dl, gl2)
            tail = shortcut.pull_tail(walk, tail, gl2)
            tail = shortcut.long_last_piece(walk, tail)
            last = tail[-1]
            end_heading = last.curve.heading[-1] if last.curve is not None else back.goal[2]
        tried_count += 1
        total = partial + sum(p.cost for p in tail)
        if best is None or total < best[0]:
            best = (
                total,
                [*head, *(_framed(layered(p, walk.patch), fd) for p in tail)],
                float(end_heading) + fd[2],
                ends,
            )
    if best is None:
        raise PlanError(
            f"no {walk.patch.layer} -> {run.patch.layer} -> {walk.patch.layer} plan: "
            f"{len(firsts)} walk legs into a blend, {run_legs} run legs searched, "
            f"no way back to walking found"
        )
    total, pieces, end_heading, (a, b, c, d) = best
    goal_reached = np.array(goal)
    if np.isnan(goal[2]):
        goal_reached[2] = end_heading
    legs = [walk.patch.layer, run.patch.layer, walk.patch.layer]
    return Plan(
        pieces,
        float(total),
        int(expansions),
        time.perf_counter() - t0,
        tuple(start),
        tuple(goal_reached),
        {
            "layer": "+".join(dict.fromkeys(legs)),
            "legs": legs,
            "transitions": [
                {
                    "from": wr.source,
                    "to": wr.target,
                    "begin": a.tolist(),
                    "end": b.tolist(),
                    "cost": c_wr,
                },
                {
                    "from": rw.source,
                    "to": rw.target,
                    "begin": c.tolist(),
                    "end": d.tolist(),
                    "cost": c_rw,
                },
            ],
            "walk_legs_into_run": len(firsts),
            "run_legs": run_legs,
            "compositions_tried": tried_count,
            "compositions_bounded": bounded,
            "cost_shortened": float(total),
            "traversals_used": sum(p.kind == "traversal" for p in pieces),
        },
    )


def _search(planner, start, goal, margin_tiles, max_expansions, **node):
    """The planner's search (framed) from ``start`` to ``goal`` (local states), beginning
    or ending on a node (``start_key`` / ``goal_key``); None when there is no way."""
    try:
        return planner.plan_local(start, goal, margin_tiles, max_expansions, False, **node)
    except PlanError:
        return None


def _framed(piece, frame):
    piece.frame = tuple(float(v) for v in frame)
    return piece


def _transition(t, target_patch, state, cost):
    return LayerPiece(
        "transition",
        cost=float(cost),
        frame=tuple(float(v) for v in state),
        patch=target_patch,
        transition=t,
    )


def plan_layer_motions(plan: Plan, standing: bool = True) -> list[Motion]:
    """World motion of every piece of a plan whose pieces carry their layer
    (:class:`LayerPiece`): each leg's pieces as :func:`~.planner.plan_motions` makes them
    (eased across the stitches of its clips), each blend placed where it begins; with
    ``standing`` the first piece starts from standing and the last stops, settling the
    hips over the goal, as in a one-layer plan."""
    pieces = plan.pieces
    ms: list[Motion] = []  # one per piece, in order
    i = 0
    while i < len(pieces):
        p = pieces[i]
        if p.kind == "transition":
            ms.append(p.transition.motion.transformed(*p.frame))
            i += 1
            continue
        j = i
        while j < len(pieces) and pieces[j].kind != "transition" and pieces[j].patch is p.patch:
            j += 1
        sub = Plan(list(pieces[i:j]), 0.0, 0, 0.0, plan.start, plan.goal)
        ms += plan_motions(p.patch, sub, standing=False)
        i = j
    if standing:
        first, last = pieces[0], pieces[-1]
        if first.kind not in CLIPS:
            ms[0] = retime.eased(ms[0], ease_in=True, ramp=first.patch.gait.frames)
        if last.kind not in CLIPS:
            gait = last.patch.gait
            ms[-1] = retime.eased(ms[-1], ease_out=True, ramp=gait.frames)
            if np.isfinite(np.asarray(plan.goal[:2], float)).all():
                ms[-1] = hips_to(ms[-1], plan.goal[:2], 2 * gait.frames)
    return ms


def glitches(plan: Plan, motions: list[Motion]) -> list[dict]:
    """Glitch records (:func:`.validate.motion_glitches`) of a plan that changes layer:
    each piece judged by the limits of its own layer's gait (a blend and the clips by the
    faster layer's, the one it is entered from or blends into), joins included."""

    def speed(patch):
        return patch.gait.cycle_distance / patch.gait.frames

    patches = {id(p.patch): p.patch for p in plan.pieces if p.patch is not None}
    fastest = max(patches.values(), key=speed)
    out = []
    for patch in patches.values():
        lim = validate.limits(patch)
        for r in validate.motion_glitches(motions, plan.pieces, lim):
            piece = plan.pieces[r["piece"]]
            own = piece.patch if piece.kind not in ("transition", *CLIPS) else fastest
            if own is patch:
                out.append(r)
    out.sort(key=lambda r: (r["frame"], r["kind"]))
    return out
