# SPDX-License-Identifier: GPL-3.0-or-later
"""Space curves: cubic Hermite curves between nodes, constant-curvature arcs, arc length.

Hermite curves are evaluated for many candidates at once ((C, M) arrays) because the bake
fits thousands of them; tangent magnitudes are ``scale * chord`` so one scalar per curve
controls its length (the paper's "scale the tangent vectors").
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

# measure(pos, vel, acc[, kappa]) of sampled curves (C, M, 2) -> (C,): arc length, cycles, ...
Measure = Callable[..., np.ndarray]


def unit(angle: float | np.ndarray) -> np.ndarray:
    angle = np.asarray(angle, float)
    return np.stack((np.cos(angle), np.sin(angle)), axis=-1)


def _basis(u):
    """Hermite basis polynomials at params u (M,) for position, velocity, acceleration:
    three (4, M) arrays of the weights of p0, m0, p1, m1."""
    u = np.asarray(u, float)
    u2, u3 = u * u, u * u * u
    pos = np.stack((2 * u3 - 3 * u2 + 1, u3 - 2 * u2 + u, -2 * u3 + 3 * u2, u3 - u2))
    vel = np.stack((6 * u2 - 6 * u, 3 * u2 - 4 * u + 1, -6 * u2 + 6 * u, 3 * u2 - 2 * u))
    acc = np.stack((12 * u - 6, 6 * u - 4, -12 * u + 6, 6 * u - 2))
    return pos, vel, acc


def _combine(weights, a, b):
    """(C, M, 2) curves weights[0] x a + weights[1] x b for weights (2, M), points a, b
    (C, 2), as one matrix product laid out (C, 2, M) so each coordinate is contiguous."""
    c = a.shape[0]
    ctrl = np.stack((a, b), axis=-1).reshape(c * 2, 2)  # rows (curve, coordinate)
    return (ctrl @ weights).reshape(c, 2, -1).transpose(0, 2, 1)


def _hermite_parts(p0, d0, p1, d1, u):
    """Hermite curves (C,) at params u (M,) split by their tangent scale: for position,
    velocity and acceleration, (fixed, per unit scale) (C, M, 2) arrays, the value at
    scale s being fixed + s * per unit (the tangents are s x chord x d)."""
    p0, d0, p1, d1 = (np.atleast_2d(np.asarray(a, float)) for a in (p0, d0, p1, d1))
    chord = np.linalg.norm(p1 - p0, axis=-1)[:, None]
    return [
        (_combine(b[[0, 2]], p0, p1), _combine(b[[1, 3]], d0 * chord, d1 * chord))
        for b in _basis(u)
    ]


def hermite(
    p0: np.ndarray,
    d0: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
    scale: float | np.ndarray,
    u: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """Positions, first and second derivatives (C, M, 2) of Hermite curves at params u (M,).

    ``p0, p1`` (C, 2) end points, ``d0, d1`` (C, 2) unit end directions, ``scale`` (C,).
    """
    p0, d0, p1, d1 = (np.atleast_2d(np.asarray(a, float)) for a in (p0, d0, p1, d1))
    m = np.linalg.norm(p1 - p0, axis=-1)[:, None] * np.asarray(scale, float).reshape(-1, 1)
    c = p0.shape[0]
    ctrl = np.stack((p0, d0 * m, p1, d1 * m), axis=-1).reshape(c * 2, 4)
    return tuple((ctrl @ b).reshape(c, 2, -1).transpose(0, 2, 1) for b in _basis(u))


def curvature(vel: np.ndarray, acc: np.ndarray) -> np.ndarray:
    """Signed curvature (1/m) from derivatives (..., 2); positive turns left."""
    vx, vy = vel[..., 0], vel[..., 1]
    cross = vx * acc[..., 1] - vy * acc[..., 0]
    speed = np.maximum(np.sqrt(vx * vx + vy * vy), 1e-9)
    return cross / (speed * speed * speed)


def follows_turn_limits(
    pos: np.ndarray, vel: np.ndarray, kmin: float, kmax: float, slack: float = 0.02
) -> np.ndarray:
    """(C,) True where sampled curves (C, M, 2) turn, between every two samples, no more
    than the curvature limits allow over the distance between them (plus ``slack``
    radians). Curvature at the samples misses a cusp: where the speed vanishes the tangent
    flips by 180 degrees between two samples while a straight back-and-forth has zero
    curvature everywhere; the character would spin round on the spot."""
    h = np.unwrap(np.arctan2(vel[..., 1], vel[..., 0]), axis=-1)
    dh = np.diff(h, axis=-1)
    ds = np.linalg.norm(np.diff(pos, axis=-2), axis=-1)
    ok = (dh <= kmax * ds * 1.05 + slack) & (dh >= kmin * ds * 1.05 - slack)
    return ok.all(axis=-1)


def arc_lengths(pos: np.ndarray) -> np.ndarray:
    """Cumulative chord length along sampled curves (..., M, 2) -> (..., M)."""
    dx, dy = np.diff(pos[..., 0], axis=-1), np.diff(pos[..., 1], axis=-1)
    seg = np.sqrt(dx * dx + dy * dy)
    return np.concatenate((np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)), axis=-1)


@dataclass
class Curve:
    """One space curve sampled densely and indexed by arc length."""

    s: np.ndarray  # (M,) cumulative arc length
    pos: np.ndarray  # (M, 2)
    heading: np.ndarray  # (M,) unwrapped tangent angle
    kappa: np.ndarray  # (M,) signed curvature

    @property
    def length(self) -> float:
        return float(self.s[-1])

    def at(self, s: float | np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(x, y, heading, curvature) arrays at arc lengths ``s``."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        x = np.interp(s, self.s, self.pos[:, 0])
        y = np.interp(s, self.s, self.pos[:, 1])
        h = np.interp(s, self.s, self.heading)
        k = np.interp(s, self.s, self.kappa)
        return x, y, h, k

    def total_turn(self) -> float:
        return float(np.sum(np.abs(np.diff(self.heading))))


def joined(a: Curve, b: Curve) -> Curve:
    """One curve running along ``a`` then ``b`` (b starts where a ends)."""
    turns = np.round((a.heading[-1] - b.heading[0]) / (2 * np.pi)) * 2 * np.pi
    return Curve(
        np.concatenate((a.s, a.s[-1] + b.s[1:])),
        np.concatenate((a.pos, b.pos[1:])),
        np.concatenate((a.heading, b.heading[1:] + turns)),
        np.concatenate((a.kappa, b.kappa[1:])),
    )


def hermite_curve(
    p0: np.ndarray, d0: np.ndarray, p1: np.ndarray, d1: np.ndarray, scale: float, samples: int = 257
) -> Curve:
    """The :class:`Curve` of one Hermite curve, ``samples`` samples evenly in its parameter."""
    return hermite_curves(
        np.atleast_2d(p0),
        np.atleast_2d(d0),
        np.atleast_2d(p1),
        np.atleast_2d(d1),
        np.atleast_1d(scale),
        samples,
    )[0]


def hermite_curves(
    p0: np.ndarray,
    d0: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
    scale: float | np.ndarray,
    samples: int = 257,
) -> list[Curve]:
    """:func:`hermite_curve` of many curves (C,) at once: a list of C curves."""
    pos, vel, acc = hermite(p0, d0, p1, d1, scale, np.linspace(0.0, 1.0, samples))
    pos = np.ascontiguousarray(pos)
    heading = np.unwrap(np.arctan2(vel[..., 1], vel[..., 0]), axis=-1)
    s, kappa = arc_lengths(pos), curvature(vel, acc)
    return [Curve(s[i], pos[i], heading[i], kappa[i]) for i in range(pos.shape[0])]


def curve_length(pos: np.ndarray, vel: np.ndarray, acc: np.ndarray) -> np.ndarray:
    return arc_lengths(pos)[..., -1]


DEFAULT_SCALES = np.linspace(0.25, 4.0, 76)  # below ~0.25 a Hermite curve folds into a corner
TABULATE_BATCH = 100_000  # samples evaluated together when tabulating few curves


def tabulate(
    p0: np.ndarray,
    d0: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
    measure: Measure = curve_length,
    scales: np.ndarray = DEFAULT_SCALES,
    samples: int = 96,
    shares_curvature: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """``measure`` and largest |curvature| of curves (C,) at every scale of a grid (C, S).
    The curves at each scale are their fixed part plus the scale times their tangent part
    (:func:`_hermite_parts`); with ``shares_curvature`` the measure is called with the
    curvature this computes anyway, ``measure(pos, vel, acc, kappa)``."""
    c = p0.shape[0]
    u = np.linspace(0.0, 1.0, samples)
    values = np.empty((c, scales.size))
    bend = np.empty((c, scales.size))
    (pf, pu), (vf, vu), (af, au) = _hermite_parts(p0, d0, p1, d1, u)
    # Few curves: several scales in one call (as one batch of curves); many: one at a time.
    step = max(1, TABULATE_BATCH // (c * samples))
    for i in range(0, scales.size, step):
        sc = scales[i : i + step, None, None, None]
        pos, vel, acc = (
            (f[None] + sc * t[None]).reshape(-1, samples, 2)
            for f, t in ((pf, pu), (vf, vu), (af, au))
        )
        kappa = curvature(vel, acc)
        got = measure(pos, vel, acc, kappa) if shares_curvature else measure(pos, vel, acc)
        values[:, i : i + step] = got.reshape(-1, c).T
        bend[:, i : i + step] = np.abs(kappa).max(axis=1).reshape(-1, c).T
    return values, bend


def fit_scale(
    p0: np.ndarray,
    d0: np.ndarray,
    p1: np.ndarray,
    d1: np.ndarray,
    target: float | np.ndarray,
    measure: Measure = curve_length,
    scales: np.ndarray = DEFAULT_SCALES,
    samples: int = 96,
    table: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Tangent scale per curve whose ``measure`` equals ``target`` (C,), NaN where none does.

    ``measure(pos, vel, acc)`` maps sampled curves (C, M, 2) to (C,) (arc length by
    default; gait cycles for the bake). It is tabulated over a grid of scales (or taken
    from ``table``, see :func:`tabulate`); of the crossings of the target, the one whose
    curves bend least is refined by regula falsi.
    """
    p0, d0, p1, d1 = (np.atleast_2d(np.asarray(a, float)) for a in (p0, d0, p1, d1))
    c = p0.shape[0]
    target = np.broadcast_to(np.asarray(target, float), (c,))
    u = np.linspace(0.0, 1.0, samples)

    def evaluate(idx, sc):
        return measure(*hermite(p0[idx], d0[idx], p1[idx], d1[idx], sc, u))

    values, bend = (
        table if table is not None else tabulate(p0, d0, p1, d1, measure, scales, samples)
    )
    tol = 1e-6 * np.maximum(np.abs(target), 1.0)
    out = np.full(c, np.nan)
    # A straight curve keeps its chord length over a range of scales: take scale 1, where
    # the parameter runs at uniform speed.
    flat = np.abs(values[:, 0] - target) <= tol
    if flat.any():
        idx = np.flatnonzero(flat)
        flat[idx] = np.abs(evaluate(idx, np.ones(idx.size)) - target[idx]) <= tol[idx]
    out[flat] = 1.0
    diff = values - target[:, None]
    cross = (diff[:, :-1] < 0) & (diff[:, 1:] >= -tol[:, None])
    pair_bend = np.where(cross, np.maximum(bend[:, :-1], bend[:, 1:]), np.inf)
    first = np.argmin(pair_bend, axis=1) + 1
    ok = cross.any(axis=1) & ~flat
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return out
    f = first[idx]
    lo_s, hi_s = scales[f - 1].copy(), scales[f].copy()
    lo_v, hi_v = values[idx, f - 1].copy(), values[idx, f].copy()
    tg = target[idx]
    for _ in range(4):  # regula falsi, keeping the crossing bracketed
        sc = lo_s + (tg - lo_v) / np.maximum(hi_v - lo_v, 1e-12) * (hi_s - lo_s)
        v = evaluate(idx, sc)
        below = v < tg
        lo_s, lo_v = np.where(below, sc, lo_s), np.where(below, v, lo_v)
        hi_s, hi_v = np.where(below, hi_s, sc), np.where(below, hi_v, v)
    out[idx] = lo_s + (tg - lo_v) / np.maximum(hi_v - lo_v, 1e-12) * (hi_s - lo_s)
    return out


def arc_frame(
    p0: np.ndarray, heading0: float, kappa: float, s: float | np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Position (..., 2) and heading on a constant-curvature arc after arc length ``s``."""
    s = np.asarray(s, float)
    h = heading0 + kappa * s
    if abs(kappa) < 1e-9:
        pos = np.asarray(p0)[None] + s[:, None] * unit(heading0)[None]
    else:
        r = 1.0 / kappa
        cx = p0[0] - r * np.sin(heading0)
        cy = p0[1] + r * np.cos(heading0)
        pos = np.stack((cx + r * np.sin(h), cy - r * np.cos(h)), axis=-1)
    return pos, h


def arc_project(p0: np.ndarray, heading0: float, kappa: float, points: np.ndarray) -> np.ndarray:
    """Arc length of the closest point on the arc for each point (N, 2)."""
    points = np.asarray(points, float)
    if abs(kappa) < 1e-9:
        return (points - p0) @ unit(heading0)
    r = 1.0 / kappa
    c = np.array([p0[0] - r * np.sin(heading0), p0[1] + r * np.cos(heading0)])
    d = points - c
    ang = np.arctan2(d[:, 1], d[:, 0])
    start = np.arctan2(p0[1] - c[1], p0[0] - c[0])
    dang = np.unwrap(np.concatenate(([start], ang)))[1:] - start
    return dang / kappa
