# SPDX-License-Identifier: GPL-3.0-or-later
"""Dubins paths: the shortest ground paths of bounded curvature between two states.

A walk can turn no tighter than its turn clips show, so the shortest way from a standing
start (position, facing) onto the node graph, or from a node into the goal, is a Dubins
path (Dubins 1957): two arcs of the turning radius joined by a straight line or a third
arc (words LSL, RSR, LSR, RSL, RLR, LRL). The closed forms here follow Shkel & Lumelsky
(2001) and are vectorised over many pairs of states, so the connectors of every node
around a start or goal cost a few array operations; only the ones the search reaches are
sampled and tested against footprints. The curvature jumps where arcs meet; the curvature
used for blending turn loops is smoothed over ``BLEND_SMOOTHING`` metres so the body
leans into a turn without a pop.
"""

import numpy as np

from ..patch.curves import Curve

WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")
SIGN = {"L": 1.0, "R": -1.0, "S": 0.0}
BLEND_SMOOTHING = 0.35  # metres over which the blending curvature is averaged
SAMPLE_SPACING = 0.04  # metres between curve samples (exact footprint tests)


def _mod2pi(a):
    return np.mod(a, 2 * np.pi)


def words(
    p0: np.ndarray, h0: np.ndarray, p1: np.ndarray, h1: np.ndarray, radius: float | np.ndarray
) -> np.ndarray:
    """(W, N, 3) segment lengths (metres) of the six words for N state pairs (NaN where
    a word does not exist). ``p0, p1`` (N, 2), ``h0, h1`` (N,), ``radius`` a number or
    one per pair (N,)."""
    p0, p1 = np.atleast_2d(p0).astype(float), np.atleast_2d(p1).astype(float)
    h0, h1 = (
        np.broadcast_to(np.asarray(h0, float), p0.shape[:1]),
        np.broadcast_to(np.asarray(h1, float), p1.shape[:1]),
    )
    radius = np.asarray(radius, float)
    dx, dy = p1[:, 0] - p0[:, 0], p1[:, 1] - p0[:, 1]
    d = np.hypot(dx, dy) / radius
    th = _mod2pi(np.arctan2(dy, dx))
    a, b = _mod2pi(h0 - th), _mod2pi(h1 - th)
    sa, sb, ca, cb = np.sin(a), np.sin(b), np.cos(a), np.cos(b)
    cab = np.cos(a - b)
    # Each word's three lengths written straight into its rows, NaN where it does not
    # exist (the same values as stacking them and masking: a third of the time).
    out = np.empty((6, d.size, 3))
    dd, sab, sapb = d * d, sa - sb, sa + sb

    def put(w, ok, t, p, q):
        row = out[w]
        row[:, 0], row[:, 1], row[:, 2] = t, p, q
        row[~ok] = np.nan

    with np.errstate(invalid="ignore"):
        # LSL
        p2 = 2 + dd - 2 * cab + 2 * d * sab
        t1 = np.arctan2(cb - ca, d + sa - sb)
        put(0, p2 >= 0, _mod2pi(-a + t1), np.sqrt(p2), _mod2pi(b - t1))
        # RSR
        p2 = 2 + dd - 2 * cab + 2 * d * (sb - sa)
        t1 = np.arctan2(ca - cb, d - sa + sb)
        put(1, p2 >= 0, _mod2pi(a - t1), np.sqrt(p2), _mod2pi(-b + t1))
        # LSR
        p2 = -2 + dd + 2 * cab + 2 * d * sapb
        p = np.sqrt(p2)
        t2 = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, p)
        put(2, p2 >= 0, _mod2pi(-a + t2), p, _mod2pi(-_mod2pi(b) + t2))
        # RSL
        p2 = dd - 2 + 2 * cab - 2 * d * sapb
        p = np.sqrt(p2)
        t2 = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, p)
        put(3, p2 >= 0, _mod2pi(a - t2), p, _mod2pi(b - t2))
        # RLR
        tmp = (6 - dd + 2 * cab + 2 * d * sab) / 8
        p = _mod2pi(2 * np.pi - np.arccos(np.clip(tmp, -1, 1)))
        t = _mod2pi(a - np.arctan2(ca - cb, d - sa + sb) + p / 2)
        put(4, np.abs(tmp) <= 1, t, p, _mod2pi(a - b - t + p))
        # LRL
        tmp = (6 - dd + 2 * cab + 2 * d * (sb - sa)) / 8
        p = _mod2pi(2 * np.pi - np.arccos(np.clip(tmp, -1, 1)))
        t = _mod2pi(-a - np.arctan2(ca - cb, d + sa - sb) + p / 2)
        put(5, np.abs(tmp) <= 1, t, p, _mod2pi(_mod2pi(b) - a - t + p))
    out *= radius[:, None] if radius.ndim else radius
    return out


def turns(lengths: np.ndarray, radius: float | np.ndarray) -> np.ndarray:
    """(W, N) total |heading change| of each word: its arcs' lengths over the radius (a
    number, or one per pair (N,))."""
    arcs = np.array([[w[0] != "S", w[1] != "S", w[2] != "S"] for w in WORDS], float)
    return np.einsum("wnk,wk->wn", np.nan_to_num(lengths), arcs) / radius


SIGNS = np.array([[SIGN[letter] for letter in w] for w in WORDS])  # (6, 3) turn of each part


def _advance(x, y, h, k, length):
    """State after ``length`` metres of curvature ``k`` from (x, y, h) (arrays): the
    chord of the arc, ``length`` x sinc(k length / 2) long, runs along the mean heading
    (exactly ``length`` along ``h`` on a straight)."""
    half = 0.5 * k * length
    chord = length * np.sinc(half / np.pi)
    mid = h + half
    return x + chord * np.cos(mid), y + chord * np.sin(mid), h + 2.0 * half


def samples(
    p0: np.ndarray,
    h0: float | np.ndarray,
    word: int | np.ndarray,
    lengths: np.ndarray,
    radius: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Samples of many words at once: arc length (P,), positions (P, 2), headings (P,),
    curvatures (P,) and each path's first sample (C + 1,). ``p0`` (C, 2), ``h0``, ``word``
    (indices into ``WORDS``), ``radius`` (C,), ``lengths`` (C, 3). Each path has
    ceil(length / ``SAMPLE_SPACING``) + 1 samples (3 at least), evenly spaced from its
    start to its end."""
    p0 = np.atleast_2d(np.asarray(p0, float))
    lengths = np.atleast_2d(np.asarray(lengths, float))
    c = lengths.shape[0]
    h0, radius = (np.broadcast_to(np.asarray(a, float), (c,)) for a in (h0, radius))
    word = np.broadcast_to(np.asarray(word, int), (c,))
    bounds = np.cumsum(lengths, axis=1)  # ends of the three parts
    total = bounds[:, 2]
    n = np.maximum(np.ceil(total / SAMPLE_SPACING).astype(int), 2) + 1
    first = np.concatenate(([0], np.cumsum(n)))
    owner = np.repeat(np.arange(c), n)
    # Per-path values spread to the samples by 1-D takes (cheaper than 2-D indexing).
    i = np.arange(first[-1]) - first[:-1].take(owner)
    s = i * (total / (n - 1)).take(owner)
    last = i == (n - 1).take(owner)
    s[last] = total[owner[last]]
    # Which of the three parts each sample lies on; a part of zero length owns none (the
    # last sample belongs to the last part that has a length).
    part = np.minimum(
        (bounds[:, 0].take(owner) <= s).astype(int)
        + (bounds[:, 1].take(owner) <= s)
        + (total.take(owner) <= s),
        2,
    )
    part = np.where((part == 2) & (lengths[:, 2].take(owner) <= 0.0), 1, part)
    part = np.where((part == 1) & (lengths[:, 1].take(owner) <= 0.0), 0, part)
    kap = SIGNS[word] / radius[:, None]  # (C, 3)
    x, y, h = [p0[:, 0]], [p0[:, 1]], [h0]
    for k in (0, 1):
        nx, ny, nh = _advance(x[-1], y[-1], h[-1], kap[:, k], lengths[:, k])
        x.append(nx)
        y.append(ny)
        h.append(nh)
    at = owner * 3 + part  # (path, part) of each sample in the (C, 3) arrays, flattened
    x, y, h = (np.stack(v, 1).reshape(-1).take(at) for v in (x, y, h))  # state at its part
    begin = np.column_stack((np.zeros(c), bounds[:, :2])).reshape(-1).take(at)
    k = kap.reshape(-1).take(at)
    px, py, ph = _advance(x, y, h, k, s - begin)
    return s, np.column_stack((px, py)), ph, k, first


def curve(p0: np.ndarray, h0: float, word: int | str, lengths: np.ndarray, radius: float) -> Curve:
    """The sampled :class:`Curve` of one word (an index into ``WORDS``, or its letters)
    from state (p0, h0) with segment ``lengths`` (3,)."""
    if not isinstance(word, (int, np.integer)):
        word = WORDS.index(word)
    s, pos, heading, kappa, _ = samples(
        np.asarray(p0, float)[None], h0, word, np.asarray(lengths, float)[None], radius
    )
    return Curve(s, pos, heading, smoothed(s, kappa))


def smoothed(s: np.ndarray, kappa: np.ndarray) -> np.ndarray:
    """Curvature averaged over a window of ``BLEND_SMOOTHING`` metres (samples are evenly
    spaced in arc length)."""
    if s.size < 3:
        return kappa
    step = s[1] - s[0]
    half = int(round(0.5 * BLEND_SMOOTHING / max(step, 1e-9)))
    if half < 1:
        return kappa
    padded = np.concatenate((np.full(half, kappa[0]), kappa, np.full(half, kappa[-1])))
    c = np.concatenate(([0.0], np.cumsum(padded)))
    return (c[2 * half + 1 :] - c[: -2 * half - 1]) / (2 * half + 1)
