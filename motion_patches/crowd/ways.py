# SPDX-License-Identifier: GPL-3.0-or-later
"""Where the characters still to be placed walk: a walker held up does not stop in their way.

The resolver places a crowd one character at a time (:func:`~.crowd.resolve`); one held up
by those before it may stand still for a while in an idle hold. Where it stands, everyone
placed after it whose path runs there must wait for it to walk on, and in a doorway or a
corridor that is everyone: a hold in the opening stops the flow through it, the waits add
up along the crowd and the last ones find no time left. Crowd tools have walkers wait
before a bottleneck, not in it; so here a character holds only where none of those still
to be placed walks (:meth:`Ways.crossed`), found from the paths all of them were planned
on. It may still wait at its start, and holds anywhere once the others are all placed.
"""

import numpy as np

from .reservations import COLUMNS, cell_keys, column_ranges, in_ranges

STRIDE = 4  # every this many frames of a path are kept (about 0.2 m apart at a walk)
BETWEEN_M = 0.1  # the most a frame of a path lies from the nearest point kept of it


class Ways:
    """The ground tracks of a crowd's characters, a point every :data:`STRIDE` frames,
    sorted by the cell they lie in (``spacing`` and :data:`BETWEEN_M` wide: a point within
    that of another lies in its cell or a neighbour)."""

    def __init__(self, tracks: list[np.ndarray], spacing: float):
        pts, owner = [], []
        for i, t in enumerate(tracks):
            t = np.asarray(t, float)[:, :2]
            kept = np.vstack((t[::STRIDE], t[-1:]))
            pts.append(kept)
            owner.append(np.full(len(kept), i, np.int32))
        self.reach = self.cell = float(spacing) + BETWEEN_M
        xy = np.concatenate(pts) if pts else np.empty((0, 2))
        own = np.concatenate(owner) if owner else np.empty(0, np.int32)
        key = self._keys(xy)
        order = np.argsort(key, kind="stable")
        self.key, self.xy, self.owner = key[order], xy[order], own[order]

    def _keys(self, xy):
        return cell_keys(xy, self.cell)

    def _close(self, track: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(frame of ``track``, point kept) of every kept point within the spacing of it."""
        if not self.key.size or not len(track):
            return np.empty(0, int), np.empty(0, int)
        rows, ent = in_ranges(self.key, *column_ranges(self._keys(track)))
        rows = rows // COLUMNS  # a point's columns of cells
        d = self.xy[ent] - track[rows]
        close = np.einsum("ij,ij->i", d, d) < self.reach**2
        return rows[close], ent[close]

    def crossed(self, track: np.ndarray, waiting: np.ndarray) -> np.ndarray:
        """Bool per frame of ``track``: within the spacing of the path of a character
        ``waiting`` (bool per character) to be placed."""
        track = np.asarray(track, float)[:, :2]
        out = np.zeros(len(track), bool)
        if not waiting.any():
            return out
        rows, ent = self._close(track)
        out[rows[waiting[self.owner[ent]]]] = True
        return out

    def met(self, track: np.ndarray) -> np.ndarray:
        """The characters (sorted indices) whose paths come within the spacing of ``track``
        somewhere: the only ones it can meet, whenever either walks."""
        _, ent = self._close(np.asarray(track, float)[:, :2])
        return np.unique(self.owner[ent])
