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


# --- Cubic keys --------------------------------------------------------------------------
#
# A Bezier key whose handles sit a third of the way to its neighbouring keys (in frames)
# makes Blender's curve between two keys a cubic in the frame itself (the Bezier's x is then
# linear in its parameter): the Hermite cubic through the two keys' values with the slopes
# their handles give. So the curve Blender plays is known exactly here, and keys are kept
# only where that cubic strays from the planned values by more than a tolerance given in
# what shows (degrees of a bone's rotation, millimetres of the hips). A walk needs a few
# such keys a second per channel where linear keys need one on most frames.

DEGREE = np.pi / 180.0
ANGLE = 0.5 * DEGREE  # how far a bone's played rotation may be from the plan
LENGTH = 1e-3  # how far a played location may be from the plan, metres
CURVE_BYTES = 330  # an F-curve's own blocks in a .blend (struct, path, key array head): estimated


def slopes(values: ArrayLike) -> np.ndarray:
    """(F, C) per-frame slopes of ``values`` (F, C): central differences, one-sided at the
    ends. The slope each cubic key takes on its frame."""
    v = np.asarray(values, float)
    out = np.zeros_like(v)
    if len(v) > 1:
        out[1:-1] = 0.5 * (v[2:] - v[:-2])
        out[0] = v[1] - v[0]
        out[-1] = v[-1] - v[-2]
    return out


def hermite(x: ArrayLike, y: ArrayLike, m: ArrayLike, at: ArrayLike) -> np.ndarray:
    """Values at frames ``at`` of the curve Blender plays through keys on frames ``x`` (K,)
    with values ``y`` (K,) and slopes ``m`` (K,) per frame (handles at a third of each
    interval): the Hermite cubic between keys, the end keys' values outside. A NaN slope
    marks a linear key (the segment it starts is a line)."""
    x, y, m = (np.asarray(a, float) for a in (x, y, m))
    at = np.asarray(at, float)
    if x.size == 1:
        return np.full(at.shape, y[0])
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    h = x[i + 1] - x[i]
    t = np.clip((at - x[i]) / h, 0.0, 1.0)
    y0, y1 = y[i], y[i + 1]
    m0, m1 = m[i] * h, m[i + 1] * h
    t2, t3 = t * t, t * t * t
    cubic = (
        (2 * t3 - 3 * t2 + 1) * y0
        + (t3 - 2 * t2 + t) * m0
        + (-2 * t3 + 3 * t2) * y1
        + (t3 - t2) * m1
    )
    return np.where(np.isnan(m[i]), y0 + (y1 - y0) * t, cubic)


def _around(keep: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(2F - 1, C) the key at or before, and the key after, each frame and half frame
    (the last key for points on or past it), of the kept frames ``keep`` (F, C)."""
    n = len(keep)
    idx = np.arange(n)[:, None]
    prev = np.maximum.accumulate(np.where(keep, idx, 0), axis=0)
    nxt = np.minimum.accumulate(np.where(keep, idx, n - 1)[::-1], axis=0)[::-1]
    f = np.arange(2 * n - 1) // 2  # the frame at or before each point
    return prev[f], nxt[np.minimum(f + 1, n - 1)]


def _dense(
    v: np.ndarray, m: np.ndarray, keep: np.ndarray | None, around=None, points=None
) -> np.ndarray:
    """(2F - 1, C) what the cubic keys ``keep`` (F, C) of ``v`` with slopes ``m`` play on
    every frame and half frame, all columns at once (``around``: :func:`_around` of
    ``keep``, when known; ``points``: only those of the 2F - 1 points, whose ``around``
    it then is)."""
    n, c = v.shape
    if points is None:
        points = np.arange(2 * n - 1)
    if around is None:
        assert keep is not None
        lo, hi = _around(keep)
        lo, hi = lo[points], hi[points]
    else:
        lo, hi = around
    at = points[:, None] / 2.0
    h = np.maximum(hi - lo, 1)
    t = np.clip((at - lo) / h, 0.0, 1.0)
    i0, i1 = lo * c + np.arange(c), hi * c + np.arange(c)  # flat indices: one gather each
    vf, mf = v.ravel(), m.ravel()
    y0 = vf[i0]
    d = vf[i1] - y0
    m0, m1 = mf[i0] * h, mf[i1] * h
    # the Hermite cubic of :func:`hermite`, in Horner's form
    return y0 + t * (m0 + t * ((3.0 * d - 2.0 * m0 - m1) + t * (m0 + m1 - 2.0 * d)))


def _reference(v: np.ndarray, m: np.ndarray) -> np.ndarray:
    """(2F - 1, C) the plan on every frame and half frame: the values, and between frames
    the cubic through the two frames with the slopes ``m`` (the motion's own smooth
    course, not the line between frames, which cuts every bend by its curvature)."""
    out = np.empty((2 * len(v) - 1,) + v.shape[1:])
    out[0::2] = v
    out[1::2] = 0.5 * (v[:-1] + v[1:]) + 0.125 * (m[:-1] - m[1:])
    return out


def _chord_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angle between unit quaternions ``a`` and ``b`` (..., 4), either sign."""
    d = np.minimum(np.linalg.norm(a - b, axis=-1), np.linalg.norm(a + b, axis=-1))
    return 4.0 * np.arcsin(np.minimum(d * 0.5, 1.0))


class Rotations:
    """Columns that are one rotation channel per bone: ``columns`` (B, k) indices of the
    (F, C) values, ``to_quat`` maps (..., k) channel values to unit quaternions (..., 4)
    as Blender plays them (a quaternion is normalised, Euler and axis-angle converted).
    Their error is the angle between the rotations played and planned, within ``angle``."""

    def __init__(self, columns: ArrayLike, to_quat: Any, angle: float = ANGLE):
        self.columns = np.asarray(columns, int).reshape(-1, np.shape(columns)[-1])
        self.to_quat = to_quat
        self.angle = float(angle)


def _unit_errors(played, ref, tol, rotations, units, n_units, active=None):
    """(P, U) error of each unit over its tolerance (1: just within) at every point.
    ``active`` (U,) bool: only those units are judged (the others read 0)."""
    err = np.zeros((played.shape[0], n_units))
    lone = np.flatnonzero(units < 0)
    if active is not None:
        lone = lone[active[-units[lone] - 1]]
    if lone.size:  # a lone column is its own unit
        err[:, -units[lone] - 1] = np.abs(played[:, lone] - ref[:, lone]) / tol[lone]
    for r in rotations:
        cols = r.columns
        if active is not None:
            cols = cols[active[units[cols[:, 0]]]]
            if not cols.size:
                continue
        a = _chord_angle(r.to_quat(played[:, cols]), r.to_quat(ref[:, cols])) / r.angle
        err[:, units[cols[:, 0]]] = a
    return err


def _units_of(n_cols, tol, rotations):
    """Unit index per column: a rotation's k columns share one unit (their keys); every
    other column is its own. Returned as (units (C,), n): rotation columns hold their
    unit's index, a lone column ``-(its unit) - 1``."""
    units = np.full(n_cols, -1)
    n = 0
    for r in rotations:
        for cols in r.columns:
            units[cols] = n
            n += 1
    lone = np.flatnonzero(units == -1)
    units[lone] = -(n + np.arange(lone.size)) - 1
    return units, n + lone.size


def cubic_keys(
    values: ArrayLike,
    tol: ArrayLike,
    rotations: tuple = (),
    between: bool = True,
    give_up_at: int | None = None,
) -> dict:
    """Cubic keys of every column of ``values`` (F, C) within tolerance: ``tol`` (C,) per
    column (or one for all) in the column's units, except the columns of ``rotations``
    (:class:`Rotations`), judged together as the rotation they play, within an angle.

    Checked on every frame and, with ``between``, every half frame (a strip scaled to
    another scene rate plays the keys between frames): against the values, and between
    frames against the plan's own cubic there (:func:`_reference`). A unit (one column,
    or a bone's rotation columns) starts with keys on its first and last frames; each
    interval that misses anywhere gets a key on its worst frame, until none misses. Then
    a column whose unit stays within tolerance when it is held at its mid-range is made
    constant (one key).

    ``give_up_at``: a unit that keeps that many frames stops taking keys (it costs more
    than one sample a frame and is stored as samples: its ``keep`` is then partial, and
    it is held against the plan as samples play, exact on frames and linear between).

    Returns {"keep": (F, C) bool kept frames, "values" and "slopes" (F, C) the keys take
    on each frame, "constant": (C,) bool, "value": (C,) the constant's value,
    "gave_up": (C,) bool the columns to store as samples}."""
    v = np.asarray(values, float)
    n, c = v.shape
    tol = np.broadcast_to(np.asarray(tol, float), (c,)).copy()
    units, n_units = _units_of(c, tol, rotations)
    col_unit = np.where(units < 0, -units - 1, units)
    m = slopes(v)
    v_key = v
    ref = _reference(v, m)
    # the points judged: every frame and, with ``between``, every half frame
    points = np.arange(0, 2 * n - 1, 1 if between else 2)
    judged = ref[points]
    keep_u = np.zeros((n, n_units), bool)
    keep_u[[0, -1]] = True
    # a unit whose every interval fits keeps fitting (its keys no longer change): only the
    # units that took a key last pass are played and judged again
    active = np.ones(n_units, bool)
    gave_up = np.zeros(n_units, bool)
    played = np.empty((points.size, c))
    while n > 2:
        act = np.flatnonzero(active)
        cols = np.flatnonzero(active[col_unit])
        lo, hi = _around(keep_u[:, act])
        lo, hi = lo[points], hi[points]
        at = np.cumsum(active) - 1  # a unit's place among the active ones
        on = at[col_unit[cols]]
        played[:, cols] = _dense(v_key[:, cols], m[:, cols], None, (lo[:, on], hi[:, on]), points)
        err = _unit_errors(played, judged, tol, rotations, units, n_units, active)[:, act]
        # between two keys a frame apart no key can be added: what is played there stays
        err[hi - lo <= 1] = 0.0
        # the worst point of each interval between keys, per unit: points of one interval
        # are consecutive, so each interval is one run of the unit-major flattening
        flat_err = err.T.ravel()
        seg = (lo + np.arange(act.size) * n).T.ravel()
        new = np.r_[True, seg[1:] != seg[:-1]]
        run = np.cumsum(new) - 1
        worst = np.maximum.reduceat(flat_err, np.flatnonzero(new))
        hit = np.flatnonzero((flat_err > 1.0) & (flat_err == worst[run]))
        if not hit.size:
            break
        hit = hit[np.r_[True, run[hit[1:]] != run[hit[:-1]]]]  # the first worst of a run
        k, point = np.divmod(hit, points.size)
        point = points[point]
        unit = act[k]
        # a frame, or the half frame's neighbour that is no key yet
        frame = (point + 1) // 2
        frame = np.where(keep_u[frame, unit], point // 2, frame)
        keep_u[frame, unit] = True
        active[:] = False
        active[unit] = True
        if give_up_at is not None:
            gave_up |= active & (keep_u.sum(axis=0) >= give_up_at)
            active &= ~gave_up
            if not active.any():
                break
    keep = keep_u[:, col_unit]
    constant = np.zeros(c, bool)
    value = 0.5 * (v.max(axis=0) + v.min(axis=0)) if n else np.zeros(c)
    # columns held at their mid-range, one position of every rotation unit at a time
    order = [[j] for j in np.flatnonzero(units < 0)]
    width = max((r.columns.shape[1] for r in rotations), default=0)
    order += [[r.columns[:, k] for r in rotations if k < r.columns.shape[1]] for k in range(width)]
    played = _dense(v_key, m, keep, points=points) if n else v
    sampled = gave_up[col_unit]
    if n and sampled.any():  # samples: the values on frames, linear between
        samples = np.empty((2 * n - 1, int(sampled.sum())))
        samples[0::2] = v[:, sampled]
        samples[1::2] = 0.5 * (v[:-1, sampled] + v[1:, sampled])
        played[:, sampled] = samples[points]
    # points between keys a frame apart keep what those keys play (see above)
    excused = np.zeros(0, bool)
    if n:
        lo, hi = _around(keep_u)
        excused = hi - lo <= 1
        excused[1::2, gave_up] = True  # nor between samples
        excused[0::2] = False  # frames themselves are never excused
        excused = excused[points]
    for group in order:
        cols = np.concatenate([np.ravel(g) for g in group]) if group else np.zeros(0, int)
        if not cols.size or not n:
            continue
        trial = played.copy()
        trial[:, cols] = value[cols]
        touched = np.zeros(n_units, bool)
        touched[col_unit[cols]] = True
        err = _unit_errors(trial, judged, tol, rotations, units, n_units, touched)
        err[excused] = 0.0
        ok = err.max(axis=0) <= 1.0
        take = cols[ok[col_unit[cols]]]
        played[:, take] = value[take]
        constant[take] = True
    keep[:, constant] = False
    keep[0, constant] = True
    return {
        "keep": keep,
        "values": v_key,
        "slopes": m,
        "constant": constant,
        "value": value,
        "gave_up": sampled & ~constant,
    }


def play(values: ArrayLike, fit: dict, at: ArrayLike) -> np.ndarray:
    """(len(at), C) what the cubic keys ``fit`` (:func:`cubic_keys`) of ``values`` play at
    frames ``at``, column by column as Blender evaluates them."""
    v = np.asarray(values, float)
    out = np.empty((np.size(at), v.shape[1]))
    for j in range(v.shape[1]):
        if fit["constant"][j]:
            out[:, j] = fit["value"][j]
            continue
        k = np.flatnonzero(fit["keep"][:, j])
        out[:, j] = hermite(k, fit["values"][k, j], fit["slopes"][k, j], at)
    return out


def cubic_bytes(fit: dict) -> int:
    """Bytes the cubic keys ``fit`` add to a .blend: a key each, and each curve's own."""
    return int(fit["keep"].sum()) * KEY_BYTES + fit["keep"].shape[1] * CURVE_BYTES
