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

from . import poses
from .environment import distance_to_polygon
from .node_keys import next_entry, pack

POSITION_TOLERANCE = 0.2            # metres between the segment frame and the keyframe
HEADING_TOLERANCE = np.radians(20)  # radians
POSE_TOLERANCE = 1.5                # times the best phase's pose distance (relative)
BLEND_FRAMES = 8                    # frames eased across each stitch
CLIP_CLEARANCE = 0.15               # metres kept from other props along the clip's own path
MAX_PER_END = 12                    # cheapest connections kept at each keyframe


@dataclass
class Connection:
    """A segment cut at a frame: the walk into a clip's entry or out of its exit."""
    tile: tuple
    segment: int
    frame: int
    error: float
    cost: float          # Eq. 5 cost of the used part


@dataclass
class Stitch:
    prop: str
    clip_index: int
    entry: Connection
    exit: Connection
    cost: float          # whole edge: entry part + clip + exit part
    from_key: int
    to_key: int


def phase_pose_distance(gait, motion_frame_root, motion_frame_rot):
    """(N,) pose distance of every phase of the straight loop to one pose."""
    lp = gait.straight
    f = poses.pose_features(lp.root_local, lp.rotations)
    t = poses.pose_features(motion_frame_root[None], motion_frame_rot[None])[0]
    return np.sqrt(((f - t) ** 2).sum(axis=1))


def _candidates(patch, env, state, phase_ok, exclude, at_entry, alpha, beta, gamma):
    """Segments crossing the keyframe's cell with a frame close to ``state``."""
    tile = env.tile_of(state[:2])
    origin = np.array(tile, float) * patch.side
    local = state[:2] - origin
    c = patch.cell_size
    cell = int(np.clip(local[1] // c, 0, patch.cells - 1) * patch.cells
               + np.clip(local[0] // c, 0, patch.cells - 1))
    bit = np.uint64(1) << np.uint64(cell)
    segs = np.flatnonzero((patch.seg_mask & bit) != 0)
    if segs.size == 0:
        return []
    ground, arc, first = patch.all_ground()
    lens = first[segs + 1] - first[segs]
    rows = np.repeat(first[segs] - np.concatenate(([0], np.cumsum(lens)[:-1])), lens) + np.arange(lens.sum())
    d = np.linalg.norm(ground[rows, :2] - local, axis=1)
    offs = np.concatenate(([0], np.cumsum(lens)[:-1]))
    best = np.minimum.reduceat(d, offs)
    # first index of the minimum within each segment's run
    is_min = d == np.repeat(best, lens)
    idx = np.flatnonzero(is_min)
    owner = np.searchsorted(offs, idx, side="right") - 1
    firsts = np.full(segs.size, -1)
    for o, i in zip(owner[::-1], idx[::-1]):
        firsts[o] = i
    f = firsts - offs                      # frame within the segment
    gr = ground[rows[firsts]]
    dh = np.abs((gr[:, 2] - state[2] + np.pi) % (2 * np.pi) - np.pi)
    n = patch.gait.frames
    ok = ((f >= 2) & (f <= lens - 3) & (best <= POSITION_TOLERANCE) & (dh <= HEADING_TOLERANCE)
          & phase_ok[f % n])
    out = []
    for k in np.flatnonzero(ok):
        seg, fk = int(segs[k]), int(f[k])
        g, s = patch.ground(seg)
        used = g[:fk + 1] if at_entry else g[fk:]
        if env.blocked(used[::2, :2] + origin, exclude=(exclude,)).any():
            continue
        length = s[fk] if at_entry else s[-1] - s[fk]
        turn = float(np.abs(np.diff(used[:, 2])).sum())
        frames = fk if at_entry else g.shape[0] - 1 - fk
        effort = patch.effort_rate * frames / patch.gait.fps
        # The eased stitch walks the position gap and turns the heading gap: pay for both,
        # which also keeps the A* heuristic consistent across stitched edges.
        cost = alpha * (length + best[k]) + beta * (turn + dh[k]) + gamma * effort
        err = best[k] / POSITION_TOLERANCE + dh[k] / HEADING_TOLERANCE
        out.append(Connection(tile, seg, fk, float(err), float(cost)))
    out.sort(key=lambda cn: cn.cost)
    return out[:MAX_PER_END]


def stitch(patch, env, prop, clip_index, alpha, beta, gamma):
    """Every edge a traversal copy adds to the low-level graph (maybe none)."""
    clip = prop.clips[clip_index]
    world = prop.world_clip(clip)
    others = [env.obstacles[n] for n in env.obstacles if n != prop.name]
    if any(np.any(distance_to_polygon(world.ground[:, :2], o.polygon) < CLIP_CLEARANCE)
           for o in others if _near(o, world.ground[:, :2])):
        return []  # another prop stands in the way of the jump itself
    gait = patch.gait
    d_in = phase_pose_distance(gait, clip.motion.root_local[0], clip.motion.rotations[0])
    d_out = phase_pose_distance(gait, clip.motion.root_local[-1], clip.motion.rotations[-1])
    ins = _candidates(patch, env, world.ground[0], d_in <= POSE_TOLERANCE * d_in.min(),
                      prop.name, True, alpha, beta, gamma)
    if not ins:
        return []
    outs = _candidates(patch, env, world.ground[-1], d_out <= POSE_TOLERANCE * d_out.min(),
                       prop.name, False, alpha, beta, gamma)
    clip_cost = alpha * clip.length() + beta * clip.turn() + gamma * clip.effort
    result = []
    for a in ins:
        from_key = int(pack(a.tile[0], a.tile[1], patch.seg_entry[a.segment]))
        for b in outs:
            i, j, local = next_entry(patch, b.tile, b.segment)
            to_key = int(pack(i, j, local))
            result.append(Stitch(prop.name, clip_index, a, b, a.cost + clip_cost + b.cost,
                                 from_key, to_key))
    return result


def _near(obstacle, points, margin=1.0):
    lo, hi = obstacle.bounds()
    return bool(np.all(points.min(axis=0) < hi + margin) and np.all(points.max(axis=0) > lo - margin))
