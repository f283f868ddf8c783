# SPDX-License-Identifier: GPL-3.0-or-later
"""Layout-check verdicts without Blender: which props block a pair, spec validation."""

import numpy as np
import pytest

from motion_patches.props.blocking import blocking_props
from motion_patches.props.environment import Environment, Obstacle
from motion_patches.quality import layout_spec


def test_blocking_props_are_read_from_the_occluded_cells():
    """What a layout check names for unreachable pairs, on synthetic walls (no planning)."""

    def rect(name, x0, y0, x1, y1):
        return Obstacle(name, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))

    def env(*obstacles):
        e = Environment(2.4, 8, 0.25)
        for ob in obstacles:
            e.place(ob)
        return e

    start, goal = np.array([0.0, 0.0, 0.0]), np.array([4.0, 0.0, 0.0])
    far = rect("FarCrate", 20, 20, 21, 21)
    wall = env(rect("Wall", 2.0, -30, 2.3, 30), far)
    assert blocking_props(wall, start, goal) == (["Wall"], "separated")
    slot = env(rect("WallS", 2.0, -30, 2.3, -0.6), rect("WallN", 2.0, 0.6, 2.3, 30), far)
    assert blocking_props(slot, start, goal) == (["WallN", "WallS"], "narrow")
    cage = env(
        rect("N", 3, 1, 5, 1.3),
        rect("S", 3, -1.3, 5, -1),
        rect("E", 5, -1.3, 5.3, 1.3),
        rect("W", 2.7, -1.3, 3, 1.3),
        rect("Outside", 0.5, 2, 1, 2.5),
        far,
    )
    assert blocking_props(cage, start, goal) == (["E", "N", "S", "W"], "separated")
    assert blocking_props(wall, np.array([1.9, 5.0, 0.0]), goal) == (["Wall"], "start")
    assert blocking_props(env(), start, goal) == ([], "unknown")


def test_a_spec_gets_defaults_and_per_pair_limits_win():
    spec = layout_spec.normalise(
        {
            "limits": {"max_seconds": 20},
            "pairs": [
                {"character": "Walker", "goal": "Desk"},
                {
                    "start": [0, 0, 90],
                    "goal": [6, 6, 0],
                    "max_seconds": 12,
                    "allow_traversal": False,
                },
            ],
        }
    )
    a, b = spec["pairs"]
    assert a["name"] == "Walker -> Desk" and a["limits"]["max_seconds"] == 20.0
    assert a["limits"]["must_reach"] is True and a["limits"]["allow_traversal"] is True
    assert b["start"] == [0.0, 0.0, 90.0] and b["limits"]["max_seconds"] == 12.0
    assert b["limits"]["allow_traversal"] is False


@pytest.mark.parametrize(
    "spec, needle",
    [
        ([], "top level"),
        ({"pairs": []}, "non-empty list"),
        ({"pairs": [{"goal": "G"}]}, "either 'character' or 'start'"),
        ({"pairs": [{"start": "A"}]}, "'goal' is missing"),
        ({"pairs": [{"start": [1, 2], "goal": "G"}]}, "[x, y, heading_deg]"),
        (
            {"pairs": [{"start": "A", "goal": "G", "max_seconds": -1}]},
            "max_seconds must be a number",
        ),
        ({"pairs": [{"start": "A", "goal": "G", "must_reach": "yes"}]}, "must_reach must be true"),
        ({"pairs": [{"start": "A", "goal": "G"}], "speed": 3}, "unknown key(s) speed"),
        ({"pairs": [{"start": "A", "goal": "G", "exclude": "Wall"}]}, "exclude must be a list"),
    ],
)
def test_a_bad_spec_is_refused_with_the_key_named(spec, needle):
    with pytest.raises(layout_spec.SpecError, match="layout spec") as err:
        layout_spec.normalise(spec)
    assert needle in str(err.value)


def test_the_verdict_lists_every_broken_limit():
    lim = dict(layout_spec.LIMIT_DEFAULTS, max_seconds=10.0, max_length=5.0, allow_traversal=False)
    r = {"reachable": True, "seconds": 12.0, "length_m": 4.0, "cost": 9.0, "traversals": 1}
    out = layout_spec.judge(r, lim)
    assert len(out) == 2 and "12.00 s of motion exceeds max_seconds 10" in out[0]
    assert "allow_traversal is false" in out[1]
    blocked = {
        "reachable": False,
        "error": "x",
        "blocked_by": ["Wall"],
        "blocked_reason": "separated",
    }
    assert layout_spec.judge(blocked, lim) == ["unreachable: blocked by Wall (separated)"]
    assert layout_spec.judge(blocked, dict(lim, must_reach=False)) == []


@pytest.mark.parametrize(
    "spec",
    [
        {"radius": float("nan"), "pairs": [{"start": "A", "goal": "G"}]},
        {"pairs": [{"start": "A", "goal": "G", "max_seconds": float("nan")}]},
        {"pairs": [{"start": "A", "goal": "G", "max_length": float("inf")}]},
        {"pairs": [{"start": [0, float("nan"), 0], "goal": "G"}]},
    ],
)
def test_not_a_number_is_refused(spec):
    with pytest.raises(layout_spec.SpecError, match="layout spec"):
        layout_spec.normalise(spec)


def test_goal_facing_is_exact_unless_a_pair_says_any():
    spec = layout_spec.normalise(
        {"pairs": [{"start": "A", "goal": "G"}, {"start": "A", "goal": "G", "goal_facing": "any"}]}
    )
    assert [p["goal_facing"] for p in spec["pairs"]] == ["exact", "any"]
    with pytest.raises(layout_spec.SpecError, match="goal_facing"):
        layout_spec.normalise({"pairs": [{"start": "A", "goal": "G", "goal_facing": "left"}]})
