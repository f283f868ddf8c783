# SPDX-License-Identifier: GPL-3.0-or-later
"""Footprints: what a mesh covers on the ground, as the convex polygons the planner needs.

The environment tests points and cells against *convex* polygons (:mod:`.environment`). A
mesh is turned into them here, one rule for every caller (obstacles of the scene, tagged
props, the Object Patch panel):

* **Thin shapes block.** A hull narrower than ``MIN_THICKNESS`` (a vertical plane is a
  segment in plan, a vertical line of vertices a point) is grown by a square of that side
  (:func:`outline`), so a wall modelled as a plane blocks as a 2 cm board would.
* **Non-convex meshes block by their outline.** A mesh is split into islands (vertices
  joined by faces or edges). An island whose faces, projected on the ground, cover its
  convex hull (a box, a cylinder, a chair) is that hull. Any other island (an L-shaped wall,
  the four walls of a room as one mesh) is the projections of its faces, each its own convex
  part, so the inside of an open room stays open. Parts are grouped by ground cells of
  ``GROUP_CELLS`` per island side when an island has more than ``MAX_PARTS`` faces (a cell's
  faces then make one hull: concavities smaller than a cell are filled).
* **What the body meets.** Islands entirely below or above the body band are left out
  (floors, ceilings, lamps overhead). Within an open island (not watertight), faces
  entirely outside the band are left out too (a floor face joined to the walls of a room);
  a watertight island keeps its caps, as its projection is the solid's.

Never imports bpy.
"""

import numpy as np
from numpy.typing import ArrayLike

from .environment import convex_hull, distance_to_polygon

BODY_BAND = (0.05, 1.8)  # metres above the ground: what a walking body overlaps
MIN_THICKNESS = 0.02  # metres: the least width of a footprint (a plane wall's board)
MAX_PARTS = 400  # faces of one island above which parts are grouped by cells
GROUP_CELLS = 16  # cells per side of an island's bounding box when grouping
COVER_SAMPLES = 32  # samples per side of an island's hull in the convexity test


def outline(points: ArrayLike, thickness: float = MIN_THICKNESS) -> np.ndarray | None:
    """Counter-clockwise convex polygon (P >= 3, 2) holding plan points (N, 2), at least
    ``thickness`` wide (a segment or a point is grown by a square of that side); None
    when there are no points."""
    pts = np.asarray(points, float).reshape(-1, 2)
    if not len(pts):
        return None
    hull = convex_hull(pts)
    if len(hull) >= 3 and width(hull) >= thickness:
        return hull
    h = thickness / 2
    square = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    return convex_hull((hull[:, None, :] + square[None]).reshape(-1, 2))


def width(polygon: np.ndarray) -> float:
    """Least width of a convex polygon: over its edges, the farthest vertex from the edge's
    line (rotating calipers' answer, by brute force: polygons here are small)."""
    a = np.asarray(polygon, float)
    e = np.roll(a, -1, axis=0) - a
    length = np.hypot(e[:, 0], e[:, 1])
    keep = length > 1e-12
    if keep.sum() < 2:
        return 0.0
    e, a0, length = e[keep], a[keep], length[keep]
    d = (
        np.abs(
            e[:, None, 0] * (a[None, :, 1] - a0[:, None, 1])
            - e[:, None, 1] * (a[None, :, 0] - a0[:, None, 0])
        )
        / length[:, None]
    )
    return float(d.max(axis=1).min())


def area(polygon: np.ndarray) -> float:
    """Area (m²) of a polygon (shoelace)."""
    if polygon is None or len(polygon) < 3:
        return 0.0
    x, y = polygon[:, 0], polygon[:, 1]
    return float(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2)


def _components(n, pairs):
    """Island label (the smallest vertex index of its island) of each of ``n`` vertices
    joined by index ``pairs`` (K, 2): minimum labels propagated along the pairs, with
    pointer jumping, until they settle."""
    labels = np.arange(n)
    if not len(pairs):
        return labels
    a, b = pairs[:, 0], pairs[:, 1]
    while True:
        m = np.minimum(labels[a], labels[b])
        new = labels.copy()
        np.minimum.at(new, a, m)
        np.minimum.at(new, b, m)
        while True:
            jumped = new[new]
            if np.array_equal(jumped, new):
                break
            new = jumped
        if np.array_equal(new, labels):
            return labels
        labels = new


def _covered(polys, hull):
    """True when the polygons ``polys`` cover the convex ``hull`` to within one sample
    spacing (``COVER_SAMPLES`` per side of its bounding box)."""
    lo, hi = hull.min(axis=0), hull.max(axis=0)
    step = max(float((hi - lo).max()) / COVER_SAMPLES, 1e-3)
    xs = np.arange(lo[0] + step / 2, hi[0], step)
    ys = np.arange(lo[1] + step / 2, hi[1], step)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack((gx.ravel(), gy.ravel()))
    pts = pts[distance_to_polygon(pts, hull) <= 0.0]
    for poly in sorted(polys, key=area, reverse=True):
        if not len(pts):
            return True
        plo, phi = poly.min(axis=0) - step, poly.max(axis=0) + step
        near = np.all((pts >= plo) & (pts <= phi), axis=1)
        if near.any():
            hit = np.zeros(len(pts), bool)
            hit[near] = distance_to_polygon(pts[near], poly) <= step
            pts = pts[~hit]
    return not len(pts)


def parts(
    vertices: ArrayLike,
    face_vertex: ArrayLike = (),
    face_start: ArrayLike = (),
    face_total: ArrayLike = (),
    edges: ArrayLike = (),
    band: tuple[float, float] = BODY_BAND,
) -> list[np.ndarray]:
    """Convex parts [(P, 2)] of a mesh given in world space: ``vertices`` (N, 3), faces as
    flat vertex indices ``face_vertex`` with each face's ``face_start`` and ``face_total``,
    ``edges`` (E, 2) vertex index pairs (loose edges join islands; face edges may be
    given too). See the module docstring for the rule; [] when nothing is in the band."""
    v = np.asarray(vertices, float).reshape(-1, 3)
    n = len(v)
    if not n:
        return []
    fv = np.asarray(face_vertex, np.int64).ravel()
    fs = np.asarray(face_start, np.int64).ravel()
    ft = np.asarray(face_total, np.int64).ravel()
    first = np.repeat(fs, ft)
    pairs = [np.column_stack((fv[first], fv))]
    ed = np.asarray(edges, np.int64).reshape(-1, 2)
    pairs.append(ed)
    used = np.zeros(n, bool)
    used[fv] = True
    used[ed.ravel()] = True
    loose = np.flatnonzero(~used)
    if len(loose) > 1:  # loose vertices (no edge, no face) are one island: a line of them
        pairs.append(np.column_stack((np.full(len(loose) - 1, loose[0]), loose[1:])))
    label = _components(n, np.concatenate(pairs))
    z = v[:, 2]
    # Per face: z range, its island; an edge counted twice in a watertight island.
    zmin = np.minimum.reduceat(z[fv], fs) if len(fs) else np.zeros(0)
    zmax = np.maximum.reduceat(z[fv], fs) if len(fs) else np.zeros(0)
    open_islands = set()
    if len(fs):
        pos = np.arange(len(fv)) - first
        nxt = fv[first + (pos + 1) % np.repeat(ft, ft)]
        e = np.sort(np.column_stack((fv, nxt)), axis=1)
        # each edge as one integer (rows compared whole): unique on them is a plain sort
        _, inverse, counts = np.unique(
            e[:, 0] * n + e[:, 1], return_inverse=True, return_counts=True
        )
        bad = counts[inverse.ravel()] != 2
        open_islands = set(label[e[bad, 0]].tolist())
    in_band_face = (zmax >= band[0]) & (zmin <= band[1])
    # Islands in label order; each one's vertices and faces in index order (one sort each).
    vorder = np.argsort(label, kind="stable")
    islands, vfirst = np.unique(label[vorder], return_index=True)
    vbounds = np.append(vfirst, n)
    top = np.maximum.reduceat(z[vorder], vfirst)
    bottom = np.minimum.reduceat(z[vorder], vfirst)
    face_island = label[fv[fs]] if len(fs) else np.zeros(0, np.int64)
    forder = np.argsort(face_island, kind="stable")
    fbounds = np.searchsorted(face_island[forder], np.append(islands, n))
    out = []
    for k, isl in enumerate(islands):
        if top[k] < band[0] or bottom[k] > band[1]:
            continue
        verts = vorder[vbounds[k] : vbounds[k + 1]]
        faces = forder[fbounds[k] : fbounds[k + 1]]
        if isl in open_islands:
            faces = faces[in_band_face[faces]]
        if len(faces):
            elements = [fv[fs[f] : fs[f] + ft[f]] for f in faces]
        else:  # edges or loose vertices only: the band's vertices
            elements = [verts[(z[verts] >= band[0]) & (z[verts] <= band[1])]]
            if not len(elements[0]):
                elements = [verts]
        out += _island_parts(v[:, :2], elements)
    return out


def _island_parts(xy, elements):
    """Convex parts of one island whose elements (faces) are vertex index arrays."""
    hull = outline(xy[np.concatenate(elements)])
    if len(elements) == 1 or _bounds_hull(xy, elements, hull):
        return [hull]
    if len(elements) > MAX_PARTS:
        lo, hi = hull.min(axis=0), hull.max(axis=0)
        cell = np.maximum((hi - lo) / GROUP_CELLS, 1e-6)
        centre = np.array([xy[e].mean(axis=0) for e in elements])
        key = np.floor((centre - lo) / cell).astype(np.int64)
        key = key[:, 0] * (GROUP_CELLS + 1) + key[:, 1]
        elements = [
            np.concatenate([elements[i] for i in np.flatnonzero(key == k)]) for k in np.unique(key)
        ]
    polys = [outline(xy[e]) for e in elements]
    if _covered(polys, hull):
        return [hull]
    return polys


def _bounds_hull(xy, elements, hull):
    """True when the faces that wind counter-clockwise in plan (``elements``: vertex index
    loops) join into exactly the hull's boundary, each hull edge once: a convex solid's
    upper faces (a box's top, a cylinder's cap). Then their plan covers the hull, and the
    island is its hull without outlining each face and sampling the cover (:func:`_covered`).

    Why that is the general rule's answer: winding numbers add over edge chains. The faces'
    boundaries summed, an edge walked both ways cancelling, are the hull's boundary, which
    winds once round every point inside the hull; so every such point has a face winding
    round it, and lies in that face's outline. :func:`_covered` then finds every sample
    covered and the general rule returns the hull too. Edges are matched on plan positions
    (vertices one above the other are one point; a vertical face adds nothing) and compared
    with the hull's corners as :func:`..environment.convex_hull` rounds them; anything else
    (collinear points on the boundary, a grown thin hull, a concave island) answers False
    and the general rule decides."""
    flat = np.concatenate(elements)
    sizes = np.array([len(e) for e in elements])
    if not len(flat) or sizes.min() < 3:
        return False
    starts = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    after = np.arange(1, len(flat) + 1)
    after[starts + sizes - 1] = starts  # each loop closes on its first vertex
    p, q = xy[flat], xy[flat[after]]
    twice_area = np.add.reduceat(p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0], starts)
    ccw = np.repeat(twice_area > 0, sizes)
    # plan positions as complex numbers: unique on them sorts by x then y, as on rows
    points, ids = np.unique(p[:, 0] + 1j * p[:, 1], return_inverse=True)
    points, ids = np.column_stack((points.real, points.imag)), ids.reshape(-1)
    a, b = ids[ccw], ids[after][ccw]
    a, b = a[a != b], b[a != b]
    if not len(a):
        return False
    m = len(points)
    keys, counts = np.unique(a * m + b, return_counts=True)
    rev = (keys % m) * m + keys // m  # the same edge walked the other way
    at = np.minimum(np.searchsorted(keys, rev), len(keys) - 1)
    net = counts - np.where(keys[at] == rev, counts[at], 0)
    left = keys[net > 0]
    if (net > 1).any() or len(left) != len(hull):
        return False
    corner = {tuple(c): i for i, c in enumerate(hull.tolist())}
    rounded = points.round(9).tolist()
    src = [corner.get(tuple(rounded[k // m]), -1) for k in left]
    dst = [corner.get(tuple(rounded[k % m]), -1) for k in left]
    h = len(hull)
    return (
        min(src + dst) >= 0
        and len(set(src)) == h
        and all(d == (s + 1) % h for s, d in zip(src, dst))
    )
