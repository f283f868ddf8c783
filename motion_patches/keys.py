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

import numpy as np

KEY_BYTES = 72  # a BezTriple in a .blend
SAMPLE_BYTES = 16  # an FPoint
BASE = 64  # the coarsest key spacing tried, frames


def linear_keys(values, tol, base=BASE, give_up_at=None):
    """Mask (F, C) of the frames to key per column of ``values`` (F, C) so that linear
    interpolation between kept frames is within ``tol`` of every value; the first and last
    frames are always kept. Intervals that miss are halved until they fit (vectorised over
    the columns still refining: a few passes).

    ``give_up_at``: stop refining a column once it keeps that many frames (it will be
    stored as samples, :func:`plan_columns`; its mask is then partial) and return
    ``(mask, gave_up (C,))``."""
    v = np.asarray(values, float)
    if v.ndim == 1:
        return linear_keys(v[:, None], tol, base)[:, 0]
    n, c = v.shape
    keep = np.zeros((n, c), bool)
    keep[::base] = True
    keep[-1] = True
    gave_up = np.zeros(c, bool)
    active = np.arange(c)
    idx = np.arange(n)[:, None]
    while active.size:
        k, va = keep[:, active], v[:, active]
        cols = np.arange(active.size)[None]
        prev = np.maximum.accumulate(np.where(k, idx, 0), axis=0)
        nxt = np.minimum.accumulate(np.where(k, idx, n - 1)[::-1], axis=0)[::-1]
        w = (idx - prev) / np.maximum(nxt - prev, 1)
        line = va[prev, cols] * (1 - w) + va[nxt, cols] * w
        f, col = np.nonzero((np.abs(line - va) > tol) & ~k)
        keep[(prev[f, col] + nxt[f, col]) // 2, active[col]] = True
        refining = np.zeros(active.size, bool)
        refining[col] = True
        if give_up_at is not None:
            full = keep[:, active].sum(axis=0) >= give_up_at
            gave_up[active[full & refining]] = True
            refining &= ~full
        active = active[refining]
    return keep if give_up_at is None else (keep, gave_up)


def plan(values, tol):
    """How to store one channel (F,): ("constant", None), ("keys", kept frame indices) or
    ("samples", None), the cheapest that plays every value within ``tol``."""
    return plan_columns(np.asarray(values, float)[:, None], tol)[0]


def plan_columns(values, tol):
    """:func:`plan` of every column of ``values`` (F, C), the kept keys of all the
    channels that vary found in one vectorised :func:`linear_keys` (a pose has ~100)."""
    v = np.asarray(values, float)
    if v.size == 0:
        return [("constant", None)] * v.shape[1]
    varies = np.ptp(v, axis=0) > tol
    out = [("constant", None)] * v.shape[1]
    cols = np.flatnonzero(varies)
    if cols.size:
        n = v.shape[0]
        # keys cost more than samples from this many on: stop refining such a column
        limit = -(-n * SAMPLE_BYTES // KEY_BYTES)
        keep, gave_up = linear_keys(v[:, cols], tol, give_up_at=limit)
        for c, k, many in zip(cols, keep.T, gave_up):
            kept = np.flatnonzero(k)
            out[c] = (
                ("keys", kept)
                if not many and kept.size * KEY_BYTES < n * SAMPLE_BYTES
                else ("samples", None)
            )
    return out
