# SPDX-License-Identifier: GPL-3.0-or-later
"""Proxy bodies' geometry (a capsule per bone, sized from the skeleton) and the straight
clip a bake is pre-filled with: the core's part, with real CMU skeletons and clips."""

import numpy as np
import pytest

from motion_patches.kinematics import clip as clipmod
from motion_patches.kinematics import proxy_body

from conftest import cmu


def segment_distances(points, a, b):
    d = b - a
    t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * d), axis=1)


@pytest.mark.parametrize("length, radius", [(0.4, 0.06), (0.006, 0.11), (2.0, 0.02)])
def test_a_capsule_is_closed_wound_outwards_and_at_its_radius_from_its_bone(length, radius):
    verts, faces = proxy_body.capsule(length, radius)
    assert len(verts) == 2 + 4 * proxy_body.SIDES  # low-poly: 34 vertices
    # Closed: every edge is shared by exactly two faces, once each way.
    edges = {}
    for f in faces:
        for a, b in zip(f, f[1:] + f[:1]):
            edges[(a, b)] = edges.get((a, b), 0) + 1
    assert all(n == 1 and edges.get((b, a)) == 1 for (a, b), n in edges.items())
    # Wound outwards: the divergence theorem gives a positive volume, about the capsule's
    # (a cylinder and a ball) less what eight sides and two steps per cap cut off.
    vol = sum(
        np.dot(verts[f[0]], np.cross(verts[f[i]], verts[f[i + 1]])) / 6
        for f in faces
        for i in range(1, len(f) - 1)
    )
    exact = np.pi * radius**2 * length + 4 / 3 * np.pi * radius**3
    assert 0.6 * exact < vol < exact
    d = segment_distances(verts, np.zeros(3), np.array([0.0, length, 0.0]))
    assert np.allclose(d, radius, atol=1e-12)


def test_radii_give_limbs_by_length_a_trunk_and_a_head():
    skel = cmu("16_15").skeleton
    rest = skel.rest[:, :3, 3]
    names = skel.names
    # Bone i of the proxy runs from joint i to its child (the CMU chain's next joint).
    child = {p: j for j, p in enumerate(skel.parents) if p >= 0}
    tails = np.array([rest[child.get(j, j)] for j in range(len(names))])
    lengths = np.linalg.norm(tails - rest, axis=1)
    r = dict(zip(names, proxy_body.bone_radii(skel.parents, lengths, tails[:, 2])))
    assert r["Hips"] == r["LowerBack"] == r["Spine"] == proxy_body.TORSO_RADIUS
    assert r["Head"] == proxy_body.HEAD_RADIUS
    lo, hi = proxy_body.LIMB_RADIUS
    assert r["LeftUpLeg"] == pytest.approx(
        proxy_body.LIMB_FRACTION * lengths[names.index("LeftUpLeg")]
    )
    assert r["LeftToeBase"] == lo and lo < r["LeftForeArm"] < r["LeftUpLeg"] <= hi
    # In centimetres (a rig of 100 units a metre): the same body, a hundred times the units.
    cm = proxy_body.bone_radii(skel.parents, lengths * 100, tails[:, 2], metres_per_unit=0.01)
    assert np.allclose(cm, 100 * np.array(list(r.values())))


def test_the_straight_clip_is_the_walk_that_goes_furthest_straight():
    clips = [cmu(n) for n in ("16_06", "16_18", "16_15")]  # a jump, a turn, the walk
    assert clipmod.straightest(clips) == 2
    assert clipmod.straightest(clips[:2]) is None  # a jump and a turn: no guess
    assert clipmod.straightest([cmu(n) for n in ("02_04", "02_02", "02_01")]) == 1
