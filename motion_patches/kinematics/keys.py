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

from collections.abc import Sequence
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
# the first key's right handle and the second key's left handle give. So the curve Blender
# plays is known exactly here, and keys are kept only where that cubic strays from the
# planned values by more than a tolerance given in what shows (degrees of a bone's rotation,
# millimetres of the hips).
#
# A key's two handles are free (Blender's FREE handle type): the two slopes of every
# interval between keys are its own, fitted by least squares to the plan on the frames (and
# half frames) inside it. A key costs the same 72 bytes whatever its handles, and an interval
# with two free slopes fits two more values than one whose slopes are the plan's own at its
# ends: a captured walk's bodies need 0.41x the keys (bench/bench_files.py).

DEGREE = np.pi / 180.0
ANGLE = 0.5 * DEGREE  # how far a bone's played rotation may be from the plan
LENGTH = 1e-3  # how far a played location may be from the plan, metres
CURVE_BYTES = 330  # an F-curve's own blocks in a .blend (struct, path, key array head): estimated
# How much an interval's fitted slopes are drawn to the plan's own at its ends (relative to
# the frames inside): settles the slopes of intervals with fewer frames inside than slopes.
PULL = 1e-4
# An interval longer than this many frames that misses by more than SPLIT_MISS times the
# tolerance takes keys on the middles of both sides of its worst point too: a walk's
# channels need a key every few frames, and halving a long interval one key at a time
# took a third of the fit's time (the keys found are about as many, bench_files).
SPLIT_LONG = 16
SPLIT_MISS = 8.0


def slopes(values: ArrayLike) -> np.ndarray:
    """(F, C) per-frame slopes of ``values`` (F, C): central differences, one-sided at the
    ends. The plan's own slope on each frame (its course between frames, and what an
    interval's fitted slopes are drawn to)."""
    v = np.asarray(values, float)
    out = np.zeros_like(v)
    if len(v) > 1:
        out[1:-1] = 0.5 * (v[2:] - v[:-2])
        out[0] = v[1] - v[0]
        out[-1] = v[-1] - v[-2]
    return out


def hermite(
    x: ArrayLike, y: ArrayLike, m: ArrayLike, at: ArrayLike, m_in: ArrayLike | None = None
) -> np.ndarray:
    """Values at frames ``at`` of the curve Blender plays through keys on frames ``x`` (K,)
    with values ``y`` (K,), slopes ``m`` (K,) per frame of their right handles and ``m_in``
    of their left ones (default ``m``; handles at a third of each interval): the Hermite
    cubic between keys, the end keys' values outside. A NaN slope ``m`` marks a linear key
    (the segment it starts is a line)."""
    x, y, m = (np.asarray(a, float) for a in (x, y, m))
    m_in = m if m_in is None else np.asarray(m_in, float)
    at = np.asarray(at, float)
    if x.size == 1:
        return np.full(at.shape, y[0])
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    h = x[i + 1] - x[i]
    t = np.clip((at - x[i]) / h, 0.0, 1.0)
    y0, y1 = y[i], y[i + 1]
    m0, m1 = m[i] * h, m_in[i + 1] * h
    t2, t3 = t * t, t * t * t
    cubic = (
        (2 * t3 - 3 * t2 + 1) * y0
        + (t3 - 2 * t2 + t) * m0
        + (-2 * t3 + 3 * t2) * y1
        + (t3 - t2) * m1
    )
    return np.where(np.isnan(m[i]), y0 + (y1 - y0) * t, cubic)


def _reference(v: np.ndarray) -> np.ndarray:
    """(2F - 1, C) the plan on every frame and half frame: the values, and between frames
    the line between them, what keys on every frame play (bench_files measures against
    those). Judged against the plan's own cubic there instead (central slopes), fitted
    slopes put a captured arm 0.6 degrees from the line at a half frame where the two
    are a degree apart, as they are at a few in a hundred."""
    out = np.empty((2 * len(v) - 1,) + v.shape[1:])
    out[0::2] = v
    out[1::2] = 0.5 * (v[:-1] + v[1:])
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


def _power_sums(n):
    """(7, S) sums of j**k / n**k over j = 1 .. n - 1, for k = 0 .. 6 (Faulhaber)."""
    m = n - 1.0
    m1, m2 = m * (m + 1.0), 2.0 * m + 1.0
    raw = (
        m,
        m1 / 2.0,
        m1 * m2 / 6.0,
        m1 * m1 / 4.0,
        m1 * m2 * (3.0 * m1 - 1.0) / 30.0,
        m1 * m1 * (2.0 * m1 - 1.0) / 12.0,
        m1 * m2 * (3.0 * m1 * m1 - 3.0 * m1 + 1.0) / 42.0,
    )
    return np.array([x / n**k for k, x in enumerate(raw)])


_GRAM = [np.zeros((3, 0))]  # _gram of 0, 1, 2, ... points, grown as longer intervals come


def _gram(n):
    """The sums of the products of the two slopes' weights (:meth:`_Intervals._fit_kind`)
    over the points inside intervals of ``n`` (S,) points: (s00, s01, s11), each (S,).
    With t = j / n: t (1 - t)**2 and t**2 (t - 1), so polynomials in j, summed in closed
    form instead of point by point (and kept, by ``n``, between calls)."""
    table = _GRAM[0]
    if n.max() >= table.shape[1]:
        s = _power_sums(np.arange(1, 2 * int(n.max()) + 64, dtype=float))
        table = np.zeros((3, s.shape[1] + 1))
        table[0, 1:] = s[2] - 4 * s[3] + 6 * s[4] - 4 * s[5] + s[6]  # t**2 (1 - t)**4
        table[1, 1:] = -(s[3] - 3 * s[4] + 3 * s[5] - s[6])  # -t**3 (1 - t)**3
        table[2, 1:] = s[4] - 2 * s[5] + s[6]  # t**4 (1 - t)**2
        _GRAM[0] = table
    return table[:, n]


# A rotation that bends sharply on many frames (captured jitter: fingers, toes, the legs held
# finer) needs about a key every other frame and ends as samples; its fit used to add keys
# round after round until it reached ``give_up_at``, half of a crowd body's fitting time. A
# unit whose rotation turns away from the midpoint of its two neighbours by more than KINK
# times its angle on at least KINK_SHARE of ``give_up_at`` frames gives up at once. On a
# crowd's captured bodies (60 characters of bench_crowd.py's plaza) it caught 891 of the
# 1,088 units that gave up and none that did not.
KINK = 4.0
KINK_SHARE = 0.5


class _Kind:
    """Units of one kind (a :class:`Rotations`, or the lone columns), each a row: their
    unit indices (U,), columns (U, k), the angle a rotation is judged within, and per unit
    the values, plan slopes, plan on the judged points, what the keys play there and the
    fitted slopes, as (U, frames or points, k) arrays."""

    def __init__(self, units, cols, v, m, ref, judge, to_quat, angle=None):
        self.units, self.cols, self.judge, self.to_quat = units, cols, judge, to_quat
        self.angle = angle
        self.v, self.m = (np.ascontiguousarray(x[:, cols].transpose(1, 0, 2)) for x in (v, m))
        self.ref = np.ascontiguousarray(ref[:, cols].transpose(1, 0, 2))
        # a rotation's plan as quaternions; its error is judged from their dot product
        self.ref_q = None if to_quat is None else to_quat(self.ref)
        self.played = self.ref.copy()  # on keys (and before any fit) the plan itself
        self.m_out, self.m_in = self.m.copy(), self.m.copy()


class _Intervals:
    """The plan of one :func:`cubic_keys` call, and the fit of intervals between keys:
    each interval's two slopes (per column) by least squares on the points inside it,
    judged as its unit is (a rotation by the angle it plays, any other column alone)."""

    def __init__(self, v, tol, rotations, between, units, n_units, pull=PULL, steady=None):
        self.v, self.m, self.pull, self.steady = v, slopes(v), pull, steady
        self.step = 2 if between else 1  # points per frame: frames, and half frames
        ref = _reference(v) if len(v) else v
        self.ref = ref if between else ref[0::2]
        self.kinds = []
        kind_of, row_of = np.zeros(n_units, int), np.zeros(n_units, int)
        for r in rotations:
            if r.columns.size:
                u = units[r.columns[:, 0]]
                kind_of[u], row_of[u] = len(self.kinds), np.arange(u.size)
                # within the angle A: |dot| of the unit quaternions at least cos(A / 2)
                # below about 1.5e-8 rad 1 - cos rounds to 0 (a perfect fit's error 0 / 0)
                judge = max(1.0 - np.cos(0.5 * r.angle), np.finfo(float).eps)
                self.kinds.append(
                    _Kind(u, r.columns, v, self.m, self.ref, judge, r.to_quat, r.angle)
                )
        lone = np.flatnonzero(units < 0)
        if lone.size:
            u = -units[lone] - 1
            kind_of[u], row_of[u] = len(self.kinds), np.arange(u.size)
            self.kinds.append(_Kind(u, lone[:, None], v, self.m, self.ref, tol[lone], None))
        self.kind_of, self.row_of = kind_of, row_of

    def fit(self, a, b, u, limit=False):
        """Fit intervals (a, b) of units ``u`` (S,); keep the slopes and what is played of
        those within tolerance (and, unless ``limit``, of those a frame long, where no key
        can be added). Returns the others' (indices into the S, their worst points, their
        worst errors over the tolerance)."""
        missed, worst_at, worst_of = [np.zeros(0, int)], [np.zeros(0, int)], [np.zeros(0)]
        inside = self.step * (b - a) > 1
        kinds = self.kind_of[u]
        for g in np.unique(kinds[inside]):
            which = np.flatnonzero(inside & (kinds == g))
            ok, point, worst = self._fit_kind(
                self.kinds[g], a[which], b[which], self.row_of[u[which]]
            )
            if not limit:
                ok |= b[which] - a[which] <= 1
            missed.append(which[~ok])
            worst_at.append(point[~ok])
            worst_of.append(worst[~ok])
        return np.concatenate(missed), np.concatenate(worst_at), np.concatenate(worst_of)

    def _fit_kind(self, kind, a, b, row):
        n = self.step * (b - a)  # an interval's points, its end's included
        inside = n - 1
        first = np.cumsum(inside) - inside
        seg = np.repeat(np.arange(a.size), inside)
        offset = np.arange(first[-1] + inside[-1]) - np.repeat(first, inside)
        p = offset + np.repeat(self.step * a + 1, inside)
        t = (offset + 1.0) / np.repeat(n, inside)
        t2 = t * t
        up = t2 * (3.0 - 2.0 * t)  # the Hermite basis: y1's weight (y0's is 1 - up)
        w0 = t * (1.0 - t) ** 2  # slope 0's and slope 1's, the slopes per interval
        w1 = t2 * (t - 1.0)
        rs = row[seg]
        ya, yb = kind.v[row, a], kind.v[row, b]
        ref = kind.ref[rs, p]
        base = ya[seg] + up[:, None] * (yb - ya)[seg]
        r = ref - base
        # least squares, each slope drawn to the plan's own by PULL: [[s00, s01], [s01, s11]]
        s00, s01, s11 = (x[:, None] for x in _gram(n))
        h = (b - a)[:, None].astype(float)
        q0 = np.add.reduceat(w0[:, None] * r, first) + self.pull * h * kind.m[row, a]
        q1 = np.add.reduceat(w1[:, None] * r, first) + self.pull * h * kind.m[row, b]
        g00, g11 = s00 + self.pull, s11 + self.pull
        det = g00 * g11 - s01 * s01
        m0 = (g11 * q0 - s01 * q1) / det
        m1 = (g00 * q1 - s01 * q0) / det
        played = base + w0[:, None] * m0[seg] + w1[:, None] * m1[seg]
        if kind.to_quat is None:
            off = (played[:, 0] - ref[:, 0]) / kind.judge[rs]
            err = np.abs(off)
            if self.steady is not None:  # and its change from point to point (0 on keys)
                step = np.diff(off, prepend=0.0)
                step[first] = off[first]
                last = first + inside - 1
                err = np.maximum(err, np.abs(step) / self.steady)
                err[last] = np.maximum(err[last], np.abs(off[last]) / self.steady)
        else:
            dot = np.abs(np.einsum("pk,pk->p", kind.to_quat(played), kind.ref_q[rs, p]))
            err = (1.0 - dot) / kind.judge
        worst = np.maximum.reduceat(err, first)
        ok = worst <= 1.0
        at = np.flatnonzero(err == worst[seg])
        at = at[np.r_[True, seg[at[1:]] != seg[at[:-1]]]]  # the first worst of each
        kind.m_out[row[ok], a[ok]] = m0[ok] / h[ok]
        kind.m_in[row[ok], b[ok]] = m1[ok] / h[ok]
        mine = ok[seg]
        kind.played[rs[mine], p[mine]] = played[mine]
        return ok, p[at], worst

    def jittery(self, give_up_at, n_units):
        """(U,) bool: the rotation units whose plan bends sharply on many frames (KINK)."""
        out = np.zeros(n_units, bool)
        for kind in self.kinds:
            if kind.ref_q is None:
                continue
            q = kind.ref_q[:, :: self.step]  # (U, F, 4) the plan on its frames
            bend = 2.0 * np.linalg.norm(q[:, :-2] - 2.0 * q[:, 1:-1] + q[:, 2:], axis=-1)
            many = (bend > KINK * kind.angle).sum(axis=1) >= KINK_SHARE * give_up_at
            out[kind.units] = many  # bend: radians, about
        return out

    def gather(self, name, n_cols):
        """(points or frames, C) one of the kinds' per-unit arrays, by column."""
        arrays = [getattr(k, name) for k in self.kinds]
        out = np.empty((arrays[0].shape[1] if arrays else 0, n_cols))
        for k, x in zip(self.kinds, arrays):
            out[:, k.cols] = x.transpose(1, 0, 2)
        return out


def cubic_keys(
    values: ArrayLike,
    tol: ArrayLike,
    rotations: Sequence = (),
    between: bool = True,
    give_up_at: int | None = None,
    pull: float = PULL,
    steady: float | None = None,
) -> dict:
    """Cubic keys of every column of ``values`` (F, C) within tolerance: ``tol`` (C,) per
    column (or one for all) in the column's units, except the columns of ``rotations``
    (:class:`Rotations`), judged together as the rotation they play, within an angle.

    Checked on every frame and, with ``between``, every half frame (a strip scaled to
    another scene rate plays the keys between frames): against the values, and between
    frames against the line between them (:func:`_reference`). A unit (one column, or a
    bone's rotation columns) starts with keys on its first and last frames, each key on its
    frame's value; each interval between keys takes the two slopes that fit it best (least
    squares, :class:`_Intervals`: a key's left and right slopes differ), and one that misses
    anywhere gets a key on its worst frame (and, when long and far off, on the middles of
    both sides of it: :data:`SPLIT_LONG`), until none misses. Then keys are taken out,
    every other key of a unit at a time, where the interval over both of its sides fits,
    until none can be. Then a column whose unit stays within tolerance when it is held at
    its mid-range is made constant (one key).

    ``give_up_at``: a unit that keeps that many frames while keys are added stops taking
    keys (it costs more than one sample a frame and is stored as samples: its ``keep`` is
    then partial, and it plays the plan itself, exact on frames and linear between).
    ``inserted`` says how many keys each column's unit had before any was taken out: the
    units that give up are those where it reaches ``give_up_at``, and rotations that
    jitter (:data:`KINK`), which give up before any key is added. ``pull``: how much the
    fitted slopes are drawn to the plan's own (:data:`PULL`). ``steady``: the error of a
    lone column (not of rotations) may also change by at most that much of its tolerance
    from one point to the next (a channel that carries a planted foot), None: any.

    Returns {"keep": (F, C) bool kept frames, "values" (F, C) the keys take on each frame,
    "slopes" and "slopes_in" (F, C) the slopes of each key's right and left handles,
    "constant": (C,) bool, "value": (C,) the constant's value, "gave_up": (C,) bool the
    columns to store as samples, "inserted": (C,) keys before any was taken out}."""
    v = np.asarray(values, float)
    n, c = v.shape
    tol = np.broadcast_to(np.asarray(tol, float), (c,)).copy()
    units, n_units = _units_of(c, tol, rotations)
    col_unit = np.where(units < 0, -units - 1, units)
    fit = _Intervals(v, tol, rotations, between, units, n_units, pull, steady)
    keep_u = np.zeros((n, n_units), bool)
    keep_u[[0, -1]] = True
    gave_up = np.zeros(n_units, bool)

    # keys added where intervals miss (not on units that jitter: they give up at once)
    a, b, u = np.zeros(n_units, int), np.full(n_units, max(n - 1, 0)), np.arange(n_units)
    if give_up_at is not None and n > 2:
        gave_up = fit.jittery(give_up_at, n_units)
        a, b, u = a[~gave_up], b[~gave_up], u[~gave_up]
    while a.size and n > 1:
        which, point, worst = fit.fit(a, b, u)
        a, b, u = a[which], b[which], u[which]
        # a frame, or the half frame's neighbour that is not the interval's end
        frame = point // fit.step if fit.step == 1 else (point + 1) // 2
        frame = np.where(frame >= b, point // 2, frame)
        # every interval's ends and new keys (cut) by interval (cid), to be paired up in order
        ids = np.arange(a.size)
        cuts, cids = [a, b, frame], [ids, ids, ids]
        long = (b - a > SPLIT_LONG) & (worst > SPLIT_MISS)
        for lo, hi in ((a, frame), (frame, b)):
            mid = (lo + hi) // 2
            ok = long & (mid > lo) & (mid < hi)
            cuts.append(mid[ok])
            cids.append(ids[ok])
        cut, cid = np.concatenate(cuts), np.concatenate(cids)
        inner = np.ones(cut.size, bool)
        inner[: 2 * a.size] = False
        keep_u[cut[inner], u[cid[inner]]] = True
        if give_up_at is not None:  # the units that took a key and now keep that many
            took = np.zeros(n_units, bool)
            took[u[cid[inner]]] = True
            gave_up |= took & (keep_u.sum(axis=0) >= give_up_at)
        order = np.lexsort((cut, cid))
        cut, cid = cut[order], cid[order]
        pair = cid[1:] == cid[:-1]
        a, b, u = cut[:-1][pair], cut[1:][pair], u[cid[:-1][pair]]
        if give_up_at is not None:
            go_on = ~gave_up[u]
            a, b, u = a[go_on], b[go_on], u[go_on]
    inserted = keep_u.sum(axis=0)
    # keys taken out where the interval over both sides of one fits: every other key of a
    # unit at a time (their intervals do not overlap), each tried again only once a
    # neighbour of it has gone
    stale = keep_u & (~gave_up & (inserted > 2))[None]
    parity = 1
    while True:
        ku, kf = np.nonzero(keep_u.T)
        start = np.r_[True, ku[1:] != ku[:-1]]
        end = np.r_[ku[1:] != ku[:-1], True]
        tried = ~start & ~end & stale[kf, ku]
        if not tried.any():
            break
        pos = np.arange(ku.size) - np.maximum.accumulate(np.where(start, np.arange(ku.size), 0))
        cand = np.flatnonzero(tried & (pos % 2 == parity))
        parity ^= 1
        if not cand.size:
            continue
        which, _, _ = fit.fit(kf[cand - 1], kf[cand + 1], ku[cand], limit=True)
        stale[kf[cand], ku[cand]] = False
        gone = np.ones(cand.size, bool)
        gone[which] = False
        gone = cand[gone]
        keep_u[kf[gone], ku[gone]] = False
        for side in (gone - 1, gone + 1):
            stale[kf[side], ku[side]] = True

    keep = keep_u[:, col_unit]
    played = fit.gather("played", c) if n else v
    constant = np.zeros(c, bool)
    value = 0.5 * (v.max(axis=0) + v.min(axis=0)) if n else np.zeros(c)
    judged = fit.ref
    sampled = gave_up[col_unit]
    played[:, sampled] = judged[:, sampled]  # samples play the plan (a line between frames)
    # columns held at their mid-range: every lone column at once (each its own unit), then
    # one position of every rotation unit at a time
    lone = np.flatnonzero(units < 0) if n else np.zeros(0, int)
    if lone.size:
        off = (value[lone] - judged[:, lone]) / tol[lone]
        err = np.abs(off)
        if steady is not None:
            err[1:] = np.maximum(err[1:], np.abs(np.diff(off, axis=0)) / steady)
        take = lone[err.max(axis=0) <= 1.0]
        played[:, take] = value[take]
        constant[take] = True
    width = max((r.columns.shape[1] for r in rotations), default=0)
    for k in range(width if n else 0):
        cols = np.concatenate([r.columns[:, k] for r in rotations if k < r.columns.shape[1]])
        if not cols.size:
            continue
        trial = played.copy()
        trial[:, cols] = value[cols]
        touched = np.zeros(n_units, bool)
        touched[col_unit[cols]] = True
        err = _unit_errors(trial, judged, tol, rotations, units, n_units, touched)
        ok = err.max(axis=0) <= 1.0
        take = cols[ok[col_unit[cols]]]
        played[:, take] = value[take]
        constant[take] = True
    keep[:, constant] = False
    keep[0, constant] = True
    return {
        "keep": keep,
        "values": v,
        "slopes": fit.gather("m_out", c) if n else v,
        "slopes_in": fit.gather("m_in", c) if n else v,
        "constant": constant,
        "value": value,
        "gave_up": sampled & ~constant,
        "inserted": inserted[col_unit],
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
        out[:, j] = hermite(k, fit["values"][k, j], fit["slopes"][k, j], at, fit["slopes_in"][k, j])
    return out


def cubic_bytes(fit: dict) -> int:
    """Bytes the cubic keys ``fit`` add to a .blend: a key each, and each curve's own."""
    return int(fit["keep"].sum()) * KEY_BYTES + fit["keep"].shape[1] * CURVE_BYTES
