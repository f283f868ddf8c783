# SPDX-License-Identifier: GPL-3.0-or-later
"""Turning on the spot: the end of a walk turned to the goal's heading where it stands.

A walk can only arrive at a goal facing a given way by curving into it, no tighter than
the gait's sharpest turn (0.59 m for CMU subject 16): a goal faced away from the way in
costs a loop of several metres, and a goal with a prop just behind it cannot be reached
at all. People stop and turn round on the spot instead. The shared mocap has no clip of a
turn in place, so one is DERIVED from the walk's own sharpest turn loop (16_18's 77-82
degree turning cycles): its poses and its heading change frame by frame are played as
recorded, but the ground frame does not advance (the stride's travel is removed), and
each foot is pinned by two-bone IK where it is put down, under the body, moving between
contacts along its recorded lift (:func:`stride_removed`): short steps turning the body,
at the pace and with the posture of the recorded turn. It is labelled so wherever it
shows ("turn in place (derived)").

In a plan (:func:`plan_turning`) the walk turns on the spot where a person would: at the
start when the goal lies behind, at the goal when its heading is against the way in, and
where a walk planned without still loops near an end; each turn is a piece costed by
Eq. 5 (:func:`turn_piece`).
"""

from collections.abc import Callable

import numpy as np

from ..kinematics import foot_lock, retime
from ..kinematics.contacts import runs
from ..kinematics.motion import Motion
from ..kinematics.poses import pose_features
from ..kinematics.skeleton import Skeleton
from ..patch.cycle import Loop
from ..patch.gait import Gait
from ..patch.layers import has_flight
from .connectors import ConnectedGraph
from .pieces import FacingRefused, Piece, Plan, PlanError, Unreachable

MIN_SHARE = 0.75  # the turn may end on a double-support frame from this share of the angle
SWAY = 0.5  # share of the stride's horizontal hip sway kept when stepping on the spot


MIN_LOOP_TURN = np.radians(30.0)  # a loop turning less per cycle cannot turn on the spot


def can_turn(gait: Gait, kmin: float, kmax: float) -> bool:
    """True when the gait has a loop turning at least ``MIN_LOOP_TURN`` per cycle each way
    within the curvature range ``kmin``..``kmax`` the patch was baked to follow: a patch
    of a lone straight walk (or one limited to straight segments) has nothing to turn on
    the spot with. Nor does a run (a gait with a flight phase): a runner slows to a walk to
    turn round, which a plan in the run layer alone cannot."""
    if has_flight(gait):
        return False
    for sign, limit in ((1.0, kmax), (-1.0, kmin)):
        ok = [
            sign * lp.turn >= MIN_LOOP_TURN and abs(lp.curvature) <= abs(limit) * 1.01
            for lp in gait.loops
        ]
        if not any(ok):
            return False
    return True


def turn_loop(gait: Gait, delta: float) -> Loop:
    """The gait's sharpest loop turning the way of ``delta`` (radians, + = left)."""
    k = np.array([lp.curvature for lp in gait.loops])
    return gait.loops[int(np.argmax(k) if delta > 0 else np.argmin(k))]


def matching_phase(loop: Loop, root_local: np.ndarray, rotations: np.ndarray) -> int:
    """The frame of ``loop`` whose pose is nearest a pose (root (3,), rotations (J, 4)):
    the phase the turn continues from, so the feet carry on the stride they were in."""
    f = loop.pose_features()
    x = pose_features(root_local[None], rotations[None])[0]
    return int(np.argmin(np.sum((f - x) ** 2, axis=1)))


def _both_planted(loop):
    c = np.asarray(loop.contacts, bool)
    return (c[:, 0] | c[:, 1]) & (c[:, 2] | c[:, 3])


def turn_phases(gait: Gait, delta: float, phase: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(phases (K,), heading steps (K - 1,)) of a turn in place by ``delta`` starting on
    loop frame ``phase``: the sharpest loop's frames in order, its recorded heading change
    per frame scaled so the total is exactly ``delta``; it ends on the first frame with
    both feet planted once ``MIN_SHARE`` of the angle is turned (standing, not mid-step)."""
    loop = turn_loop(gait, delta)
    n = loop.frames
    step = np.abs(loop.turn) * np.diff(loop.distance) / loop.cycle_distance  # (n,)
    both = _both_planted(loop)
    target, turned, k = abs(float(delta)), 0.0, int(phase)
    phases: list[int] = [k]
    steps: list[float] = []  # heading change per frame, as recorded
    limit = int(np.ceil(target / max(abs(loop.turn), 1e-6) * n)) + 2 * n
    while len(steps) < limit:
        turned += step[k % n]
        steps.append(step[k % n])
        k += 1
        phases.append(k)
        if turned >= (MIN_SHARE if both[k % n] else 2.0 - MIN_SHARE) * target:
            break  # on both feet once most of the way round, else a little past it
    scaled = np.array(steps) * (target / max(turned, 1e-12)) * np.sign(delta)
    return np.array(phases) % n, scaled


def frames_needed(gait: Gait, delta: float) -> int:
    """Frames of a turn in place by ``delta`` from the loop's first frame (for its cost)."""
    return turn_phases(gait, delta)[0].size


def turn_motion(
    gait: Gait,
    xy: tuple[float, float],
    heading: float,
    delta: float,
    previous: Motion | None = None,
    pinned: bool = True,
) -> Motion:
    """Motion of turning on the spot at ``xy`` from ``heading`` by ``delta``; with the
    ``previous`` motion (what the character did before) the turn starts on the loop frame
    nearest its last pose. Not eased: the caller eases it in and out (:mod:`.retime`).
    ``pinned`` False: the feet as the loop plays them, not pinned where they are put down
    (:func:`stride_removed` turns the legs alone: the frames, ground and root are the same,
    all a layout check measures)."""
    loop = turn_loop(gait, delta)
    phase = (
        0
        if previous is None
        else matching_phase(loop, previous.root_local[-1], previous.rotations[-1])
    )
    ph, steps = turn_phases(gait, delta, phase)
    h = heading + np.concatenate(([0.0], np.cumsum(steps)))
    ground = np.column_stack((np.full(ph.size, xy[0]), np.full(ph.size, xy[1]), h))
    root = loop.root_local[ph].copy()
    root[:, :2] *= SWAY  # stepping on the spot shifts the weight less than striding
    m = Motion(ground, root, loop.rotations[ph].copy(), loop.contacts[ph])
    return stride_removed(gait.skeleton, m) if pinned else m


def stride_removed(skel: Skeleton, motion: Motion) -> Motion:
    """The motion with each foot pinned where it is put down: the ground frame no longer
    advances, so the recorded stride would sweep a planted foot back under the body. A
    contact (heel or toe) is held at the ankle's position on its middle frame (the first
    one on the first frame: where the walk before left the foot), and between contacts
    the correction passes smoothly from one to the next, so the foot lifts and steps to
    its new place along its recorded swing height."""

    def offsets(side, ankle_xy, toe_xy):
        c = motion.contacts
        on = np.asarray(c[:, 2 * side] | c[:, 2 * side + 1], bool)
        n = len(ankle_xy)
        d = np.zeros((n, 2))
        starts, ends = runs(on)
        if starts.size == 0:
            return d
        for a, b in zip(starts, ends):
            anchor = ankle_xy[0] if a == 0 else ankle_xy[(a + b - 1) // 2]
            d[a:b] = anchor - ankle_xy[a:b]
        # between contacts (and before the first, after the last): smooth passage from
        # the correction of the contact frame before (none before the first) to the one after
        pairs = [(-1, starts[0])] + list(zip(ends[:-1] - 1, starts[1:])) + [(ends[-1] - 1, n)]
        for prev, nxt in pairs:
            if nxt - prev <= 1:
                continue
            d0 = np.zeros(2) if prev < 0 else d[prev]
            d1 = d[nxt] if nxt < n else d0
            t = (np.arange(prev + 1, nxt) - prev) / float(nxt - prev)
            w = t * t * (3.0 - 2.0 * t)
            d[prev + 1 : nxt] = d0 + w[:, None] * (d1 - d0)
        return d

    rot = foot_lock.lock_feet(skel, motion, offsets=offsets)
    return Motion(motion.ground, motion.root_local, rot, motion.contacts)


# -- turning on the spot in a plan ---------------------------------------------------------
LOOP_TURN = np.radians(90.0)  # a walk turning more than this near its start (goal) may loop
LOOP_REACH = 2.0  # gait cycles of way from either end where such a loop is looked for
MIN_TURN_IN_PLACE = np.radians(20.0)  # a start this close to facing the goal walks off


def plan_turning(
    planner: ConnectedGraph,
    start: np.ndarray,
    goal: np.ndarray,
    once: Callable[[np.ndarray, np.ndarray], Plan],
) -> Plan:
    """:meth:`~.planner.SegmentPlanner.plan` with turns on the spot where a person would
    turn (see there); ``once(start, goal)`` searches one walk."""
    # The goal behind the character (or its heading against the way in): turn on the
    # spot first (last), as a person does, and plan the walk once.
    bearing = float(np.arctan2(goal[1] - start[1], goal[0] - start[0]))
    ends = (
        abs(wrap(bearing - start[2])) > LOOP_TURN,
        not np.isnan(goal[2]) and abs(wrap(goal[2] - bearing)) > LOOP_TURN,
    )
    if any(ends):
        found = turned(planner, start, goal, bearing, ends, once)
        if found is not None:
            return found
    try:
        exact, error = once(start, goal), None
    except PlanError as e:
        exact, error = None, e
        if not isinstance(e, (FacingRefused, Unreachable)):
            raise  # a search limit, a goal inside a prop: no turn on the spot helps
    # A walk that still loops near an end (props in the way): the turn on the spot
    # there is tried too and the cheaper by Eq. 5 kept.
    looping = (True, True) if exact is None else loops(planner, exact)
    looping = (looping[0] and not ends[0], looping[1] and not ends[1])
    best = exact
    if any(looping):
        found = turned(planner, start, goal, bearing, looping, once)
        if found is not None and (best is None or final_cost(found) < final_cost(best)):
            best = found
            best.stats["exact_facing_cost"] = None if exact is None else final_cost(exact)
    if best is None:
        assert error is not None, "no walk only when the exact search was refused"
        raise error
    return best


def turned(
    planner: ConnectedGraph,
    start: np.ndarray,
    goal: np.ndarray,
    bearing: float,
    ends: tuple[bool, bool],
    once: Callable[[np.ndarray, np.ndarray], Plan],
) -> Plan | None:
    """The plan with a turn on the spot at the start (towards the goal) and / or at the
    goal (to its heading, the walk arriving facing any way) where ``ends`` says, or
    None when that walk finds no path (or no turn is needed after all)."""
    turn_to = bearing if ends[0] and abs(wrap(bearing - start[2])) >= MIN_TURN_IN_PLACE else None
    free = ends[1] and not np.isnan(goal[2])
    if turn_to is None and not free:
        return None
    s = start if turn_to is None else np.array([start[0], start[1], turn_to])
    g = np.array([goal[0], goal[1], np.nan]) if free else goal
    try:
        found = once(s, g)
    except PlanError:
        return None
    return with_turns(
        planner, found, start if turn_to is not None else None, goal if free else None
    )


def loops(planner: ConnectedGraph, plan: Plan) -> tuple[bool, bool]:
    """(start, goal): the walk turns more than ``LOOP_TURN`` within its first (last)
    ``LOOP_REACH`` gait cycles of way: it may loop out of the start's heading (into
    the goal's), where a turn on the spot would do."""
    reach = LOOP_REACH * planner.patch.gait.cycle_distance
    out = []
    for piece, end in ((plan.pieces[0], 0), (plan.pieces[-1], -1)):
        if piece.kind in ("traversal", "interaction", "turn"):
            out.append(False)
            continue
        c = piece.curve if piece.curve is not None else planner.segment_curve(piece)
        near = c.s <= c.s[0] + reach if end == 0 else c.s >= c.s[-1] - reach
        h = np.unwrap(c.heading[near])
        out.append(bool(h.size > 1 and np.sum(np.abs(np.diff(h))) > LOOP_TURN))
    return out[0], out[1]


def turn_piece(
    planner: ConnectedGraph, x: float, y: float, heading: float, to_heading: float
) -> Piece:
    """A turn on the spot at (x, y) from ``heading`` to ``to_heading`` (the shorter
    way), costed by Eq. 5: its turn and its time, eased in and out."""
    gait, delta = planner.patch.gait, wrap(to_heading - heading)
    frames = frames_needed(gait, delta)
    frames = retime.warp_phases(frames, True, True, gait.frames).size
    cost = planner.beta * abs(delta) + planner.gamma * planner.patch.effort_rate * frames / gait.fps
    return Piece("turn", cost=cost, turn=(float(x), float(y), float(heading), delta))


def with_turns(
    planner: ConnectedGraph,
    plan: Plan,
    start: np.ndarray | None = None,
    goal: np.ndarray | None = None,
) -> Plan:
    """``plan`` with a turn on the spot from ``start``'s heading before it and / or
    one to ``goal``'s heading after it (the plan then starts facing its first piece's
    way, ends facing any way); Eq. 5 costs count each turn and its time."""
    before = (
        [] if start is None else [turn_piece(planner, start[0], start[1], start[2], plan.start[2])]
    )
    after = [] if goal is None else [turn_piece(planner, goal[0], goal[1], plan.goal[2], goal[2])]
    added = sum(p.cost for p in before + after)
    stats = dict(
        plan.stats,
        # turn_piece's pieces carry their turn (mypy sees Piece.turn as Optional)
        turn_in_place_deg=[float(np.degrees(p.turn[3])) for p in before + after],  # type: ignore[index]
        cost_shortened=final_cost(plan) + added,
    )
    return Plan(
        before + list(plan.pieces) + after,
        plan.cost + added,
        plan.expansions,
        plan.seconds,
        tuple(start) if start is not None else plan.start,
        tuple(goal) if goal is not None else plan.goal,
        stats,
    )


def wrap(a: float) -> float:
    """The angle ``a`` in [-pi, pi)."""
    return float((a + np.pi) % (2 * np.pi) - np.pi)


def final_cost(plan: Plan) -> float:
    """Eq. 5 cost of a plan's pieces as they will be walked (after shortening)."""
    return float(plan.stats.get("cost_shortened", plan.cost))
