# SPDX-License-Identifier: GPL-3.0-or-later
"""Compact keys: the vectorised halving search keeps the frames the plain one does."""

import numpy as np
import pytest

from motion_patches.kinematics import keys


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
