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
    n = len(track)
    ramp = int(ramp) // 2 * 2
    half = ramp // 2
    can_hold = np.zeros(n, bool)
    if holdable is not None and ramp and n > ramp + 1 and max_holds > 0:
        can_hold[half : n - half] = np.asarray(holdable, bool)[half : n - half]
    down, up = _ramps(ramp) if can_hold.any() else (np.zeros(0, int), np.zeros(0, int))

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
    looks = _Looks(busy, n, down, up, can_hold)
    first = -_BLOCK  # the first layer of the block looked up
    for e in range(layers):
        sv, st = seed_v[e], stand_v[e]
        live_w, live_s = sv < _NONE, st < _NONE
        if not live_w.any() and not live_s.any():
            if not (seed_v[e + 1 :] < _NONE).any() and not (stand_v[e + 1 :] < _NONE).any():
                return None  # nothing left walking or standing
            continue
        if not first <= e < first + _BLOCK:
            first = e
            free_b, off_b, down_b, up_b = looks.block(e, min(e + _BLOCK, layers) - e)
        i = e - first
        free, off = free_b[i], off_b[i]
        # least value so far along runs of free frames (a walk carries its value forward
        # while the way is free; a busy frame ends the run)
        val = np.minimum.accumulate(np.where(free, sv, _NONE) + off) - off
        reach = val < _NONE
        how = reach.astype(np.int8) * np.int8(_WALK)
        seeded = free & (sv == val) & live_w
        how[seeded] = seed_how[e][seeded]
        walk_how[e] = how
        if reach[-1] and n - 1 + e >= goal_from:
            return _way_back(e, n - 1, walk_how, stand_how, ramp)
        # standing on: the start (before leaving) and held frames
        if reach[0] and e < max_delay and free_b[i + 1, 0] and e + 1 < layers:
            seed_v[e + 1, 0], seed_how[e + 1, 0] = min(seed_v[e + 1, 0], e + 1), _WAIT
        if live_s.any():
            ks = np.nonzero(live_s)[0]
            if e + 1 < layers:
                better = free_b[i + 1, ks] & (st[ks] < stand_v[e + 1, ks])
                stand_v[e + 1, ks[better]] = st[ks[better]]
                stand_how[e + 1, ks[better]] = _STAND
            # A ramp is looked at only where it would improve a state: most layers improve
            # none.
            if e + half < layers:  # speed up out of a hold
                ks = ks[st[ks] < seed_v[e + half, ks + half]]
                if ks.size:
                    ks = ks[~looks.ramp_busy(1, up_b, i, e, ks)]
                    seed_v[e + half, ks + half] = st[ks]
                    seed_how[e + half, ks + half] = _UP
        if looks.holds and e + half + 1 < layers:  # slow down into a hold
            ks = np.nonzero(reach[: n - ramp] & can_hold[half : n - half])[0] + half
            v = val[ks - half] + _HOLD
            better = (v // _HOLD <= max_holds) & (v < stand_v[e + half + 1, ks])
            ks, v = ks[better], v[better]
            if ks.size:
                ok = ~looks.ramp_busy(0, down_b, i, e, ks - half)
                stand_v[e + half + 1, ks[ok]] = v[ok]
                stand_how[e + half + 1, ks[ok]] = _DOWN
    return None


_BLOCK = 32  # layers whose look-ups are made at once


class _Looks:
    """What :func:`earliest` looks up in ``busy``, a block of layers at a time: whether
    each track frame is free on each layer (and the layer after), the offsets that carry a
    walk's least value along a run of free frames in one accumulate, and whether the
    slow-down into a hold (the speed-up out of one) from each track frame on each layer
    meets someone.

    Point ``j`` of a ramp from track frame k lies ``j + 1`` frames on, between track frames
    ``k + a`` and ``k + a + 1`` (``a`` its whole frames along the track). ``busy`` sheared
    by the track frame (:meth:`_sheared`: row d holds every track frame d frames after its
    own, column by column) holds that point of every k in one slice, so a block's ramps
    are ``ramp + 1`` slices each, not a look-up per layer. A ramp whose whole offsets are
    not the same from every frame that holds (rounding at the end of the track) is looked
    up point by point instead; both give the same answer."""

    def __init__(self, busy, n, down, up, can_hold):
        self.busy, self.n, self.last = busy, n, busy.shape[1] - 1
        held = np.flatnonzero(can_hold)
        self.holds = bool(held.size)
        half = len(up) // 2
        # (point-by-point ramp, its whole offsets and betweens or None), per ramp
        self.ramps = [self._ramp(down, held - half), self._ramp(up, held)] if self.holds else []
        shifts = [0, 1]  # each layer's own frame and the next (standing on)
        for _, same in self.ramps:
            if same is not None:
                a, between = same
                j = np.arange(len(a))
                shifts += (1 + j - a).tolist() + (j - a)[between].tolist()
        self.lo, self.hi = min(shifts), max(shifts)
        self.pad = 2 + max((int(same[0].max()) for _, same in self.ramps if same), default=0)

    def _ramp(self, offsets, rows):
        """(lo, hi, between) of the fractional track frames ``k + offsets`` for every track
        frame k, and (whole offsets, between) of its points when every row in ``rows`` has
        the same ones (else None)."""
        n = self.n
        u = np.arange(n)[:, None] + offsets[None]
        lo = np.clip(np.floor(u).astype(int), 0, n - 1)
        hi, between = np.minimum(lo + 1, n - 1), u > lo + 1e-9
        a, b = lo[rows[0]] - rows[0], between[rows[0]]
        same = (
            (lo[rows] - rows[:, None] == a[None]).all()
            and (hi[rows] - lo[rows] == 1).all()
            and (between[rows] == b[None]).all()
        )
        return (lo, hi, between), ((a, b) if same else None)

    def _sheared(self, e0, count):
        """(count, n + pad) bool: row i, column r: track frame r (the last one past the
        end) busy on frame ``r + e0 + i`` (``busy``'s last column for every frame after)."""
        r = np.arange(self.n + self.pad)
        t = np.clip(r[None] + e0 + np.arange(count)[:, None], 0, self.last)
        return self.busy[np.minimum(r, self.n - 1)[None], t]

    def block(self, e0, count):
        """Layers ``e0 .. e0 + count - 1``: (free (count + 1, n), run offsets (count, n),
        slow-down busy (count, n + pad) by the walking frame it leaves, speed-up busy
        (count, n + pad) by the held frame; a ramp looked up point by point: None)."""
        n = self.n
        sheared = self._sheared(e0 + self.lo, count + self.hi - self.lo)
        free = ~sheared[-self.lo : -self.lo + count + 1, :n]
        seg = np.cumsum(~free[:count], axis=1)
        off = (seg[:, -1:] + 1 - seg).astype(np.int64) * _SEG
        ramps = []
        for _, same in self.ramps:
            if same is None:
                ramps.append(None)
                continue
            a, between = same
            width = n + self.pad - int(a.max()) - 1
            hit = np.zeros((count, width), bool)
            for j, (aj, bj) in enumerate(zip(a.tolist(), between.tolist())):
                d = 1 + j - aj - self.lo  # the row of layer e0's point j
                hit |= sheared[d : d + count, aj : aj + width]
                if bj:  # and the track frame after it
                    hit |= sheared[d - 1 : d - 1 + count, aj + 1 : aj + 1 + width]
            ramps.append(hit)
        return free, off, *(ramps or (None, None))

    def ramp_busy(self, which, block, i, e, k):
        """Busy on ramp ``which`` (0: the slow-down from walking track frames ``k``, 1: the
        speed-up out of a hold on them) on layer ``e``: row ``i`` of its block's look-up
        (``block``), or point by point (on frames ``k + e + 1 ..``) where there is none."""
        if block is not None:
            return block[i, k]
        lo, hi, between = self.ramps[which][0]
        t = np.minimum(k[:, None] + e + 1 + np.arange(lo.shape[1])[None], self.last)
        return (self.busy[lo[k], t] | (between[k] & self.busy[hi[k], t])).any(1)


_HOLD = 1 << 24  # a state's value: holds * _HOLD + frames waited at the start


_NONE = 1 << 28  # no state: more than any value
_SEG = 1 << 29  # per run of free frames: later runs offset less, so none carries into the next
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
