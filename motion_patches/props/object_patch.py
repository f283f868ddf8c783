# SPDX-License-Identifier: GPL-3.0-or-later
"""Object patches: props that carry their own animation (paper Sec. 4).

A prop has a footprint (convex polygon in its own ground coordinates) and clips given
relative to it: traversal clips (jump over, vault) that the planner may stitch into the
walk, and interaction clips (sit, stand) that only start or end a path. A traversal clip
can be copied around the prop in fixed angle steps (paper: 10 degrees); copies whose
take-off or landing would touch the prop are dropped. Density bins around the prop's
extended bounds sort the clips by where they start and end, so another prop overlapping
a bin culls the clips that use it without testing them one by one.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..kinematics import contacts as contacts_mod
from ..kinematics.clip import Clip, resample
from ..kinematics.inplace import facing_yaw, to_inplace, to_world
from ..kinematics.motion import Motion
from ..kinematics.skeleton import Skeleton, forward_kinematics
from .environment import Obstacle, distance_to_polygon, inside_convex, polygons_within

TRAVERSAL, INTERACTION = "traversal", "interaction"
BINS = 4  # density bins per side of the extended bounds
HEADROOM = 0.02  # metres a traversal's body keeps above the prop it clears


@dataclass
class PatchClip:
    """A clip in prop coordinates; its first and last frames are the stitch keyframes."""

    name: str
    kind: str
    motion: Motion  # ground frames relative to the prop, in-place channels
    effort: float = 1.0  # user-supplied T of Eq. 5 for the whole clip
    layer_in: str = "walk"  # layers the clip is entered from / left in (names, "a, b" or "*";
    layer_out: str = "walk"  # motion_patches.layers.serves)
    angle: float = 0.0  # rotation of this copy about the prop (radians)

    @property
    def entry(self) -> np.ndarray:
        return self.motion.ground[0]

    @property
    def exit(self) -> np.ndarray:
        return self.motion.ground[-1]

    def length(self) -> float:
        """Metres the ground frame travels (computed once: a clip's motion is fixed)."""
        got = self.__dict__.get("_length")
        if got is None:
            got = self.__dict__["_length"] = float(
                np.linalg.norm(np.diff(self.motion.ground[:, :2], axis=0), axis=1).sum()
            )
        return got

    def turn(self) -> float:
        """Radians the ground frame turns in all (computed once)."""
        got = self.__dict__.get("_turn")
        if got is None:
            got = self.__dict__["_turn"] = float(
                np.abs(np.diff(np.unwrap(self.motion.ground[:, 2]))).sum()
            )
        return got

    def rotated(self, angle: float) -> "PatchClip":
        m = self.motion.transformed(0.0, 0.0, angle)
        return PatchClip(
            self.name, self.kind, m, self.effort, self.layer_in, self.layer_out, self.angle + angle
        )


def clip_ground(clip: Clip) -> np.ndarray:
    """Ground frame of a non-cyclic clip: the straight line from its first to its last
    root position, the root projected on it (never moving backwards), facing along it;
    a clip that barely moves (sit down) keeps its smoothed facing instead."""
    p = clip.root_pos[:, :2]
    d = p[-1] - p[0]
    dist = float(np.linalg.norm(d))
    if dist < 0.3:
        yaw = facing_yaw(clip)
        k = np.ones(9) / 9
        yaw_s = np.convolve(np.pad(yaw, 4, mode="edge"), k, "valid")
        return np.column_stack((np.repeat(p[:1], clip.frames, 0), yaw_s))
    u = d / dist
    s = np.maximum.accumulate(np.clip((p - p[0]) @ u, 0.0, dist))
    pos = p[0] + s[:, None] * u
    return np.column_stack((pos, np.full(clip.frames, np.arctan2(u[1], u[0]))))


def ends_lower(clip: Clip) -> bool:
    """True when the clip ends with the root much lower than it starts (a sit down)."""
    return clip.root_pos[-1, 2] < clip.root_pos[0, 2] - 0.2


def patch_clip_from(
    clip: Clip,
    kind: str,
    fps: float,
    effort: float = 1.0,
    anchor: np.ndarray | Sequence[float] | None = None,
    name: str | None = None,
    floor: float | None = None,
) -> PatchClip:
    """A PatchClip from a recorded clip, placed so ``anchor`` (in the clip's ground
    coordinates) sits on the prop's origin and the clip starts facing +X.

    For a traversal the default anchor is the ground position under the highest root
    frame (the top of the jump); for an interaction, where the root is lowest (seated).
    With ``floor`` the clip is moved vertically so its own capture floor lies at that
    height (the walk's), as captures differ (CMU 13_05's floor is 0.26 m below zero).
    """
    if kind not in (TRAVERSAL, INTERACTION):
        raise ValueError(f"clip kind must be '{TRAVERSAL}' or '{INTERACTION}', not '{kind}'")
    c = resample(clip, fps).validate()
    ground = clip_ground(c)
    travel = np.linalg.norm(c.root_pos[-1, :2] - c.root_pos[0, :2])
    if kind == TRAVERSAL and travel < 0.3:
        raise ValueError(
            f"clip '{clip.name}' moves the root only {travel:.2f} m: a traversal "
            f"clip must carry the character past the prop (no root motion)"
        )
    root_local, rot = to_inplace(c, ground)
    if floor is not None:
        root_local = root_local.copy()
        root_local[:, 2] += floor - contacts_mod.floor_level(c)
    con, _, _ = contacts_mod.foot_contacts(c, level_floor=True)
    if anchor is None:
        pick = np.argmax if kind == TRAVERSAL else np.argmin
        anchor = ground[int(pick(c.root_pos[:, 2])), :2]
    h0 = ground[0, 2]
    m = Motion(ground, root_local, rot, con).transformed(0.0, 0.0, -h0)
    a = np.array(
        [
            np.cos(-h0) * anchor[0] - np.sin(-h0) * anchor[1],
            np.sin(-h0) * anchor[0] + np.cos(-h0) * anchor[1],
        ]
    )
    m = m.transformed(-a[0], -a[1], 0.0)
    return PatchClip(name or clip.name, kind, m, float(effort))


def body_points(clip: PatchClip, skel: Skeleton) -> np.ndarray:
    """(N, 3) every bone's head and the middle of every bone on every frame of ``clip``,
    in prop coordinates: where the body passes (a traversal must pass above the prop)."""
    m = clip.motion
    pos, rot = to_world(skel, m.ground, m.root_local, m.rotations)
    heads = forward_kinematics(skel, pos, rot)[..., :3, 3]
    kids = np.flatnonzero(skel.parents >= 0)
    mids = 0.5 * (heads[:, kids] + heads[:, skel.parents[kids]])
    return np.concatenate((heads, mids), axis=1).reshape(-1, 3)


def clearance_over(points: np.ndarray, footprint: np.ndarray, floor: float = 0.0) -> float:
    """Height above ``floor`` of the lowest of ``points`` (:func:`body_points`) over
    ``footprint``: how high a prop there may be; inf when none passes over it."""
    over = inside_convex(points[:, :2], footprint)
    return float(points[over, 2].min() - floor) if over.any() else float("inf")


@dataclass
class ObjectPatch:
    """A prop instance: footprint, pose on the ground, clips (with copies), density bins."""

    name: str
    footprint: np.ndarray  # (P, 2) convex, counter-clockwise, prop coordinates
    clips: list = field(default_factory=list)  # PatchClip in prop coordinates (copies included)
    pose: tuple = (0.0, 0.0, 0.0)  # x, y, heading of the prop on the ground
    height: float = 0.0  # top of the prop above the floor (0: not known, nothing checked)
    # Traversal clips not offered because the body passes lower than the prop's top:
    # (clip name, its clearance over the footprint, the prop's height), metres.
    too_low: list = field(default_factory=list)

    def to_world(self, xy: ArrayLike) -> np.ndarray:
        x, y, h = self.pose
        c, s = np.cos(h), np.sin(h)
        xy = np.asarray(xy, float)
        return np.stack(
            (x + c * xy[..., 0] - s * xy[..., 1], y + s * xy[..., 0] + c * xy[..., 1]), -1
        )

    def world_footprint(self) -> np.ndarray:
        return self.to_world(self.footprint)

    def world_clip(self, clip: PatchClip) -> Motion:
        return clip.motion.transformed(*self.pose)

    def traversals(self) -> list[PatchClip]:
        return [c for c in self.clips if c.kind == TRAVERSAL]

    def interactions(self) -> list[PatchClip]:
        return [c for c in self.clips if c.kind == INTERACTION]

    def add_traversal_copies(
        self, clip: PatchClip, step_deg: float = 10.0, clearance: float = 0.05
    ) -> int:
        """Add ``clip`` rotated about the prop every ``step_deg`` degrees, keeping only the
        copies whose take-off and landing stay ``clearance`` clear of the footprint."""
        added = 0
        for a in np.radians(np.arange(0.0, 360.0, step_deg)):
            c = clip.rotated(a)
            ends = np.array([c.entry[:2], c.exit[:2]])
            if np.all(distance_to_polygon(ends, self.footprint) > clearance):
                self.clips.append(c)
                added += 1
        return added

    def keep_clearing(self, skel: Skeleton, floor: float = 0.0) -> None:
        """Drop the traversal copies whose body passes lower over the footprint than the
        prop's ``height`` (plus :data:`HEADROOM`): a jump that would sink its legs into the
        prop is not a way over it. A clip none of whose copies clears is listed in
        :attr:`too_low` with its best clearance. ``floor``: the clips' floor height."""
        if self.height <= 0.0:
            return
        kept: list[PatchClip] = []
        best: dict[str, float] = {}
        points: dict[str, np.ndarray] = {}
        for c in self.clips:
            if c.kind != TRAVERSAL:
                kept.append(c)
                continue
            # A copy is the clip turned about the prop: turn the footprint the other way.
            if c.name not in points:
                points[c.name] = body_points(c.rotated(-c.angle), skel)
            ca, sa = np.cos(-c.angle), np.sin(-c.angle)
            turned = self.footprint @ np.array([[ca, sa], [-sa, ca]])
            h = clearance_over(points[c.name], turned, floor)
            best[c.name] = max(best.get(c.name, -np.inf), h)
            if h >= self.height + HEADROOM:
                kept.append(c)
        self.clips = kept
        self.too_low = [
            (n, h, self.height)
            for n, h in best.items()
            if not any(c.name == n and c.kind == TRAVERSAL for c in kept)
        ]

    def extended_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Footprint bounds grown to contain every clip's entry and exit point."""
        pts = np.concatenate(
            [self.footprint] + [np.array([c.entry[:2], c.exit[:2]]) for c in self.clips]
        )
        return pts.min(axis=0), pts.max(axis=0)

    def occluded_bins(self, obstacles: Iterable[Obstacle]) -> np.ndarray:
        """(BINS*BINS,) True for the density bins another prop's footprint overlaps."""
        rects, _ = self.density_bins()
        out = np.zeros(len(rects), bool)
        lo, hi = self.extended_bounds()
        corners = self.to_world(
            np.array([[lo[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]], [hi[0], lo[1]]])
        )
        wlo, whi = corners.min(axis=0), corners.max(axis=0)
        polys = None
        for ob in obstacles:
            if ob.name == self.name:
                continue
            olo, ohi = ob.bounds()
            if np.any(olo > whi) or np.any(ohi < wlo):
                continue
            if polys is None:  # every bin in the world at once, and its bounds
                x0, y0, x1, y1 = rects.T
                polys = self.to_world(
                    np.stack(((x0, y0), (x1, y0), (x1, y1), (x0, y1)), axis=1).transpose(2, 1, 0)
                )
                blo, bhi = polys.min(axis=1), polys.max(axis=1)
            # Only bins whose bounds meet the footprint's can overlap it.
            meet = ~out & np.all(blo <= ohi, axis=1) & np.all(bhi >= olo, axis=1)
            for b in np.flatnonzero(meet).tolist():
                out[b] = polygons_within(polys[b], ob.polygon, 0.0)
        return out

    def density_bins(self) -> tuple[np.ndarray, np.ndarray]:
        """(BINS*BINS, 4) bin rectangles (x0, y0, x1, y1) in prop coordinates, and for every
        clip the (entry bin, exit bin) it starts and ends in (cached)."""
        cached = self.__dict__.get("_bins")
        if cached is not None and cached[0] == len(self.clips):
            return cached[1]
        result = self._density_bins()
        self.__dict__["_bins"] = (len(self.clips), result)
        return result

    def _density_bins(self):
        lo, hi = self.extended_bounds()
        size = (hi - lo) / BINS
        ix, iy = np.meshgrid(np.arange(BINS), np.arange(BINS), indexing="xy")
        x0 = lo[0] + ix.ravel() * size[0]
        y0 = lo[1] + iy.ravel() * size[1]
        rects = np.column_stack((x0, y0, x0 + size[0], y0 + size[1]))

        def bin_of(p):
            b = np.clip(((np.asarray(p) - lo) / np.maximum(size, 1e-9)).astype(int), 0, BINS - 1)
            return int(b[1] * BINS + b[0])

        idx = np.array([(bin_of(c.entry[:2]), bin_of(c.exit[:2])) for c in self.clips], int)
        return rects, idx.reshape(-1, 2)
