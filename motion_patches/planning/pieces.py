# SPDX-License-Identifier: GPL-3.0-or-later
"""Plans and their pieces, and why a plan is refused: the vocabulary the search, the
connectors, shortening and turning on the spot share (kept apart from the search so each
of them can name a piece without importing the others)."""

from dataclasses import dataclass, field

import numpy as np

from ..patch.curves import Curve
from ..props.object_patch import ObjectPatch
from .plan_frame import IDENTITY

CONNECTOR_SCALES = np.linspace(0.25, 4.0, 40)  # coarser than the bake: fitted at plan time


class PlanError(ValueError):
    """The goal cannot be reached, or the request is malformed; the message says why."""


class InsideObstacle(PlanError):
    """The start or goal is inside an obstacle or within the radius of one. The planner
    works in its own world (the scene's divided by the character's size): :meth:`text`
    says it in the scene's, given that size."""

    def __init__(self, what: str, point, radius: float):
        self.what, self.point, self.radius = what, (float(point[0]), float(point[1])), radius
        super().__init__(self.text())

    def text(self, scale: float = 1.0) -> str:
        x, y = self.point[0] * scale, self.point[1] * scale
        return (
            f"the {self.what} ({x:.2f}, {y:.2f}) is inside or within "
            f"{self.radius * scale:.2f} m of an obstacle"
        )


class SearchLimit(PlanError):
    """The search stopped at its node limit before finding a way (not proof there is none)."""


class Unreachable(PlanError):
    """The search ran out of nodes: no way within the plan region (a walk that turns on the
    spot at an end may still find one)."""


class FacingRefused(PlanError):
    """No walk can leave the start (reach the goal) facing its way: the props around leave
    no room to turn (a turn on the spot there may help)."""


@dataclass
class Piece:
    kind: str  # "segment", "part", "traversal", "start" or "goal"
    segment: int = -1  # patch segment index (kinds "segment" and "part")
    tile: tuple = (0, 0)
    curve: Curve | None = None  # in world coordinates (connectors)
    cycles: int = 0  # whole cycles (segments and start connectors)
    cost: float = 0.0
    frames: tuple[int, int] | None = None  # (first, last) frame of a segment used in part ("part")
    prop: ObjectPatch | None = None  # of a traversal
    clip_index: int = -1
    frame: tuple = IDENTITY  # plan frame (x, y, angle) taking the piece to the world
    # (x, y, heading, angle) of a turn on the spot (kind "turn"), world
    turn: tuple[float, float, float, float] | None = None
    # A crowd's idle holds laid into the piece (kind "hold"): what it was, and the frames
    # held (each (frame in the piece, frames held)).
    held_from: str = ""
    holds: tuple = ()

    @property
    def label(self) -> str:
        """What the piece plays, for reports and strip names."""
        if self.kind == "turn":
            assert self.turn is not None, "a turn piece has its turn"
            return f"turn {np.degrees(self.turn[3]):+.0f}deg in place (derived)"
        if self.kind == "segment":
            return f"seg{self.segment:04d}"
        if self.kind == "part":
            assert self.frames is not None, "a part has its frames"
            return f"seg{self.segment:04d}[{self.frames[0]}-{self.frames[1]}]"
        if self.kind == "hold":
            waits = ", ".join(f"{n} frames at +{at}" for at, n in self.holds)
            return f"{self.held_from or 'walk'} holding {waits}"
        if self.kind in ("traversal", "interaction"):
            assert self.prop is not None, "a traversal has its prop"
            c = self.prop.clips[self.clip_index]
            return f"{self.prop.name} {c.name} {np.degrees(c.angle):.0f}deg"
        return self.kind


@dataclass
class Plan:
    pieces: list
    cost: float
    expansions: int
    seconds: float
    start: tuple
    goal: tuple
    stats: dict = field(default_factory=dict)
