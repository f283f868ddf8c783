# SPDX-License-Identifier: GPL-3.0-or-later
"""Python API: the functions behind every operator and every CLI command.

Arguments are plain Blender objects, actions, names and numbers; results are small
dataclasses. Every failure is a :class:`MotionPatchesError` with a message meant for the
user, raised before the scene is changed.

One module per use case: :mod:`.baking` and :mod:`.tagging` (a patch and its props),
:mod:`.patch_files` (patch files, bone maps), :mod:`.plan` (one character), :mod:`.crowd`,
:mod:`.crowd_copies` (crowds), :mod:`.check` (analysis, layout checks), :mod:`.overlay`
(what the viewport overlay draws) and :mod:`.bodies` (proxy bodies round the bones); the
steps they share are in :mod:`.common`, :mod:`.settings`, :mod:`.solve` and
:mod:`.writing`. Operators, panels, the CLI and scripts use the names re-exported here.
"""

from ..adapter import compat, evaluate, storage
from ..adapter import scene as scene_io
from ..motion_patches.patch import layers
from ..motion_patches.quality import metrics
from .baking import bake_locomotion_patch, import_mocap
from .bodies import add_bodies, character_colour, chosen_characters, has_body, remove_bodies
from .check import analyse, check_layout, planned_pairs
from .common import (
    MAX_COORDINATE,
    MAX_DISTANCE,
    PLAN_KEY,
    active_patch_name,
    character_goal,
    character_start_prop,
    last_analysis,
    load_plan_record,
    object_patches,
    own_goal,
    path_length,
    scene_fps,
    state_dict,
)
from .crowd import CROWD_SPOT, cluster_executor, crowd_member, crowd_members, plan_crowd
from .crowd_conflicts import (
    CONFLICTS_KEY,
    crowd_conflicts,
    has_crowd_conflicts,
    select_crowd_conflicts,
)
from .crowd_copies import CROWD_COLLECTION, duplicate_crowd, remove_crowd
from .crowd_holds import CROWD_HOLD_RAMP_SECONDS, _holdable
from .errors import Cancelled, ClusterLost, MotionPatchesError, PathNotFound
from .overlay import PlanDrawing, clip_ends, footprint_info, plan_drawings, plan_fingerprints
from .patch_files import bone_map, export_patch, fill_bone_map, import_patch, set_bone_map
from .plan import plan_path
from .results import BakeResult, BodiesResult, CrowdResult, CrowdSchedule, PlanResult
from .settings import (
    DEFAULTS,
    SETTINGS,
    PlanSettings,
    plan_settings,
    planning_checked,
    planning_settings,
)
from .tagging import is_tagged, tag_object_patch
from .writing import (
    BLENDER_DEFAULT_RANGE,
    FRAME_RANGE_KEY,
    _fit_frame_range,
    _write,
    fitted_frame_range,
)

__all__ = [
    "BLENDER_DEFAULT_RANGE",
    "BakeResult",
    "BodiesResult",
    "CROWD_COLLECTION",
    "CROWD_HOLD_RAMP_SECONDS",
    "CONFLICTS_KEY",
    "CROWD_SPOT",
    "Cancelled",
    "ClusterLost",
    "cluster_executor",
    "CrowdResult",
    "CrowdSchedule",
    "DEFAULTS",
    "FRAME_RANGE_KEY",
    "MAX_COORDINATE",
    "MAX_DISTANCE",
    "MotionPatchesError",
    "PLAN_KEY",
    "PathNotFound",
    "PlanDrawing",
    "PlanResult",
    "PlanSettings",
    "SETTINGS",
    "_fit_frame_range",
    "_holdable",
    "_write",
    "active_patch_name",
    "add_bodies",
    "analyse",
    "bake_locomotion_patch",
    "bone_map",
    "character_colour",
    "character_goal",
    "character_start_prop",
    "check_layout",
    "chosen_characters",
    "clip_ends",
    "compat",
    "crowd_conflicts",
    "crowd_member",
    "crowd_members",
    "duplicate_crowd",
    "evaluate",
    "export_patch",
    "fill_bone_map",
    "fitted_frame_range",
    "has_crowd_conflicts",
    "footprint_info",
    "has_body",
    "import_mocap",
    "import_patch",
    "is_tagged",
    "last_analysis",
    "layers",
    "load_plan_record",
    "metrics",
    "object_patches",
    "own_goal",
    "path_length",
    "plan_crowd",
    "plan_drawings",
    "plan_fingerprints",
    "plan_path",
    "plan_settings",
    "planned_pairs",
    "planning_checked",
    "planning_settings",
    "remove_bodies",
    "remove_crowd",
    "scene_fps",
    "scene_io",
    "select_crowd_conflicts",
    "set_bone_map",
    "state_dict",
    "storage",
    "tag_object_patch",
]
