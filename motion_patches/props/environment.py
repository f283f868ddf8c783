# SPDX-License-Identifier: GPL-3.0-or-later
"""Environment: obstacles on the ground, the tile grid of a layer, and cell occlusion.

Tiles are instances of a locomotion patch laid on a fixed grid (tile (i, j) has its corner
at (i * side, j * side)). A tile owns only the list of obstacles overlapping it, updated
when an obstacle is added or moved, and a free-cell bitfield ``B_t`` computed lazily the
first time the planner asks (Eq. 8). The character's radius is applied to the footprints
(a cell is occluded when it comes within the radius of a footprint), so segment masks
stay one 64-bit word per tile.

Point tests go through a clearance raster, also lazy per tile: ``FINE`` x ``FINE`` raster
cells per cell, each holding, for its centre, the exact distance to the nearest footprint,
that footprint's nearest point and the distance to the next footprint (capped at the
radius + ``CLEARANCE_CAP``). From these, every point gets a lower and an upper bound of
its own distance to the footprints (:meth:`Environment.decided`); they are exact along a
footprint's edges, so only points within about a millimetre of the query radius (or by a
corner, or between two footprints close together) are tested exactly against the
footprints. The answers are those of the exact test; the raster only spares the work.
The cell bitfields ``B_t`` are read off the same raster (the cells it leaves undecided are
tested exactly).
"""

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

Tile = tuple[int, int]  # (i, j) of a tile on the ground

FULL = np.uint64(0xFFFFFFFFFFFFFFFF)
PATH_MARGIN = 0.002  # metres: sampled paths are tested this much wider (the frames between
# samples run on chords a fraction of a millimetre inside the arcs)
FINE = 4  # clearance raster cells per cell side (8 cm for the CMU walk patch)
SUB = 4  # sub-cells per cell side of the sub-cell bitfields (a divisor of FINE)
CLEARANCE_CAP = 0.15  # metres beyond the radius up to which the raster holds distances
RASTER_MIN_POINTS = 24  # fewer points are tested exactly at once (no raster work for them)
_EPS = 1e-7  # metres: rounding slack of the raster's decisions
MAX_RASTER_TILES = 1 << 18  # largest area (in tiles) the raster's grid of slots spans


@dataclass
class Obstacle:
    name: str
    polygon: np.ndarray  # (P, 2) convex footprint, counter-clockwise, world metres

    def __post_init__(self):
        self.polygon = np.asarray(self.polygon, float)
        self.lo, self.hi = self.polygon.min(axis=0), self.polygon.max(axis=0)
        # The bounds as plain floats (x0, y0, x1, y1): box tests of a few obstacles at a
        # time are cheaper in Python than in numpy.
        self.box = (float(self.lo[0]), float(self.lo[1]), float(self.hi[0]), float(self.hi[1]))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        return self.lo, self.hi

    def within(self, points: np.ndarray, radius: float) -> np.ndarray:
        """(N,) True where points come within ``radius`` of the footprint."""
        out = np.zeros(points.shape[0], bool)
        near = np.all((points > self.lo - radius) & (points < self.hi + radius), axis=1)
        if near.any():
            out[near] = distance_to_polygon(points[near], self.polygon) < radius
        return out


def _cross2(a, b):
    """z of the cross product of two 2-D vectors (numpy 2 refuses 2-D np.cross)."""
    return a[0] * b[1] - a[1] * b[0]


def convex_hull(points: ArrayLike) -> np.ndarray:
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


def _next(polygon):
    """Each vertex's successor (N, 2): ``np.roll(polygon, -1, axis=0)`` at a third of its
    cost on a few vertices."""
    return np.concatenate((polygon[1:], polygon[:1]))


def _segment_distance(points, a, b):
    """Distance of points (N, 2) to segments a (E, 2) -> b (E, 2): (N, E)."""
    ab = b - a
    t = np.clip(
        np.einsum("nek,ek->ne", points[:, None] - a[None], ab)
        / np.maximum((ab * ab).sum(-1), 1e-12)[None],
        0.0,
        1.0,
    )
    proj = a[None] + t[..., None] * ab[None]
    return np.linalg.norm(points[:, None] - proj, axis=-1)


def inside_convex(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(N,) True where points lie inside a counter-clockwise convex polygon."""
    a = polygon
    b = _next(polygon)
    cross = (b - a)[None, :, 0] * (points[:, None, 1] - a[None, :, 1]) - (b - a)[None, :, 1] * (
        points[:, None, 0] - a[None, :, 0]
    )
    return np.all(cross >= 0, axis=1)


def distance_to_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(N,) distance from points to a convex polygon (0 inside)."""
    points = np.atleast_2d(np.asarray(points, float))
    d = _segment_distance(points, polygon, _next(polygon)).min(axis=1)
    return np.where(inside_convex(points, polygon), 0.0, d)


def convex_closest(points: np.ndarray, polygon: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact distance (N,) from points (N, 2) to a convex polygon (0 inside) and the
    polygon's point nearest each (N, 2) (the point itself inside), by the edge lines:
    outside, the nearest point lies on the edge whose line the point is farthest beyond
    when the point's foot falls within that edge, else it is a vertex. One matrix product
    and a few (N, V) arrays for many points at once (either winding)."""
    points = np.asarray(points, float)
    poly = np.asarray(polygon, float)
    px, py = points[:, 0], points[:, 1]
    e = _next(poly) - poly
    keep = np.einsum("ij,ij->i", e, e) > 1e-18
    if not keep.all():
        poly, e = poly[keep], e[keep]
    if poly.shape[0] < 3:  # a point or a segment: its vertices and edge directly
        poly = np.asarray(polygon, float)[: max(poly.shape[0], 1)]
        a, b = poly[0], poly[-1]
        ab = b - a
        t = np.clip((points - a) @ ab / max(float(ab @ ab), 1e-18), 0.0, 1.0)
        q = a + t[:, None] * ab
        return np.linalg.norm(points - q, axis=1), q
    if np.sum(poly[:, 0] * e[:, 1] - poly[:, 1] * e[:, 0]) < 0:  # clockwise: turn it round
        poly = poly[::-1]
        e = _next(poly) - poly
    length2 = np.einsum("ij,ij->i", e, e)
    normal = np.column_stack((e[:, 1], -e[:, 0])) / np.sqrt(length2)[:, None]  # outward
    beyond = points @ normal.T - np.einsum("ij,ij->i", normal, poly)[None]  # (N, V)
    i = np.argmax(beyond, axis=1)
    far = beyond[np.arange(i.size), i]
    # Per-vertex values gathered once each (1-D takes: cheaper than 2-D indexing).
    vx, vy = poly[:, 0].take(i), poly[:, 1].take(i)
    ex, ey = e[:, 0].take(i), e[:, 1].take(i)
    t = ((px - vx) * ex + (py - vy) * ey) / length2.take(i)
    out = far > 0.0
    on_edge = (t >= 0.0) & (t <= 1.0) & out
    d = np.where(on_edge, far, 0.0)
    qx, qy = px - d * normal[:, 0].take(i), py - d * normal[:, 1].take(i)
    corner = np.flatnonzero(~on_edge & out)
    if corner.size:
        cx, cy = px[corner], py[corner]
        gx, gy = cx[:, None] - poly[None, :, 0], cy[:, None] - poly[None, :, 1]
        dist2 = gx * gx + gy * gy  # (Nc, V)
        k = np.argmin(dist2, axis=1)
        d[corner] = np.sqrt(np.take_along_axis(dist2, k[:, None], axis=1)[:, 0])
        qx[corner], qy[corner] = poly[k, 0], poly[k, 1]
    return d, np.column_stack((qx, qy))


def _edges_cross(poly_a, poly_b):
    """True when any edge of one polygon properly crosses an edge of the other."""
    a0, a1 = poly_a, _next(poly_a)
    b0, b1 = poly_b, _next(poly_b)

    def orient(p, q, r):
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    A0, A1 = a0[:, None], a1[:, None]
    B0, B1 = b0[None], b1[None]
    d1, d2 = orient(A0, A1, B0), orient(A0, A1, B1)
    d3, d4 = orient(B0, B1, A0), orient(B0, B1, A1)
    return bool(np.any((d1 * d2 < 0) & (d3 * d4 < 0)))


def polygons_within(poly_a: np.ndarray, poly_b: np.ndarray, radius: float) -> bool:
    """True when two convex polygons come within ``radius`` of each other."""
    if np.any(inside_convex(poly_a, poly_b)) or np.any(inside_convex(poly_b, poly_a)):
        return True
    if _edges_cross(poly_a, poly_b):  # a thin fence across a cell has no vertex inside it
        return True
    da = _segment_distance(poly_a, poly_b, _next(poly_b)).min()
    db = _segment_distance(poly_b, poly_a, _next(poly_a)).min()
    return min(da, db) < radius


def cells_within(
    x0: np.ndarray, y0: np.ndarray, size: float, polygon: np.ndarray, radius: float
) -> np.ndarray:
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
    corners = np.stack(
        (
            np.column_stack((x0, y0)),
            np.column_stack((x1, y0)),
            np.column_stack((x1, y1)),
            np.column_stack((x0, y1)),
        ),
        axis=1,
    )
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
        self._tiles_of = {}  # obstacle name -> set of tiles
        self._members = {}  # tile -> set of obstacle names
        self._free = {}  # tile -> uint64 free-cell bitfield (lazy)
        self._solid = {}  # tile -> uint64 bitfield of cells no point of which is free
        self._pack = None  # footprints as arrays for point queries (:meth:`_packed`)
        self._ob_raster = {}  # obstacle name -> its own distances (:meth:`_obstacle_raster`)
        self.occlusion_computations = 0
        self.fine = self.cells * FINE  # raster cells per tile side
        self.fine_size = self.side / self.fine  # metres
        self.rho = self.fine_size * np.sqrt(0.5) + _EPS  # centre to corner, and slack
        self.cap = self.radius + CLEARANCE_CAP
        # Tile rasters (lazy) live in one array, a slot per tile (slot 0: a tile with no
        # footprint near), found through a grid of slots over the tiles seen so far, so
        # the points of many tiles are looked up with one gather.
        self._atlas = np.empty((4, 8, self.fine**2))
        self._atlas[:, 0] = 0.0
        self._atlas[[0, 3], 0] = self.cap
        self._slots = {}  # tile -> slot
        self._sub = {}  # tile -> {radius: (free, solid)} sub-cell bitfields (its raster's)
        self._spare = list(range(7, 0, -1))
        self._grid = np.full((1, 1), -1, np.int64)
        self._grid_origin = (0, 0)

    def tile_of(self, xy: Sequence[float] | np.ndarray) -> Tile:
        return (math.floor(float(xy[0]) / self.side), math.floor(float(xy[1]) / self.side))

    def _tiles_overlapping(self, obstacle):
        x0, y0, x1, y1 = obstacle.box
        r, side = self.radius, self.side
        i0, j0 = math.floor((x0 - r) / side), math.floor((y0 - r) / side)
        i1, j1 = math.floor((x1 + r) / side), math.floor((y1 + r) / side)
        return {(i, j) for i in range(i0, i1 + 1) for j in range(j0, j1 + 1)}

    def place(self, obstacle: Obstacle) -> None:
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
        self._forget_raster(obstacle)

    def remove(self, name: str) -> None:
        self._pack = None
        for t in self._tiles_of.pop(name, ()):
            self._members[t].discard(name)
            self._free.pop(t, None)
            self._solid.pop(t, None)
        ob = self.obstacles.pop(name, None)
        if ob is not None:
            self._forget_raster(ob)

    def _forget_raster(self, obstacle):
        """Drop the rasters an obstacle's distances reach (only those computed already)."""
        self._ob_raster.pop(obstacle.name, None)
        if not self._slots:
            return
        lo, hi = obstacle.bounds()
        i0, j0 = self.tile_of(lo - self.cap)
        i1, j1 = self.tile_of(hi + self.cap)
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                # Read off the raster dropped here (a refill may take the same slot back).
                self._sub.pop((i, j), None)
                slot = self._slots.pop((i, j), None)
                if slot is None:
                    continue
                if slot:
                    self._spare.append(slot)
                gi, gj = i - self._grid_origin[0], j - self._grid_origin[1]
                if 0 <= gi < self._grid.shape[0] and 0 <= gj < self._grid.shape[1]:
                    self._grid[gi, gj] = -1

    def members(self, tile: Tile) -> set[str]:
        return self._members.get(tile, set())

    def free_cells(self, tile: Tile) -> np.uint64:
        """``B_t``: bit c set when cell c of the tile is not occluded (computed lazily)."""
        f = self._free.get(tile)
        if f is None:
            f, solid = self._occlude(tile)
            self._free[tile], self._solid[tile] = f, solid
        return f

    def cell_states(self, tile: Tile) -> tuple[np.uint64, np.uint64]:
        """(free, solid) bitfields of a tile: free cells have no point within the radius of
        an obstacle (Eq. 8's ``B_t``); solid cells no point outside it. A segment through
        cells that are neither is decided by testing its own path (the planner does)."""
        free = self.free_cells(tile)
        return free, self._solid[tile]

    def _occlude(self, tile):
        """(free, solid) bitfields of a tile, read off its clearance raster: a cell with a
        raster centre nearer than the radius to a footprint is occluded, one whose every
        raster cell is farther by the lower bounds of :meth:`decided` (taken over the
        whole raster cell) is free, and the few in between are tested exactly
        (:func:`cells_within`), so ``B_t`` is the exact Eq. 8 bitfield. A cell whose every
        raster centre is nearer than the radius - rho (half a raster cell's diagonal) has
        no free point: solid."""
        self.occlusion_computations += 1
        names = self.members(tile)
        if not names:
            return FULL, np.uint64(0)
        n, k = self.cells, FINE
        dist = self.clearance(tile)[0]
        low = self._lowest(tile)
        near = dist.reshape(n, k, n, k).min(axis=(1, 3)).ravel()  # cell index iy * cells + ix
        low = low.reshape(n, k, n, k).min(axis=(1, 3)).ravel()
        far = dist.reshape(n, k, n, k).max(axis=(1, 3)).ravel()
        occluded = near < self.radius if self.radius > 0 else near <= 0.0
        unsure = np.flatnonzero(~occluded & (low <= self.radius + _EPS))
        if unsure.size:
            c = self.side / n
            x0 = tile[0] * self.side + (unsure % n) * c
            y0 = tile[1] * self.side + (unsure // n) * c
            hit = np.zeros(unsure.size, bool)
            for name in names:
                ob = self.obstacles[name]
                near = np.flatnonzero(
                    ~hit
                    & (x0 < ob.hi[0] + self.radius)
                    & (x0 + c > ob.lo[0] - self.radius)
                    & (y0 < ob.hi[1] + self.radius)
                    & (y0 + c > ob.lo[1] - self.radius)
                )
                if near.size:
                    hit[near] = cells_within(x0[near], y0[near], c, ob.polygon, self.radius)
            occluded[unsure] = hit
        solid = far < self.radius - self.rho
        return (FULL & ~_bits(occluded)), _bits(solid)

    def _lowest(self, tile):
        """(G * G,) a lower bound of the distance to the footprints over each whole raster
        cell of a tile: the footprint's line through q across the cell (see
        :meth:`decided`), the other footprints rho nearer than at the centre."""
        dist, qx, qy, other = self.clearance(tile)
        with np.errstate(divide="ignore", invalid="ignore"):
            slack = np.where(dist > 1e-9, (np.abs(qx) + np.abs(qy)) / dist, 2.0) * (
                0.5 * self.fine_size
            )
        return np.where(
            dist < self.cap, np.minimum(dist - slack, other - self.rho), dist - self.rho
        )

    def sub_states(self, tile: Tile, radius: float) -> tuple[np.ndarray, np.ndarray]:
        """(free, solid) bitfields of the tile's sub-cells (``SUB`` x ``SUB`` per cell; bit b
        of word w for sub-cell 64 w + b, sub-cell index sy * cells * SUB + sx), each (W,)
        uint64: a free sub-cell has no point within ``radius`` of a footprint, a solid one
        no point farther, by the raster's bounds (the rest is neither). Cached per tile and
        radius while the raster stands."""
        of_tile = self._sub.setdefault(tile, {})
        got = of_tile.get(radius)
        if got is None:
            m, k = self.cells * SUB, FINE // SUB
            low = self._lowest(tile).reshape(m, k, m, k).min(axis=(1, 3)).ravel()
            high = self.clearance(tile)[0].reshape(m, k, m, k).max(axis=(1, 3)).ravel() + self.rho
            free = np.packbits(low >= radius + _EPS, bitorder="little").view(np.uint64)
            solid = np.packbits(high < radius - _EPS, bitorder="little").view(np.uint64)
            got = of_tile[radius] = (free, solid)
        return got

    def sub_mask(self, points: np.ndarray) -> np.ndarray:
        """(n, W) uint64 sub-cell bitmasks of point sets (n, M, 2) given in tile
        coordinates (0 .. side): the sub-cells the points lie in (as :meth:`sub_states`)."""
        m = self.cells * SUB
        f = np.clip(np.floor(points / (self.side / m)), 0, m - 1).astype(np.int64)
        index = f[..., 1] * m + f[..., 0]
        bits = np.zeros((points.shape[0], m * m), bool)
        np.put_along_axis(bits, index, True, axis=1)
        return np.packbits(bits, axis=1, bitorder="little").view(np.uint64)

    # -- clearance raster ------------------------------------------------------------------
    def clearance(self, tile: Tile) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The raster of a tile: four (G * G,) arrays (G = cells x ``FINE``; index
        fy * G + fx) holding at each raster cell's centre c the distance to the nearest
        footprint, the offset q - c (x, then y) of that footprint's point q nearest c, and
        the distance to the nearest other footprint (distances capped at the radius +
        ``CLEARANCE_CAP``; where capped the offset means nothing). Lazy; dropped when an
        obstacle near the tile moves."""
        slot = self._slots.get(tile)
        if slot is None:
            slot = self._fill(tile)
        a = self._atlas
        return a[0, slot], a[1, slot], a[2, slot], a[3, slot]

    def _fill(self, tile):
        """Compute a tile's raster into a free slot of the atlas; its slot."""
        g = self.fine
        lo = np.array(tile, float) * self.side
        names = self.names_in_box(lo - self.cap, lo + self.side + self.cap)
        slot = 0
        if names:
            if not self._spare:
                n = self._atlas.shape[1]
                self._atlas = np.concatenate((self._atlas, np.empty_like(self._atlas)), axis=1)
                self._spare = list(range(2 * n - 1, n - 1, -1))
            slot = self._spare.pop()
            d, qx, qy, d2 = (a.reshape(g, g) for a in self._atlas[:, slot])
            d[:], d2[:], qx[:], qy[:] = self.cap, self.cap, 0.0, 0.0
            gx, gy = tile[0] * g, tile[1] * g
            for name in names:
                x0, y0, dist, ox, oy = self._obstacle_raster(name)
                ax, ay = max(x0, gx), max(y0, gy)
                bx, by = min(x0 + dist.shape[1], gx + g), min(y0 + dist.shape[0], gy + g)
                if ax >= bx or ay >= by:
                    continue
                win = (slice(ay - gy, by - gy), slice(ax - gx, bx - gx))
                own = (slice(ay - y0, by - y0), slice(ax - x0, bx - x0))
                do, dw = dist[own], d[win]
                closer = do < dw
                d2[win] = np.where(closer, dw, np.minimum(d2[win], do))
                d[win] = np.where(closer, do, dw)
                qx[win] = np.where(closer, ox[own], qx[win])
                qy[win] = np.where(closer, oy[own], qy[win])
        self._slots[tile] = slot
        gi, gj = self._grid_cell(*tile)
        self._grid[gi, gj] = slot
        return slot

    def _grid_cell(self, i, j):
        """Index of tile (i, j) in the grid of slots, grown to hold it."""
        (i0, j0), (n, m) = self._grid_origin, self._grid.shape
        if not (i0 <= i < i0 + n and j0 <= j < j0 + m):
            ni0, nj0 = min(i0, i - 4), min(j0, j - 4)
            ni1, nj1 = max(i0 + n, i + 5), max(j0 + m, j + 5)
            grid = np.full((ni1 - ni0, nj1 - nj0), -1, np.int64)
            grid[i0 - ni0 : i0 - ni0 + n, j0 - nj0 : j0 - nj0 + m] = self._grid
            self._grid, self._grid_origin = grid, (ni0, nj0)
            i0, j0 = ni0, nj0
        return i - i0, j - j0

    def _obstacle_raster(self, name):
        """(fx0, fy0, distances (h, w), nearest-point offsets x, y (h, w)) of one footprint
        at the raster centres (global raster indices from fx0, fy0) of the box it can come
        within the cap of; distances capped."""
        got = self._ob_raster.get(name)
        if got is None:
            ob, h = self.obstacles[name], self.fine_size
            fx0, fy0 = np.floor((ob.lo - self.cap) / h).astype(int) - 1
            fx1, fy1 = np.floor((ob.hi + self.cap) / h).astype(int) + 1
            xs = (np.arange(fx0, fx1 + 1) + 0.5) * h
            ys = (np.arange(fy0, fy1 + 1) + 0.5) * h
            shape = (ys.size, xs.size)
            centres = np.empty(shape + (2,))
            centres[..., 0], centres[..., 1] = xs[None], ys[:, None]
            centres = centres.reshape(-1, 2)
            d, q = convex_closest(centres, ob.polygon)
            got = self._ob_raster[name] = (
                int(fx0),
                int(fy0),
                np.minimum(d, self.cap).reshape(shape),
                (q[:, 0] - centres[:, 0]).reshape(shape),
                (q[:, 1] - centres[:, 1]).reshape(shape),
            )
        return got

    def _raster_rows(
        self, points: np.ndarray
    ) -> tuple[tuple[np.ndarray, ...], np.ndarray, np.ndarray]:
        """The raster's four values at the cells holding world points (N, 2) (a tuple of
        (N,) arrays), and the points' offsets x, y from those cells' centres."""
        g, h = self.fine, self.fine_size
        fx, fy = np.floor(points[:, 0] / h), np.floor(points[:, 1] / h)
        ox, oy = points[:, 0] - (fx + 0.5) * h, points[:, 1] - (fy + 0.5) * h
        fx, fy = fx.astype(np.int64), fy.astype(np.int64)
        tx, ty = fx // g, fy // g
        local = (fy - ty * g) * g + (fx - tx * g)
        (i0, j0), (n, m) = self._grid_origin, self._grid.shape
        gi, gj = tx - i0, ty - j0
        inside = (gi >= 0) & (gi < n) & (gj >= 0) & (gj < m)
        if inside.all():
            slot = self._grid[gi, gj]
        else:
            slot = np.full(tx.size, -1, np.int64)
            slot[inside] = self._grid[gi[inside], gj[inside]]
        missing = slot < 0
        if missing.any():
            for t in set(zip(tx[missing].tolist(), ty[missing].tolist())):
                self.clearance(t)
            (i0, j0) = self._grid_origin
            slot = self._grid[tx - i0, ty - j0]
        a = self._atlas
        flat = slot * a.shape[2] + local  # one 1-D take per array: cheaper than 2-D indexing
        rows = tuple(a[k].reshape(-1).take(flat) for k in range(4))
        return rows, ox, oy

    def decided(
        self, rows: tuple[np.ndarray, ...], ox: np.ndarray, oy: np.ndarray, radius: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(blocked, unsure) of points at offsets (``ox``, ``oy``) from the centres of raster
        cells whose values are ``rows``, for ``radius``. With q the nearest footprint point
        of the centre c and p the point: |p - q| bounds the distance from above; the
        footprint lies beyond the line through q across c - q (it is convex and q is its
        point nearest c), so the distance of p past that line bounds the distance to it
        from below, and every other footprint is at least its distance from c minus
        |p - c| away. Where the nearest footprint is beyond the cap, the distance at c
        minus |p - c| bounds the distance from below."""
        dist, qx, qy, other = rows
        shift = np.sqrt(ox * ox + oy * oy)
        vx, vy = ox - qx, oy - qy
        near = dist < self.cap
        upper = np.where(near, np.sqrt(vx * vx + vy * vy), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            past = np.where(dist > 1e-9, -(qx * vx + qy * vy) / dist, -np.inf)
        lower = np.where(near, np.minimum(past, other - shift), dist - shift)
        blocked = upper < radius - _EPS
        unsure = ~blocked & (lower < radius + _EPS)
        return blocked, unsure

    def names_in_box(
        self, lo: Sequence[float] | np.ndarray, hi: Sequence[float] | np.ndarray
    ) -> list[str]:
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
        lx, ly, hx, hy = float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])
        obs = self.obstacles
        out = []
        for n in names:
            b = obs[n].box
            if b[0] <= hx and b[1] <= hy and b[2] >= lx and b[3] >= ly:
                out.append(n)
        out.sort()
        return out

    def near(self, xy: Sequence[float] | np.ndarray) -> list[str]:
        """Sorted names of the obstacles a point (x, y) comes within the radius of."""
        p = np.asarray(xy, float)[None, :2]
        return sorted(
            n
            for n in self.members(self.tile_of(p[0]))
            if self.obstacles[n].within(p, self.radius)[0]
        )

    def blocked(
        self, points: np.ndarray, exclude: Collection[str] = (), radius: float | None = None
    ) -> np.ndarray:
        """(N,) True where world points come within the radius (or ``radius``, at most a
        tile side more) of any obstacle but those named in ``exclude``. Many points
        (``RASTER_MIN_POINTS`` or more) go through the clearance raster first; the answer
        is the exact test's either way. With ``exclude`` (the raster holds every
        footprint, so it can only clear points) the footprints near the points are looked
        up first: with none but the excluded ones there, every point is clear."""
        points = np.atleast_2d(np.asarray(points, float))
        radius = self.radius if radius is None else float(radius)
        if exclude and len(points):
            x, y = points[:, 0], points[:, 1]  # 1-D reductions: far cheaper than axis=0 ones
            lo = (float(x.min()) - radius, float(y.min()) - radius)
            hi = (float(x.max()) + radius, float(y.max()) + radius)
            if all(math.isfinite(v) for v in (*lo, *hi)) and all(
                n in exclude for n in self.names_in_box(lo, hi)
            ):
                return np.zeros(len(points), bool)
        if (
            len(points) >= RASTER_MIN_POINTS
            and self.obstacles
            and radius + self.rho <= self.cap
            and self._rasterable(points)
        ):
            out, unsure = self.decided(*self._raster_rows(points), radius)
            if exclude:  # the raster holds every footprint: it can only clear a point
                unsure |= out
                out[:] = False
            if unsure.any():
                out[unsure] = self._blocked_exact(points[unsure], exclude, radius)
            return out
        return self._blocked_exact(points, exclude, radius)

    def _rasterable(self, points):
        """The points are finite and span few enough tiles for the raster's grid of slots
        (a handful of far-flung points is cheaper to test exactly)."""
        x, y = points[:, 0], points[:, 1]  # 1-D reductions: far cheaper than axis=0 ones
        lox, hix, loy, hiy = float(x.min()), float(x.max()), float(y.min()), float(y.max())
        if not all(math.isfinite(v) for v in (lox, hix, loy, hiy)):  # NaN spreads to min/max
            return False
        (i0, j0), (n, m) = self._grid_origin, self._grid.shape
        side = self.side
        sx = (max(hix, (i0 + n) * side) - min(lox, i0 * side)) / side
        sy = (max(hiy, (j0 + m) * side) - min(loy, j0 * side)) / side
        return sx * sy < MAX_RASTER_TILES

    def _blocked_exact(self, points, exclude, radius):
        """:meth:`blocked` by the footprints themselves (bounding boxes, then distances)."""
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
        box = np.all(points[:, None] > lo[idx][None] - radius, axis=-1) & np.all(
            points[:, None] < hi[idx][None] + radius, axis=-1
        )
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
                verts[i, : len(poly)] = poly
                verts[i, len(poly) :] = poly[-1]
            self._pack = (
                {n: i for i, n in enumerate(names)},
                np.array([self.obstacles[n].lo for n in names]).reshape(-1, 2),
                np.array([self.obstacles[n].hi for n in names]).reshape(-1, 2),
                verts,
            )
        return self._pack

    def path_blocked(self, paths: np.ndarray) -> np.ndarray:
        """(n,) True where sampled paths (n, M, 2) come within the radius of an obstacle
        anywhere between samples, to the precision of their sampling: every sample is
        tested ``PATH_MARGIN`` wider (the samples are the caller's to keep close: about
        4 cm apart for the planner's curves)."""
        n, m = paths.shape[:2]
        hit = self.blocked(paths.reshape(-1, 2), radius=self.radius + PATH_MARGIN)
        return hit.reshape(n, m).any(axis=1)

    def tile_paths_blocked(
        self, tile: Tile, paths: np.ndarray, index: np.ndarray, ox: np.ndarray, oy: np.ndarray
    ) -> np.ndarray:
        """:meth:`path_blocked` of paths (n, M, 2) lying in one tile, given the raster index
        (n, M) of each sample within the tile (fy * G + fx) and its offset x, y from that
        raster cell's centre (n, M each): the planner's segments, whose samples are fixed
        in the patch."""
        n, m = index.shape
        flat = index.ravel()
        blocked, unsure = self.decided(
            tuple(a[flat] for a in self.clearance(tile)),
            ox.ravel(),
            oy.ravel(),
            self.radius + PATH_MARGIN,
        )
        blocked, unsure = blocked.reshape(n, m), unsure.reshape(n, m)
        hit = blocked.any(axis=1)
        rows = ~hit & unsure.any(axis=1)
        if rows.any():
            sel = unsure & rows[:, None]
            exact = self._blocked_exact(paths[sel], (), self.radius + PATH_MARGIN)
            owner = np.nonzero(sel)[0]
            hit[np.unique(owner[exact])] = True
        return hit
