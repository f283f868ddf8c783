# SPDX-License-Identifier: GPL-3.0-or-later
"""What the API returns: small dataclasses of names and numbers."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class BakeResult:
    name: str
    layer: str
    stats: dict
    seconds: float
    notes: list
    armature: str = ""  # the armature the clips play on
    straight: str = ""  # action names baked
    turns: list = field(default_factory=list)
    imported: list = field(default_factory=list)  # actions imported from BVH files
    # what looks wrong and was baked anyway (a clip's timing: motion_patches.patch.timing)
    warnings: list = field(default_factory=list)


@dataclass
class PlanResult:
    character: str
    frame_start: int
    frame_end: int
    pieces: list
    cost: float
    seconds: float
    expansions: int
    strips: list
    stashed_action_track: str | None = None
    stats: dict = field(default_factory=dict)
    length_m: float = 0.0
    goal: tuple | None = None  # (x, y, heading) reached: the facing chosen when any would do


@dataclass
class CrowdResult:
    plans: list  # PlanResult per planned character, in the order given
    failed: list  # [(character name, why no path)]
    conflicts: list  # [{"a", "b", "frame", "distance_m"}] closer than two radii
    delays: dict  # character name -> frames it waits at its start
    seconds: float
    rerouted: list = field(default_factory=list)  # names re-planned round others' stretches


@dataclass
class CrowdSchedule(CrowdResult):
    """A :class:`CrowdResult` with how the crowd was kept apart beyond waits."""

    # name -> [{"frame": first scene frame standing still, "frames": how many}]
    holds: dict = field(default_factory=dict)
    order: list = field(default_factory=list)  # planned names in the order they were placed
    # [{"character", "prop", "frame", "distance_m"}]: a walk as scheduled (waits and holds
    # of the crowd included) meeting a prop that moves
    moving_conflicts: list = field(default_factory=list)


@dataclass
class BodiesResult:
    characters: list  # names of the characters given a body, in the order given
    parts: int  # capsule objects made
    meshes: int  # distinct meshes they use (a crowd of one rig shares them)
