# SPDX-License-Identifier: GPL-3.0-or-later
"""Which props keep a start from a goal: the answer a layout check gives for an
unreachable pair, read from the planner's own occluded cells (not from meshes), so it names
what the planner actually could not get past."""

from collections import deque
from collections.abc import Sequence

import numpy as np

from .environment import Environment, polygons_within


def blocking_props(
    env: Environment,
    start: Sequence[float] | np.ndarray,
    goal: Sequence[float] | np.ndarray,
    margin_tiles: int = 3,
) -> tuple[list[str], str]:
    """(names, reason) of the props that keep ``start`` from ``goal`` on ``env``.

    Read from the planner's own view: the free-cell bitfields ``B_t`` (footprints grown by
    the character's radius) of the tiles it may search (start and goal tiles plus the
    margin). Free cells are flood-filled (4-connected) from the start's cell and the goal's.

    * start or goal within the radius of props -> those props ("start" / "goal");
    * separate open areas -> the props whose occluded cells border both areas, i.e. the
      wall between them; if no single prop does (a barrier several props thick), the props
      bordering the smaller area ("separated");
    * one open area (a point could pass, the walk cannot fit or turn through) -> the props
      whose occluded cells lie within two cells of the shortest open cell path, those with
      most such cells first ("narrow");
    * nothing found -> ([], "unknown") (e.g. start and goal too close to join the graph).
    """
    for what, pt in (("start", start), ("goal", goal)):
        near = env.near(pt)
        if near:
            return near, what
    if not env.obstacles:
        return [], "unknown"
    side, cells = env.side, env.cells
    c = side / cells
    ts, tg = env.tile_of(start[:2]), env.tile_of(goal[:2])
    i0, j0 = min(ts[0], tg[0]) - margin_tiles, min(ts[1], tg[1]) - margin_tiles
    i1, j1 = max(ts[0], tg[0]) + margin_tiles, max(ts[1], tg[1]) + margin_tiles
    W, H = (i1 - i0 + 1) * cells, (j1 - j0 + 1) * cells
    free = np.ones((H, W), bool)
    bit = np.arange(cells * cells, dtype=np.uint64)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if not env.members((i, j)):
                continue
            f = np.uint64(env.free_cells((i, j)))
            block = ((f >> bit) & np.uint64(1)).astype(bool).reshape(cells, cells)  # [iy, ix]
            y0, x0 = (j - j0) * cells, (i - i0) * cells
            free[y0 : y0 + cells, x0 : x0 + cells] = block

    def cell_of(p):
        gx = int(np.clip(np.floor(p[0] / c) - i0 * cells, 0, W - 1))
        gy = int(np.clip(np.floor(p[1] / c) - j0 * cells, 0, H - 1))
        return gy, gx

    cs, cg = cell_of(start), cell_of(goal)
    free[cs] = free[cg] = True
    comp_s, parent = _flood(free, cs)

    def owners(cells_yx):
        """prop name -> number of the given occluded cells it occludes."""
        count = {}
        for gy, gx in cells_yx:
            x0, y0 = (gx + i0 * cells) * c, (gy + j0 * cells) * c
            box = np.array([[x0, y0], [x0 + c, y0], [x0 + c, y0 + c], [x0, y0 + c]])
            tile = env.tile_of((x0 + c / 2, y0 + c / 2))
            for n in env.members(tile):
                if polygons_within(box, env.obstacles[n].polygon, env.radius):
                    count[n] = count.get(n, 0) + 1
        return count

    if not comp_s[cg]:
        comp_g, _ = _flood(free, cg)
        bs, bg = owners(_border(comp_s, free)), owners(_border(comp_g, free))
        both = sorted(set(bs) & set(bg))
        if not both:
            both = sorted(bg if comp_g.sum() <= comp_s.sum() else bs)
        return both, "separated"
    path = []
    node = cg
    while node is not None:
        path.append(node)
        node = parent.get(node)
    touch = np.zeros_like(free)
    for gy, gx in path:
        touch[max(gy - 2, 0) : gy + 3, max(gx - 2, 0) : gx + 3] = True
    count = owners(zip(*np.nonzero(touch & ~free)))
    return sorted(count, key=lambda n: (-count[n], n)), ("narrow" if count else "unknown")


def _flood(free, seed):
    """Cells reachable from ``seed`` over free cells (4-connected) and BFS parents."""
    H, W = free.shape
    seen = np.zeros_like(free)
    seen[seed] = True
    parent = {seed: None}
    q = deque([seed])
    while q:
        y, x = q.popleft()
        for ny, nx in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1)):
            if 0 <= ny < H and 0 <= nx < W and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                parent[(ny, nx)] = (y, x)
                q.append((ny, nx))
    return seen, parent


def _border(comp, free):
    """Occluded cells 4-adjacent to a component."""
    grow = comp.copy()
    grow[1:] |= comp[:-1]
    grow[:-1] |= comp[1:]
    grow[:, 1:] |= comp[:, :-1]
    grow[:, :-1] |= comp[:, 1:]
    return list(zip(*np.nonzero(grow & ~free)))
