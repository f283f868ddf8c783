# SPDX-License-Identifier: GPL-3.0-or-later
"""When to walk a fixed path through a crowd: the earliest arrival over waits and holds.

A character placed in a crowd keeps its path; only its timing may change (prioritised
planning along a fixed path, the time dimension of a space-time search). Its walk is a
time warp of its track: standing at its start a while, then walking at the recorded pace,
slowing to an idle hold on a double-support frame (:func:`motion_patches.kinematics.retime.
hold_phases`, feet planted), standing, and walking on, as often as it needs. The search runs
over states (track frame ``k``, frames of delay so far ``e``), the character being at
``track[k]`` on frame ``k + e``: walking advances ``k``; standing at the start or in a hold
advances ``e``; slowing down and speeding up are fixed stretches whose every frame is checked
where the warp really puts the root. Layers of ``e`` are searched in order, so the first
arrival whose goal stays free is the earliest one; among those the one with the shortest
wait at its start (holds before waits). Every checked point costs one look-up in the
reservation table, and only the layers up to the arrival are looked at: a character nobody
is in the way of costs one pass over its track.
"""

import numpy as np

from ..kinematics import retime


def _ramps(ramp):
    """(down, up) fractional track offsets of the slow-down into a hold on frame ``at``
    (frame ``at - ramp / 2`` is offset 0; ``ramp + 1`` entries for the frames after it, the
    last on the hold) and of the speed-up out of it (``ramp`` entries, from the frame after
    the hold's last, relative to ``at``)."""
    half = ramp // 2
    u = retime.hold_phases(2 * ramp + 3, ramp + 1, 1, ramp)  # at = ramp + 1, hold 1 frame
    a0 = ramp + 1 - half
    down = u[a0 + 1 : a0 + ramp + 2] - a0  # frames a0+1 .. a1 (stopped on its last)
    up = u[a0 + ramp + 2 : a0 + 2 * ramp + 2] - (ramp + 1)  # a2+1 .. a2+ramp
    return down, up


def earliest(
    track: np.ndarray,
    busy: np.ndarray,
    holdable: np.ndarray | None,
    ramp: int,
    max_delay: int,
    max_extra: int,
    max_holds: int = 1,
) -> tuple[int, tuple[tuple[int, int], ...]] | None:
    """The earliest timing of ``track`` (frames, 2) that ``busy`` never stops, or None:
    ``(delay, holds)``, ``delay`` frames standing at the start, ``holds`` [(frame, frames)]
    idle holds as :class:`~.crowd.Schedule` keeps them (each frame on the track as the holds
    before it left it). ``busy`` (frames, T) bool: ``track[k]`` is too close to someone on
    frame ``t`` (:meth:`~.crowd.Reservations.busy`; a point between two track frames, on a
    slow-down or speed-up, is taken as busy when either is). Its last column stands for
    every frame after it, so the goal must be free there and from the arrival on.
    ``holdable`` (bool per frame, None: no holds) marks the frames a hold may stop on,
    ``ramp`` (even) the frames of each slow-down and speed-up; the start wait is at most
    ``max_delay`` frames, all the extra time (wait, holds and their ramps) at most
    ``max_extra``, with ``T > frames + max_extra``. At most ``max_holds`` holds; of the
    earliest arrivals, one with the fewest holds, then the shortest wait at the start."""
    track = np.asarray(track, float)
    busy = np.asarray(busy, bool)
    n, last = len(track), busy.shape[1] - 1
    ramp = int(ramp) // 2 * 2
    half = ramp // 2
    k_all = np.arange(n)
    can_hold = np.zeros(n, bool)
    if holdable is not None and ramp and n > ramp + 1 and max_holds > 0:
        can_hold[half : n - half] = np.asarray(holdable, bool)[half : n - half]
    down, up = _ramps(ramp) if can_hold.any() else (np.zeros(0, int), np.zeros(0, int))

    def ramp_points(offsets):
        """(lo, hi, between) of the fractional track frames ``k + offsets`` for every
        track frame k (rows): the frames either side and whether it lies between them."""
        u = k_all[:, None] + offsets[None]
        lo = np.clip(np.floor(u).astype(int), 0, n - 1)
        return lo, np.minimum(lo + 1, n - 1), u > lo + 1e-9

    def at(points, k, t):
        """Busy at the ramp ``points`` from track frames ``k`` on frames ``t``."""
        lo, hi, between = points
        t = np.minimum(t, last)
        return busy[lo[k], t] | (between[k] & busy[hi[k], t])

    # the goal: free on every frame from the arrival on (the first frame it stays free)
    goal = busy[n - 1, n - 1 :]
    if goal[-1] or busy[0, 0]:
        return None
    goal_from = n - 1 + (int(np.nonzero(goal)[0][-1]) + 1 if goal.any() else 0)
    # dense layers e: the least value (:data:`_HOLD`) of each walking / standing state and
    # how it was reached (codes of :func:`_way_back`)
    layers = max_extra + 1
    seed_v = np.full((layers + half + 2, n), _NONE)
    seed_how = np.zeros((layers + half + 2, n), np.int8)
    stand_v = np.full((layers + half + 2, n), _NONE)
    walk_how = np.zeros((layers, n), np.int8)
    stand_how = np.zeros((layers + half + 2, n), np.int8)
    seed_v[0, 0], seed_how[0, 0] = 0, _START
    downs, ups = ramp_points(down), ramp_points(up)
    step, first = 32, -64  # layers whose free frames are looked up at once, the first
    for e in range(layers):
        sv, st = seed_v[e], stand_v[e]
        live_w, live_s = sv < _NONE, st < _NONE
        if not live_w.any() and not live_s.any():
            if not (seed_v[e + 1 :] < _NONE).any() and not (stand_v[e + 1 :] < _NONE).any():
                return None  # nothing left walking or standing
            continue
        if not first <= e < first + step:
            rows = np.minimum(k_all[None, :] + np.arange(e, min(e + step, layers))[:, None], last)
            frees, first = ~busy[k_all[None, :], rows], e
        free = frees[e - first]
        val = _run_min(np.where(free, sv, _NONE), free)
        how = np.where(val < _NONE, _WALK, 0).astype(np.int8)
        seeded = free & (sv == val) & live_w
        how[seeded] = seed_how[e][seeded]
        walk_how[e] = how
        reach = val < _NONE
        if reach[-1] and n - 1 + e >= goal_from:
            return _way_back(e, n - 1, walk_how, stand_how, ramp)
        # standing on: the start (before leaving) and held frames
        if reach[0] and e < max_delay and not busy[0, min(e + 1, last)] and e + 1 < layers:
            seed_v[e + 1, 0], seed_how[e + 1, 0] = min(seed_v[e + 1, 0], e + 1), _WAIT
        if live_s.any():
            ks = np.nonzero(live_s)[0]
            if e + 1 < layers:
                ok = ~busy[ks, np.minimum(ks + e + 1, last)]
                better = ok & (st[ks] < stand_v[e + 1, ks])
                stand_v[e + 1, ks[better]] = st[ks[better]]
                stand_how[e + 1, ks[better]] = _STAND
            # A ramp is looked at only where it would improve a state: most layers improve
            # none, and the look-up is the costly part.
            if e + half < layers:  # speed up out of a hold
                ks = ks[st[ks] < seed_v[e + half, ks + half]]
                if ks.size:
                    t = ks[:, None] + e + 1 + np.arange(ramp)[None]
                    ks = ks[~at(ups, ks, t).any(1)]
                    seed_v[e + half, ks + half] = st[ks]
                    seed_how[e + half, ks + half] = _UP
        if can_hold.any() and e + half + 1 < layers:  # slow down into a hold
            ks = np.nonzero(reach[: n - ramp] & can_hold[half : n - half])[0] + half
            v = val[ks - half] + _HOLD
            better = (v // _HOLD <= max_holds) & (v < stand_v[e + half + 1, ks])
            ks, v = ks[better], v[better]
            if ks.size:
                t = (ks - half)[:, None] + e + 1 + np.arange(ramp + 1)[None]
                ok = ~at(downs, ks - half, t).any(1)
                stand_v[e + half + 1, ks[ok]] = v[ok]
                stand_how[e + half + 1, ks[ok]] = _DOWN
    return None


def _run_min(v, free):
    """Least value so far along runs of ``free`` frames (a walk carries its value forward
    while the way is free; a busy frame ends the run)."""
    seg = np.cumsum(~free)
    off = (seg[-1] + 1 - seg).astype(np.int64) * _SEG
    return np.minimum.accumulate(v + off) - off


_HOLD = 1 << 24  # a state's value: holds * _HOLD + frames waited at the start


_NONE = 1 << 28  # no state: more than any value
_SEG = 1 << 29
_START, _WALK, _WAIT, _UP = 1, 2, 3, 4  # how a walking state was reached
_STAND, _DOWN = 1, 2  # how a standing state was reached


def _way_back(e, k, walk_how, stand_how, ramp):
    """(delay, holds) of the state walking on track frame ``k`` with ``e`` frames of delay."""
    half = ramp // 2
    holds, walking = [], True
    delay, hold_end = 0, None
    while True:
        if walking:
            how = walk_how[e, k]
            if how == _WALK:
                k -= 1
            elif how == _START:
                break
            elif how == _WAIT:  # stood at the start until here
                delay = e
                break
            else:  # up: out of a hold on frame k - half
                k, e, walking = k - half, e - half, False
                hold_end = e
        else:
            if stand_how[e, k] == _STAND:
                e -= 1
            else:  # down: the hold began here
                holds.append((k, hold_end - e + 1))
                k, e, walking = k - half, e - half - 1, True
    # holds in track order, each frame shifted by the holds before it
    out, shift = [], 0
    for k, h in sorted(holds):
        out.append((k + shift, h))
        shift += h + ramp
    return delay, tuple(out)
