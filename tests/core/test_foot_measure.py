# SPDX-License-Identifier: GPL-3.0-or-later
"""The label-free foot measure on synthetic feet: each figure reads what was built into the
trajectory, and each fails when the fault it looks for is put in."""

import numpy as np
import pytest

from motion_patches.kinematics.skeleton import Skeleton
from motion_patches.quality import foot_measure as fm

from conftest import cmu
from rig_names import MIXAMO

FPS = 30.0
ANKLE = 0.08  # ankle above the toe's floor when standing


def walk(steps=6, plant_s=0.5, swing_s=0.4, lift=0.08, stride=0.7, floor=0.02):
    """Toe and ankle positions (F, 2, 3) of two feet taking turns: a plant, then a swing
    forward by ``stride`` under a half sine ``lift`` high, the toe rising before it moves
    on and touching down after it stops, as a recorded toe does (a foot waits planted while
    the other swings). Floor at ``floor`` metres, so nothing leans on z = 0."""
    n_plant, n_swing = int(round(plant_s * FPS)), int(round(swing_s * FPS))
    toe = []
    x = [0.0, 0.35]
    for s in range(steps):
        k = s % 2
        for i in range(n_plant):
            toe.append([[x[0], 0.1, floor], [x[1], -0.1, floor]])
        for i in range(1, n_swing + 1):
            t = i / n_swing
            p = [[x[0], 0.1, floor], [x[1], -0.1, floor]]
            u = np.clip((t - 0.25) / 0.5, 0.0, 1.0)
            p[k][0] = x[k] + stride * 0.5 * (1 - np.cos(np.pi * u))
            p[k][2] = floor + lift * np.sin(np.pi * t)
            toe.append(p)
        x[k] += stride
    for i in range(n_plant):
        toe.append([[x[0], 0.1, floor], [x[1], -0.1, floor]])
    toe = np.array(toe)
    ankle = toe.copy()
    ankle[..., 0] -= 0.15
    ankle[..., 2] += ANKLE
    return toe, ankle


def test_a_clean_walk_reads_clean():
    toe, ankle = walk()
    m = fm.measure(toe, ankle, FPS)
    assert m["skate"]["mean_cm_per_s"] < 1e-9 and m["skate"]["steps"] > 60
    assert m["pops"] == 0
    assert m["swings"] == 6
    assert m["min_swing_clearance_cm"] > 1.0  # the sine leaves the floor at once
    assert m["max_end_ankle_off_cm"] < 1e-6
    assert m["standing_ankle_cm"] == pytest.approx([ANKLE * 100] * 2)
    assert 0.4 < m["planted_fraction"] < 0.9


def test_a_sliding_planted_foot_is_skate_however_fast():
    """A foot sliding on the floor is counted at any speed: no label drops it."""
    for speed in (0.2, 1.5):  # m/s: slow, and faster than a label's 'moving' cut
        toe, ankle = walk()
        clean = fm.measure(toe, ankle, FPS)["skate"]["mean_cm_per_s"]
        n = int(0.5 * FPS)  # the left foot's first plant
        slide = np.minimum(np.arange(len(toe)), n - 1) * speed / FPS
        toe[:, 0, 0] += slide
        ankle[:, 0, 0] += slide
        m = fm.measure(toe, ankle, FPS)
        assert m["skate"]["max_cm_per_s"] == pytest.approx(speed * 100, rel=1e-6), speed
        assert m["skate"]["mean_cm_per_s"] > clean + 0.04 * speed * 100
        assert m["weighted_skate"]["max_cm_per_s"] == pytest.approx(speed * 100, rel=1e-6)


def test_weighted_skate_weighs_by_height():
    """A toe gliding 1 cm above its lowest counts 2 - 2^0.4 of its speed; at 3 cm, above
    the cut-off, nothing."""
    f = int(2 * FPS)
    x = np.arange(f) * 0.5 / FPS  # 0.5 m/s
    x[0] = x[1]  # still while it rises from its lowest
    for hover, weight in ((0.01, 2 - 2**0.4), (0.03, None)):
        toe = np.zeros((f, 1, 3))
        toe[:, 0, 0] = x
        toe[:, 0, 2] = hover
        toe[0, 0, 2] = 0.0  # its lowest
        m = fm.measure(toe, toe + [0, 0, ANKLE], FPS)
        if weight is None:
            assert m["weighted_skate"]["max_cm_per_s"] == 0.0
        else:
            assert m["weighted_skate"]["p95_cm_per_s"] == pytest.approx(50 * weight, rel=1e-6)


def test_a_short_touch_is_not_a_plant():
    """A toe in the air touching the floor for 0.1 s, then standing for 0.3 s."""
    z = np.full(int(2 * FPS), 0.1)
    z[10:13] = 0.0  # touch
    z[40:49] = 0.0  # stand
    toe = np.zeros((z.size, 1, 3))
    toe[:, 0, 2] = z
    plant = fm.planted(toe, FPS)[:, 0]
    assert not plant[10:13].any() and plant[40:49].all() and plant.sum() == 9


def test_a_one_frame_pop_is_found():
    toe, ankle = walk()
    m0 = fm.measure(toe, ankle, FPS)
    toe[5:, 0, 0] += 0.02  # the planted left toe jumps 2 cm between frames 4 and 5
    m = fm.measure(toe, ankle, FPS)
    assert m0["pops"] == 0 and m["pops"] == 1
    assert m["max_pop_cm"] == pytest.approx(2.0)


def test_a_swing_scraping_the_floor_shows_in_its_clearance():
    toe, ankle = walk()
    clean = fm.measure(toe, ankle, FPS)["min_swing_clearance_cm"]
    low = walk(lift=0.004)[0]
    scraped = fm.measure(low, ankle, FPS)["min_swing_clearance_cm"]
    assert clean > 2.0 and scraped < 0.4


def test_end_ankles_on_tiptoe_show():
    toe, ankle = walk()
    ankle[-1, 1, 2] += 0.05  # the right heel raised 5 cm on the last frame
    m = fm.measure(toe, ankle, FPS)
    assert m["max_end_ankle_off_cm"] == pytest.approx(5.0)
    assert m["last_ankle_cm"][1] == pytest.approx((ANKLE + 0.05) * 100)
    m = fm.measure(toe, ankle, FPS, standing=[0.1, 0.1])
    assert m["first_ankle_cm"][0] == pytest.approx(ANKLE * 100)
    assert m["max_end_ankle_off_cm"] == pytest.approx(3.0)


def test_feet_are_found_by_role_in_any_naming(walk16):
    skel = walk16.skeleton
    ankles, toes = fm.foot_bones(skel)
    assert [skel.names[i] for i in ankles + toes] == [
        "LeftFoot",
        "RightFoot",
        "LeftToeBase",
        "RightToeBase",
    ]
    mix = Skeleton([MIXAMO.get(n, n) for n in skel.names], skel.parents, skel.rest)
    assert fm.foot_bones(mix) == (ankles, toes)


def test_a_recorded_walk_plants_and_clears():
    """CMU 16_15: every swing clears the floor, no pops, a slow planted toe."""
    c = cmu("16_15")
    ankles, toes = fm.foot_bones(c.skeleton)
    p = c.joint_positions()
    m = fm.measure(p[:, toes], p[:, ankles], c.fps)
    assert m["pops"] == 0 and m["swings"] >= 6
    assert 0.3 < m["min_swing_clearance_cm"] < 3.0
    assert m["skate"]["mean_cm_per_s"] < 20.0
