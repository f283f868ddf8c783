# SPDX-License-Identifier: GPL-3.0-or-later
"""The planning settings of a request: given values over the scene's, checked, as one
:class:`~motion_patches.planning.settings.PlanSettings` carried down to the planner."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ..motion_patches.planning.settings import PLANNING as DEFAULTS
from ..motion_patches.planning.settings import SETTINGS, PlanSettings
from .errors import MotionPatchesError

if TYPE_CHECKING:
    import bpy

__all__ = [
    "DEFAULTS",
    "SETTINGS",
    "PlanSettings",
    "plan_settings",
    "planning_checked",
    "planning_settings",
]


def planning_checked(**values: Any) -> PlanSettings:
    """:meth:`PlanSettings.checked` with :class:`MotionPatchesError` naming a bad value."""
    try:
        return PlanSettings.checked(**values)
    except ValueError as e:
        raise MotionPatchesError(str(e)) from None


def plan_settings(scene: bpy.types.Scene, **given: object) -> PlanSettings:
    """The planning settings of a request (the names of
    :data:`motion_patches.planning.settings.SETTINGS`): each one given (not None) as given,
    the others the scene's (its Planning panel, which starts from those defaults). All are
    checked: :class:`MotionPatchesError` names a bad one. One rule for the operators, the
    CLI and scripts."""
    s = scene.motion_patches
    values = {}
    for key in DEFAULTS:
        v = given.pop(key, None)
        values[key] = getattr(s, key) if v is None else v
    if given:
        raise TypeError(f"not planning settings: {', '.join(sorted(given))}")
    return planning_checked(**values)


def planning_settings(scene: bpy.types.Scene, **given: object) -> dict:
    """:func:`plan_settings` as a dict {name: value} (what the CLI reports as used)."""
    return plan_settings(scene, **given).as_dict()
