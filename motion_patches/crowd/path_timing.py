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


def earliest(track, busy, holdable, ramp, max_delay, max_extra, max_holds=1):
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
    down, up = _ramps(ramp) if can_hold.any() else (None, None)

    def at(u, t):
        """Busy at fractional track frames ``u`` on frames ``t`` (same shape)."""
        lo = np.clip(np.floor(u).astype(int), 0, n - 1)
        hi = np.minimum(lo + 1, n - 1)
        t = np.minimum(t, last)
        return busy[lo, t] | np.where(u > lo + 1e-9, busy[hi, t], False)

    # the goal: free on every frame from the arrival on (the first frame it stays free)
    goal = busy[n - 1, n - 1 :]
    if goal[-1]:
        return None
    goal_from = n - 1 + (int(np.nonzero(goal)[0][-1]) + 1 if goal.any() else 0)
    inf = np.iinfo(np.int64).max
    # per layer e: how each walking / standing state was reached, its value the least
    # (holds, start wait) of the ways there (:data:`_HOLD`)
    walk_from, stand_from = {}, {}
    seeds = {0: {0: (0, ("start",))}} if not busy[0, 0] else {}
    stand = {}  # e -> {k: (value, how)}
    for e in range(max_extra + 1):
        if not seeds and not stand:
            return None  # nothing left walking or standing
        s = seeds.pop(e, {})
        st = stand.pop(e, {})
        if not s and not st:
            continue
        free = ~busy[k_all, np.minimum(k_all + e, last)]
        # walking: from each seed forward while free, the least value winning
        val = np.full(n, inf)
        par = [None] * n
        for k in sorted(s):
            if free[k] and s[k][0] < val[k]:
                val[k], par[k] = s[k]
        if s:
            run_from = min(s)
            # forward fill while free: the least value of the seeds before in the run
            for k in range(run_from + 1, n):
                if free[k] and val[k - 1] < val[k]:
                    val[k], par[k] = val[k - 1], ("walk",)
        reach = val < inf
        walk_from[e] = par
        if reach[-1] and n - 1 + e >= goal_from:
            return _way_back(e, n - 1, walk_from, stand_from, ramp)
        # standing on: the start (before leaving) and held frames
        if reach[0] and e < max_delay and not busy[0, min(e + 1, last)]:
            seeds.setdefault(e + 1, {})[0] = (e + 1, ("wait",))
        stand_from[e] = {k: v[1] for k, v in st.items()}
        if st:
            ks = np.array(sorted(st), int)
            vs = np.array([st[int(k)][0] for k in ks])
            if e + 1 <= max_extra:
                for k, v in zip(ks, vs):
                    if not busy[k, min(k + e + 1, last)]:
                        _offer(stand, e + 1, int(k), (int(v), ("stand",)))
            if e + half <= max_extra:  # speed up out of a hold
                t = ks[:, None] + e + 1 + np.arange(ramp)[None]
                ok = ~at(ks[:, None] + up[None], t).any(1)
                for k, v in zip(ks[ok], vs[ok]):
                    layer = seeds.setdefault(e + half, {})
                    cand = (int(v), ("up", int(k)))
                    if cand[0] < layer.get(int(k) + half, (inf,))[0]:
                        layer[int(k) + half] = cand
        if can_hold.any() and e + half + 1 <= max_extra:  # slow down into a hold
            ks = np.nonzero(reach[: n - ramp] & can_hold[half : n - half])[0] + half
            if ks.size:
                t = (ks - half)[:, None] + e + 1 + np.arange(ramp + 1)[None]
                ok = ~at((ks - half)[:, None] + down[None], t).any(1)
                for k in ks[ok]:
                    v = int(val[k - half]) + _HOLD
                    if v // _HOLD <= max_holds:
                        _offer(stand, e + half + 1, int(k), (v, ("down",)))
    return None


_HOLD = 1 << 24  # a state's value: holds * _HOLD + frames waited at the start


def _offer(table, e, k, value):
    layer = table.setdefault(e, {})
    if k not in layer or value[0] < layer[k][0]:
        layer[k] = value


def _way_back(e, k, walk_from, stand_from, ramp):
    """(delay, holds) of the state walking on track frame ``k`` with ``e`` frames of delay."""
    half = ramp // 2
    holds, state = [], ("walk", k, e)
    delay, hold_end = 0, None
    while True:
        kind, k, e = state
        if kind == "walk":
            how = walk_from[e][k]
            if how[0] == "walk":
                state = ("walk", k - 1, e)
            elif how[0] == "start":
                break
            elif how[0] == "wait":  # stood at the start until here
                delay = e
                break
            else:  # up: out of a hold on frame how[1]
                hold_end = e - half
                state = ("stand", how[1], e - half)
        else:
            how = stand_from[e][k]
            if how[0] == "stand":
                state = ("stand", k, e - 1)
            else:  # down: the hold began here
                e0 = e - half - 1  # walking layer before the slow-down
                holds.append((k, hold_end - e + 1, e0))
                state = ("walk", k - half, e0)
    # holds in track order, each frame shifted by the holds before it
    out, shift = [], 0
    for k, h, _ in sorted(holds):
        out.append((k + shift, h))
        shift += h + ramp
    return delay, tuple(out)
