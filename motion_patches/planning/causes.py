# SPDX-License-Identifier: GPL-3.0-or-later
"""Why a plan found no path: the props in the way, the locomotion patch, or the search limit.

The planner says where it got stuck (no way out of the start, into the goal, or between
them); a user needs to know what to change. :func:`plan_explained` plans and, when no path
is found, names the cause, tried in this order:

* **the search limit**: the search stopped at its node limit, not at a closed way;
* **the patch**: the same request on open ground (no props at all) fails too, so no prop
  is to blame: the patch's walks turn too wide (or connect too sparsely) for this start
  and goal;
* **the props**: those that keep the start from the goal, read from the planner's own
  occluded cells (:func:`.blocking.blocking_props`, the layout check's answer); where no
  prop walls the way off cell by cell, the props the open-ground walk runs into.

Never imports bpy.
"""

import contextlib
import inspect
from collections.abc import Iterable, Iterator

import numpy as np

from ..patch.locomotion_patch import entry_share
from ..props.blocking import blocking_props
from ..props.environment import Environment
from .motions import piece_motion
from .pieces import Plan, PlanError
from .planner import SegmentPlanner

SEARCH_LIMIT = inspect.signature(SegmentPlanner.plan).parameters["max_expansions"].default
MARGIN_TILES = inspect.signature(SegmentPlanner.plan).parameters["margin_tiles"].default
NAMED = 4  # props named in a message at most


class NoPath(PlanError):
    """No path, with its cause: ``cause`` is "search limit", "patch" or "props" and
    ``props`` the names of the props to blame (empty unless the cause is props)."""

    def __init__(self, message: str, cause: str, props: Iterable[str] = ()) -> None:
        super().__init__(message)
        self.cause, self.props = cause, list(props)


@contextlib.contextmanager
def counted(planner: SegmentPlanner) -> Iterator[list[int]]:
    """Within the block ``planner`` counts the nodes its searches expand: yields a list
    whose only item is the count so far."""
    count = [0]
    expand = planner.expand

    def counting(key):
        count[0] += 1
        return expand(key)

    # An instance attribute shadows the method for the block (mypy forbids it of a method).
    planner.expand = counting  # type: ignore[method-assign]
    try:
        yield count
    finally:
        del planner.expand


def plan_explained(
    planner: SegmentPlanner,
    start: np.ndarray,
    goal: np.ndarray,
    margin_tiles: int = MARGIN_TILES,
    max_expansions: int = SEARCH_LIMIT,
) -> Plan:
    """``planner.plan(start, goal)``; when it finds no path, :class:`NoPath` whose message is
    the planner's followed by the cause."""
    with counted(planner) as expanded:
        try:
            return planner.plan(
                start, goal, margin_tiles=margin_tiles, max_expansions=max_expansions
            )
        except PlanError as exc:
            failure = exc
    cause, props, text = no_path_cause(
        planner,
        start,
        goal,
        margin_tiles,
        max_expansions if expanded[0] >= max_expansions else None,
    )
    raise NoPath(f"{str(failure).rstrip('.')}. Cause: {text}", cause, props) from None


def _turn_radius(planner):
    """Metres: the tightest turn the planner's patch makes (either way)."""
    return 1.0 / max(min(-planner.kmin, planner.kmax), 1e-9)


def no_path_cause(
    planner: SegmentPlanner,
    start: np.ndarray,
    goal: np.ndarray,
    margin_tiles: int = MARGIN_TILES,
    limit_hit: int | None = None,
) -> tuple[str, list[str], str]:
    """(cause, prop names, sentence) for a plan of ``planner`` from ``start`` to ``goal``
    (world (x, y, heading)) that found no path; ``limit_hit``: the node limit its search
    stopped at, if it did."""
    patch, env = planner.patch, planner.world_env
    if limit_hit:
        return (
            "search limit",
            [],
            (
                f"the search limit: the search stopped after {limit_hit:,} nodes without closing "
                f"the way; plan to a nearer goal first and on from there"
            ),
        )
    walk = (
        f"the walk keeps {env.radius:.2f} m from props and turns no tighter than "
        f"{_turn_radius(planner):.2f} m"
    )
    free = SegmentPlanner(
        patch,
        Environment(env.side, env.cells, env.radius),
        planner.alpha,
        planner.beta,
        planner.gamma,
        turn_in_place=planner.turn_in_place,
    )
    try:
        found = free.plan(
            np.asarray(start, float), np.asarray(goal, float), margin_tiles=margin_tiles
        )
    except PlanError:
        return (
            "patch",
            [],
            (
                f"the locomotion patch: even on open ground none of its walks joins this start "
                f"to this goal ({walk}; {entry_share(patch):.0%} of its entry states have a way "
                f"on); give the walk more room between start and goal, or re-bake the patch with "
                f"a turn clip so it turns tighter"
            ),
        )
    names, reason = blocking_props(env, start, goal, margin_tiles)
    if not names:
        names, reason = _props_along(env, patch, found), "along"
    who = ", ".join(repr(n) for n in names[:NAMED]) + (", ..." if len(names) > NAMED else "")
    one = len(names) == 1
    if reason in ("start", "goal"):
        text = f"the {reason} is within {env.radius:.2f} m of {who}: move it into the open"
    elif reason == "separated":
        text = (
            f"{who} wall{'s' if one else ''} the goal off from the start (no way round "
            f"within {margin_tiles} tiles, {margin_tiles * env.side:.1f} m): move "
            f"{'it' if one else 'them'} or open a gap"
        )
    elif names:
        text = (
            f"{who} leave{'s' if one else ''} no way the walk can fit and turn through "
            f"({walk}): widen the gap or move {'it' if one else 'them'}"
        )
    else:
        text = (
            f"the props within {margin_tiles} tiles of start and goal leave no way the "
            f"walk can make ({walk})"
        )
    return "props", names, text


def _props_along(env, patch, plan):
    """Names of the props the ground path of ``plan`` (planned without props) runs within
    the radius of, those it meets most often first."""
    ground = np.concatenate([piece_motion(patch, p).ground[:, :2] for p in plan.pieces])
    count = {}
    for p in ground[env.blocked(ground)]:
        for n in env.near(p):
            count[n] = count.get(n, 0) + 1
    return sorted(count, key=lambda n: (-count[n], n))
