# SPDX-License-Identifier: GPL-3.0-or-later
"""Compact keys: the vectorised halving search keeps the frames the plain one does."""

import numpy as np
import pytest

from motion_patches.kinematics import keys, quat


def halving(v, tol, base=keys.BASE):
    """The search one column at a time, as written in keys.py's docstring: intervals
    between kept frames that miss a value by more than ``tol`` are halved until none does."""
    n = len(v)
    kept = set(range(0, n, base)) | {n - 1}
    todo = sorted(kept)
    todo = list(zip(todo[:-1], todo[1:]))
    while todo:
        lo, hi = todo.pop()
        inner = np.arange(lo + 1, hi)
        if not inner.size:
            continue
        w = (inner - lo) / (hi - lo)
        if np.any(np.abs(v[lo] * (1 - w) + v[hi] * w - v[inner]) > tol):
            mid = (lo + hi) // 2
            kept.add(mid)
            todo += [(lo, mid), (mid, hi)]
    mask = np.zeros(n, bool)
    mask[sorted(kept)] = True
    return mask


def columns(rng, n):
    t = np.arange(n)
    return np.column_stack(
        [
            np.sin(t * 0.05),  # smooth: keys
            np.cumsum(rng.normal(size=n)) * 1e-3,  # noise: samples
            np.where(t < n // 2, 0.0, (t - n // 2) * 0.01),  # a kink: few keys
            np.zeros(n),  # constant
            np.where(t % 7 == 0, 1e-3, 0.0),  # spikes
            np.cumsum(rng.normal(size=n)) * 1e-6,  # noise just above the tolerance
            np.sin(t * 0.3) * 1e-4,
        ]
    )


@pytest.mark.parametrize("n", [1, 2, 3, 54, 65, 109, 129, 1002])
def test_linear_keys_match_the_plain_halving(n):
    v = columns(np.random.default_rng(n), n)
    got = keys.linear_keys(v, 1e-5)
    for c in range(v.shape[1]):
        assert np.array_equal(got[:, c], halving(v[:, c], 1e-5)), c


@pytest.mark.parametrize("n", [54, 109, 1002])
def test_giving_up_on_a_column_changes_no_choice(n):
    """plan_columns stops refining a column once keys would cost more than samples: the
    choice of every column is still the one the full search gives."""
    v = columns(np.random.default_rng(n + 1), n)
    plans = keys.plan_columns(v, 1e-5)
    kinds = set()
    for c, (how, kept) in enumerate(plans):
        full = halving(v[:, c], 1e-5)
        if np.ptp(v[:, c]) <= 1e-5:
            want = "constant"
        elif full.sum() * keys.KEY_BYTES < n * keys.SAMPLE_BYTES:
            want = "keys"
            assert np.array_equal(kept, np.flatnonzero(full))
        else:
            want = "samples"
        assert how == want, c
        kinds.add(how)
    assert kinds == {"constant", "keys", "samples"}  # the data exercises every choice
    mask, gave_up = keys.linear_keys(v, 1e-5, give_up_at=-(-n * 16 // 72))
    assert gave_up.any() and not gave_up.all()


def test_columns_just_under_and_over_the_cost_of_samples():
    """Waves of many amplitudes: some columns need just fewer keys than samples would
    cost, some just more; each is stored as the full search says."""
    n = 109
    limit = -(-n * keys.SAMPLE_BYTES // keys.KEY_BYTES)  # keys cost more from here on
    t = np.arange(n)
    v = np.column_stack([a * np.sin(t * 0.2) for a in np.logspace(-4.5, -1, 300)])
    counts = np.array([halving(v[:, c], 1e-5).sum() for c in range(v.shape[1])])
    assert np.any((counts >= limit - 3) & (counts < limit))
    assert np.any((counts >= limit) & (counts <= limit + 3))
    for c, (how, kept) in enumerate(keys.plan_columns(v, 1e-5)):
        assert how == ("keys" if counts[c] < limit else "samples"), (c, counts[c])


@pytest.mark.parametrize("n", [3, 54, 109, 1002])
def test_the_frames_every_keying_keeps_are_a_lower_bound(n):
    """must_keep never counts more frames than the plain halving keeps (synthetic columns,
    among them noise just above the tolerance and waves just around it)."""
    v = columns(np.random.default_rng(n + 2), n)
    t = np.arange(n)
    v = np.column_stack([v] + [a * np.sin(t * 0.2) for a in np.logspace(-5, -3, 40)])
    full = np.array([halving(v[:, c], 1e-5).sum() for c in range(v.shape[1])])
    bound = keys.must_keep(v, 1e-5)
    assert np.all(bound <= full)
    assert np.any((bound > 2) & (bound >= 0.9 * full))  # close where the column is noisy


@pytest.mark.parametrize("start, n", [(0, 53), (200, 109), (0, None)])
def test_mocap_channels_are_stored_as_the_plain_halving_says(walk16, start, n):
    """On captured channels (CMU 16_15: every bone's quaternion, the root's position)
    plan_columns, which skips the search for the columns must_keep settles, makes the
    choice and keeps the keys of the full search, column by column."""
    n = n or walk16.frames  # None: the whole clip
    rot = walk16.rotations[start : start + n].reshape(n, -1)
    v = np.column_stack((walk16.root_pos[start : start + n], rot))
    limit = -(-n * keys.SAMPLE_BYTES // keys.KEY_BYTES)
    settled = keys.must_keep(v, 1e-5) >= limit
    assert settled.sum() > v.shape[1] // 2  # the shortcut is taken for most channels
    kinds = set()
    for c, (how, kept) in enumerate(keys.plan_columns(v, 1e-5)):
        full = halving(v[:, c], 1e-5)
        if np.ptp(v[:, c]) <= 1e-5:
            want = "constant"
        elif full.sum() < limit:
            want = "keys"
            assert np.array_equal(kept, np.flatnonzero(full)), c
        else:
            want = "samples"
        assert how == want, c
        kinds.add(how)
    assert "samples" in kinds and "constant" in kinds


# --- cubic keys --------------------------------------------------------------------------


def bezier_as_blender(x0, y0, x1, y1, m0, m1, at):
    """Blender's evaluation of one Bezier segment with handles a third of the way along:
    the Bezier's x solved for its parameter (here by bisection), then its y."""
    h = x1 - x0
    px = np.array([x0, x0 + h / 3, x1 - h / 3, x1])
    py = np.array([y0, y0 + m0 * h / 3, y1 - m1 * h / 3, y1])

    def bez(p, t):
        return (
            (1 - t) ** 3 * p[0]
            + 3 * (1 - t) ** 2 * t * p[1]
            + 3 * (1 - t) * t**2 * p[2]
            + t**3 * p[3]
        )

    lo, hi = np.zeros_like(at), np.ones_like(at)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = bez(px, mid) < at
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return bez(py, 0.5 * (lo + hi))


def test_hermite_is_the_bezier_blender_plays():
    rng = np.random.default_rng(5)
    x = np.cumsum(rng.integers(1, 9, 8)).astype(float)
    y, m = rng.normal(size=8), rng.normal(size=8)
    at = np.linspace(x[0], x[-1], 301)
    got = keys.hermite(x, y, m, at)
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, 6)
    want = bezier_as_blender(x[i], y[i], x[i + 1], y[i + 1], m[i], m[i + 1], at)
    assert np.allclose(got, want, atol=1e-9)
    assert keys.hermite(x, y, m, [x[0] - 5])[0] == y[0]  # constant outside the keys


def test_hermite_plays_free_handles_as_blender():
    """Each key's left and right handles with slopes of their own (FREE handles): between
    two keys Blender plays the first's right handle and the second's left one."""
    rng = np.random.default_rng(6)
    x = np.cumsum(rng.integers(1, 9, 8)).astype(float)
    y, m, m_in = rng.normal(size=8), rng.normal(size=8), rng.normal(size=8)
    at = np.linspace(x[0], x[-1], 301)
    got = keys.hermite(x, y, m, at, m_in)
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, 6)
    want = bezier_as_blender(x[i], y[i], x[i + 1], y[i + 1], m[i], m_in[i + 1], at)
    assert np.allclose(got, want, atol=1e-9)


def walk_rotations(n, fps, rng):
    """Bone rotations (F, J, 4) of a swinging walk with capture noise of ~0.1 degree."""
    t = np.arange(n)[:, None] / fps
    amp = rng.uniform(0.05, 0.6, (1, 6))
    axis = rng.normal(size=(6, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = amp * np.sin(2 * np.pi * 0.9 * t + rng.uniform(0, 6, (1, 6)))
    angle = angle + np.radians(0.1) * rng.normal(size=angle.shape)
    q = np.concatenate((np.cos(angle / 2)[..., None], np.sin(angle / 2)[..., None] * axis), -1)
    q[:, 5] = [1.0, 0.0, 0.0, 0.0]  # a bone that never turns
    return q


@pytest.mark.parametrize("fps", [24, 30, 120])
def test_cubic_keys_play_every_bone_within_the_angle(fps):
    """Evaluated as Blender does (normalised quaternions, on every frame and between
    frames) every bone is within the angle of the plan; far fewer keys than frames."""
    rng = np.random.default_rng(fps)
    q = walk_rotations(4 * fps, fps, rng)
    n, j, _ = q.shape
    loc = np.cumsum(rng.normal(size=(n, 3)) * 1e-3, axis=0) + np.linspace(0, 1, n)[:, None]
    values = np.concatenate((loc, q.reshape(n, -1)), axis=1)
    tol = np.full(values.shape[1], np.inf)
    tol[:3] = keys.LENGTH
    rot = keys.Rotations(3 + np.arange(j * 4).reshape(j, 4), quat.normalize)
    fit = keys.cubic_keys(values, tol, (rot,))
    at = np.arange(0, n - 1 + 1e-9, 0.25)
    played = keys.play(values, fit, at)
    planned = np.stack(
        [np.interp(at, np.arange(n), values[:, c]) for c in range(values.shape[1])], 1
    )
    # on frames: the plan itself
    whole = at == np.round(at)
    angle = keys._chord_angle(
        quat.normalize(played[:, 3:].reshape(-1, j, 4)),
        quat.normalize(planned[:, 3:].reshape(-1, j, 4)),
    )
    assert angle[whole].max() <= keys.ANGLE * (1 + 1e-9)
    assert np.abs(played[whole, :3] - planned[whole, :3]).max() <= keys.LENGTH * (1 + 1e-9)
    # between frames: near the line keys on every frame play (the cubic bends, the line does not)
    assert angle.max() <= 2 * keys.ANGLE
    assert fit["constant"][3 + 5 * 4 : 3 + 6 * 4].all()  # the still bone: one key per curve
    assert fit["keep"].sum() < 0.5 * fit["keep"].size
    assert (
        keys.cubic_bytes(fit)
        == fit["keep"].sum() * keys.KEY_BYTES + values.shape[1] * keys.CURVE_BYTES
    )


def test_a_smooth_channel_needs_a_few_keys_a_second():
    t = np.arange(241) / 120.0
    v = np.column_stack((0.3 * np.sin(2 * np.pi * t), 0.01 * t * t))
    fit = keys.cubic_keys(v, 1e-4)
    played = keys.play(v, fit, np.arange(241))
    assert np.abs(played - v).max() <= 1e-4 * (1 + 1e-9)
    assert fit["keep"][:, 0].sum() <= 30  # 2 s of a 1 Hz swing at 120 fps: 240 frames
    assert fit["constant"][1] is np.False_ and fit["keep"][:, 1].sum() <= 4


@pytest.mark.parametrize("between", [True, False])
def test_giving_up_on_cubic_keys_changes_no_choice_of_the_others(between):
    """A unit that reaches the cost of samples stops taking keys (it is stored as samples):
    exactly the units whose full fit took that many keys (before any was taken out) give
    up, every unit the full fit keeps that many keys on is among them, and every other
    column keeps the very keys the full fit keeps."""
    rng = np.random.default_rng(3)
    n = 120
    q = walk_rotations(n, 30, rng)
    j = q.shape[1]
    noisy = q + rng.normal(size=q.shape) * 0.01 * (np.arange(j) % 2 == 0)[None, :, None]
    values = np.concatenate((np.cumsum(rng.normal(size=(n, 3)) * 1e-3, 0), noisy.reshape(n, -1)), 1)
    tol = np.full(values.shape[1], np.inf)
    tol[:3] = keys.LENGTH
    rot = keys.Rotations(3 + np.arange(j * 4).reshape(j, 4), quat.normalize)
    limit = -(-n * keys.SAMPLE_BYTES // keys.KEY_BYTES)
    full = keys.cubic_keys(values, tol, (rot,), between)
    part = keys.cubic_keys(values, tol, (rot,), between, give_up_at=limit)
    heavy = (full["inserted"] >= limit) & ~full["constant"]
    assert heavy.any() and (~heavy & ~full["constant"]).any()  # both kinds are here
    assert np.array_equal(part["gave_up"], heavy & ~part["constant"])
    assert not ((full["keep"].sum(axis=0) >= limit) & ~full["constant"] & ~heavy).any()
    kept = ~heavy
    assert np.array_equal(part["keep"][:, kept], full["keep"][:, kept])
    assert np.array_equal(part["constant"][kept], full["constant"][kept])


def test_a_jittering_rotation_gives_up_before_any_key_is_added():
    """A rotation whose capture jitters by degrees from frame to frame would end as
    samples: it gives up at once (its fit adds no key), the smooth bones keep the keys they
    keep without it, and without ``give_up_at`` nothing gives up."""
    rng = np.random.default_rng(5)
    n = 120
    q = walk_rotations(n, 30, rng)
    jitter = np.radians(2.0) * rng.normal(size=(n, 3))  # bone 0: two degrees of jitter
    q[:, 0] = quat.mul(q[:, 0], np.concatenate((np.ones((n, 1)), 0.5 * jitter), 1))
    q[:, 0] = quat.normalize(q[:, 0])
    values = q.reshape(n, -1)
    rot = keys.Rotations(np.arange(q.shape[1] * 4).reshape(-1, 4), quat.normalize)
    tol = np.full(values.shape[1], np.inf)
    limit = -(-n * keys.SAMPLE_BYTES // keys.KEY_BYTES)
    part = keys.cubic_keys(values, tol, (rot,), True, give_up_at=limit)
    full = keys.cubic_keys(values, tol, (rot,), True)
    assert part["gave_up"][:4].all() and (part["inserted"][:4] == 2).all()
    assert (full["inserted"][:4] >= limit).all()  # it would have cost more than samples
    smooth = np.arange(4, values.shape[1])
    assert not part["gave_up"][smooth].any()
    assert np.array_equal(part["keep"][:, smooth], full["keep"][:, smooth])
    assert not full["gave_up"].any()


def test_keys_judged_on_frames_only_hold_there():
    """``between=False`` (a strip that plays its keys on whole frames only): every frame
    within the tolerance, and no more keys than when half frames are judged too."""
    rng = np.random.default_rng(8)
    t = np.arange(200)
    v = np.column_stack((np.sin(t * 0.21) + rng.normal(size=200) * 1e-4, np.cos(t * 0.05)))
    on = keys.cubic_keys(v, 1e-3, between=False)
    both = keys.cubic_keys(v, 1e-3)
    assert np.abs(keys.play(v, on, t) - v).max() <= 1e-3 * (1 + 1e-9)
    assert on["keep"].sum() <= both["keep"].sum()


def test_each_interval_plays_the_cubic_nearest_the_plan():
    """Between two keys the two slopes are the interval's own: the least-squares fit of
    the Hermite cubic through the keys to the plan on the frames inside (drawn to the plan's
    own slopes only by a hair), not the plan's slopes at the keys."""
    rng = np.random.default_rng(11)
    t = np.arange(150)
    v = (np.sin(t * 0.13) + 0.02 * rng.normal(size=150))[:, None]
    fit = keys.cubic_keys(v, 0.01, between=False)
    k = np.flatnonzero(fit["keep"][:, 0])
    assert 2 < k.size < 75
    worse = 0
    for a, b in zip(k[:-1], k[1:]):
        inner = np.arange(a + 1, b)
        if inner.size < 2:
            continue
        u = (inner - a) / (b - a)
        basis = np.column_stack(((b - a) * u * (1 - u) ** 2, (b - a) * u * u * (u - 1)))
        line = v[a, 0] + (3 * u * u - 2 * u**3) * (v[b, 0] - v[a, 0])
        best = np.linalg.lstsq(basis, v[inner, 0] - line, rcond=None)[0]
        got = np.array([fit["slopes"][a, 0], fit["slopes_in"][b, 0]])
        # the cubic played inside: the least-squares one (the hair of pull aside)
        assert np.abs(basis @ (got - best)).max() <= 1e-3, (a, b)
        own = keys.slopes(v)[[a, b], 0]
        worse += np.sum((basis @ own - v[inner, 0] + line) ** 2) > np.sum(
            (basis @ got - v[inner, 0] + line) ** 2
        )
    assert worse > 0  # the plan's own slopes fit worse somewhere


def test_no_key_is_left_that_could_go():
    """After keys are taken out, every key but the ends is needed: the interval over both
    of its sides, fitted as any interval is, misses the tolerance somewhere."""
    rng = np.random.default_rng(12)
    t = np.arange(200)
    v = np.column_stack((np.sin(t * 0.1), np.cos(t * 0.037))) + 0.003 * rng.normal(size=(200, 2))
    tol = 0.01
    fit = keys.cubic_keys(v, tol, between=False)
    for c in range(2):
        k = np.flatnonzero(fit["keep"][:, c])
        assert k.size > 3
        for i in range(1, k.size - 1):
            a, b = k[i - 1], k[i + 1]
            alone = keys.cubic_keys(v[a : b + 1, c : c + 1], tol, between=False)
            assert alone["inserted"][0] > 2, (c, k[i])  # the interval alone needs a key


@pytest.mark.parametrize("steady", [None, 0.5])
def test_a_steady_fit_changes_its_error_little_from_frame_to_frame(steady):
    """``steady``: what the keys play is off the plan by at most the tolerance, and that
    offset changes by at most ``steady`` times the tolerance from one frame to the next (a
    planted foot carried by the channel does not jitter). Without it the offset jumps."""
    rng = np.random.default_rng(13)
    t = np.arange(240)
    v = np.column_stack((0.01 * t + 0.002 * np.sin(t * 1.7), np.sin(t * 0.05)))
    v += 0.0003 * rng.normal(size=v.shape)
    tol = 1e-3
    fit = keys.cubic_keys(v, tol, between=False, steady=steady)
    off = keys.play(v, fit, t) - v
    assert np.abs(off).max() <= tol * (1 + 1e-9)
    jump = np.abs(np.diff(off, axis=0)).max()
    if steady is None:
        assert jump > 0.5 * tol
    else:
        assert jump <= steady * tol * (1 + 1e-9)


def test_rotations_judged_within_a_hair_still_fit():
    """An angle too small for ``1 - cos`` in double precision (1e-9 rad) is judged at the
    precision there is: the fit ends, every frame on a key plays the plan, and no point is
    further off than that precision allows."""
    rng = np.random.default_rng(3)
    n = 40
    q = walk_rotations(n, 30, rng)
    values = q.reshape(n, -1)
    rot = keys.Rotations(np.arange(q.shape[1] * 4).reshape(-1, 4), quat.normalize, angle=1e-9)
    fit = keys.cubic_keys(values, np.full(values.shape[1], np.inf), (rot,), True)
    played = keys.play(values, fit, np.arange(n))
    for b in range(q.shape[1]):
        pq = quat.normalize(played[:, 4 * b : 4 * b + 4])
        dot = np.abs(np.einsum("fc,fc->f", pq, q[:, b]))
        assert (1.0 - dot).max() <= 4 * np.finfo(float).eps
