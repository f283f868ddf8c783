# SPDX-License-Identifier: GPL-3.0-or-later
"""Rest offsets: the closed-form affine inverse agrees with LAPACK's, and a skeleton's
offsets are made once and cannot be changed by a caller."""

import numpy as np
import pytest

from motion_patches.kinematics import quat
from motion_patches.kinematics.skeleton import Skeleton, affine_inverse


def test_affine_inverse_is_the_inverse_of_any_affine_matrix():
    rng = np.random.default_rng(4)
    m = np.tile(np.eye(4), (64, 1, 1))
    rot = quat.to_matrix(quat.normalize(rng.normal(size=(64, 4))))
    shear = np.eye(3) + 0.3 * rng.normal(size=(64, 3, 3))  # scaled, sheared: not only rigid
    m[:, :3, :3] = rot @ shear
    m[:, :3, 3] = rng.normal(size=(64, 3)) * 50.0
    inv = affine_inverse(m)
    assert np.allclose(inv @ m, np.eye(4), atol=1e-9)
    assert np.allclose(inv, np.linalg.inv(m), atol=1e-9)
    assert np.allclose(affine_inverse(m[0]), np.linalg.inv(m[0]), atol=1e-9)  # one matrix


def test_local_rest_is_made_once_and_read_only():
    rest = np.tile(np.eye(4), (3, 1, 1))
    rest[1, :3, 3] = (0.0, 0.0, 0.5)
    rest[2, :3, 3] = (0.0, 0.2, 0.9)
    skel = Skeleton(["hips", "spine", "head"], np.array([-1, 0, 1]), rest)
    a, b = skel.local_rest(), skel.local_rest()
    assert a is b
    assert np.allclose(a[2, :3, 3], (0.0, 0.2, 0.4))
    with pytest.raises(ValueError):
        a[0, 0, 0] = 2.0
