# SPDX-License-Identifier: GPL-3.0-or-later
"""Locomotion patch: the tilable square of motion segments for one layer (paper Sec. 6).

The square's side is two straight cycles; it is split into cells x cells cells and carries
``nodes`` nodes on each edge. For every entry node and heading (the inward normal and 45
degrees either side) and every exit node and heading on another edge, a cubic Hermite
curve is fitted so that following it takes a whole number of gait cycles; curves that
bend more than the gait's turns or leave the square are culled. A segment stores its
curve (its frames are synthesised on demand), its cell bitmask ``B_P`` and cost terms.
A patch too sparse to connect tiles is refused (:class:`SparsePatch`).
"""

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..kinematics import poses
from ..kinematics.motion import Motion
from ..quality.validate import segment_glitches
from . import curves
from .curves import Curve
from .gait import Gait
from .synthesis import cycles_along, follow, frame_arclengths

EDGES = 4  # 0 south (y = 0), 1 east (x = side), 2 north (y = side), 3 west (x = 0)
DIRECTIONS = 8  # headings in 45 degree steps, direction d has heading d * 45 degrees
SEGMENT_ARRAYS = (  # the per-segment fields of LocomotionPatch, in their order
    "seg_entry",
    "seg_exit",
    "seg_scale",
    "seg_cycles",
    "seg_mask",
    "seg_length",
    "seg_turn",
    "seg_effort",
    "seg_pose",
)
INWARD = np.array([2, 4, 6, 0])  # direction of each edge's inward normal
MAX_CYCLES = 4
MIN_ENTRY_SHARE = 0.5
"""Share of entry states (every node, the three inward headings) that need at least one
segment on for a bake to be kept. Straight walks with turn clips reach 92 % (CMU 16_15 +
16_18; 100 % at 4x4 cells, 4 or 3 nodes); 16_15 alone 75 % (at its 1 m bend), and 33 %
when bent to 2 m at most (or any wider radius), where a walk can go straight and turn once
but no pillar field is crossed; 8 % with the limits it had before straight clips could
bend (a 443 m radius one way, no turn the other)."""
PATH_SAMPLES = 160  # points per segment for exact footprint tests (4 cycles ~ 5.3 m)


class SparsePatch(ValueError):
    """A bake whose segments leave too many entry states without a way on."""


def node_id(
    edge: int | np.ndarray, slot: int | np.ndarray, direction: int | np.ndarray, nodes: int
) -> np.ndarray:
    return (np.asarray(edge) * nodes + np.asarray(slot)) * DIRECTIONS + np.asarray(direction)


def split_node_id(node: int | np.ndarray, nodes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    node = np.asarray(node)
    return node // (nodes * DIRECTIONS), (node // DIRECTIONS) % nodes, node % DIRECTIONS


def node_position(
    edge: int | np.ndarray, slot: int | np.ndarray, side: float, nodes: int
) -> np.ndarray:
    """Local (x, y) of node slots on edges; slots run along +x or +y."""
    edge = np.asarray(edge)
    t = (np.asarray(slot) + 0.5) * side / nodes
    x = np.select([edge == 0, edge == 1, edge == 2, edge == 3], [t, side, t, 0.0])
    y = np.select([edge == 0, edge == 1, edge == 2, edge == 3], [0.0, t, side, t])
    return np.stack((x, y), axis=-1)


@dataclass
class LocomotionPatch:
    layer: str
    gait: Gait
    side: float
    cells: int
    nodes: int
    effort_rate: float  # effort T per second of motion for this layer
    seg_entry: np.ndarray  # (S,) local node id of the entry state
    seg_exit: np.ndarray  # (S,) local node id of the exit state
    seg_scale: np.ndarray  # (S,) Hermite tangent scale
    seg_cycles: np.ndarray  # (S,) whole gait cycles
    seg_mask: np.ndarray  # (S,) uint64 cell bitmask B_P
    seg_length: np.ndarray  # (S,) metres, integral of ds
    seg_turn: np.ndarray  # (S,) radians, integral of |d theta|
    seg_effort: np.ndarray  # (S,) effort T
    seg_pose: np.ndarray  # (S, 2) pose cluster of entry and exit node
    pose_centres: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def cell_size(self) -> float:
        return self.side / self.cells

    @property
    def segment_count(self) -> int:
        return int(self.seg_entry.size)

    def endpoints(
        self, seg: int | np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """p0, d0, p1, d1 arrays of segments (local coordinates, unit directions), read off
        a table of every segment's made once (the planner asks for one segment at a time
        while it shortens a path: a tenth of a millisecond each, made afresh)."""
        table = self.__dict__.get("_endpoints")
        if table is None:
            table = self.__dict__["_endpoints"] = self._endpoints(np.arange(self.segment_count))
        p0, d0, p1, d1 = table
        return np.array(p0[seg]), np.array(d0[seg]), np.array(p1[seg]), np.array(d1[seg])

    def _endpoints(self, seg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`endpoints` computed (element by element: the same bits for any ``seg``)."""
        e0, k0, h0 = split_node_id(self.seg_entry[seg], self.nodes)
        e1, k1, h1 = split_node_id(self.seg_exit[seg], self.nodes)
        return (
            node_position(e0, k0, self.side, self.nodes),
            curves.unit(h0 * np.pi / 4),
            node_position(e1, k1, self.side, self.nodes),
            curves.unit(h1 * np.pi / 4),
        )

    def curve(self, seg: int) -> Curve:
        p0, d0, p1, d1 = self.endpoints(np.array([seg]))
        return curves.hermite_curve(p0[0], d0[0], p1[0], d1[0], self.seg_scale[seg])

    def curves(self, segs: np.ndarray) -> list[Curve]:
        """:meth:`curve` of many segments, sampled together."""
        p0, d0, p1, d1 = self.endpoints(np.asarray(segs))
        return curves.hermite_curves(p0, d0, p1, d1, self.seg_scale[segs])

    def motion(self, seg: int, poses: bool = True, at: int | None = None) -> Motion:
        """Synthesised in-place motion of one segment, in patch coordinates (``poses``
        False: ground and root only; ``at``: that frame alone; :func:`follow`)."""
        cycles = int(self.seg_cycles[seg])
        return follow(self.gait, self.curve(seg), cycles=cycles, poses=poses, at=at)

    def all_ground(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every segment's ground frames stacked (T, 3), arc lengths (T,), and each
        segment's first row (S + 1,): one array to search when stitching (cached)."""
        cache = self.__dict__.get("_all_ground")
        if cache is None:
            done = self.__dict__.setdefault("_ground_cache", {})
            todo = [s for s in range(self.segment_count) if s not in done]
            for seg, c in zip(todo, self.curves(np.array(todo, int)) if todo else ()):
                self.ground(seg, c)
            parts = [self.ground(s) for s in range(self.segment_count)]
            start = np.concatenate(([0], np.cumsum([p[0].shape[0] for p in parts])))
            cache = (
                np.concatenate([p[0] for p in parts]),
                np.concatenate([p[1] for p in parts]),
                start,
            )
            self.__dict__["_all_ground"] = cache
        return cache

    def path_points(self) -> np.ndarray:
        """(S, PATH_SAMPLES, 2) points along every segment's curve, patch coordinates, at
        most about 4 cm apart: what the planner tests exactly against footprints when a
        segment crosses cells only partly occluded (cached)."""
        pts = self.__dict__.get("_path_points")
        if pts is None:
            p0, d0, p1, d1 = self.endpoints(np.arange(self.segment_count))
            pts, _, _ = curves.hermite(
                p0, d0, p1, d1, self.seg_scale, np.linspace(0.0, 1.0, PATH_SAMPLES)
            )
            pts = self.__dict__["_path_points"] = np.ascontiguousarray(pts)
        return pts

    def ground(self, seg: int, curve: Curve | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(F, 3) ground frames of a segment (patch coordinates) and (F,) arc lengths,
        without synthesising poses; cached, as stitching looks at many segments
        (``curve``: the segment's curve, when the caller has it)."""
        cache = self.__dict__.setdefault("_ground_cache", {})
        g = cache.get(seg)
        if g is None:
            c = self.curve(seg) if curve is None else curve
            _, s, _ = frame_arclengths(self.gait, c, int(self.seg_cycles[seg]))
            x, y, h, _ = c.at(s)
            g = cache[seg] = (np.column_stack((x, y, h)), s)
        return g

    def without(self, segments: Iterable[int]) -> "LocomotionPatch":
        """The patch with the given segments removed (caches dropped)."""
        keep = np.setdiff1d(np.arange(self.segment_count), np.asarray(segments, int))
        arrays = {name: getattr(self, name)[keep] for name in SEGMENT_ARRAYS}
        return LocomotionPatch(
            self.layer,
            self.gait,
            self.side,
            self.cells,
            self.nodes,
            self.effort_rate,
            pose_centres=self.pose_centres,
            stats=self.stats,
            **arrays,
        )

    def costs(self, alpha: float, beta: float, gamma: float) -> np.ndarray:
        """Eq. 5 cost of every segment for the weights of one character."""
        return alpha * self.seg_length + beta * self.seg_turn + gamma * self.seg_effort

    def by_entry(self) -> tuple[np.ndarray, np.ndarray]:
        """CSR index: segments of entry state e are order[start[e]:start[e + 1]]."""
        n = EDGES * self.nodes * DIRECTIONS
        order = np.argsort(self.seg_entry, kind="stable")
        start = np.searchsorted(self.seg_entry[order], np.arange(n + 1))
        return order, start


def cell_mask(points: np.ndarray, side: float, cells: int) -> np.ndarray:
    """uint64 bitmask of the cells of a square of ``side`` that points (..., M, 2) visit."""
    c = side / cells
    ix = np.clip(np.floor(points[..., 0] / c).astype(np.int64), 0, cells - 1)
    iy = np.clip(np.floor(points[..., 1] / c).astype(np.int64), 0, cells - 1)
    bits = np.left_shift(np.uint64(1), (iy * cells + ix).astype(np.uint64))
    return np.bitwise_or.reduce(bits, axis=-1)


def candidate_states(nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """All (entry id, exit id) pairs: entries point inward, exits outward, other edges."""
    entry_list, exit_list = [], []
    for e in range(EDGES):
        for k in range(nodes):
            for dd in (-1, 0, 1):
                entry_list.append((e, k, (INWARD[e] + dd) % DIRECTIONS))
                exit_list.append((e, k, (INWARD[e] + 4 + dd) % DIRECTIONS))
    entries, exits = np.array(entry_list), np.array(exit_list)
    ei, xi = np.meshgrid(np.arange(len(entries)), np.arange(len(exits)), indexing="ij")
    ei, xi = ei.ravel(), xi.ravel()
    keep = entries[ei, 0] != exits[xi, 0]
    return entries[ei[keep]], exits[xi[keep]]


def bake(
    gait: Gait,
    cells: int = 8,
    nodes: int = 8,
    side: float | None = None,
    effort_rate: float = 1.0,
    curvature_margin: float = 1.0,
    progress: Callable[[float], object] | None = None,
) -> LocomotionPatch:
    """Bake the locomotion patch of a gait; ``progress(fraction)`` is called as it goes."""
    if cells * cells > 64:
        raise ValueError(f"{cells}x{cells} cells do not fit a 64-bit cell bitmask")
    side = float(side or 2.0 * gait.cycle_distance)
    entries, exits = candidate_states(nodes)
    p0 = node_position(entries[:, 0], entries[:, 1], side, nodes)
    p1 = node_position(exits[:, 0], exits[:, 1], side, nodes)
    d0 = curves.unit(entries[:, 2] * np.pi / 4)
    d1 = curves.unit(exits[:, 2] * np.pi / 4)
    kmin, kmax = gait.kappa_limits
    kmin, kmax = kmin * curvature_margin, kmax * curvature_margin
    ncand = p0.shape[0]
    scale = np.full(ncand, np.nan)
    cycles = np.zeros(ncand, int)
    reason = np.full(ncand, "no fit", dtype=object)

    def measure(pos, vel, acc, kappa=None):
        return cycles_along(gait, pos, vel, acc, kappa=kappa)

    u = np.linspace(0.0, 1.0, 257)
    table = curves.tabulate(p0, d0, p1, d1, measure, shares_curvature=True)
    if progress:
        progress(0.4)
    for n in range(1, MAX_CYCLES + 1):
        todo = np.flatnonzero(np.isnan(scale))
        if todo.size == 0:
            break
        sc = curves.fit_scale(
            p0[todo],
            d0[todo],
            p1[todo],
            d1[todo],
            float(n),
            measure=measure,
            table=(table[0][todo], table[1][todo]),
        )
        fitted = ~np.isnan(sc)
        idx, sc = todo[fitted], sc[fitted]
        if idx.size:
            pos, vel, acc = curves.hermite(p0[idx], d0[idx], p1[idx], d1[idx], sc, u)
            kap = curves.curvature(vel, acc)
            bends = (
                (kap.min(axis=1) < kmin)
                | (kap.max(axis=1) > kmax)
                | ~curves.follows_turn_limits(pos, vel, kmin, kmax)
            )
            eps = 1e-6
            outside = np.any((pos < -eps) | (pos > side + eps), axis=(1, 2))
            good = ~bends & ~outside
            reason[idx[bends]] = "curvature"
            reason[idx[outside & ~bends]] = "outside"
            scale[idx[good]] = sc[good]
            cycles[idx[good]] = n
        if progress:
            progress(0.4 + n / MAX_CYCLES * 0.5)

    keep = np.flatnonzero(~np.isnan(scale))
    pos, vel, acc = curves.hermite(p0[keep], d0[keep], p1[keep], d1[keep], scale[keep], u)
    seg_length = curves.arc_lengths(pos)[:, -1]
    heading = np.unwrap(np.arctan2(vel[..., 1], vel[..., 0]), axis=1)
    seg_turn = np.abs(np.diff(heading, axis=1)).sum(axis=1)
    seg_mask = cell_mask(pos, side, cells)
    frames = cycles[keep] * gait.frames
    seg_effort = effort_rate * frames / gait.fps

    # Pose clusters over the node poses the loops offer; each segment's first and last
    # synthesised frame is then labelled with its nearest cluster.
    phase0 = np.zeros(len(gait.loops), int)
    feats = poses.pose_features(
        np.stack([lp.root_local[0] for lp in gait.loops]),
        np.stack([lp.rotations[0] for lp in gait.loops]),
    )
    centres, _ = poses.cluster_until(feats, max_spread=0.5)
    straight_end = gait.pose(phase0[:1], gait.straight_weights(1))
    end_label = poses.nearest(centres, poses.pose_features(straight_end[0], straight_end[1]))[0]
    seg_pose = np.full((keep.size, 2), end_label, int)

    culled = {
        r: int(np.sum(reason[np.isnan(scale)] == r)) for r in ("curvature", "outside", "no fit")
    }
    stats: dict[str, Any] = {
        "candidates": int(ncand),
        "kept": int(keep.size),
        "culled": int(ncand - keep.size),
        "culled_by": culled,
        "pose_clusters": int(centres.shape[0]),
        "cycles_histogram": {
            int(n): int(np.sum(cycles[keep] == n)) for n in range(1, MAX_CYCLES + 1)
        },
        "curvature_limits": [kmin, kmax],
    }
    patch = LocomotionPatch(
        gait.layer,
        gait,
        side,
        cells,
        nodes,
        float(effort_rate),
        node_id(entries[keep, 0], entries[keep, 1], entries[keep, 2], nodes),
        node_id(exits[keep, 0], exits[keep, 1], exits[keep, 2], nodes),
        scale[keep],
        cycles[keep],
        seg_mask,
        seg_length,
        seg_turn,
        seg_effort,
        seg_pose,
        centres,
        stats,
    )
    # The validator looks at every kept segment's frames: a spin, a backward step or a
    # jump the curve checks missed is culled here rather than played.

    bad = segment_glitches(patch)
    culled["glitch"] = len(bad)
    if bad:
        patch = patch.without(bad)
        stats.update(kept=patch.segment_count, culled=int(ncand - patch.segment_count))
    stats["entry_share"] = entry_share(patch)
    if stats["entry_share"] < MIN_ENTRY_SHARE:
        raise SparsePatch(sparse_message(patch))
    if progress:
        progress(1.0)
    return patch


def entry_share(patch: LocomotionPatch) -> float:
    """Share of the patch's entry states (every node, its three inward headings) that at
    least one segment leaves from: where a walk entering the tile there can go on."""
    return float(np.unique(patch.seg_entry).size / (EDGES * patch.nodes * 3))


def sparse_message(patch: LocomotionPatch) -> str:
    """Why a bake is refused as too sparse (from its ``stats``), and what to add."""
    stats = patch.stats
    by = stats["culled_by"]
    kmin, kmax = stats["curvature_limits"]
    radius = 1.0 / max(min(-kmin, kmax), 1e-9)
    why = [f"{by['curvature']:,} bend tighter than the gait turns (radius {radius:.2f} m)"]
    why += [
        f"{by[k]:,} {what}"
        for k, what in (
            ("no fit", "fit no whole number of cycles"),
            ("outside", "leave the patch"),
            ("glitch", "spin, step back or jump"),
        )
        if by.get(k)
    ]
    return (
        f"the patch is too sparse to plan with: only {stats['entry_share']:.0%} of entry "
        f"states have a way on (at least {MIN_ENTRY_SHARE:.0%} are needed). Of "
        f"{stats['candidates']:,} candidate segments {stats['kept']:,} are kept; "
        f"{', '.join(why)}. Add a turn clip (a walk turning left or right) so segments "
        f"can bend tighter" + (", or bake with more nodes per edge" if patch.nodes < 4 else "")
    )
