# SPDX-License-Identifier: GPL-3.0-or-later
"""Accessibility psi (Eq. 2), density rho and traversal probability tau (Eq. 3).

psi is precomputed once per kind of prop: the prop is placed at sampled spots of one
locomotion patch and, at each, the traversal paths its clips create (stitch edges) are
counted against the patch segments it occludes. At plan time, for a tile the high-level
search expands, each prop's density bins covered by other props give rho_jk (bins
weighted by their closeness to the tile's entry edge j and exit edge k), and
``tau_jk = psi (1 - rho_jk)``; the tile takes the best prop, scaled by its share of free
cells. All of it is lazy: nothing is computed for tiles the search never reaches.
"""

import hashlib
from collections.abc import Callable, Iterable

import numpy as np

from ..patch.locomotion_patch import LocomotionPatch
from ..props.environment import Environment, Obstacle
from ..props.object_patch import ObjectPatch
from .settings import PlanSettings
from .stitching import stitch

_DEFAULTS = PlanSettings()

_PSI: dict[tuple[str, float, float], float] = {}  # signature of a kind of prop -> psi
EDGE_POINTS = np.array([[0.5, 0.0], [1.0, 0.5], [0.5, 1.0], [0.0, 0.5]])  # edge mid-points / side


def signature(prop: ObjectPatch) -> str:
    """What makes two props the same kind for psi: footprint and clips."""
    h = hashlib.sha1(np.ascontiguousarray(prop.footprint).tobytes())
    for c in prop.clips:
        h.update(c.name.encode())
        h.update(np.ascontiguousarray(c.motion.ground[[0, -1]]).round(6).tobytes())
    return h.hexdigest()


def accessibility(
    patch: LocomotionPatch,
    prop: ObjectPatch,
    radius: float,
    spots: tuple[float, ...] = (0.35, 0.65),
    weights: tuple[float, float, float] = (_DEFAULTS.alpha, _DEFAULTS.beta, _DEFAULTS.gamma),
) -> float:
    """psi of a kind of prop (cached): mean over sampled placements of T / O, at most 1."""
    key = (signature(prop), round(radius, 4), patch.side)
    if key in _PSI:
        return _PSI[key]
    ratios: list[float] = []
    for fx in spots:
        for fy in spots:
            env = Environment(patch.side, patch.cells, radius)
            placed = ObjectPatch(
                prop.name, prop.footprint, prop.clips, pose=(fx * patch.side, fy * patch.side, 0.0)
            )
            env.place(Obstacle(placed.name, placed.world_footprint()))
            free = env.free_cells((0, 0))
            occluded = int(np.sum((patch.seg_mask & free) != patch.seg_mask))
            created = sum(
                len(stitch(patch, env, placed, i, *weights))
                for i, c in enumerate(placed.clips)
                if c.kind == "traversal"
            )
            ratios.append(created / max(occluded, 1))
    psi = min(1.0, float(np.mean(ratios)))
    _PSI[key] = psi
    return psi


def density(
    prop: ObjectPatch, obstacles: Iterable[Obstacle], tile_origin: np.ndarray, side: float
) -> np.ndarray:
    """(4, 4) rho_jk: the weighted share of the prop's density bins other props cover,
    bins weighted by closeness to entry edge j and exit edge k of the tile."""
    rects, _ = prop.density_bins()
    occluded = prop.occluded_bins(obstacles).astype(float)
    centres = prop.to_world(
        np.column_stack(((rects[:, 0] + rects[:, 2]) / 2, (rects[:, 1] + rects[:, 3]) / 2))
    )
    edges = np.asarray(tile_origin, float) + EDGE_POINTS * side
    d = np.linalg.norm(centres[:, None] - edges[None], axis=-1)  # (bins, 4)
    w = np.exp(-d / side)
    rho = np.zeros((4, 4))
    for j in range(4):
        for k in range(4):
            wk = w[:, j] + w[:, k]
            rho[j, k] = float(np.sum(wk * occluded) / np.sum(wk))
    return rho


def tile_traversal(
    patch: LocomotionPatch,
    env: Environment,
    props_in_tile: list[ObjectPatch],
    tile: tuple[int, int],
    psi_of: Callable[[ObjectPatch], float],
) -> np.ndarray:
    """(4, 4) tau of a tile: the best prop's psi (1 - rho_jk), times the free-cell share."""
    if not props_in_tile:
        return np.zeros((4, 4))
    free = env.free_cells(tile)
    share = bin(int(free)).count("1") / float(patch.cells * patch.cells)
    origin = np.array(tile, float) * patch.side
    best = np.zeros((4, 4))
    for prop in props_in_tile:
        rho = density(prop, env.obstacles.values(), origin, patch.side)
        best = np.maximum(best, psi_of(prop) * (1.0 - rho))
    return best * share
