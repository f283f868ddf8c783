# SPDX-License-Identifier: GPL-3.0-or-later
"""Space-curve following: a gait's loops played along a curve, turns blended by curvature.

The root is bound to the curve by the loops' own travelled distance and faces the curve's
tangent (paper Sec. 6). Near both ends of a segment the blend eases back to the straight
loop, so every node carries the same pose and segments join without a pop.
"""

import numpy as np

from ..kinematics.motion import Motion
from .curves import Curve, arc_lengths, curvature
from .gait import Gait

RAMP = 0.25  # of a straight cycle's distance: blend easing length at segment ends
WEIGHT_WINDOW = 0.125  # of a gait cycle's frames: loop weights averaged this far either side


def cycles_along(
    gait: Gait,
    pos: np.ndarray,
    vel: np.ndarray,
    acc: np.ndarray,
    eased: tuple[bool, bool] = (True, True),
    kappa: np.ndarray | None = None,
) -> np.ndarray:
    """Gait cycles needed to follow sampled curves (..., M, 2) -> (...).

    The phase advances by ds / D(w(s)) with D the blended cycle distance at the eased
    curvature, so a curve's "whole number of cycles" accounts for shorter turning strides.
    ``kappa``: the curves' curvature, when the caller has it already (it is not changed).
    """
    s = arc_lengths(pos)
    kap = curvature(vel, acc) if kappa is None else kappa.copy()
    length = s[..., -1:]
    kap *= _ease(s, length, gait.cycle_distance * RAMP, eased)
    d = gait.blended_distance(kap)
    dmid = d[..., 1:] + d[..., :-1]
    dmid *= 0.5
    return np.sum(np.diff(s, axis=-1) / dmid, axis=-1)


def cycles_along_many(
    gait: Gait, pos: np.ndarray, first: np.ndarray, eased: tuple[bool, bool] = (True, True)
) -> np.ndarray:
    """:func:`cycles_along` of many sampled curves at once, each with the derivatives
    ``np.gradient`` takes of its samples: ``pos`` (N, 2) holds the curves one after the
    other, curve c from row ``first[c]`` to ``first[c + 1]`` (at least 3 rows each)."""
    first = np.asarray(first)
    start, end = first[:-1], first[1:] - 1
    counts = first[1:] - first[:-1]

    def gradient(a):
        g = np.empty_like(a)
        g[1:-1] = (a[2:] - a[:-2]) / 2.0
        g[start] = a[start + 1] - a[start]
        g[end] = a[end] - a[end - 1]
        return g

    vel = gradient(pos)
    acc = gradient(vel)
    d = np.diff(pos, axis=0)
    step = np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])
    step[end[:-1]] = 0.0  # from one curve to the next
    total = np.concatenate(([0.0], np.cumsum(step)))
    s = total - np.repeat(total[start], counts)
    ease = _ease(s, np.repeat(s[end], counts), gait.cycle_distance * RAMP, eased)
    dist = gait.blended_distance(curvature(vel, acc) * ease)
    ds = np.diff(s)
    ds[end[:-1]] = 0.0
    terms = ds / (0.5 * (dist[1:] + dist[:-1]))
    return np.add.reduceat(np.append(terms, 0.0), start)


def _ease(s, length, ramp_len, eased):
    """Easing weights (smoothsteps over ``ramp_len`` from each eased end) at arc lengths."""
    e = np.ones_like(s)
    ramp = max(ramp_len, 1e-9)
    for on, d in ((eased[0], s / ramp), (eased[1], (length - s) / ramp)):
        if on:
            np.clip(d, 0.0, 1.0, out=d)
            e *= d * d * (3.0 - 2.0 * d)  # 1 where d = 1
    return e


def double_support(gait: Gait) -> np.ndarray:
    """Phases of the straight loop in the middle of each stretch with both feet planted
    (a heel or toe of each; ascending, empty for a gait that has none, as a run): where a
    walk can stop with the last step landed, or start with a foot about to lift. Kept on
    the gait for as long as its straight loop's contacts are the same (read only): every
    piece of a plan's motion asks for them."""
    lp = gait.straight
    kept = gait.__dict__.get("_double_support")
    if kept is not None and kept[0] is lp and kept[1] is lp.contacts:
        return kept[2]
    c = np.asarray(lp.contacts, bool)
    both = (c[:, 0] | c[:, 1]) & (c[:, 2] | c[:, 3])
    n = both.size
    if both.all() or not both.any():
        out = np.zeros(0, int)
    else:
        shift = int(np.argmin(both))  # a frame with one foot up: no stretch wraps past it
        rolled = np.roll(both, -shift)
        d = np.diff(np.concatenate(([0], rolled.astype(int), [0])))
        starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
        out = np.sort(((starts + ends - 1) // 2 + shift) % n)
    out.flags.writeable = False
    gait.__dict__["_double_support"] = (lp, lp.contacts, out)
    return out


def _stretched(phase_at: np.ndarray, total: float) -> np.ndarray:
    """Cycles along a curve (``phase_at``, from 0) scaled to end on ``total``; a curve of no
    length (steps on the spot) advances evenly instead of dividing by zero."""
    if phase_at[-1] > 1e-12:
        return phase_at * (total / phase_at[-1])
    return np.linspace(0.0, total, phase_at.size)


def frame_arclengths(
    gait: Gait,
    curve: Curve,
    cycles: int | str | None = None,
    start_phase: int = 0,
    eased: tuple[bool, bool] = (True, True),
    phases: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frame phases (K,), arc length of the root on the curve per frame (K,), and the
    curve's easing weights: the timing of :func:`follow` without building any pose.
    ``phases``: the phases a ``"to node"`` motion may start on and a motion without
    ``cycles`` may end on (:func:`double_support`: a start or a stop); the stride is
    stretched along the curve to the nearest (by under a quarter cycle)."""
    n = gait.frames
    ease = _ease(curve.s, curve.length, gait.cycle_distance * RAMP, eased)
    dist = gait.blended_distance(curve.kappa * ease)
    dmid = 0.5 * (dist[1:] + dist[:-1])
    phase_at = np.concatenate(([0.0], np.cumsum(np.diff(curve.s) / dmid)))  # cycles along curve
    straight = gait.straight
    profile = straight.distance / straight.cycle_distance  # (n + 1,) within-cycle fraction
    some = phases is not None and len(phases) > 0
    if cycles == "to node" and some:
        # Starting on one of ``phases`` and ending on the node pose: the whole number of
        # cycles and the start phase whose travel is nearest the curve's.
        whole, start_phase = _nearest_phase(phase_at[-1], profile, phases, start=True)
        phase_at = _stretched(phase_at, whole - profile[start_phase])
        total = whole * n - start_phase
    elif cycles == "to node":
        # Any length, ending on the node pose: start at the phase that leaves a whole
        # number of cycles to the end (the stride stretched by under one frame's travel).
        whole = max(int(np.ceil(phase_at[-1] - 0.5 / n)), 1)
        start_phase = int(np.argmin(np.abs(profile[:n] - (whole - phase_at[-1]))))
        if whole - profile[start_phase] <= 0:
            start_phase = 0
        phase_at = _stretched(phase_at, whole - profile[start_phase])
        total = whole * n - start_phase
    elif cycles is None and some:
        # Ending on one of ``phases``: the stop's last step lands.
        base = profile[start_phase % n]
        whole, end = _nearest_phase(phase_at[-1], profile, phases, start=False, base=base)
        phase_at = _stretched(phase_at, whole + profile[end] - base)
        total = whole * n + end - start_phase % n
    elif cycles is not None:
        assert not isinstance(cycles, str), cycles  # "to node" is the one word
        phase_at = _stretched(phase_at, cycles)
        total = cycles * n
    else:
        total = int(np.ceil(phase_at[-1] * n - 1e-9))
    k = np.arange(total + 1) + start_phase
    c = k // n
    target = c + profile[k % n] - (start_phase // n + profile[start_phase % n])
    target = np.clip(target, 0.0, phase_at[-1])
    target[-1] = phase_at[-1]
    return k, np.interp(target, phase_at, curve.s), ease


def _nearest_phase(travel, profile, phases, start, base=0.0):
    """(whole cycles, phase) of ``phases`` whose travel is nearest ``travel`` (cycles):
    ``whole - profile[phase]`` from a start phase to the node pose (``start``), else
    ``whole + profile[phase] - base`` from a phase ``base`` into its cycle; never shorter
    than a tenth of a cycle."""
    best = None
    for ph in np.asarray(phases, int):
        p = profile[ph]
        for whole in range(max(int(np.floor(travel)) - 1, 0), int(np.ceil(travel)) + 3):
            length = whole - p if start else whole + p - base
            if length < 0.1:
                continue
            err = abs(length - travel)
            if best is None or err < best[0]:
                best = (err, whole, int(ph))
    assert best is not None, "a cycle or two always fits"
    return best[1], best[2]


def held_weights(weights: np.ndarray, half: int) -> np.ndarray:
    """Loop weights (K, L) averaged over ``half`` frames either side, the window shrinking
    towards both ends so the first and last frames keep their own weights (a segment still
    starts and ends on the node pose). Loops of neighbouring curvatures can be different
    takes (16_15's straight walk beside 16_18's gentle turns): however gently the
    curvature changes, the weights swap those loops within a frame or two where their
    curvatures are close, and bones the takes hold differently (a thumb, the head) would
    step several times faster than in either clip."""
    n = weights.shape[0]
    if half < 1 or n < 3:
        return weights
    f = np.arange(n)
    h = np.minimum(np.minimum(f, n - 1 - f), half)
    c = np.concatenate((np.zeros((1, weights.shape[1])), np.cumsum(weights, axis=0)))
    return (c[f + h + 1] - c[f - h]) / (2 * h + 1)[:, None]


def follow(
    gait: Gait,
    curve: Curve,
    cycles: int | str | None = None,
    start_phase: int = 0,
    eased: tuple[bool, bool] = (True, True),
    phases: np.ndarray | None = None,
    poses: bool = True,
    at: int | None = None,
) -> Motion:
    """Motion of the gait along ``curve``.

    With ``cycles`` the motion lasts exactly ``cycles`` loops (the curve was fitted to it)
    and ends on the node pose; without, it stops where the curve ends, mid-cycle if need be
    (on one of ``phases`` if given); with ``cycles="to node"`` it starts at the phase (of
    ``phases``) that makes it end on the node pose.
    ``poses`` False: the ground frames and root alone (what a layout check measures), the
    body left out (no joint; the contacts of the first loop): the blended poses are most
    of the work.
    ``at``: frame ``at`` of that motion alone (-1: its last), a motion of one frame; each
    frame is posed on its own, so it is the same frame the whole motion has.
    """
    k, s, ease = frame_arclengths(gait, curve, cycles, start_phase, eased, phases)
    x, y, h, _ = curve.at(s)
    weights = gait.weights(np.interp(s, curve.s, curve.kappa * ease))
    weights = held_weights(weights, max(int(round(gait.frames * WEIGHT_WINDOW)), 0))
    if at is not None:
        k, x, y, h, weights = np.asarray(k)[[at]], x[[at]], y[[at]], h[[at]], weights[[at]]
    if poses:
        root, rot, contacts = gait.pose(k, weights)
    else:
        ph = np.asarray(k) % gait.frames
        root = np.zeros((ph.size, 3))
        for i, lp in enumerate(gait.loops):
            root += lp.root_local[ph] * weights[:, i : i + 1]
        rot, contacts = gait.loops[0].rotations[ph, :0], gait.loops[0].contacts[ph]
    return Motion(np.column_stack((x, y, h)), root, rot, contacts)
