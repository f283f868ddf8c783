# SPDX-License-Identifier: GPL-3.0-or-later
"""Compact keys: how many values a channel really needs, for small .blend files.

A planned channel is one value per frame. Blender stores a keyframe in 72 bytes (a
BezTriple, handles included, whatever the interpolation) but a *sampled* point (an F-curve
converted to samples) in 16; a .blend written by Blender 4.5 is not compressed. So each
channel is stored the cheapest way that plays back the same values:

* a constant channel as one key;
* else linear keys on the frames :func:`linear_keys` keeps (every other frame lies within
  ``tol`` of the line between its neighbouring keys), when they cost less than samples;
* else one sample per frame (exact at every frame, linear in between, as the keys were).

``tol`` is small (1e-5: metres, radians, quaternion components), far below what shows,
so the choice changes the file, not the motion.
"""

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

KEY_BYTES = 72  # a BezTriple in a .blend
SAMPLE_BYTES = 16  # an FPoint
BASE = 64  # the coarsest key spacing tried, frames


def linear_keys(
    values: np.ndarray, tol: float, base: int = BASE, give_up_at: int | None = None
) -> Any:
    """Mask (F, C) of the frames to key per column of ``values`` (F, C) so that linear
    interpolation between kept frames is within ``tol`` of every value; the first and last
    frames are always kept. Intervals that miss are halved until they fit.

    Vectorised over the intervals still failing, of every column at once: each pass
    tests only the frames inside those (an interval that fits keeps fitting), so the work
    shrinks as the keys settle. ``give_up_at``: stop refining a column once it keeps that
    many frames (it will be stored as samples, :func:`plan_columns`; its mask is then
    partial) and return ``(mask, gave_up (C,))``."""
    v = np.asarray(values, float)
    if v.ndim == 1:
        return linear_keys(v[:, None], tol, base)[:, 0]
    n, c = v.shape
    keep = np.zeros((n, c), bool)
    keep[::base] = True
    keep[-1] = True
    gave_up = np.zeros(c, bool)
    ends = np.flatnonzero(keep[:, 0]) if n else np.zeros(0, int)
    lo = np.tile(ends[:-1], c)  # intervals [lo, hi] between kept frames, per column
    hi = np.tile(ends[1:], c)
    col = np.repeat(np.arange(c), max(ends.size - 1, 0))
    count = np.full(c, ends.size)
    flat = v.ravel()
    while lo.size:
        inner = hi - lo - 1
        has = inner > 0
        lo, hi, col, inner = lo[has], hi[has], col[has], inner[has]
        if not lo.size:
            break
        first = np.cumsum(inner) - inner  # where each interval's inner frames begin
        f = np.arange(first[-1] + inner[-1]) + np.repeat(lo + 1 - first, inner)
        a, b = np.repeat(lo, inner), np.repeat(hi, inner)
        k = np.repeat(col, inner)
        w = (f - a) / (b - a)
        line = flat[a * c + k] * (1 - w) + flat[b * c + k] * w
        missed = np.add.reduceat(np.abs(line - flat[f * c + k]) > tol, first) > 0
        lo, hi, col = lo[missed], hi[missed], col[missed]
        mid = (lo + hi) // 2
        keep[mid, col] = True
        added = np.bincount(col, minlength=c)
        count += added
        if give_up_at is not None:
            full = count >= give_up_at
            gave_up |= full & (added > 0)
            go_on = ~full[col]
            lo, hi, col, mid = lo[go_on], hi[go_on], col[go_on], mid[go_on]
        lo, hi, col = np.concatenate((lo, mid)), np.concatenate((mid, hi)), np.tile(col, 2)
    return keep if give_up_at is None else (keep, gave_up)


def plan(values: ArrayLike, tol: float) -> tuple[str, np.ndarray | None]:
    """How to store one channel (F,): ("constant", None), ("keys", kept frame indices) or
    ("samples", None), the cheapest that plays every value within ``tol``."""
    return plan_columns(np.asarray(values, float)[:, None], tol)[0]


def must_keep(values: ArrayLike, tol: float) -> np.ndarray:
    """(C,) a lower bound on the frames any linear keying of each column of ``values``
    (F, C) within ``tol`` keeps: the first and last, and every frame whose second
    difference exceeds 4 ``tol``. (Within one linear piece the three frames round an inner
    frame are each within ``tol`` of a line, whose second difference is zero, so theirs is
    at most 4 ``tol``: a frame bending more is a key of every keying, the dyadic one of
    :func:`linear_keys` too.)"""
    v = np.asarray(values, float)
    n = v.shape[0]
    if n < 3:
        return np.full(v.shape[1], n)
    bend = np.abs(v[:-2] - 2.0 * v[1:-1] + v[2:])
    # a hair over 4 tol, so rounding in the difference never counts a frame that fits
    return np.count_nonzero(bend > 4.0 * tol * (1.0 + 1e-9) + 1e-15, axis=0) + 2


def plan_columns(values: ArrayLike, tol: float) -> list[tuple[str, np.ndarray | None]]:
    """:func:`plan` of every column of ``values`` (F, C), the kept keys of all the
    channels that vary found in one vectorised :func:`linear_keys` (a pose has ~100).

    A column that keeps at least as many frames as samples cost whatever the keys
    (:func:`must_keep`: one pass of second differences) is stored as samples without
    refining its keys: most channels of captured motion bend on most frames."""
    v = np.asarray(values, float)
    if v.size == 0:
        return [("constant", None)] * v.shape[1]
    varies = np.ptp(v, axis=0) > tol
    out: list[tuple[str, np.ndarray | None]] = [("constant", None)] * v.shape[1]
    n = v.shape[0]
    # keys cost more than samples from this many on: stop refining such a column
    limit = -(-n * SAMPLE_BYTES // KEY_BYTES)
    cols = np.flatnonzero(varies)
    if cols.size:
        sampled = must_keep(v[:, cols], tol) >= limit
        for c in cols[sampled]:
            out[c] = ("samples", None)
        cols = cols[~sampled]
    if cols.size:
        keep, gave_up = linear_keys(v[:, cols], tol, give_up_at=limit)
        keyed = ~gave_up & (keep.sum(axis=0) * KEY_BYTES < n * SAMPLE_BYTES)
        for c, k, as_keys in zip(cols, keep.T, keyed):
            out[c] = ("keys", np.flatnonzero(k)) if as_keys else ("samples", None)
    return out
