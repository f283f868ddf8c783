# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowds of independently planned characters kept apart in space and time.

Each character's path is planned on its own against the props (the paper plans one
character), with the spots where the others stand still as extra obstacles: their starts
and goals (:func:`standing_spots`). The crowd is then resolved in priority order against
a space-time reservation table (:class:`Reservations`): a character that would come too
close to one placed before it is re-timed along its path (:mod:`.path_timing`: idle holds
mid-walk, time warps to a stop on a double-support frame with feet planted, and a later
start; holds only out of the way of those still to be placed, :mod:`.ways`), else
re-routed round where the other walks then; pairs left are mended locally, then by
restarts with raised priorities, where a counter-flow met head-on in a narrow way split
into lanes (:mod:`.lanes`). What none of these clears is reported by pair and frame, not
hidden.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..kinematics import retime
from . import lanes, path_timing, ways
from .reservations import Reservations


def disc(centre: Sequence[float] | np.ndarray, radius: float, sides: int = 12) -> np.ndarray:
    """(sides, 2) convex polygon round a disc of ``radius`` about a point (its sides touch
    the circle, so nothing inside the polygon's inner circle is missed), counter-clockwise."""
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    r = radius / np.cos(np.pi / sides)
    return np.column_stack((centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)))


# metres a standing spot's disc is grown beyond the spacing, besides the hips' sway (the
# ``margin`` of :func:`standing_spots`): the planner keeps its radius from a footprint to
# within a few millimetres (grown corners are polygons), and a path round another's start
# kept 0.495-0.499 m from it, where 0.5 was asked (10,000 characters)
SPOT_MARGIN = 0.01


def standing_spots(
    ends: Sequence[tuple[Sequence[float], Sequence[float]]] | np.ndarray,
    n: int,
    spacing: float,
    radius: float,
    box: tuple[np.ndarray, np.ndarray] | None = None,
    every: bool = True,
    margin: float = SPOT_MARGIN,
) -> list[tuple[int, np.ndarray]]:
    """[(index, polygon)] of the spots character ``n`` walks around, as discs that keep
    ``spacing`` between roots once grown by the planner's ``radius``: with ``every``, the
    start and the goal of every other character (index ``2 m`` the start of character
    ``m``, ``2 m + 1`` its goal); else only where the others stand while it walks if they
    walk in priority order, the goals of those before it and the starts of those after it.

    The crowd is resolved in an order of its own, and its walkers wait and hold, so which of
    them still stand at their start or already at their goal while one walks by is not
    known when it is planned: a plan past the goal of one ranked after it leaves that one
    to arrive only once it has gone by, a plan past the start of one ranked before it has
    that one set off before it comes, and in a dense crowd such orders chain until no
    timing keeps them all. Round every spot there is no such order to keep; the fewer spots
    are for a walker they box in. ``ends`` [(start, goal)] are (x, y, heading) states; a
    spot within that distance of ``n``'s own start or goal is left out (it could not start
    or arrive at all), and so is one whose disc lies wholly outside ``box`` (lo, hi) when
    given: where its plan never looks. ``margin``: metres each disc is grown beyond the
    spacing (the planner's slack, and the hips' sway about the path planned: the crowd
    keeps the hips apart, the planner the ground track)."""
    if spacing <= 0:
        return []
    grow = max(spacing - radius, 0.05) + margin
    if isinstance(ends, np.ndarray):  # (characters, start / goal, 2+) already
        both = ends[:, :, :2]
    else:
        both = np.array([[s[:2], g[:2]] for s, g in ends], float)  # (characters, start / goal, 2)
    mine = both[n]
    if every:
        index = np.arange(2 * len(ends))
    else:
        m = np.arange(len(ends))
        index = np.where(m < n, 2 * m + 1, 2 * m)  # goals before it, starts after
    where = both.reshape(-1, 2)[index]
    near = np.linalg.norm(where[:, None, :] - mine[None], axis=2).min(axis=1) < grow + radius
    keep = ~near & (index // 2 != n)
    ring = disc((0.0, 0.0), grow)
    if box is not None:
        reach = float(np.abs(ring).max())
        keep &= ((where + reach >= box[0]) & (where - reach <= box[1])).all(axis=1)
    keep = np.nonzero(keep)[0]
    return [(int(index[k]), ring + where[k]) for k in keep]


def timeline(track: np.ndarray, delay: int, horizon: int) -> np.ndarray:
    """(horizon, 2) positions of a ground ``track`` started ``delay`` frames late: it
    stands at its first point before and at its last point after."""
    t = np.clip(np.arange(horizon) - delay, 0, len(track) - 1)
    return track[t]


def ghosts(
    line: np.ndarray,
    frame: int,
    spacing: float,
    radius: float,
    fps: float,
    window_seconds: float = 1.5,
    step_m: float = 0.3,
) -> list[np.ndarray]:
    """Discs [(polygon)] where a character walks around ``frame``: its positions on
    ``line`` (its timeline, :func:`timeline`) over ``window_seconds`` either side, every
    ``step_m`` metres, as obstacles that keep ``spacing`` between two roots once the planner
    grows them by ``radius``. Re-planning another character round them routes it round
    where this one is at that time (a space-time reservation of those frames, made static)."""
    w = int(round(window_seconds * fps))
    pts = line[max(frame - w, 0) : frame + w + 1]
    keep = [pts[0]]
    for p in pts[1:]:
        if np.linalg.norm(p - keep[-1]) >= step_m:
            keep.append(p)
    grow = max(spacing - radius, 0.05)
    return [disc(p, grow) for p in keep]


def held_track(
    track: ArrayLike, at: float, hold: int, ramp: int, holdable: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray | None]:
    """``track`` (frames, 2) with an idle hold (:func:`motion_patches.retime.hold_phases`),
    and ``holdable`` (bool per frame) carried along: true on the frames of the held track
    that replay a holdable frame whole (so a later hold may be put there too)."""
    track = np.asarray(track, float)
    u = retime.hold_phases(len(track), at, hold, ramp)
    lo = np.minimum(np.floor(u).astype(int), len(track) - 2)
    w = (u - lo)[:, None]
    out = track[lo] * (1 - w) + track[lo + 1] * w
    if holdable is None:
        return out, None
    near = np.rint(u).astype(int)
    return out, np.asarray(holdable, bool)[near] & (np.abs(u - near) < 1e-9)


def hold_frames(holdable: np.ndarray | None, before: int, ramp: int, count: int = 3) -> list[int]:
    """Up to ``count`` frames to hold on, latest first: frames where ``holdable`` (bool per
    track frame; double support on a walking piece) whose slow-down ends before frame
    ``before`` and whose ramps fit in the track, at least a ramp apart."""
    if holdable is None:
        return []
    n, half = len(holdable), ramp // 2
    ok = np.nonzero(holdable)[0]
    ok = ok[(ok - half >= 0) & (ok + half <= n - 1) & (ok + half < before)]
    out = []
    for k in ok[::-1]:
        if not out or out[-1] - k >= ramp:
            out.append(int(k))
        if len(out) == count:
            break
    return out


@dataclass
class Schedule:
    """How a character walks its track in the crowd: ``delay`` frames standing at its start,
    idle ``holds`` [(frame, frames)] applied in turn (each frame on the track as the holds
    before it left it), on the track of re-plan ``version`` (0: its first plan, n: the
    n-th re-plan round others); ``track`` is what it then walks."""

    delay: int = 0
    holds: tuple = ()
    version: int = 0
    track: np.ndarray | None = None
    holdable: np.ndarray | None = None
    rank: int = 0
    base: tuple = None  # (track, holdable) of its version before any wait or hold

    @property
    def rerouted(self) -> bool:
        return self.version > 0


def _too_close(conflicts):
    return sum(len(v[0]) for v in conflicts.values())


def _lengths(step, most):
    """Hold or wait lengths to try, shortest first: ``step`` doubling up to ``most``."""
    out, n = [], step
    while n < most:
        out.append(n)
        n *= 2
    return out + [int(most) // step * step] if most >= step else out


def _shortest(clears, longest, step):
    """Shorten a length that clears (``clears(n) -> conflicts or None``, ``longest`` known
    to clear) by halving the gap to the longest length below it that does not: the
    shortest clearing length to within ``step`` where clearing grows with the length."""
    lo, hi = longest // 2 // step * step, longest
    while hi - lo > step:
        mid = (lo + hi) // 2 // step * step
        if mid > lo and clears(mid):
            hi = mid
        else:
            lo = mid if mid > lo else hi - step
    return hi


def _improve(table, s, found, max_delay, max_hold, step, ramp):
    """The next schedule from ``s`` (which meets ``found``): a short idle hold before the
    first frame too close that clears everything, else a short further wait that does,
    else whichever tried leaves the fewest frames too close (None: none is better). Lengths
    are tried doubling from ``step`` and a clearing one is then shortened by halving."""
    first = min(int(v[0][0]) for v in found.values()) - s.delay
    held = sum(h for _, h in s.holds)
    options = []

    def hold(k, h):
        track, mask = held_track(s.track, k, h, ramp, s.holdable)
        c = table.check(track, s.delay)
        option = Schedule(s.delay, s.holds + ((k, h),), s.version, track, mask, base=s.base)
        options.append((_too_close(c), h, option, c))
        return not c

    def wait(d):
        c = table.check(s.track, s.delay + d)
        option = Schedule(s.delay + d, s.holds, s.version, s.track, s.holdable, base=s.base)
        options.append((_too_close(c), d, option, c))
        return not c

    for h in _lengths(step, max_hold - held):
        for k in hold_frames(s.holdable, first, ramp):
            if hold(k, h):
                h = _shortest(lambda n: hold(k, n), h, step)
                return next(
                    o[2:] for o in options if o[1] == h and o[2].holds[-1][0] == k and not o[3]
                )
    for d in _lengths(step, max_delay - s.delay):
        if wait(d):
            d = _shortest(wait, d, step)
            return next(
                o[2:]
                for o in options
                if o[1] == d
                and o[2].delay == s.delay + d
                and not o[2].holds[len(s.holds) :]
                and not o[3]
            )
    if not options:
        return None, found
    best = min(options, key=lambda o: o[:2])
    if best[0] >= _too_close(found):
        return None, found
    return best[2], best[3]


def _extra(timing, ramp):
    """Frames a timing (delay, holds) adds to its walk: the wait, each hold and its ramps."""
    delay, holds = timing
    return delay + sum(h + ramp for _, h in holds)


def _found_by(timing, max_delay, max_extra, max_holds, ramp):
    """Whether :func:`path_timing.earliest` within ``max_delay``, ``max_extra`` and
    ``max_holds`` finds ``timing`` (delay, holds), the answer of a search allowing more.
    It does when ``timing`` fits in it: the earliest arrival of the wider search is then
    one it can reach, and of those the wider one took the fewest holds, then the shortest
    wait, which it prefers alike (states are kept by that value, ties broken in the same
    order of moves); so the narrower search need not be run."""
    delay, holds = timing
    return delay <= max_delay and len(holds) <= max_holds and _extra(timing, ramp) <= max_extra


def _timed(table, s, max_delay, max_hold, ramp, found):
    """``s`` re-timed to its earliest arrival clear of everyone reserved
    (:func:`path_timing.earliest`: a wait at its start and idle holds on the way), with the
    conflicts left (none); ``s`` and ``found`` unchanged when no timing within the longest
    wait and holds clears it. One hold alone is tried first (a walk that stops where it
    must rather than one that starts late, as :func:`_improve` prefers), then a wait and
    one hold, then a wait and up to four holds."""
    tries = ((0, 1), (max_delay, 1), (max_delay, 4))
    if s.holdable is None:
        tries = ((max_delay, 0),)
    busy = table.busy(s.track, max(table.horizon, len(s.track)) + max_delay + max_hold + 1)
    # the widest search (the last) first: when it finds nothing, none of the others will
    timing = path_timing.earliest(
        s.track, busy, s.holdable, ramp, tries[-1][0], tries[-1][0] + max_hold, tries[-1][1]
    )
    for wait, holds in tries[:-1] if timing is not None else ():
        if _found_by(timing, wait, wait + max_hold, holds, ramp):
            break  # the earliest of all is one this search allows: it finds that one too
        if _extra(timing, ramp) > wait + max_hold:
            continue  # it arrives no earlier than the earliest of all: later than it may
        first = path_timing.earliest(s.track, busy, s.holdable, ramp, wait, wait + max_hold, holds)
        if first is not None:
            timing = first
            break
    if timing is None:
        return s, found
    delay, holds = timing
    track, mask = s.track, s.holdable
    for k, h in holds:
        track, mask = held_track(track, k, h, ramp, mask)
    timed = Schedule(delay, s.holds + holds, s.version, track, mask, s.rank, s.base)
    left = table.check(track, delay)
    return (timed, left) if _too_close(left) < _too_close(found) else (s, found)


REPLAN_AHEAD = 16  # at most this many characters placed while one is re-planned
# Only characters whose paths keep this far (metres) from the path and the discs of one being
# re-planned are placed while it is: a re-route stays near its first path, so it would not
# have met them (a doorway's crowd, all through one gap, is placed strictly in turn).
REPLAN_CLEAR = 2.0


class _Now:
    """A re-plan worked out when its answer is asked for (no cluster to hand it to)."""

    def __init__(self, replan, i, discs):
        self.replan, self.i, self.discs = replan, i, discs

    def result(self):
        return self.replan(self.i, self.discs)


def _resolve_once(
    order,
    tracks,
    replan,
    spacing,
    radius,
    fps,
    max_delay,
    step,
    ramp,
    max_hold,
    holdable,
    rounds,
    stages,
    versions,
    fixed=None,
    replan_later=None,
    settled=None,
):
    """One pass of :func:`resolve` placing the characters in ``order``; ``versions``
    counts each character's re-plans over all passes (its next one's number). ``fixed``
    {character: schedule}: characters kept as they are, reserved before the others.

    A character to be re-planned may be placed after some characters that come after it
    in ``order``: those whose paths keep :data:`REPLAN_CLEAR` from its path and the discs
    it is re-planned round (:class:`_Clear`), at most :data:`REPLAN_AHEAD` of them; its
    re-plan, asked for with ``replan_later(i, discs)`` (an answer whose ``result()`` is
    ``replan``'s), is worked out on a cluster's worker while they are placed. The order
    does not depend on whether there is a cluster, so the crowd comes out the same in
    process and on one. ``settled(i, schedule)`` is told of each character as it is placed.
    Returns (schedules, conflicts, table, the characters in the order they were placed)."""
    table = Reservations(spacing)
    schedules, conflicts = [None] * len(tracks), []
    paths, waiting = ways.Ways(tracks, spacing), np.ones(len(tracks), bool)
    for i, s in (fixed or {}).items():
        table.reserve(i, s.track, s.delay)
        schedules[i], waiting[i] = s, False
    later = replan_later or (replan and (lambda i, discs: _Now(replan, i, discs)))

    def clear(track, mask):  # holds only out of the way of those still to be placed
        return None if mask is None else np.asarray(mask, bool) & ~paths.crossed(track, waiting)

    def place(i):
        """Character i's attempts: yields the discs to re-plan it round (and the track it
        tried last), is sent the re-plan's answer, and returns its best schedule and what
        it still meets."""
        waiting[i] = False
        track = np.asarray(tracks[i], float)[:, :2]
        s = Schedule(0, (), 0, track, clear(track, holdable[i]))
        s.base = (s.track, holdable[i])
        best, reserved = None, []
        for attempt in range(rounds + 1):
            found = table.check(s.track)
            if found:
                s, found = _timed(table, s, max_delay, max_hold, ramp, found)
            for _ in range(stages):
                if not found:
                    break
                better, c = _improve(table, s, found, max_delay, max_hold, step, ramp)
                if better is None:
                    break
                s, found = better, c
            if best is None or _too_close(found) < _too_close(best[1]):
                best = (s, found)
            if not best[1] or attempt == rounds or replan is None:
                break
            horizon = max(table.horizon, len(s.track) + s.delay) + 1
            for j, (_, frame, _) in found.items():
                d, walked = table.placed[j]
                reserved += ghosts(timeline(walked, d, horizon), frame, spacing, radius, fps)
            new = yield list(reserved), s.track
            # those placed while it was re-planned are in the table now
            best = (best[0], table.check(best[0].track, best[0].delay))
            if new is None:
                break
            versions[i] += 1
            track = np.asarray(new[0], float)[:, :2]
            s = Schedule(0, (), versions[i], track, clear(track, new[1]))
            s.base = (s.track, new[1])
        return best

    def step_on(i, attempts, answer):
        """Character i's attempts run on with ``answer``: placed, or its re-plan asked for."""
        try:
            discs, track = attempts.send(answer)
        except StopIteration as done:
            s, found = done.value
            table.reserve(i, s.track, s.delay)
            schedules[i] = s
            placed.append(i)
            conflicts.extend(_pairs(found, i))
            if settled is not None:
                settled(i, s)
            return
        clear_of = _Clear([track, *discs], REPLAN_CLEAR)
        pending.append((turn + REPLAN_AHEAD, i, attempts, later(i, discs), clear_of))

    # pending: (last turn it may wait to, character, its attempts, re-plan asked, _Clear)
    placed, pending = [], []
    for turn, i in enumerate(order):
        while pending and (pending[0][0] < turn or any(not p[4].of(tracks[i]) for p in pending)):
            _, k, attempts, answer, _ = pending.pop(0)
            step_on(k, attempts, answer.result())
        step_on(i, place(i), None)
    turn = len(order)
    while pending:
        _, k, attempts, answer, _ = pending.pop(0)
        step_on(k, attempts, answer.result())
    return schedules, conflicts, table, placed


class _Clear:
    """Whether a path keeps ``margin`` from some ``shapes`` (paths and polygons, (N, 2)
    points): cells ``margin`` wide hold their points, and a point in none of those cells or
    their neighbours is further than ``margin`` from all of them (a coarse test: some a
    little further count as near)."""

    def __init__(self, shapes, margin):
        self.margin = float(margin)
        pts = np.concatenate([np.asarray(p, float)[:, :2] for p in shapes])
        c = np.floor(pts / self.margin).astype(np.int64)
        ring = np.array([(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)], np.int64)
        c = (c[:, None, :] + ring[None]).reshape(-1, 2)
        self.keys = np.unique(c[:, 0] << 32 ^ (c[:, 1] & 0xFFFFFFFF))

    def of(self, track):
        c = np.floor(np.asarray(track, float)[:, :2] / self.margin).astype(np.int64)
        keys = c[:, 0] << 32 ^ (c[:, 1] & 0xFFFFFFFF)
        return not np.isin(keys, self.keys).any()


def _repair(table, schedules, conflicts, max_delay, max_hold, ramp):
    """Conflicts left mended locally, cheaper than a restart: a character still too close
    is freed with those it meets, placed first and re-timed (:func:`_timed`), then they are
    re-timed round it; kept where all of them come clear, else put back as they were. When
    that fails, the group is widened to everyone its plan meets were it to walk at once
    (those whose timings leave it no way through) and tried again. ``schedules`` and
    ``table`` are changed in place; the ranks of the group are re-dealt in their new order.
    Returns how many groups were mended."""
    mended = 0
    for b in list(dict.fromkeys(c["b"] for c in conflicts)):
        s = schedules[b]
        if not table.check(s.track, s.delay):
            continue  # mended with another group
        table.remove(b)
        near = sorted(table.check(s.track, s.delay), key=lambda j: schedules[j].rank)
        met = sorted(set(table.check(s.base[0])) - set(near), key=lambda j: schedules[j].rank)
        table.reserve(b, s.track, s.delay)
        for group in [[b] + near, [b] + near + met][: 2 if met else 1]:
            new = _in_turn(table, schedules, group, max_delay, max_hold, ramp)
            if new is not None:
                for i, rank in zip(group, sorted(schedules[i].rank for i in group)):
                    new[i].rank = rank
                    schedules[i] = new[i]
                mended += 1
                break
    return mended


def _in_turn(table, schedules, group, max_delay, max_hold, ramp):
    """The characters of ``group`` (reserved in ``table``) freed and placed again in its
    order, each re-timed from its plan before any wait or hold (:func:`_timed`): {character:
    schedule} when all of them come clear (reserved so), else None (the table as it was)."""
    old = {i: schedules[i] for i in group}
    for i in group:
        table.remove(i)
    new = {}
    for i in group:
        fresh = Schedule(0, (), old[i].version, *old[i].base, old[i].rank, old[i].base)
        c = table.check(fresh.track)
        timed, c = _timed(table, fresh, max_delay, max_hold, ramp, c) if c else (fresh, c)
        if c:
            break
        table.reserve(i, timed.track, timed.delay)
        new[i] = timed
    if len(new) == len(group):
        return new
    for i in new:
        table.remove(i)
    for i in group:
        table.reserve(i, old[i].track, old[i].delay)
    return None


def _left(schedules, spacing):
    """The conflicts of ``schedules`` placed in their ranks' order, as :func:`resolve`
    reports them (indices of ``schedules``)."""
    ranked = sorted(range(len(schedules)), key=lambda k: schedules[k].rank)
    out = conflicts_of(
        [schedules[k].track for k in ranked], [schedules[k].delay for k in ranked], spacing
    )
    for c in out:
        c["a"], c["b"] = ranked[c["a"]], ranked[c["b"]]
    return out


def resolve(
    tracks: Sequence[np.ndarray],
    replan: Callable[[int, list[np.ndarray]], tuple[np.ndarray, np.ndarray | None] | None] | None,
    spacing: float,
    radius: float,
    fps: float,
    max_delay: int,
    step: int,
    ramp: int | None = None,
    max_hold: int | None = None,
    holdable: Sequence[np.ndarray | None] | None = None,
    rounds: int = 2,
    stages: int = 6,
    restarts: int = 4,
    replan_later: Callable[[int, list[np.ndarray]], Any] | None = None,
    settled: Callable[[int, Schedule], Any] | None = None,
) -> tuple[list[Schedule], list[dict[str, Any]]]:
    """Schedules and the conflicts left for ``tracks`` [(frames, 2)] in priority order,
    all starting on frame 0: each character in turn is checked against the
    :class:`Reservations` of those before it and, when it comes closer than ``spacing``,
    first re-timed to its earliest arrival clear of them all (:func:`_timed`,
    :func:`path_timing.earliest`: a wait at the start and idle holds on the way, one hold
    preferred; a hold is never where one still to be placed walks, :class:`ways.Ways`, so
    no walker stands in a doorway the others have yet to go through); when no such timing
    fits in the longest wait and holds, changed by (at most ``stages`` changes, the first
    that clears everything, in this order of preference):

    1. an idle hold (whole ``step`` frames, all its holds at most ``max_hold``, see
       :func:`_improve` for which lengths are tried) on a
       double-support frame of its walk (``holdable[i]``: bool per frame of ``tracks[i]``,
       None: no holds) before the first frame too close, slowing down and speeding up
       over ``ramp`` frames;
    2. waiting longer at its start (``step`` frames, at most ``max_delay`` in all);
    3. else the change leaving the fewest frames too close, and again from there.

    Still too close, it is re-planned (``replan(i, discs) -> (track, holdable) or None``,
    each call a new version of its plan, :attr:`Schedule.version`; None: never) round the
    discs where the others it meets walk around those frames (:func:`ghosts`), and the
    above is done again, at most ``rounds`` times. Meanwhile the characters after it whose
    paths keep clear of it may be placed (:func:`_resolve_once`): ``replan_later(i,
    discs)`` asks for the re-plan at once (an answer whose ``result()`` is ``replan``'s,
    worked out on a cluster meanwhile); None: ``replan`` when its answer is taken.
    ``settled(i, schedule)`` is told of each character placed, in every pass, as it is
    placed (what a character comes out with may still change in a later pass or repair):
    work that follows from a schedule may start before the crowd is resolved.

    When conflicts are left, each character still too close is first mended locally
    (:func:`_repair`: freed with those it meets, placed before them and all re-timed), and
    what is still left makes the crowd be resolved again from the start with the characters
    that met them placed first (prioritised planning's restart with raised priorities), at
    most ``restarts`` times, and the pass with the fewest frames too close is kept. In a
    large crowd a restart places again only the neighbourhood of the pairs left
    (:func:`_neighbourhood`, a ring further after each that gained nothing), the others kept
    as in the best pass so far, placed before them: its cost is that of the neighbourhood,
    not of the crowd. Before a restart, a
    counter-flow left meeting head-on in a narrow way is split into lanes
    (:func:`lanes.form`), the same over the passes that follow. What is left is reported:
    [{"a", "b" (indices, ``a`` placed first), "frame" (closest), "first_frame", "frames",
    "distance_m"}]. :attr:`Schedule.rank` is each character's place in the order of the pass
    kept."""
    ramp = int(ramp if ramp is not None else round(fps)) // 2 * 2
    max_hold = max_delay if max_hold is None else max_hold
    step = max(int(step), 1)
    holdable = list(holdable) if holdable is not None else [None] * len(tracks)
    order, versions, best = list(range(len(tracks))), [0] * len(tracks), None
    tracks, laned = list(tracks), {}  # laned: {character: version of its lane plan}
    strips = {}  # {character: the strips keeping it in its lane}, kept when it is re-routed
    places = []  # the lanes' places (midpoint, axis), the same over the passes
    on_lane = replan and (lambda i, discs: replan(i, strips.get(i, []) + discs))
    later = replan_later and (lambda i, discs: replan_later(i, strips.get(i, []) + discs))
    fixed = None  # the characters a restart keeps as they were (None: none)
    wider = 0  # rings added to a restart's neighbourhood, one per restart that gained nothing
    for _ in range(restarts + 1):
        schedules, conflicts, table, placed = _resolve_once(
            [i for i in order if fixed is None or i not in fixed],
            tracks,
            on_lane,
            spacing,
            radius,
            fps,
            max_delay,
            step,
            ramp,
            max_hold,
            holdable,
            rounds,
            stages,
            versions,
            fixed,
            later,
            settled,
        )
        order = [i for i in order if fixed is not None and i in fixed] + placed
        for rank, i in enumerate(order):
            schedules[i].rank = rank
            if i in laned and schedules[i].version == 0:  # on its lane plan
                schedules[i].version = laned[i]
        if conflicts and _repair(table, schedules, conflicts, max_delay, max_hold, ramp):
            conflicts = _left(schedules, spacing)
        left = sum(c["frames"] for c in conflicts)
        if best is None or left < best[0]:
            best = (left, schedules, conflicts)
        elif fixed is not None:  # a restart among neighbours that gained nothing: reach further
            wider += 1
        if not conflicts:
            break
        formed = {}
        if replan is not None:  # lanes where pairs meet head-on, for the passes that follow
            formed = lanes.form(
                table.placed, conflicts, tracks, laned, replan, versions, spacing, radius, places
            )
            for i, (version, track, mask, lane) in formed.items():
                laned[i], tracks[i], holdable[i], strips[i] = version, track, mask, lane
        first = list(dict.fromkeys(c["b"] for c in conflicts))
        order = first + [i for i in order if i not in first]
        seeds = {c[k] for c in conflicts + best[2] for k in ("a", "b")} | set(formed)
        hood = _neighbourhood(tracks, best[1], seeds, spacing, LOCAL_RINGS + wider)
        if hood is None:  # most of the crowd: all of it placed again
            fixed = None
        else:  # the rest kept as in the best pass, placed before
            fixed = {i: replace(best[1][i]) for i in range(len(tracks)) if i not in hood}
            kept = sorted(fixed, key=lambda i: fixed[i].rank)
            order = kept + [i for i in order if i in hood]
    return best[1], best[2]


LOCAL_SHARE = 0.5  # a restart placing more of the crowd than this places all of it again
LOCAL_RINGS = 2  # how many steps out from those left too close a restart reaches


def _neighbourhood(tracks, schedules, seeds, spacing, rings=LOCAL_RINGS):
    """The characters a restart places again, or None for all of them: ``seeds`` and every
    character whose path (as planned, ``tracks``, or as walked in ``schedules``) comes
    within the spacing of theirs, and of those, ``rings`` steps out. Nobody
    further can meet them whenever either walks, so in a large crowd the pairs left are
    cleared by a restart among their neighbours, the others kept where they were placed
    (prioritised planning's restart, at the cost of a neighbourhood, not of the crowd)."""
    n = len(tracks)
    paths = ways.Ways([*tracks, *(s.track for s in schedules)], spacing)
    hood, edge = set(seeds), set(seeds)
    for _ in range(rings):
        met = set()
        for i in edge:
            for track in (tracks[i], schedules[i].track):
                met.update(int(j) % n for j in paths.met(track))
        edge = met - hood
        hood |= edge
        if len(hood) > LOCAL_SHARE * n:
            return None
    return hood


def conflicts_of(
    tracks: Sequence[np.ndarray], delays: Sequence[int], spacing: float
) -> list[dict[str, Any]]:
    """Every pair of ``tracks`` (in order, started ``delays`` frames late) closer than
    ``spacing`` on some frame, as :func:`resolve` reports them: the check of what is
    finally written, independent of how it was resolved."""
    table, out = Reservations(spacing), []
    for i, (track, d) in enumerate(zip(tracks, delays)):
        track = np.asarray(track, float)[:, :2]
        out.extend(_pairs(table.check(track, d), i))
        table.reserve(i, track, d)
    return out


def _pairs(found, b):
    """The conflicts of ``b`` with those it meets (``found``: :meth:`Reservations.check`),
    as :func:`resolve` reports them, by the other's index."""
    return [
        {
            "a": j,
            "b": b,
            "frame": frame,
            "first_frame": int(frames[0]),
            "frames": int(len(frames)),
            "distance_m": dist,
        }
        for j, (frames, frame, dist) in sorted(found.items())
    ]
