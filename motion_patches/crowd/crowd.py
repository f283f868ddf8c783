# SPDX-License-Identifier: GPL-3.0-or-later
"""Crowds of independently planned characters kept apart in space and time.

Each character's path is planned on its own against the props (the paper plans one
character), with the spots where the others stand still while it walks as extra
obstacles: the goals of the characters before it in priority and the starts of those
after it. The crowd is then resolved in priority order against a space-time reservation
table (:class:`Reservations`): a character that would come too close to one placed
before it is re-timed along its path (:mod:`.path_timing`: idle holds mid-walk, time warps
to a stop on a double-support frame with feet planted, and a later start), else re-routed
round where the other walks then; pairs left are mended locally, then by restarts with
raised priorities. What none of these clears is reported by pair and frame, not hidden.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..kinematics import retime
from . import lanes, path_timing


def disc(centre: Sequence[float] | np.ndarray, radius: float, sides: int = 12) -> np.ndarray:
    """(sides, 2) convex polygon round a disc of ``radius`` about a point (its sides touch
    the circle, so nothing inside the polygon's inner circle is missed), counter-clockwise."""
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    r = radius / np.cos(np.pi / sides)
    return np.column_stack((centre[0] + r * np.cos(a), centre[1] + r * np.sin(a)))


def standing_spots(
    ends: Sequence[tuple[Sequence[float], Sequence[float]]],
    n: int,
    spacing: float,
    radius: float,
    box: tuple[np.ndarray, np.ndarray] | None = None,
) -> list[tuple[int, np.ndarray]]:
    """[(index, polygon)] of the spots character ``n`` walks around: the goals of the
    characters before it and the starts of those after it, as discs that keep ``spacing``
    between roots once grown by the planner's ``radius``. ``ends`` [(start, goal)] are
    (x, y, heading) states; a spot within that distance of ``n``'s own start or goal is
    left out (it could not start or arrive at all), and so is one whose disc lies wholly
    outside ``box`` (lo, hi) when given: where its plan never looks."""
    if spacing <= 0:
        return []
    grow = max(spacing - radius, 0.05)
    mine = np.array([ends[n][0][:2], ends[n][1][:2]], float)
    where = np.array([(g if m < n else s)[:2] for m, (s, g) in enumerate(ends)], float)
    near = np.linalg.norm(where[:, None, :] - mine[None], axis=2).min(axis=1) < grow + radius
    keep = ~near & (np.arange(len(ends)) != n)
    ring = disc((0.0, 0.0), grow)
    if box is not None:
        reach = float(np.abs(ring).max())
        keep &= ((where + reach >= box[0]) & (where - reach <= box[1])).all(axis=1)
    keep = np.nonzero(keep)[0]
    return [(int(m), ring + where[m]) for m in keep]


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


# --- space-time reservations ------------------------------------------------------------

_OFF = 1 << 20  # cell indices are shifted by this into a key's 21-bit fields


class _Sorted:
    """Reserved root positions (frame, xy, owner) sorted by an int64 key, in runs: each
    reservation is a run of its own, and the newest run is merged into the one before
    while that one holds at most four times as much (a log-structured merge). Runs grow
    geometrically, so there are O(log N) of them to look through and every entry is
    copied O(log N) times in all, whatever the size of the crowd. An owner's entries
    always lie in one run (in key order), so what a look-up finds of one owner comes in
    the order of the queries."""

    _COLUMNS = ("key", "frame", "xy", "owner")

    def __init__(self):
        self.runs = []

    @property
    def size(self):
        return sum(run["key"].size for run in self.runs)

    def insert(self, key, frame, xy, owner):
        order = np.argsort(key, kind="stable")
        run = {
            "key": key[order],
            "frame": frame[order],
            "xy": xy[order],
            "owner": np.full(key.size, owner, np.int32),
        }
        self.runs.append(run)
        while len(self.runs) > 1 and self.runs[-2]["key"].size <= 4 * self.runs[-1]["key"].size:
            new = self.runs.pop()
            old = self.runs.pop()
            both = {c: np.concatenate((old[c], new[c])) for c in self._COLUMNS}
            order = np.argsort(both["key"], kind="stable")
            self.runs.append({c: both[c][order] for c in self._COLUMNS})

    def remove(self, owner):
        for i, run in enumerate(self.runs):
            keep = run["owner"] != owner
            if not keep.all():
                self.runs[i] = {c: run[c][keep] for c in self._COLUMNS}
        self.runs = [run for run in self.runs if run["key"].size]

    def near(self, q):
        """(query index, frame, xy, owner) of every entry whose key is one of ``q``."""
        out = []
        for run in self.runs:
            lo = np.searchsorted(run["key"], q, "left")
            n = np.searchsorted(run["key"], q, "right") - lo
            hit = np.nonzero(n)[0]
            if hit.size:
                n = n[hit]
                ent = np.repeat(lo[hit] - np.cumsum(n) + n, n) + np.arange(n.sum())
                got = (run["frame"][ent], run["xy"][ent], run["owner"][ent])
                out.append((np.repeat(hit, n), *got))
        if not out:
            return np.empty(0, int), np.empty(0, np.int64), np.empty((0, 2)), np.empty(0, int)
        return tuple(np.concatenate(c) for c in zip(*out))


class Reservations:
    """A space-time reservation table (prioritised planning: Silver's cooperative
    pathfinding, with frames as time steps): every reserved character holds the cells its
    root passes through on each frame of its walk, and two standing spots, its start until
    it leaves and its goal from its arrival on. A character placed later is checked against
    them all: its walk against the others' walks and spots, its own spots against both.

    Cells are ``spacing`` and :attr:`SLACK` wide, so two roots closer than that are in the
    same cell or neighbours (nine cells to look in); a sparse table (sorted int64 keys of
    frame and cell) keeps memory to the frames walked, whatever the size of the plaza.
    Lookups are vectorised over frames."""

    def __init__(self, spacing):
        self.spacing = float(spacing)
        self.cell = self.spacing + self.SLACK
        self.moving = _Sorted()  # keyed by (frame, cell)
        self.spot_keys = np.empty(0, np.int64)  # standing spots: sorted cell keys
        self.spots = np.empty((0, 5), float)  # x, y, first frame, end frame (inf), owner
        self.by_cell = _Sorted()  # moving again, keyed by cell alone
        self.placed = {}  # index -> (delay, track)
        self.horizon = 0

    def _cells(self, xy):
        return np.floor(np.asarray(xy, float) / self.cell).astype(np.int64) + _OFF

    @staticmethod
    def _key(t, c):
        return (np.asarray(t, np.int64) << 42) | (c[..., 0] << 21) | c[..., 1]

    SLACK = 0.05  # metres cells are wider than the spacing: the most :meth:`busy` adds
    _RING = np.array([(i, j) for i in range(-1, 2) for j in range(-1, 2)], np.int64)
    _RING_KEYS = (_RING[:, 0] << 21) + _RING[:, 1]  # added to a cell key: the cells round it

    def _moving_near(self, t, xy):
        """(query row, xy, owner) of moving entries on frame ``t[row]`` in the cell of
        ``xy[row]`` or next to it."""
        if not self.moving.size or not len(t):
            return np.empty(0, int), np.empty((0, 2)), np.empty(0, int)
        c = self._cells(xy)[:, None, :] + self._RING[None]
        q = self._key(np.repeat(np.asarray(t)[:, None], len(self._RING), 1), c).ravel()
        rows, _, where, owner = self.moving.near(q)
        return rows // len(self._RING), where, owner

    def _spots_near(self, xy):
        """Indices of standing spots in the cells of the points ``xy`` or next to them."""
        if not self.spot_keys.size:
            return np.empty(0, int)
        c = self._cells(xy)
        c = np.unique(c[:, 0] << 21 | c[:, 1])  # the cells of the points, once each
        q = np.unique((c[:, None] + self._RING_KEYS[None]).ravel())
        lo = np.searchsorted(self.spot_keys, q, "left")
        n = np.searchsorted(self.spot_keys, q, "right") - lo
        hit = np.nonzero(n)[0]
        if not hit.size:
            return np.empty(0, int)
        n = n[hit]  # disjoint ranges of the sorted keys, in order: already sorted and unique
        return np.repeat(lo[hit] - np.cumsum(n) + n, n) + np.arange(n.sum())

    def busy(self, track: np.ndarray, frames: int, margin: float = 0.01) -> np.ndarray:
        """(len(track), frames) bool: ``track[k]`` closer than the spacing (and ``margin``)
        to a reserved root on frame ``t`` (walking then, or standing at its start or goal
        then), for every frame from 0; the last column stands for every frame after it.
        Found from the cells about the track over all frames at once (the entries sorted by
        cell), so its cost follows the traffic near the track, not the frames searched."""
        if margin > self.SLACK:
            raise ValueError(f"a margin of at most {self.SLACK} m, not {margin}")
        track = np.asarray(track, float)
        n, s2 = len(track), (self.spacing + margin) ** 2
        out = np.zeros((n, frames + 2), np.int32)
        if self.by_cell.size:
            c = self._cells(track)[:, None, :] + self._RING[None]
            rows, when, where, _ = self.by_cell.near((c[..., 0] << 21 | c[..., 1]).ravel())
            if rows.size:
                rows = rows // len(self._RING)
                d = where - track[rows]
                close = np.einsum("ij,ij->i", d, d) < s2
                t = np.minimum(when[close], frames)
                np.add.at(out, (rows[close], t), 1)
                np.add.at(out, (rows[close], t + 1), -1)
        near = self._spots_near(track)
        if near.size:  # standing: a span of frames each
            sp = self.spots[near]
            d = track[:, None, :] - sp[None, :, :2]
            k, j = np.nonzero(np.einsum("kjx,kjx->kj", d, d) < s2)
            lo = np.minimum(sp[j, 2], frames).astype(int)
            hi = np.minimum(sp[j, 3], frames + 1).astype(int)
            keep = lo < hi
            np.add.at(out, (k[keep], lo[keep]), 1)
            np.add.at(out, (k[keep], hi[keep]), -1)
        return (np.cumsum(out, axis=1) > 0)[:, : frames + 1]

    def check(self, track: ArrayLike, delay: int = 0) -> dict[int, tuple[np.ndarray, int, float]]:
        """Conflicts of a character walking ``track`` (frames, 2) from frame ``delay`` on,
        standing at its first point before and at its last point after: {other index:
        (frames too close (sorted array), closest frame, distance there)}."""
        track = np.asarray(track, float)
        d, n, s = int(delay), len(track), self.spacing
        found = []  # (other, frame, distance) arrays
        # walk against walks
        t = np.arange(d, d + n)
        rows, where, owner = self._moving_near(t, track)
        if rows.size:
            dist = np.linalg.norm(where - track[rows], axis=1)
            close = dist < s
            found.append((owner[close], t[rows[close]], dist[close]))
        # my start (before I leave) and goal (after I arrive) against the others' walks
        end = max(self.horizon, d + n)
        for frames, xy in ((np.arange(0, d), track[0]), (np.arange(d + n, end), track[-1])):
            if frames.size:
                rows, where, owner = self._moving_near(
                    frames, np.broadcast_to(xy, (frames.size, 2))
                )
                if rows.size:
                    dist = np.linalg.norm(where - xy, axis=1)
                    close = dist < s
                    found.append((owner[close], frames[rows[close]], dist[close]))
        # everything of mine against the others' standing spots
        near = self._spots_near(track)
        if near.size:
            sp = self.spots[near]
            dist = np.linalg.norm(track[:, None, :] - sp[None, :, :2], axis=2)  # (n, S)
            when = t[:, None]
            close = (dist < s) & (when >= sp[None, :, 2]) & (when < sp[None, :, 3])
            r, k = np.nonzero(close)
            found.append((sp[k, 4].astype(int), t[r], dist[r, k]))
            for (a, b), xy in (((0, d), track[0]), ((d + n, np.inf), track[-1])):
                dist = np.linalg.norm(sp[:, :2] - xy, axis=1)
                lo, hi = np.maximum(sp[:, 2], a), np.minimum(sp[:, 3], b)
                for k in np.nonzero((dist < s) & (lo < hi))[0]:  # both standing: every frame
                    frames = np.arange(int(lo[k]), int(min(hi[k], max(end, lo[k] + 1))))
                    found.append(
                        (np.full(frames.size, int(sp[k, 4])), frames, np.full(frames.size, dist[k]))
                    )
        out = {}
        if not found:
            return out
        who = np.concatenate([f[0] for f in found]).astype(int)
        when = np.concatenate([f[1] for f in found]).astype(np.int64)
        dist = np.concatenate([f[2] for f in found])
        for j in np.unique(who):
            m = who == j
            k = int(np.argmin(dist[m]))
            out[int(j)] = (np.unique(when[m]), int(when[m][k]), float(dist[m][k]))
        return out

    def reserve(self, index: int, track: ArrayLike, delay: int = 0) -> None:
        """Hold ``track``'s cells over its frames and its two standing spots for ``index``."""
        track = np.asarray(track, float)
        d, n = int(delay), len(track)
        t = np.arange(d, d + n)
        c = self._cells(track)
        self.moving.insert(self._key(t, c), t, track, index)
        self.by_cell.insert(c[:, 0] << 21 | c[:, 1], t, track, index)
        spots = np.array([[*track[0], 0, d, index], [*track[-1], d + n, np.inf, index]], float)
        spots = spots[spots[:, 2] < spots[:, 3]]
        c = self._cells(spots[:, :2])
        skeys = c[:, 0] << 21 | c[:, 1]
        order = np.argsort(skeys)  # np.insert keeps the given order at one position
        skeys, spots = skeys[order], spots[order]
        at = np.searchsorted(self.spot_keys, skeys)
        self.spot_keys = np.insert(self.spot_keys, at, skeys)
        self.spots = np.insert(self.spots, at, spots, axis=0)
        self.placed[index] = (d, track)
        self.horizon = max(self.horizon, d + n)

    def remove(self, index: int) -> None:
        """Free everything ``index`` holds (the others keep their places)."""
        self.moving.remove(index)
        self.by_cell.remove(index)
        keep = self.spots[:, 4] != index
        self.spot_keys, self.spots = self.spot_keys[keep], self.spots[keep]
        del self.placed[index]
        self.horizon = max((d + len(t) for d, t in self.placed.values()), default=0)

    def line(self, index: int, horizon: int) -> np.ndarray:
        """(horizon, 2) positions of a reserved character (as :func:`timeline`)."""
        d, track = self.placed[index]
        return timeline(track, d, horizon)


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


def _found_by(timing, max_delay, max_extra, max_holds, ramp):
    """Whether :func:`path_timing.earliest` within ``max_delay``, ``max_extra`` and
    ``max_holds`` finds ``timing`` (delay, holds), the answer of a search allowing more.
    It does when ``timing`` fits in it: the earliest arrival of the wider search is then
    one it can reach, and of those the wider one took the fewest holds, then the shortest
    wait, which it prefers alike (states are kept by that value, ties broken in the same
    order of moves); so the narrower search need not be run."""
    delay, holds = timing
    extra = delay + sum(h + ramp for _, h in holds)
    return delay <= max_delay and len(holds) <= max_holds and extra <= max_extra


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
):
    """One pass of :func:`resolve` placing the characters in ``order``; ``versions``
    counts each character's re-plans over all passes (its next one's number)."""
    table = Reservations(spacing)
    schedules, conflicts = [None] * len(tracks), []
    for i in order:
        track = tracks[i]
        s = Schedule(0, (), 0, np.asarray(track, float)[:, :2], holdable[i])
        s.base = (s.track, s.holdable)
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
                reserved += ghosts(table.line(j, horizon), frame, spacing, radius, fps)
            new = replan(i, list(reserved))
            if new is None:
                break
            versions[i] += 1
            s = Schedule(0, (), versions[i], np.asarray(new[0], float)[:, :2], new[1])
            s.base = (s.track, s.holdable)
        s, found = best
        table.reserve(i, s.track, s.delay)
        schedules[i] = s
        for j, (frames, frame, dist) in sorted(found.items()):
            conflicts.append(
                {
                    "a": j,
                    "b": i,
                    "frame": frame,
                    "first_frame": int(frames[0]),
                    "frames": int(len(frames)),
                    "distance_m": dist,
                }
            )
    return schedules, conflicts, table


def _repair(table, schedules, conflicts, max_delay, max_hold, ramp):
    """Conflicts left mended locally, cheaper than a restart: a character still too close
    is freed with those it meets, placed first and re-timed (:func:`_timed`), then they are
    re-timed round it; kept where all of them come clear, else put back as they were.
    ``schedules`` and ``table`` are changed in place; the ranks of the group are re-dealt in
    their new order. Returns how many groups were mended."""
    mended = 0
    for b in list(dict.fromkeys(c["b"] for c in conflicts)):
        if not table.check(schedules[b].track, schedules[b].delay):
            continue  # mended with another group
        found = _without(table, b, schedules[b])
        group = [b] + sorted(found, key=lambda j: schedules[j].rank)
        old = {i: schedules[i] for i in group}
        for i in group[1:]:
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
        if len(new) < len(group):
            for i in new:
                table.remove(i)
            for i in group:
                table.reserve(i, old[i].track, old[i].delay)
            continue
        for i, rank in zip(group, sorted(old[i].rank for i in group)):
            new[i].rank = rank
            schedules[i] = new[i]
        mended += 1
    return mended


def _without(table, i, s):
    """The conflicts of ``s`` (character ``i``, reserved) against the others."""
    table.remove(i)
    found = table.check(s.track, s.delay)
    table.reserve(i, s.track, s.delay)
    return found


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
) -> tuple[list[Schedule], list[dict[str, Any]]]:
    """Schedules and the conflicts left for ``tracks`` [(frames, 2)] in priority order,
    all starting on frame 0: each character in turn is checked against the
    :class:`Reservations` of those before it and, when it comes closer than ``spacing``,
    first re-timed to its earliest arrival clear of them all (:func:`_timed`,
    :func:`path_timing.earliest`: a wait at the start and idle holds anywhere on the way,
    one hold preferred); when no such timing fits in the longest wait and holds, changed by
    (at most ``stages`` changes, the first that clears everything, in this order of
    preference):

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
    above is done again, at most ``rounds`` times.

    When conflicts are left, each character still too close is first mended locally
    (:func:`_repair`: freed with those it meets, placed before them and all re-timed), and
    what is still left makes the crowd be resolved again from the start with the
    characters that met them placed first (prioritised planning's restart with raised
    priorities), at most ``restarts`` times, and the pass with the fewest frames too close
    is kept. What is left is reported: [{"a", "b" (indices, ``a`` placed first), "frame"
    (closest), "first_frame", "frames", "distance_m"}]. :attr:`Schedule.rank` is each
    character's place in the order of the pass kept."""
    ramp = int(ramp if ramp is not None else round(fps)) // 2 * 2
    max_hold = max_delay if max_hold is None else max_hold
    step = max(int(step), 1)
    holdable = list(holdable) if holdable is not None else [None] * len(tracks)
    order, versions, best = list(range(len(tracks))), [0] * len(tracks), None
    tracks, laned = list(tracks), {}  # laned: {character: version of its lane plan}
    strips = {}  # {character: the strips keeping it in its lane}, kept when it is re-routed
    on_lane = replan and (lambda i, discs: replan(i, strips.get(i, []) + discs))
    for _ in range(restarts + 1):
        schedules, conflicts, table = _resolve_once(
            order,
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
        )
        for rank, i in enumerate(order):
            schedules[i].rank = rank
            if i in laned and schedules[i].version == 0:  # on its lane plan
                schedules[i].version = laned[i]
        if conflicts and _repair(table, schedules, conflicts, max_delay, max_hold, ramp):
            conflicts = _left(schedules, spacing)
        left = sum(c["frames"] for c in conflicts)
        if best is None or left < best[0]:
            best = (left, schedules, conflicts)
        if not conflicts:
            break
        if replan is not None:  # lanes where pairs meet head-on, for the passes that follow
            formed = lanes.form(
                table.placed, conflicts, tracks, laned, replan, versions, spacing, radius
            )
            for i, (version, track, mask, lane) in formed.items():
                laned[i], tracks[i], holdable[i], strips[i] = version, track, mask, lane
        first = list(dict.fromkeys(c["b"] for c in conflicts))
        order = first + [i for i in order if i not in first]
    return best[1], best[2]


def conflicts_of(
    tracks: Sequence[np.ndarray], delays: Sequence[int], spacing: float
) -> list[dict[str, Any]]:
    """Every pair of ``tracks`` (in order, started ``delays`` frames late) closer than
    ``spacing`` on some frame, as :func:`resolve` reports them: the check of what is
    finally written, independent of how it was resolved."""
    table, out = Reservations(spacing), []
    for i, (track, d) in enumerate(zip(tracks, delays)):
        track = np.asarray(track, float)[:, :2]
        for j, (frames, frame, dist) in sorted(table.check(track, d).items()):
            out.append(
                {
                    "a": j,
                    "b": i,
                    "frame": frame,
                    "first_frame": int(frames[0]),
                    "frames": int(len(frames)),
                    "distance_m": dist,
                }
            )
        table.reserve(i, track, d)
    return out
