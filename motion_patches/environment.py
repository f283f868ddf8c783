"""Environment: obstacles on the ground, the tile grid of a layer, and cell occlusion.

Tiles are instances of a locomotion patch laid on a fixed grid (tile (i, j) has its corner
at (i * side, j * side)). A tile owns only the list of obstacles overlapping it, updated
when an obstacle is added or moved, and a free-cell bitfield ``B_t`` computed lazily the
first time the planner asks (Eq. 8). The character's radius is applied to the footprints
(a cell is occluded when it comes within the radius of a footprint), so segment masks
stay one 64-bit word per tile.
"""

from dataclasses import dataclass

import numpy as np

FULL = np.uint64(0xFFFFFFFFFFFFFFFF)
PATH_MARGIN = 0.002  # metres: sampled paths are tested this much wider (the frames between
                     # samples run on chords a fraction of a millimetre inside the arcs)


@dataclass
class Obstacle:
    name: str
    polygon: np.ndarray  # (P, 2) convex footprint, counter-clockwise, world metres

    def __post_init__(self):
        self.polygon = np.asarray(self.polygon, float)
        self.lo, self.hi = self.polygon.min(axis=0), self.polygon.max(axis=0)

    def bounds(self):
        return self.lo, self.hi

    def within(self, points, radius):
        """(N,) True where points come within ``radius`` of the footprint."""
        out = np.zeros(points.shape[0], bool)
        near = np.all((points > self.lo - radius) & (points < self.hi + radius), axis=1)
        if near.any():
            out[near] = distance_to_polygon(points[near], self.polygon) < radius
        return out


def _cross2(a, b):
    """z of the cross product of two 2-D vectors (numpy 2 refuses 2-D np.cross)."""
    return a[0] * b[1] - a[1] * b[0]


def convex_hull(points):
    """Counter-clockwise convex hull (monotone chain) of points (N, 2)."""
    pts = np.unique(np.asarray(points, float).round(9), axis=0)
    if pts.shape[0] < 3:
        return pts
    pts = pts[np.lexsort((pts[:, 1], pts[:, 0]))]

    def half(seq):
        out = []
        for p in seq:
            while len(out) >= 2 and _cross2(out[-1] - out[-2], p - out[-2]) <= 0:
                out.pop()
            out.append(p)
        return out
    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _segment_distance(points, a, b):
    """Distance of points (N, 2) to segments a (E, 2) -> b (E, 2): (N, E)."""
    ab = b - a
    t = np.clip(np.einsum("nek,ek->ne", points[:, None] - a[None], ab)
                / np.maximum((ab * ab).sum(-1), 1e-12)[None], 0.0, 1.0)
    proj = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None] - proj, axis=-1)


def inside_convex(points, polygon):
    """(N,) True where points lie inside a counter-clockwise convex polygon."""
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    cross = ((b - a)[None, :, 0] * (points[:, None, 1] - a[None, :, 1])
             - (b - a)[None, :, 1] * (points[:, None, 0] - a[None, :, 0]))
    return np.all(cross >= 0, axis=1)


def distance_to_polygon(points, polygon):
    """(N,) distance from points to a convex polygon (0 inside)."""
    points = np.atleast_2d(np.asarray(points, float))
    d = _segment_distance(points, polygon, np.roll(polygon, -1, axis=0)).min(axis=1)
    return np.where(inside_convex(points, polygon), 0.0, d)


def _edges_cross(poly_a, poly_b):
    """True when any edge of one polygon properly crosses an edge of the other."""
    a0, a1 = poly_a, np.roll(poly_a, -1, axis=0)
    b0, b1 = poly_b, np.roll(poly_b, -1, axis=0)

    def orient(p, q, r):
        return ((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
                - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))
    A0, A1 = a0[:, None], a1[:, None]
    B0, B1 = b0[None], b1[None]
    d1, d2 = orient(A0, A1, B0), orient(A0, A1, B1)
    d3, d4 = orient(B0, B1, A0), orient(B0, B1, A1)
    return bool(np.any((d1 * d2 < 0) & (d3 * d4 < 0)))


def polygons_within(poly_a, poly_b, radius):
    """True when two convex polygons come within ``radius`` of each other."""
    if np.any(inside_convex(poly_a, poly_b)) or np.any(inside_convex(poly_b, poly_a)):
        return True
    if _edges_cross(poly_a, poly_b):  # a thin fence across a cell has no vertex inside it
        return True
    da = _segment_distance(poly_a, poly_b, np.roll(poly_b, -1, axis=0)).min()
    db = _segment_distance(poly_b, poly_a, np.roll(poly_a, -1, axis=0)).min()
    return min(da, db) < radius


def cells_within(x0, y0, size, polygon, radius):
    """(K,) True for the square cells (corner x0, y0; side ``size``) that come within
    ``radius`` of a convex polygon: the exact distance between two convex shapes, for all
    cells of a tile at once."""
    x1, y1 = x0 + size, y0 + size
    px, py = polygon[:, 0][None], polygon[:, 1][None]
    # Polygon vertices to the cells (axis-aligned boxes): zero when a vertex is inside.
    dx = np.maximum(np.maximum(x0[:, None] - px, 0.0), px - x1[:, None])
    dy = np.maximum(np.maximum(y0[:, None] - py, 0.0), py - y1[:, None])
    d = np.hypot(dx, dy).min(axis=1)
    # Cell corners to the polygon (zero when a corner is inside it).
    corners = np.stack((np.column_stack((x0, y0)), np.column_stack((x1, y0)),
                        np.column_stack((x1, y1)), np.column_stack((x0, y1))), axis=1)
    flat = corners.reshape(-1, 2)
    dc = distance_to_polygon(flat, polygon).reshape(-1, 4).min(axis=1)
    d = np.minimum(d, dc)
    # A polygon edge crossing a cell with no vertex of either inside it (a thin fence).
    lo, hi = polygon.min(axis=0), polygon.max(axis=0)
    boxed = (d > 0) & (x0 <= hi[0]) & (x1 >= lo[0]) & (y0 <= hi[1]) & (y1 >= lo[1])
    for k in np.flatnonzero(boxed):
        if _edges_cross(corners[k], polygon):
            d[k] = 0.0
    return d < max(radius, 1e-12) if radius > 0 else d <= 0.0


def cells_covered(x0, y0, size, polygon, radius):
    """(K,) True for the square cells lying wholly within ``radius`` of a convex polygon:
    the polygon grown by the radius is convex, so a cell is inside when its four corners
    are. No point of such a cell can be walked; a segment crossing it is occluded."""
    corners = np.stack((np.column_stack((x0, y0)), np.column_stack((x0 + size, y0)),
                        np.column_stack((x0 + size, y0 + size)),
                        np.column_stack((x0, y0 + size))), axis=1)
    d = distance_to_polygon(corners.reshape(-1, 2), polygon).reshape(-1, 4)
    return np.all(d < radius, axis=1) if radius > 0 else np.all(d <= 0.0, axis=1)


def _bits(flags):
    """uint64 with bit c set where ``flags[c]``."""
    idx = np.flatnonzero(flags).astype(np.uint64)
    return np.bitwise_or.reduce(np.left_shift(np.uint64(1), idx)) if idx.size else np.uint64(0)


class Environment:
    """Obstacles and the lazily occluded tile grid of one locomotion patch size."""

    def __init__(self, side, cells, radius):
        self.side = float(side)
        self.cells = int(cells)
        self.radius = float(radius)
        self.obstacles = {}
        self._tiles_of = {}     # obstacle name -> set of tiles
        self._members = {}      # tile -> set of obstacle names
        self._free = {}         # tile -> uint64 free-cell bitfield (lazy)
        self._solid = {}        # tile -> uint64 bitfield of cells no point of which is free
        self._pack = None       # footprints as arrays for point queries (:meth:`_packed`)
        self.occlusion_computations = 0

    def tile_of(self, xy):
        return (int(np.floor(xy[0] / self.side)), int(np.floor(xy[1] / self.side)))

    def _tiles_overlapping(self, obstacle):
        lo, hi = obstacle.bounds()
        lo, hi = lo - self.radius, hi + self.radius
        i0, j0 = self.tile_of(lo)
        i1, j1 = self.tile_of(hi)
        return {(i, j) for i in range(i0, i1 + 1) for j in range(j0, j1 + 1)}

    def place(self, obstacle):
        """Add or move an obstacle: only tile membership changes (no occlusion work)."""
        self.remove(obstacle.name)
        self._pack = None
        self.obstacles[obstacle.name] = obstacle
        tiles = self._tiles_overlapping(obstacle)
        self._tiles_of[obstacle.name] = tiles
        for t in tiles:
            self._members.setdefault(t, set()).add(obstacle.name)
            self._free.pop(t, None)
            self._solid.pop(t, None)

    def remove(self, name):
        self._pack = None
        for t in self._tiles_of.pop(name, ()):
            self._members[t].discard(name)
            self._free.pop(t, None)
            self._solid.pop(t, None)
        self.obstacles.pop(name, None)

    def members(self, tile):
        return self._members.get(tile, set())

    def free_cells(self, tile):
        """``B_t``: bit c set when cell c of the tile is not occluded (computed lazily)."""
        f = self._free.get(tile)
        if f is None:
            f, solid = self._occlude(tile)
            self._free[tile], self._solid[tile] = f, solid
        return f

    def cell_states(self, tile):
        """(free, solid) bitfields of a tile: free cells have no point within the radius of
        an obstacle (Eq. 8's ``B_t``); solid cells no point outside it. A segment through
        cells that are neither is decided by testing its own path (the planner does)."""
        free = self.free_cells(tile)
        return free, self._solid[tile]

    def _occlude(self, tile):
        self.occlusion_computations += 1
        names = self.members(tile)
        if not names:
            return FULL, np.uint64(0)
        c = self.side / self.cells
        ix, iy = np.meshgrid(np.arange(self.cells), np.arange(self.cells), indexing="xy")
        x0 = tile[0] * self.side + ix.ravel() * c
        y0 = tile[1] * self.side + iy.ravel() * c
        occluded = np.zeros(x0.size, bool)
        solid = np.zeros(x0.size, bool)
        for n in names:
            occluded |= cells_within(x0, y0, c, self.obstacles[n].polygon, self.radius)
            solid |= cells_covered(x0, y0, c, self.obstacles[n].polygon, self.radius)
        return (FULL & ~_bits(occluded)), _bits(solid)

    def names_in_box(self, lo, hi):
        """Names of the obstacles whose bounds overlap the box ``lo``-``hi`` (world)."""
        i0, j0 = self.tile_of(lo)
        i1, j1 = self.tile_of(hi)
        if (i1 - i0 + 1) * (j1 - j0 + 1) > len(self._tiles_of) * 4:
            names = self.obstacles.keys()  # a box larger than the scene: look at each once
        else:
            names = set()
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    names |= self._members.get((i, j), set())
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        return sorted(n for n in names
                      if np.all(self.obstacles[n].lo <= hi) and np.all(self.obstacles[n].hi >= lo))

    def near(self, xy):
        """Sorted names of the obstacles a point (x, y) comes within the radius of."""
        p = np.asarray(xy, float)[None, :2]
        return sorted(n for n in self.members(self.tile_of(p[0]))
                      if self.obstacles[n].within(p, self.radius)[0])

    def blocked(self, points, exclude=(), radius=None):
        """(N,) True where world points come within the radius (or ``radius``, at most a
        tile side more) of any obstacle."""
        points = np.atleast_2d(np.asarray(points, float))
        radius = self.radius if radius is None else float(radius)
        out = np.zeros(points.shape[0], bool)
        tiles = set(map(tuple, np.floor(points / self.side).astype(int).tolist()))
        if radius > self.radius:  # membership holds footprints grown by self.radius only
            tiles = {(i + di, j + dj) for i, j in tiles for di in (-1, 0, 1) for dj in (-1, 0, 1)}
        near = set()
        for t in tiles:
            near |= self.members(t)
        near -= set(exclude)
        if not near:
            return out
        if len(near) <= 2 or (self._pack is None and len(self.obstacles) > 50 * len(near)):
            for n in near:  # a few footprints of a large scene: not worth packing them all
                out |= self.obstacles[n].within(points, radius)
            return out
        index, lo, hi, verts = self._packed()
        idx = np.fromiter((index[n] for n in near), int, len(near))
        # Bounding boxes first, for every (point, obstacle) pair at once; then the exact
        # distance to the convex footprint only for the pairs that pass.
        box = (np.all(points[:, None] > lo[idx][None] - radius, axis=-1)
               & np.all(points[:, None] < hi[idx][None] + radius, axis=-1))
        pi, ci = np.nonzero(box)
        if pi.size:
            a = verts[idx[ci]]
            ab = np.roll(a, -1, axis=1) - a
            ap = points[pi][:, None] - a
            t = np.clip(np.sum(ap * ab, -1) / np.maximum(np.sum(ab * ab, -1), 1e-12), 0.0, 1.0)
            gap = ap - t[..., None] * ab
            dist = np.sqrt(np.min(np.sum(gap * gap, -1), axis=1))
            inside = np.all(ab[..., 0] * ap[..., 1] - ab[..., 1] * ap[..., 0] >= 0, axis=1)
            hit = (dist < radius) | (inside & (radius > 0))  # distance 0 inside, as within()
            out[pi[hit]] = True
        return out

    def _packed(self):
        """Every footprint in arrays (cached until an obstacle is placed or removed):
        {name: row}, bounds lo / hi (M, 2), vertices (M, V, 2) padded by repeating the
        last one (a zero-length edge changes no distance and no inside test)."""
        if self._pack is None:
            names = list(self.obstacles)
            v = max((len(self.obstacles[n].polygon) for n in names), default=1)
            verts = np.zeros((len(names), v, 2))
            for i, n in enumerate(names):
                poly = self.obstacles[n].polygon
                verts[i, :len(poly)] = poly
                verts[i, len(poly):] = poly[-1]
            self._pack = ({n: i for i, n in enumerate(names)},
                          np.array([self.obstacles[n].lo for n in names]).reshape(-1, 2),
                          np.array([self.obstacles[n].hi for n in names]).reshape(-1, 2), verts)
        return self._pack

    def path_blocked(self, paths, spacing):
        """(n,) True where sampled paths (n, M, 2), samples at most ``spacing`` apart,
        come within the radius of an obstacle anywhere between samples (to the precision
        of the sampling): every fourth sample first, the rest only where those do not
        settle it (a point farther than radius + 2 x spacing from every footprint clears
        the stretch around it)."""
        n, m = paths.shape[:2]
        r = self.radius + PATH_MARGIN
        coarse = np.concatenate((paths[:, ::4], paths[:, -1:]), axis=1)
        hit = self.blocked(coarse.reshape(-1, 2), radius=r).reshape(n, -1).any(axis=1)
        unsure = np.flatnonzero(~hit)
        if unsure.size:
            close = self.blocked(coarse[unsure].reshape(-1, 2), radius=r + 2.0 * spacing)
            close = close.reshape(unsure.size, -1).any(axis=1)
            fine = unsure[close]
            if fine.size:
                hit[fine] = self.blocked(paths[fine].reshape(-1, 2), radius=r).reshape(fine.size, -1).any(axis=1)
        return hit
