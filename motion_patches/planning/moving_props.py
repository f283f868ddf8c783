# SPDX-License-Identifier: GPL-3.0-or-later
"""Props that move while a character walks (paper Sec. 4.4): asleep and awake, path repair.

A prop keyframed in Blender is known for the whole shot, so what the paper does at run time
is done here ahead of time, in the same terms. A prop is *awake* while it moves and *asleep*
while it stands still. The global plan sees the props asleep at the plan's first frame (the
caller leaves the awake ones out). The planned walk is then played against every moving
prop's track: where the character would come within its radius of a prop's footprint at the
same moment, the prop's bounds are extended along its velocity (its footprint swept over
the next few seconds) and only the piece of the path that meets it is
searched again with that swept footprint as an obstacle
(:meth:`~.planner.SegmentPlanner.replan_run`); the rest of the path is kept and the new run
joins it on its lattice nodes. A prop that falls asleep across the path (a cart parked in
the way) is the same case with a still footprint. Since a repaired run takes its own time,
the walk is played again until nothing meets a prop, a few rounds at most; what cannot be
repaired is reported by prop and frame, never hidden.

Tracks are rigid motions on the ground (x, y, yaw over time) of a footprint given in the
prop's own frame: carts, doors, vehicles. A prop that changes shape or scale while it moves
is followed only by its rigid part.
"""

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ..kinematics.motion import Motion, concatenate
from ..patch.locomotion_patch import LocomotionPatch
from ..props.environment import Obstacle, convex_hull
from .pieces import Plan, PlanError
from .planner import SegmentPlanner
from .shortcut import LOCOMOTION

STILL_SPEED = 1e-3  # m/s (and rad/s x 1 m) under which a prop is asleep
SWEEP_AHEAD_S = 2.5  # seconds of a prop's motion swept ahead of a conflict (its velocity)
SWEEP_BEHIND_S = 0.5  # and behind it (the way it came is free again soon after)
MAX_ROUNDS = 6  # repairs tried per plan before the remaining conflicts are reported
MAX_DELAY_S = 6.0  # longest wait at the start offered instead of a detour
DELAY_STEP_S = 0.25


@dataclass
class PropTrack:
    """A prop's footprint moving rigidly over time."""

    name: str
    polygon: np.ndarray  # (P, 2) convex footprint in the prop's own frame (pose 0, 0, 0)
    times: np.ndarray  # (K,) seconds from the plan's first frame, increasing
    poses: np.ndarray  # (K, 3) world x, y, yaw at those times
    _hull_cache: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.polygon = np.asarray(self.polygon, float)
        self.times = np.asarray(self.times, float)
        self.poses = np.asarray(self.poses, float)
        if self.times.ndim != 1 or self.poses.shape != (self.times.size, 3) or self.times.size < 1:
            raise ValueError(f"prop track '{self.name}': times (K,) and poses (K, 3) needed")
        if np.any(np.diff(self.times) <= 0):
            raise ValueError(f"prop track '{self.name}': times must increase")

    def pose_at(self, t: float | np.ndarray) -> np.ndarray:
        """(N, 3) poses at times ``t`` (N,): linear between samples, held before the first
        and after the last (a prop rests before and after its keyframes)."""
        t = np.atleast_1d(np.asarray(t, float))
        yaw = np.unwrap(self.poses[:, 2])
        return np.stack(
            [
                np.interp(t, self.times, self.poses[:, 0]),
                np.interp(t, self.times, self.poses[:, 1]),
                np.interp(t, self.times, yaw),
            ],
            -1,
        )

    def polygon_at(self, pose: np.ndarray) -> np.ndarray:
        """The footprint (M, 2) placed at ``pose`` (x, y, angle)."""
        c, s = np.cos(pose[2]), np.sin(pose[2])
        x, y = self.polygon[:, 0], self.polygon[:, 1]
        return np.column_stack((pose[0] + c * x - s * y, pose[1] + s * x + c * y))

    def moving(self) -> np.ndarray:
        """(K - 1,) True where the prop moves between consecutive samples (awake)."""
        if self.times.size < 2:
            return np.zeros(0, bool)
        dt = np.diff(self.times)
        reach = np.abs(self.polygon).max() if self.polygon.size else 0.0
        step = np.linalg.norm(np.diff(self.poses[:, :2], axis=0), axis=1) + reach * np.abs(
            np.diff(np.unwrap(self.poses[:, 2]))
        )
        return step / dt > STILL_SPEED

    def awake_at(self, t: float) -> bool:
        """True when the prop moves at time ``t`` (it is awake)."""
        m = self.moving()
        if m.size == 0 or t < self.times[0] or t >= self.times[-1]:
            return False
        i = int(np.searchsorted(self.times, t, side="right")) - 1
        return bool(m[min(i, m.size - 1)])

    def awake_intervals(self) -> list[tuple[float, float]]:
        """[(t0, t1)] seconds while the prop moves."""
        m = self.moving()
        out, i = [], 0
        while i < m.size:
            if m[i]:
                j = i
                while j + 1 < m.size and m[j + 1]:
                    j += 1
                out.append((float(self.times[i]), float(self.times[j + 1])))
                i = j + 1
            else:
                i += 1
        return out

    def swept(self, t0: float, t1: float, step: float = 0.1) -> list[Obstacle]:
        """Obstacles covering the footprint over times ``t0``-``t1``: the convex hull of
        the footprints at each pair of neighbouring instants (``step`` s apart, and every
        sample between), which is the area a convex footprint sweeps while it translates."""
        ts = np.concatenate(
            (np.arange(t0, t1, step), [t1], self.times[(self.times > t0) & (self.times < t1)])
        )
        ts = np.unique(ts)
        polys = [self.polygon_at(p) for p in self.pose_at(ts)]
        out = []
        for k in range(len(polys)):
            pair = polys[k] if k + 1 == len(polys) else np.vstack((polys[k], polys[k + 1]))
            if k + 1 < len(polys) and np.allclose(polys[k], polys[k + 1]):
                continue  # still: the next footprint (or the last) covers it
            out.append(Obstacle(f"{self.name}@{ts[k]:.2f}s", convex_hull(pair)))
        return out


@dataclass
class Conflict:
    prop: str
    frame: int  # frame of the planned motion (from 0) where the walk meets the prop
    piece: int  # index of the plan piece walked then
    distance: float  # metres from the character's ground point to the prop's footprint

    def describe(self, fps: float, frame_start: int = 0, scene_fps: float | None = None) -> str:
        """Where and when, in the scene's frames (``frame`` counts the motion's frames at
        ``fps`` from ``frame_start``; the scene may run at ``scene_fps``)."""
        at = frame_start + int(round(self.frame * (scene_fps or fps) / fps))
        return (
            f"'{self.prop}' meets the walk at frame {at} ({self.frame / fps:.1f} s in, "
            f"{self.distance:.2f} m from its footprint)"
        )


def piece_frames(motions: list[Motion]) -> np.ndarray:
    """(N + 1,) first frame of each piece in the concatenated motion (:func:`concatenate`
    shares each boundary frame between two pieces: it counts as the later one's), and the
    motion's frame count at the end."""
    counts = np.array([m.frames for m in motions])
    starts = np.concatenate(([0], np.cumsum(counts[:-1] - 1)))
    return np.concatenate((starts, [starts[-1] + counts[-1]]))


def conflicts(
    motions: list[Motion], tracks: list[PropTrack], radius: float, fps: float, delay: float = 0.0
) -> list[Conflict]:
    """The first frame at which the planned walk comes within ``radius`` of each moving
    prop's footprint at that moment: [Conflict], earliest first. ``delay``: seconds the
    walk starts after the tracks' time 0 (the character stands still until then)."""
    m = concatenate(motions)
    xy = m.ground[:, :2]
    t = delay + np.arange(m.frames) / fps
    bounds = piece_frames(motions)
    out = []
    for tr in tracks:
        d = _distances(xy, tr.pose_at(t), tr.polygon)
        if delay > 0:  # standing at the start meanwhile
            wait = np.arange(0.0, delay, 0.1)
            if (
                _distances(np.repeat(xy[:1], wait.size, 0), tr.pose_at(wait), tr.polygon) < radius
            ).any():
                out.append(Conflict(tr.name, 0, 0, 0.0))
                continue
        hit = np.flatnonzero(d < radius)
        if hit.size:
            f = int(hit[0])
            piece = int(np.searchsorted(bounds, f, side="right")) - 1
            out.append(Conflict(tr.name, f, min(piece, len(motions) - 1), float(d[f])))
    return sorted(out, key=lambda c: c.frame)


def _distances(xy, poses, polygon):
    """(F,) distance from each point to the footprint at the same frame's pose (0 inside)."""
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    dx, dy = xy[:, 0] - poses[:, 0], xy[:, 1] - poses[:, 1]
    local = np.column_stack((c * dx + s * dy, -s * dx + c * dy))  # into the prop's frame
    a = polygon
    b = np.roll(a, -1, axis=0)
    ab = b - a
    ap = local[:, None, :] - a[None]
    tt = np.clip((ap * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)[None], 0, 1)
    gap = ap - tt[..., None] * ab[None]
    d = np.sqrt((gap * gap).sum(-1).min(axis=1))
    cross = ab[None, :, 0] * ap[..., 1] - ab[None, :, 1] * ap[..., 0]
    inside = np.all(cross >= 0, axis=1) | np.all(cross <= 0, axis=1)
    return np.where(inside, 0.0, d)


def wait_needed(
    motions: list[Motion],
    tracks: list[PropTrack],
    radius: float,
    fps: float,
    longest: float = MAX_DELAY_S,
) -> float | None:
    """Seconds to wait at the start (``DELAY_STEP_S`` steps) after which the walk meets no
    moving prop, or None within ``longest``."""
    for d in np.arange(DELAY_STEP_S, longest + 1e-9, DELAY_STEP_S):
        if not conflicts(motions, tracks, radius, fps, float(d)):
            return float(d)
    return None


def avoid(
    planner: SegmentPlanner,
    patch: LocomotionPatch,
    plan: Plan,
    tracks: list[PropTrack],
    motions_of: Callable[[Plan], list[Motion]],
    max_rounds: int = MAX_ROUNDS,
    longest_wait: float = MAX_DELAY_S,
) -> tuple[Plan, float, list[dict], list[Conflict]]:
    """``plan`` made clear of the moving props ``tracks``: (plan, wait, repairs, unresolved).

    ``motions_of(plan)`` gives the plan's piece motions as they will be played (eased
    starts and stops included; see :func:`~.planner.plan_motions`). Each round finds the
    earliest conflict and weighs two answers: waiting at the start until the prop has
    gone by (:func:`wait_needed`, up to ``longest_wait`` seconds), and a detour: that
    prop's footprint swept from
    ``SWEEP_BEHIND_S`` before the conflict to ``SWEEP_AHEAD_S`` after (its bounds extended
    along its velocity, as the paper's local avoidance does, so the way passes behind a
    moving prop) and only the piece walked then re-planned round it, with every footprint
    swept so far as an obstacle; when that piece has no way round, the run grows a piece at
    a time up to the whole path. The answer that arrives sooner is taken (a wait ends the
    rounds: it clears every prop). ``wait``: seconds; ``repairs``: [{prop, frame, pieces,
    kept}]; ``unresolved``: the conflicts left, by prop and frame."""
    fps = patch.gait.fps
    radius = planner.world_env.radius
    repairs: list[dict] = []
    extra: list[Obstacle] = []  # every footprint swept so far
    for _ in range(max_rounds):
        motions = motions_of(plan)
        found = conflicts(motions, tracks, radius, fps)
        if not found:
            return plan, 0.0, repairs, []
        wait = wait_needed(motions, tracks, radius, fps, longest_wait) if longest_wait > 0 else None
        c = found[0]
        track = next(t for t in tracks if t.name == c.prop)
        t = c.frame / fps
        extra += track.swept(max(t - SWEEP_BEHIND_S, 0.0), t + SWEEP_AHEAD_S)
        n = len(plan.pieces)
        first = last = c.piece
        done = None
        while done is None:
            while first > 0 and plan.pieces[first].kind not in LOCOMOTION:
                first -= 1
            while last < n - 1 and plan.pieces[last].kind not in LOCOMOTION:
                last += 1
            try:
                done = planner.replan_run(plan, first, last, extra)
            except PlanError:
                if first == 0 and last == n - 1:
                    break
                first, last = max(first - 1, 0), min(last + 1, n - 1)
        if done is None:  # no way round: wait if that helps
            return (plan, wait, repairs, []) if wait is not None else (plan, 0.0, repairs, found)
        longer = (
            sum(m.frames - 1 for m in motions_of(done)) - sum(m.frames - 1 for m in motions)
        ) / fps
        if wait is not None and wait <= longer:
            return plan, wait, repairs, []
        repairs.append(
            {
                "prop": c.prop,
                "frame": c.frame,
                "pieces": [first, last],
                "kept": n - (last + 1 - first),
                "seconds_longer": float(longer),
            }
        )
        plan = done
    return plan, 0.0, repairs, conflicts(motions_of(plan), tracks, radius, fps)
