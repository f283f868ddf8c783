# SPDX-License-Identifier: GPL-3.0-or-later
"""The plan frame: the tile lattice of one plan, anchored at the start and turned to the goal.

Tiles own no precomputed data (occlusion is lazy, Sec. 4.2), so nothing ties the lattice
to the world's origin. Each plan lays it so that the start sits in the middle of a tile on
a row of nodes and the lattice's +x axis points at the goal: walking straight to the goal
is then a line of straight segments through node slots, not a zig-zag between 45-degree
lattice headings, and the lattice no longer depends on where the scene's origin happens
to be. The planner works in these local coordinates (obstacles and props are moved into
them); every planned piece carries the frame that takes it back to the world.
"""

import math
from dataclasses import replace

import numpy as np

from ..props.environment import Environment, Obstacle
from ..props.object_patch import ObjectPatch

IDENTITY = (0.0, 0.0, 0.0)  # (x, y, angle): local -> world is rotate by angle, then shift


def lattice_frame(
    start: np.ndarray, goal: np.ndarray, side: float, nodes: int
) -> tuple[float, float, float]:
    """(x, y, angle) of the plan frame: +x along start -> goal (the start heading when the
    two coincide), the start at the middle of tile (0, 0) on the middle row of nodes."""
    d = np.asarray(goal[:2], float) - np.asarray(start[:2], float)
    angle = float(np.arctan2(d[1], d[0])) if np.hypot(*d) > 1e-6 else float(start[2])
    anchor = np.array([0.5 * side, (nodes // 2 + 0.5) * side / nodes])
    c, s = np.cos(angle), np.sin(angle)
    origin = np.asarray(start[:2], float) - np.array(
        [c * anchor[0] - s * anchor[1], s * anchor[0] + c * anchor[1]]
    )
    return (float(origin[0]), float(origin[1]), angle)


def to_local(frame: tuple[float, float, float], xy: np.ndarray) -> np.ndarray:
    """World points (..., 2) in the plan frame."""
    x, y, a = frame
    p = np.asarray(xy, float) - np.array([x, y])
    c, s = np.cos(a), np.sin(a)
    return np.stack((c * p[..., 0] + s * p[..., 1], -s * p[..., 0] + c * p[..., 1]), axis=-1)


def to_world(frame: tuple[float, float, float], xy: np.ndarray) -> np.ndarray:
    """Plan-frame points (..., 2) in the world."""
    x, y, a = frame
    p = np.asarray(xy, float)
    c, s = np.cos(a), np.sin(a)
    return np.stack((c * p[..., 0] - s * p[..., 1] + x, s * p[..., 0] + c * p[..., 1] + y), axis=-1)


def state_to_local(frame: tuple[float, float, float], state: np.ndarray) -> np.ndarray:
    """(x, y, heading) in the plan frame (a NaN heading, "any facing", stays NaN)."""
    p = to_local(frame, np.asarray(state[:2], float))
    return np.array([p[0], p[1], state[2] - frame[2]])


def plan_region(
    start: np.ndarray,
    goal: np.ndarray,
    side: float,
    nodes: int,
    margin_tiles: int,
    tile_side: float | None = None,
) -> tuple[tuple[float, float, float], np.ndarray, np.ndarray, tuple[int, int, int, int]]:
    """(frame, local start, local goal, region): the plan frame of ``start`` -> ``goal`` (a
    patch of ``side`` metres and ``nodes`` per side) and the tiles (i0, j0, i1, j1,
    inclusive, local, ``tile_side`` wide: the environment's, by default the patch's) a plan
    searches: those of its ends and ``margin_tiles`` round them."""
    frame = lattice_frame(start, goal, side, nodes)
    ls, lg = state_to_local(frame, start), state_to_local(frame, goal)
    t = side if tile_side is None else tile_side
    ts = (math.floor(float(ls[0]) / t), math.floor(float(ls[1]) / t))
    tg = (math.floor(float(lg[0]) / t), math.floor(float(lg[1]) / t))
    region = (
        min(ts[0], tg[0]) - margin_tiles,
        min(ts[1], tg[1]) - margin_tiles,
        max(ts[0], tg[0]) + margin_tiles,
        max(ts[1], tg[1]) + margin_tiles,
    )
    return frame, ls, lg, region


def region_box(
    frame: tuple[float, float, float], lo: tuple, hi: tuple, pad: float
) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) world box round the local box ``lo``-``hi``, ``pad`` metres wider: where the
    obstacles a plan in that box sees are looked up (:func:`local_environment`)."""
    corners = to_world(
        frame, np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]], float)
    )
    return corners.min(axis=0) - pad, corners.max(axis=0) + pad


def local_environment(
    env: Environment, frame: tuple[float, float, float], lo: tuple, hi: tuple
) -> Environment:
    """An environment in the plan frame holding the obstacles of ``env`` that come within
    its radius of the local box ``lo``-``hi`` (found through ``env``'s tile membership, so a
    scene of many props costs only the ones near the plan)."""
    wlo, whi = region_box(frame, lo, hi, env.radius)
    out = Environment(env.side, env.cells, env.radius)
    names = list(env.names_in_box(wlo, whi))
    if not names:
        return out
    # Every footprint moved in one transform, then split back obstacle by obstacle.
    polygons = [env.obstacles[name].polygon for name in names]
    ends = np.cumsum([p.shape[0] for p in polygons])[:-1]
    for name, polygon in zip(names, np.split(to_local(frame, np.concatenate(polygons)), ends)):
        out.place(Obstacle(name, polygon))
    return out


def local_prop(prop: ObjectPatch, frame: tuple[float, float, float]) -> ObjectPatch:
    """An object patch moved into the plan frame (its own clips and footprint unchanged)."""
    x, y, h = prop.pose
    p = to_local(frame, np.array([x, y]))
    out = replace(prop, pose=(float(p[0]), float(p[1]), float(h - frame[2])))
    prop.density_bins()  # in prop coordinates: computed once, on the prop itself, and shared
    out.__dict__["_bins"] = prop.__dict__["_bins"]
    return out
