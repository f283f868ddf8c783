# SPDX-License-Identifier: GPL-3.0-or-later
"""The planning settings, described once: name, default, range, unit, label and help.

The scene's Planning panel and the add-on preferences (``props.PLANNING``), the CLI's flags
and the API's checks are all derived from :data:`SETTINGS`, so a setting cannot have one
range in the panel and another in a script. A request's settings travel from the door to
the planner as one :class:`PlanSettings`."""

import math
from collections.abc import Iterable
from dataclasses import dataclass, fields, replace
from typing import TypeVar

_T = TypeVar("_T")


@dataclass(frozen=True)
class Setting:
    """One planning setting. ``kind`` is float, bool or str; a str setting is one of
    ``choices`` ((value, label, help) with lower-case values); a float lies in
    [``minimum``, ``maximum``] (the panel's slider stops at ``soft_maximum``)."""

    name: str
    default: object
    kind: type
    label: str
    help: str
    minimum: float | None = None
    maximum: float | None = None
    soft_maximum: float | None = None
    unit: str = ""  # "m" for lengths (the panel shows the scene's length unit)
    choices: tuple = ()
    flag: str = ""  # the CLI's words for it (default: the name with dashes)
    # The CLI's switches in place of one flag: (value, words, help) each, mutually exclusive
    # (--foot-lock / --no-foot-lock); an empty help is the setting's, or the choice's.
    switches: tuple = ()

    @property
    def values(self) -> tuple:
        return tuple(c[0] for c in self.choices)

    def check(self, value: object, where: str = "") -> float | bool | str:
        """``value`` as this setting holds it (float, bool or a lower-case choice), or
        ValueError naming the setting, the range and the value."""
        what = where + self.name.replace("_", " ")
        if self.kind is float:
            lo, hi = self.minimum, self.maximum
            assert lo is not None and hi is not None, "a float setting has a range"
            try:
                v = float(value)  # type: ignore[arg-type]  # any value is tried; the except catches
                ok = not isinstance(value, bool) and math.isfinite(v)
            except (TypeError, ValueError):
                ok = False
            if ok and lo <= v <= hi:
                return v
            unit = " of metres" if self.unit == "m" else ""
            raise ValueError(
                f"{what} must be a number{unit} from {self.minimum:g} to {self.maximum:g}, "
                f"not {value!r}"
            )
        if self.kind is bool:
            if value in (True, False):
                return bool(value)
            raise ValueError(f"{what} must be True or False, not {value!r}")
        choice = value.lower() if isinstance(value, str) else value
        if isinstance(choice, str) and choice in self.values:  # the values are str
            return choice
        raise ValueError(
            f"{what} must be {' or '.join(repr(a) for a in self.values)}, not {value!r}"
        )


MAX_WEIGHT = 1e6  # alpha, beta, gamma above this overflow the search's costs

SETTINGS = (
    Setting("alpha", 1.0, float, "Distance (α)", "Cost per metre walked", 0.0, MAX_WEIGHT, 10.0),
    Setting("beta", 0.5, float, "Turning (β)", "Cost per radian turned", 0.0, MAX_WEIGHT, 10.0),
    Setting(
        "gamma",
        0.2,
        float,
        "Effort (γ)",
        "Cost per unit of effort (jumping a prop costs its clip's effort)",
        0.0,
        MAX_WEIGHT,
        10.0,
    ),
    Setting(
        "radius",
        0.25,
        float,
        "Character Radius",
        "Clearance kept between the root and props",
        0.05,
        2.0,
        unit="m",
    ),
    Setting(
        "stitching",
        "dynamic",
        str,
        "Stitching",
        "How traversal clips of object patches join the search",
        choices=(
            ("dynamic", "Dynamic", "Stitch traversal clips lazily, when the search needs them"),
            (
                "static",
                "Static",
                "Stitch every traversal clip before searching (Lee 2006 baseline)",
            ),
        ),
    ),
    Setting(
        "foot_lock",
        True,
        bool,
        "Lock Planted Feet",
        "Pin each planted foot with leg IK (an Add track over the walk) so it does not slide",
        switches=(
            (True, "foot-lock", ""),
            (False, "no-foot-lock", "Leave planted feet as synthesised (no leg IK track)"),
        ),
    ),
    Setting(
        "goal_facing",
        "exact",
        str,
        "Goal Facing",
        "Which way the character faces at the goal",
        choices=(
            ("exact", "Exact", "Arrive facing the goal object's facing (its -Y axis)"),
            ("any", "Any", "Arrive facing whichever way is cheapest (e.g. a goal in a dead end)"),
        ),
        switches=(("any", "any-facing", ""), ("exact", "exact-facing", "")),
    ),
    Setting(
        "turn_in_place",
        True,
        bool,
        "Turn on the Spot",
        "Where a walk would loop to leave the start or reach the goal facing its way, stop "
        "and turn on the spot (a turn derived from the walk's sharpest turn loop; the mocap "
        "has no turn-in-place clip)",
        switches=(
            (True, "turn-in-place", ""),
            (False, "no-turn-in-place", "Walk the loops instead of turning on the spot"),
        ),
    ),
)
BY_NAME = {s.name: s for s in SETTINGS}
PLANNING = {s.name: s.default for s in SETTINGS}  # name -> default
STITCHING = BY_NAME["stitching"].values
GOAL_FACING = BY_NAME["goal_facing"].values


def _default(name: str, kind: type[_T]) -> _T:
    """The default of setting ``name``, which is a ``kind``."""
    value = BY_NAME[name].default
    assert isinstance(value, kind), name
    return value


@dataclass(frozen=True)
class PlanSettings:
    """The settings of one plan request, checked (:meth:`checked`), carried from the door
    (panel, CLI, script) to the planner in place of loose keyword arguments."""

    alpha: float = _default("alpha", float)
    beta: float = _default("beta", float)
    gamma: float = _default("gamma", float)
    radius: float = _default("radius", float)
    stitching: str = _default("stitching", str)
    foot_lock: bool = _default("foot_lock", bool)
    goal_facing: str = _default("goal_facing", str)
    turn_in_place: bool = _default("turn_in_place", bool)

    def __post_init__(self) -> None:
        # With every weight 0 every path costs nothing: the search has nothing to prefer
        # and wanders (a cost-0 plan of any length).
        if self.alpha == self.beta == self.gamma == 0.0:
            raise ValueError(
                "the weights alpha, beta and gamma are all 0: every path would cost nothing; "
                "give at least one a positive weight"
            )

    @classmethod
    def checked(cls, where: str = "", **values: object) -> "PlanSettings":
        """Settings from ``values`` (defaults for those left out), each checked by its
        :class:`Setting`; ValueError names the first bad one, TypeError an unknown name."""
        unknown = set(values) - set(BY_NAME)
        if unknown:
            raise TypeError(f"not planning settings: {', '.join(sorted(unknown))}")
        settings = {k: BY_NAME[k].check(v, where) for k, v in values.items()}
        return cls(**settings)  # type: ignore[arg-type]  # each is checked as its field's kind

    def replaced(self, **values: object) -> "PlanSettings":
        """A copy with ``values`` checked and put in."""
        # mypy reads ``values`` as possibly holding checked's ``where`` (they are settings)
        return replace(self, **PlanSettings.checked(**values).given(values))  # type: ignore[arg-type]

    def given(self, names: Iterable[str]) -> dict:
        """The settings ``names`` as a dict."""
        return {k: getattr(self, k) for k in names}

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}
