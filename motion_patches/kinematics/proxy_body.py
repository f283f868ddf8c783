# SPDX-License-Identifier: GPL-3.0-or-later
"""Proxy bodies: a low-poly capsule round every bone, so a character reads as a figure
in the viewport and in renders, not as bone sticks (motion capture rigs have no mesh).

Only the skeleton is known, so the sizes come from it: a limb's thickness from its length,
the torso (the bones most of the skeleton hangs from) and the head (the highest leaf bone)
from fixed human sizes. Everything is in metres here; the caller converts to the rig's
units (a rig under a 0.01 object scale has centimetre bones).
"""

from collections.abc import Sequence

import numpy as np

LIMB_FRACTION = 0.16  # a limb's radius, as a fraction of its length
LIMB_RADIUS = (0.02, 0.065)  # metres: the thinnest (fingers, toes) and thickest limb
TORSO_RADIUS = 0.11  # metres: hips and spine, whose capsules overlap into a trunk
HEAD_RADIUS = 0.09  # metres
TORSO_SHARE = 0.5  # a bone with at least this share of the skeleton below it is the torso
SIDES = 8  # around each capsule


def bone_radii(
    parents: Sequence[int],
    lengths: np.ndarray,
    tail_heights: np.ndarray,
    metres_per_unit: float = 1.0,
) -> np.ndarray:
    """Capsule radius of every bone, in the bones' own units: ``LIMB_FRACTION`` of its
    length within ``LIMB_RADIUS``; ``TORSO_RADIUS`` for a bone with at least
    ``TORSO_SHARE`` of the bones below it; ``HEAD_RADIUS`` for the leaf bone whose tail is
    highest (``tail_heights``: world height of each tail, rest pose). ``parents``: index of
    each bone's parent, -1 for a root, parents before children or in any order."""
    n = len(parents)
    lengths = np.asarray(lengths, float) * metres_per_unit
    below = np.zeros(n, int)  # bones below each bone
    for j in range(n):
        p = parents[j]
        seen = set()
        while p >= 0 and p not in seen:  # up the chain; a cycle in bad data ends it
            seen.add(p)
            below[p] += 1
            p = parents[p]
    radii = np.clip(LIMB_FRACTION * lengths, *LIMB_RADIUS)
    if n > 2:
        radii[below >= TORSO_SHARE * (n - 1)] = TORSO_RADIUS
    leaves = np.flatnonzero(below == 0)
    if n > 2 and len(leaves):
        radii[leaves[np.argmax(np.asarray(tail_heights, float)[leaves])]] = HEAD_RADIUS
    return radii / metres_per_unit


def capsule(length: float, radius: float, sides: int = SIDES) -> tuple[np.ndarray, list]:
    """(vertices (V, 3), faces [vertex index tuples]) of a closed capsule along +Y from 0
    to ``length`` (a bone's head to its tail, in its own axes): a cylinder of ``sides``
    sides with a two-step hemisphere at each end, reaching ``radius`` beyond the ends
    (joints overlap, as round joints do). Quads along the sides, triangles at the poles."""
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([np.cos(a), np.zeros(sides), np.sin(a)], axis=1)
    c45 = np.sqrt(0.5)
    rings = [  # (y, ring radius) from the head's pole to the tail's
        (-radius * c45, radius * c45),
        (0.0, radius),
        (length, radius),
        (length + radius * c45, radius * c45),
    ]
    verts = [np.array([[0.0, -radius, 0.0]])]
    verts += [ring * r + np.array([0.0, y, 0.0]) for y, r in rings]
    verts.append(np.array([[0.0, length + radius, 0.0]]))
    v = np.concatenate(verts)
    top = len(v) - 1
    faces: list = []
    for k in range(sides):
        k1 = (k + 1) % sides
        faces.append((0, 1 + k, 1 + k1))  # head pole; every face wound outwards
        for r in range(len(rings) - 1):
            a0, b0 = 1 + r * sides, 1 + (r + 1) * sides
            faces.append((a0 + k, b0 + k, b0 + k1, a0 + k1))
        last = 1 + (len(rings) - 1) * sides
        faces.append((top, last + k1, last + k))
    return v, faces
