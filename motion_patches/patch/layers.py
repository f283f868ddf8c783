# SPDX-License-Identifier: GPL-3.0-or-later
"""Layers: one locomotion patch per gait, and the choice between them (paper Sec. 5).

Each layer's patch is baked from its own clips, so its tile side and node spacing follow
its pace (two straight cycles: a 4.5 m run tile over a 2.6 m walk tile for CMU subject
16); the tiles of each layer are laid over the same ground independently. A plan asks for
one layer or for "auto": the plan is then made in every layer and the cheapest Eq. 5
cost wins (the paper picks the layer by the cost of its high-level path; the full
low-level plan per layer is used here, as the tile costs of Eq. 4 are estimates that
cannot tell a hurdle taken from a hurdle walked round).

Costs of two layers compare only if effort is counted the same way: a layer's effort
rate T per second is its metabolic power relative to walking (:func:`effort_rate`).

Traversal clips declare the layer they are entered from and left in (``layer_in``,
``layer_out``); a patch uses a clip only when it declares the patch's layer on both
sides (:func:`serves`).
"""

from collections.abc import Sequence
from typing import Any

import numpy as np

from .gait import Gait

GAITS = ("walk", "run", "auto")

WALK_EFFORT_RATE = 1.0
"""Effort per second of walking: the unit the effort weight gamma is given in."""

RUN_COST_PER_METRE = 2.0
"""Running costs about twice the energy per metre that walking does at its usual pace
(Margaria et al. 1963: about 1 kcal/kg/km running at any speed, 0.5 walking near
1.2 m/s), so a run's effort per second is 2 x its speed / ``REFERENCE_WALK_SPEED``."""

REFERENCE_WALK_SPEED = 1.2  # m/s: the walking pace ``WALK_EFFORT_RATE`` is counted at
FLIGHT_SHARE = 0.05  # share of a cycle with no foot planted that makes a gait a run


def has_flight(gait: Gait) -> bool:
    """True when the gait's straight cycle has a flight phase (frames with no foot
    joint planted): a run, whatever its layer is called."""
    c = np.asarray(gait.straight.contacts, bool)
    return bool(np.mean(~c.any(axis=1)) >= FLIGHT_SHARE)


def speed(gait: Gait) -> float:
    """Metres per second of the gait's straight cycle."""
    return float(gait.cycle_distance * gait.fps / gait.frames)


def effort_rate(gait: Gait) -> float:
    """Effort T per second of a layer: ``WALK_EFFORT_RATE`` for a gait without flight,
    ``RUN_COST_PER_METRE`` x speed / ``REFERENCE_WALK_SPEED`` for a run (2 x 2.81 / 1.2 =
    4.7 for CMU 16_35). With the default weights a metre of running then costs a little
    more than a metre of walking (alpha + gamma x rate / speed: 1.33 against 1.18), so a
    run is chosen where it saves way (a hurdle instead of a detour), not everywhere."""
    if has_flight(gait):
        return RUN_COST_PER_METRE * speed(gait) / REFERENCE_WALK_SPEED
    return WALK_EFFORT_RATE


def serves(clip: Any, layer: str) -> bool:
    """A traversal clip is used by the patch of ``layer`` when both its incoming and its
    outgoing layer name it (each a name, a comma-separated list of names, or "*" for
    every layer: the 16_06 standing jump may serve "walk, run")."""

    def names(text):
        return {n.strip() for n in str(text).split(",") if n.strip()}

    return all(
        "*" in names(side) or layer in names(side) for side in (clip.layer_in, clip.layer_out)
    )


def for_layer(prop: Any, layer: str) -> Any:
    """The object patch with only the traversal clips that serve ``layer`` (interaction
    clips are kept: they start or end a path in whatever layer it walks)."""
    from dataclasses import replace

    keep = [c for c in prop.clips if c.kind != "traversal" or serves(c, layer)]
    if len(keep) == len(prop.clips):
        return prop
    return replace(prop, clips=keep)


def check_gait(gait_choice: str) -> str:
    """Refuse a layer choice that is not a layer name or "auto"; returns it stripped."""
    if not isinstance(gait_choice, str) or not gait_choice.strip():
        raise ValueError(
            f"the gait must be a layer name (walk, run) or 'auto', not {gait_choice!r}"
        )
    return gait_choice.strip()


def choose(costs: Sequence[float | None]) -> int | None:
    """Index of the cheapest of the layers' plan costs (ties: the first given, walk
    before run); None when no layer has a plan (cost None)."""
    best: int | None = None
    for i, c in enumerate(costs):
        if c is not None and (best is None or c < costs[best]):  # type: ignore[operator]
            best = i
    return best
