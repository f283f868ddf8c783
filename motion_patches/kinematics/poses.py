# SPDX-License-Identifier: GPL-3.0-or-later
"""Pose clusters: k-means over poses, used to label the pose a node carries.

Nodes join segments only when their pose labels agree, so the labelling decides which
segments may follow each other without a pop (paper Sec. 6, k-means after Duda et al.).
"""

import numpy as np
from numpy.typing import ArrayLike

from . import quat


def pose_features(root_local: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """(K, D) feature vectors: root height and every joint's rotation vector."""
    rot = quat.log(rotations).reshape(rotations.shape[0], -1)
    return np.column_stack((root_local[:, 2:3], rot))


def kmeans(
    x: np.ndarray, k: int, iterations: int = 50, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Centres (k, D) and labels (K,) by Lloyd's algorithm with k-means++ seeding."""
    x = np.asarray(x, float)
    rng = np.random.default_rng(seed)
    k = min(k, x.shape[0])
    seeds = [x[rng.integers(x.shape[0])]]
    for _ in range(1, k):
        d2 = np.min(((x[:, None] - np.array(seeds)[None]) ** 2).sum(-1), axis=1)
        if d2.sum() <= 0:
            break
        seeds.append(x[rng.choice(x.shape[0], p=d2 / d2.sum())])
    centres = np.array(seeds)
    labels = np.zeros(x.shape[0], int)
    for _ in range(iterations):
        d2 = ((x[:, None] - centres[None]) ** 2).sum(-1)
        new = np.argmin(d2, axis=1)
        if np.array_equal(new, labels) and _ > 0:
            break
        labels = new
        for j in range(centres.shape[0]):
            if np.any(labels == j):
                centres[j] = x[labels == j].mean(axis=0)
    return centres, labels


def cluster_until(
    x: np.ndarray, max_spread: float, max_k: int = 8, seed: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Fewest k-means clusters whose members all lie within ``max_spread`` of their centre."""
    for k in range(1, max_k + 1):
        centres, labels = kmeans(x, k, seed=seed)
        spread = np.sqrt(((x - centres[labels]) ** 2).sum(-1)).max()
        if spread <= max_spread:
            break
    return centres, labels


def nearest(centres: np.ndarray, x: ArrayLike) -> np.ndarray:
    return np.argmin(((np.asarray(x)[:, None] - centres[None]) ** 2).sum(-1), axis=1)
