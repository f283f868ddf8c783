# SPDX-License-Identifier: GPL-3.0-or-later
"""Stitching a traversal clip of an object patch into the tiled locomotion (Sec. 4.3).

The clip's first keyframe (position, heading, pose) indexes one cell of the tile under
it; every segment through that cell is tested frame by frame for the error against the
keyframe, and those under the thresholds become entry connections (walk the segment up
to that frame, then the clip). The last keyframe gives exit connections the same way
(join a segment at that frame and walk on to its exit node). Each entry x exit pair is a
new edge of the low-level graph, from the entry segment's entry node to the exit
segment's exit node. The used parts are checked exactly against the footprints (grown by
the character's radius) with the traversed prop left out, where the paper applies an
extra mask to Eq. 8: with 0.33 m cells the bitmask would reject take-offs that are
physically clear (a line of chairs 0.5 m apart occludes every cell next to the line).
"""

from dataclasses import dataclass

import numpy as np

from ..kinematics import poses
from ..patch.gait import Gait
from ..patch.locomotion_patch import LocomotionPatch, node_id, split_node_id
from ..patch.node_keys import NEXT_EDGE, TILE_STEP, pack
from ..props.environment import Environment
from ..props.object_patch import ObjectPatch

POSITION_TOLERANCE = 0.2  # metres between the segment frame and the keyframe
HEADING_TOLERANCE = np.radians(20)  # radians
POSE_TOLERANCE = 1.5  # times the best phase's pose distance (relative)
BLEND_FRAMES = 8  # frames eased across each stitch
CLIP_CLEARANCE = 0.15  # metres kept from other props along the clip's own path
MAX_PER_END = 12  # cheapest connections kept at each keyframe


@dataclass
class Connection:
    """A segment cut at a frame: the walk into a clip's entry or out of its exit."""

    tile: tuple
    segment: int
    frame: int
    error: float
    cost: float  # Eq. 5 cost of the used part


@dataclass
class Stitch:
    prop: str
    clip_index: int
    entry: Connection
    exit: Connection
    cost: float  # whole edge: entry part + clip + exit part
    from_key: int
    to_key: int


def phase_pose_distance(
    gait: Gait, motion_frame_root: np.ndarray, motion_frame_rot: np.ndarray
) -> np.ndarray:
    """(N,) pose distance of every phase of the straight loop to one pose (remembered per
    loop and pose: every copy of a clip has the same keyframe poses)."""
    lp = gait.straight
    memo = lp.__dict__.setdefault("_pose_distances", {})
    key = (np.asarray(motion_frame_root).tobytes(), np.asarray(motion_frame_rot).tobytes())
    got = memo.get(key)
    if got is None:
        f = lp.pose_features()
        t = poses.pose_features(motion_frame_root[None], motion_frame_rot[None])[0]
        got = memo[key] = np.sqrt(((f - t) ** 2).sum(axis=1))
    return got


def _cell_frames(patch):
    """Per cell of the patch, the rows of ``patch.all_ground()`` (ascending) whose frame
    lies within ``POSITION_TOLERANCE`` of the cell, and the segment of each row (cached
    on the patch): a keyframe in the cell can only be matched by these frames."""
    got = patch.__dict__.get("_stitch_cells")
    if got is None:
        ground, _, first = patch.all_ground()
        owner = np.repeat(np.arange(first.size - 1), np.diff(first))
        c, n = patch.cell_size, patch.cells
        lo = np.clip(np.floor((ground[:, :2] - POSITION_TOLERANCE) / c), 0, n - 1).astype(int)
        hi = np.clip(np.floor((ground[:, :2] + POSITION_TOLERANCE) / c), 0, n - 1).astype(int)
        cells, rows = [], []
        for dy in range(3):
            for dx in range(3):
                cx, cy = lo[:, 0] + dx, lo[:, 1] + dy
                ok = np.flatnonzero((cx <= hi[:, 0]) & (cy <= hi[:, 1]))
                cells.append(cy[ok] * n + cx[ok])
                rows.append(ok)
        cells, rows = np.concatenate(cells), np.concatenate(rows)
        order = np.lexsort((rows, cells))
        cells, rows = cells[order], rows[order]
        start = np.searchsorted(cells, np.arange(n * n + 1))
        got = patch.__dict__["_stitch_cells"] = [
            (rows[a:b], owner[rows[a:b]]) for a, b in zip(start[:-1], start[1:])
        ]
    return got


def _cell_rows(patch, cell):
    """The rows of :func:`_cell_frames` of segments through ``cell`` (its bit set in
    their cell masks), their segments, their frames' x and y, and the runs of rows of
    one segment: where each starts, its segment and the segment's frame count (cached
    per patch and cell: every copy whose keyframe falls in the cell reads the same);
    per row, its run and its place."""
    memo = patch.__dict__.setdefault("_stitch_cell_rows", {})
    got = memo.get(cell)
    if got is None:
        rows, owner = _cell_frames(patch)[cell]
        keep = (patch.seg_mask[owner] & (np.uint64(1) << np.uint64(cell))) != 0
        rows, owner = rows[keep], owner[keep]
        ground, _, first = patch.all_ground()
        offs = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]]) if rows.size else rows
        segs = owner[offs]
        got = memo[cell] = (
            rows,
            ground[rows, 0].copy(),
            ground[rows, 1].copy(),
            offs,
            segs,
            first[segs + 1] - first[segs],
            np.repeat(np.arange(offs.size), np.diff(np.r_[offs, rows.size])),
            np.arange(rows.size),
        )
    return got


def _candidates(patch, env, state, phase_ok, exclude, at_entry, alpha, beta, gamma):
    """Segments crossing the keyframe's cell with a frame close to ``state``: of each the
    frame nearest the keyframe (the first, of equally near ones), kept when it is within
    the position, heading and pose tolerances."""
    tile = env.tile_of(state[:2])
    origin = np.array(tile, float) * patch.side
    local = state[:2] - origin
    c, n_cells = patch.cell_size, patch.cells
    cx = min(max(int(local[0] // c), 0), n_cells - 1)
    cy = min(max(int(local[1] // c), 0), n_cells - 1)
    ground, arc, first = patch.all_ground()
    # Only the frames near the cell can lie within the tolerance of the keyframe, so the
    # nearest frame of a segment crossing the cell is among them whenever it matters.
    rows, gx, gy, offs, segs, lens, run, at = _cell_rows(patch, cy * n_cells + cx)
    if rows.size == 0:
        return []
    dx, dy = gx - local[0], gy - local[1]
    d2 = dx * dx + dy * dy  # squared: the same nearest frames, without a root per row
    near = np.minimum.reduceat(d2, offs)
    # the first row of each segment's run where its minimum is
    firsts = np.minimum.reduceat(np.where(d2 == near[run], at, d2.size), offs)
    best = np.hypot(dx[firsts], dy[firsts])
    f = rows[firsts] - first[segs]  # frame within the segment
    gr = ground[rows[firsts]]
    dh = np.abs((gr[:, 2] - state[2] + np.pi) % (2 * np.pi) - np.pi)
    n = patch.gait.frames
    ok = (
        (f >= 2)
        & (f <= lens - 3)
        & (best <= POSITION_TOLERANCE)
        & (dh <= HEADING_TOLERANCE)
        & phase_ok[f % n]
    )
    ks = np.flatnonzero(ok)
    if ks.size == 0:
        return []
    seg, fk, start = segs[ks], f[ks], first[segs[ks]]
    end = first[seg + 1] - 1  # last row of each segment
    lo, hi = (start, start + fk) if at_entry else (start + fk, end)  # the used rows
    length = arc[hi] - arc[lo]
    turn = _turned(patch)[hi] - _turned(patch)[lo]
    frames = hi - lo
    effort = patch.effort_rate * frames / patch.gait.fps
    # The eased stitch walks the position gap and turns the heading gap: pay for both,
    # which also keeps the A* heuristic consistent across stitched edges.
    cost = alpha * (length + best[ks]) + beta * (turn + dh[ks]) + gamma * effort
    err = best[ks] / POSITION_TOLERANCE + dh[ks] / HEADING_TOLERANCE
    # The cheapest MAX_PER_END connections whose used parts (every other frame) keep the
    # radius from the other props are kept: the parts are tested cheapest first, a few
    # more than are still wanted at a time, until enough are clear (most never are).
    order = np.argsort(cost, kind="stable")
    keep, done = [], 0
    while len(keep) < MAX_PER_END and done < order.size:
        want = MAX_PER_END - len(keep)
        batch = order[done : done + want + want // 2 + 2]
        done += batch.size
        b_lo, b_hi = lo[batch], hi[batch]
        counts = (b_hi - b_lo) // 2 + 1
        owner = np.repeat(np.arange(batch.size), counts)
        starts = np.cumsum(counts) - counts
        tested = b_lo[owner] + 2 * (np.arange(counts.sum()) - starts[owner])
        hit = env.blocked(ground[tested, :2] + origin, exclude=(exclude,))
        keep += batch[~np.logical_or.reduceat(hit, starts)].tolist()
    keep = keep[:MAX_PER_END]
    return [Connection(tile, int(seg[k]), int(fk[k]), float(err[k]), float(cost[k])) for k in keep]


def _turned(patch):
    """(T,) radians turned along ``patch.all_ground()`` from each segment's first frame
    to each row (cached on the patch): the turn between two frames of a segment is a
    difference."""
    got = patch.__dict__.get("_stitch_turned")
    if got is None:
        ground, _, first = patch.all_ground()
        step = np.abs(np.diff(ground[:, 2]))
        step[first[1:-1] - 1] = 0.0  # from one segment's last frame to the next's first
        total = np.concatenate(([0.0], np.cumsum(step)))
        got = patch.__dict__["_stitch_turned"] = total
    return got


def part_speed(patch: LocomotionPatch) -> float:
    """The fastest average speed (m/s) of any part a connection can use: a segment from
    its first frame to a later one, or from a frame to its last, at least 2 frames apart
    (cached on the patch). Parts of a cycle can walk faster than the gait's cycles on
    average, so bounds of a part's effort divide its length by this."""
    got = patch.__dict__.get("_stitch_part_speed")
    if got is None:
        _, arc, first = patch.all_ground()
        owner = np.repeat(np.arange(first.size - 1), np.diff(first))
        rows = np.arange(arc.size)
        into = rows - first[owner]  # frames from the segment's first frame
        out = first[owner + 1] - 1 - rows  # frames to its last
        speed = 0.0
        for frames, length in (
            (into, arc - arc[first[owner]]),
            (out, arc[first[owner + 1] - 1] - arc),
        ):
            ok = frames >= 2
            if ok.any():
                speed = max(speed, float((length[ok] / frames[ok]).max()))
        got = patch.__dict__["_stitch_part_speed"] = speed * patch.gait.fps
    return got


def stitch(
    patch: LocomotionPatch,
    env: Environment,
    prop: ObjectPatch,
    clip_index: int,
    alpha: float,
    beta: float,
    gamma: float,
) -> list[Stitch]:
    """Every edge a traversal copy adds to the low-level graph (maybe none)."""
    table = stitch_table(patch, env, prop, clip_index, alpha, beta, gamma)
    if table is None:
        return []
    ins, outs, from_keys, to_keys, clip_cost = table
    return [
        Stitch(prop.name, clip_index, a, b, a.cost + clip_cost + b.cost, from_key, to_key)
        for a, from_key in zip(ins, from_keys)
        for b, to_key in zip(outs, to_keys)
    ]


def stitch_table(
    patch: LocomotionPatch,
    env: Environment,
    prop: ObjectPatch,
    clip_index: int,
    alpha: float,
    beta: float,
    gamma: float,
) -> tuple[list[Connection], list[Connection], list[int], list[int], float] | None:
    """The edges of :func:`stitch` as a table, or None when there are none: (entry
    connections, exit connections, their node keys (lists), the clip's Eq. 5 cost). Edge
    (a, b) runs from ``from_keys[a]`` to ``to_keys[b]`` and costs ``ins[a].cost +
    clip_cost + outs[b].cost`` (the planner makes :class:`Stitch` objects only of the
    edges its path takes)."""
    clip = prop.clips[clip_index]
    world = prop.world_clip(clip)
    if env.blocked(world.ground[:, :2], exclude=(prop.name,), radius=CLIP_CLEARANCE).any():
        return None  # another prop stands in the way of the jump itself
    gait = patch.gait
    d_in = phase_pose_distance(gait, clip.motion.root_local[0], clip.motion.rotations[0])
    d_out = phase_pose_distance(gait, clip.motion.root_local[-1], clip.motion.rotations[-1])
    ins = _candidates(
        patch,
        env,
        world.ground[0],
        d_in <= POSE_TOLERANCE * d_in.min(),
        prop.name,
        True,
        alpha,
        beta,
        gamma,
    )
    if not ins:
        return None
    outs = _candidates(
        patch,
        env,
        world.ground[-1],
        d_out <= POSE_TOLERANCE * d_out.min(),
        prop.name,
        False,
        alpha,
        beta,
        gamma,
    )
    if not outs:
        return None
    clip_cost = alpha * clip.length() + beta * clip.turn() + gamma * clip.effort
    return ins, outs, _from_keys(patch, ins), _to_keys(patch, outs), clip_cost


def _from_keys(patch, conns):
    """Node keys (a list) of the entry nodes of the connections' segments (one tile)."""
    tile = conns[0].tile
    segs = np.array([c.segment for c in conns])
    return pack(tile[0], tile[1], patch.seg_entry[segs]).tolist()


def _to_keys(patch, conns):
    """Node keys (a list) of the nodes the connections' segments lead to (one tile):
    :func:`.node_keys.next_entry` of each, at once."""
    tile = conns[0].tile
    segs = np.array([c.segment for c in conns])
    e1, k1, h1 = split_node_id(patch.seg_exit[segs], patch.nodes)
    step = TILE_STEP[e1]
    local = node_id(NEXT_EDGE[e1], k1, h1, patch.nodes)
    return pack(tile[0] + step[:, 0], tile[1] + step[:, 1], local).tolist()
