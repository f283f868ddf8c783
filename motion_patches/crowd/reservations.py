# SPDX-License-Identifier: GPL-3.0-or-later
"""The space-time reservation table of a crowd: where each character placed walks on each
frame and where it stands before and after, looked up by cell (:class:`Reservations`)."""

import numpy as np
from numpy.typing import ArrayLike

_OFF = 1 << 20  # cell indices are shifted by this into a key's 21-bit fields
# A cell's column of three (y - 1 .. y + 1) is one range of keys (a key's low 21 bits are its
# y cell): the nine cells round a point are three look-ups, giving their entries in the order
# of the nine.
_COLUMN_SHIFTS = np.arange(-1, 2, dtype=np.int64) << 21
COLUMNS = len(_COLUMN_SHIFTS)  # key ranges :func:`column_ranges` gives per cell key


def cells(xy: ArrayLike, cell: float) -> np.ndarray:
    """(..., 2) int64 cell indices of points ``xy`` (..., 2) on a grid of ``cell`` metres,
    shifted into a key's 21-bit fields."""
    return np.floor(np.asarray(xy, float) / cell).astype(np.int64) + _OFF


def cell_keys(xy: ArrayLike, cell: float) -> np.ndarray:
    """(N,) the int64 key of each point's cell (x cell in the high field, y in the low 21
    bits: a column of cells is one range of keys, :func:`column_ranges`)."""
    c = cells(xy, cell)
    return c[:, 0] << 21 | c[:, 1]


def column_ranges(keys: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) key ranges (len(keys) * 3) of the three columns of cells round each cell
    key, key by key."""
    k = (np.asarray(keys, np.int64)[:, None] + _COLUMN_SHIFTS[None]).ravel()
    return k - 1, k + 1


def in_ranges(keys: np.ndarray, lo: ArrayLike, hi: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(query index, entry index) of every entry of the sorted ``keys`` in ``[lo[q],
    hi[q]]``, query by query, each query's entries in key order."""
    first = np.searchsorted(keys, lo, "left")
    n = np.searchsorted(keys, hi, "right") - first
    hit = np.nonzero(n > 0)[0]
    n = n[hit]
    return np.repeat(hit, n), np.repeat(first[hit] - np.cumsum(n) + n, n) + np.arange(n.sum())


class _Sorted:
    """Reserved root positions (frame, xy, owner) sorted by an int64 key, in runs: each
    reservation is a run of its own, and the newest run is merged into the one before
    while that one holds at most four times as much (a log-structured merge). Runs grow
    geometrically, so there are O(log N) of them to look through and every entry is
    copied O(log N) times in all, whatever the size of the crowd. An owner's entries
    always lie in one run (in key order), so what a look-up finds of one owner comes in
    the order of the queries.

    A removal only marks the reservation's entries dead (each entry carries the number of
    the reservation that made it); look-ups pass them over, merges leave them out, and all
    runs are swept once the dead outnumber the living. Removing by scanning every run cost
    a resolution of 10,000 characters a fifth of its time (each re-timing removes one)."""

    _COLUMNS = ("key", "frame", "xy", "owner", "stamp")

    def __init__(self):
        self.runs = []
        self.size = 0  # living entries
        self._dead = 0
        self._alive = np.zeros(64, bool)  # by reservation number
        self._count = np.zeros(64, np.int64)  # entries of each reservation
        self._stamp = {}  # owner -> the numbers of its living reservations
        self._next = 0

    def insert(self, key, frame, xy, owner):
        stamp = self._next
        self._next += 1
        if stamp >= self._alive.size:
            self._alive = np.concatenate((self._alive, np.zeros(self._alive.size, bool)))
            self._count = np.concatenate((self._count, np.zeros(self._count.size, np.int64)))
        self._alive[stamp], self._count[stamp] = True, key.size
        self._stamp.setdefault(owner, []).append(stamp)
        self.size += key.size
        order = np.argsort(key, kind="stable")
        run = {
            "key": key[order],
            "frame": frame[order],
            "xy": xy[order],
            "owner": np.full(key.size, owner, np.int32),
            "stamp": np.full(key.size, stamp, np.int32),
        }
        self.runs.append(run)
        while len(self.runs) > 1 and self.runs[-2]["key"].size <= 4 * self.runs[-1]["key"].size:
            new = self.runs.pop()
            old = self.runs.pop()
            both = {c: np.concatenate((old[c], new[c])) for c in self._COLUMNS}
            living = self._alive[both["stamp"]]
            if not living.all():  # the dead left out
                self._dead -= int(living.size - np.count_nonzero(living))
                both = self._rows(both, living)
            self.runs.append(self._rows(both, np.argsort(both["key"], kind="stable")))

    @classmethod
    def _rows(cls, run, which):
        """``run`` with every column taken at ``which`` (a mask or an order)."""
        return {c: run[c][which] for c in cls._COLUMNS}

    def remove(self, owner):
        stamps = self._stamp.pop(owner, [])
        if not stamps:
            return
        self._alive[stamps] = False
        n = int(self._count[stamps].sum())
        self.size -= n
        self._dead += n
        if self._dead > self.size:  # swept: look-ups stay in proportion to the living
            for i, run in enumerate(self.runs):
                living = self._alive[run["stamp"]]
                if not living.all():
                    self.runs[i] = self._rows(run, living)
            self.runs = [run for run in self.runs if run["key"].size]
            self._dead = 0

    def within(self, lo, hi):
        """(query index, frame, xy, owner) of every living entry whose key lies in
        ``[lo[q], hi[q]]`` for some query q, each query's in key order."""
        out = []
        for run in self.runs:
            rows, ent = in_ranges(run["key"], lo, hi)
            if ent.size:
                if self._dead:
                    living = self._alive[run["stamp"][ent]]
                    ent, rows = ent[living], rows[living]
                got = (run["frame"][ent], run["xy"][ent], run["owner"][ent])
                out.append((rows, *got))
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
        return cells(xy, self.cell)

    @staticmethod
    def _key(t, c):
        return (np.asarray(t, np.int64) << 42) | (c[..., 0] << 21) | c[..., 1]

    SLACK = 0.05  # metres cells are wider than the spacing: the most :meth:`busy` adds
    # added to a cell key: the cells round it
    _RING_KEYS = np.array([(i << 21) + j for i in range(-1, 2) for j in range(-1, 2)], np.int64)

    def _moving_near(self, t, xy):
        """(query row, xy, owner) of moving entries on frame ``t[row]`` in the cell of
        ``xy[row]`` or next to it."""
        if not self.moving.size or not len(t):
            return np.empty(0, int), np.empty((0, 2)), np.empty(0, int)
        rows, _, where, owner = self.moving.within(*column_ranges(self._key(t, self._cells(xy))))
        return rows // COLUMNS, where, owner

    def _spots_near(self, xy):
        """Indices of standing spots in the cells of the points ``xy`` or next to them."""
        if not self.spot_keys.size:
            return np.empty(0, int)
        c = np.unique(cell_keys(xy, self.cell))  # the cells of the points, once each
        q = np.unique((c[:, None] + self._RING_KEYS[None]).ravel())
        # disjoint ranges of the sorted keys, in order: already sorted and unique
        return in_ranges(self.spot_keys, q, q)[1]

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
            rows, when, where, _ = self.by_cell.within(*column_ranges(cell_keys(track, self.cell)))
            if rows.size:
                rows = rows // COLUMNS
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
        self.by_cell.insert(cell_keys(track, self.cell), t, track, index)
        spots = np.array([[*track[0], 0, d, index], [*track[-1], d + n, np.inf, index]], float)
        spots = spots[spots[:, 2] < spots[:, 3]]
        skeys = cell_keys(spots[:, :2], self.cell)
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
