# SPDX-License-Identifier: GPL-3.0-or-later
"""Footprints of meshes as a user models them: thin walls block, rooms stay open."""

import numpy as np
import pytest

from motion_patches.props import footprint as fp
from motion_patches.props.environment import Environment, Obstacle


def prism(outline, z0, z1, cap_tris, caps=True):
    """Triangles of an extruded outline (K, 2) from z0 to z1: side quads as two triangles
    each, caps from ``cap_tris`` (index triples into the outline). Returns the mesh as
    (vertices, face_vertex, face_start, face_total)."""
    k = len(outline)
    v = np.vstack(
        (np.column_stack((outline, np.full(k, z0))), np.column_stack((outline, np.full(k, z1))))
    )
    tris = []
    for i in range(k):
        j = (i + 1) % k
        tris += [(i, j, k + j), (i, k + j, k + i)]
    if caps:
        tris += [tuple(t[::-1]) for t in cap_tris] + [tuple(np.add(t, k)) for t in cap_tris]
    return mesh(v, tris)


def mesh(v, faces):
    fv = np.concatenate([np.asarray(f) for f in faces]) if faces else np.zeros(0, int)
    total = np.array([len(f) for f in faces], int)
    start = np.concatenate(([0], np.cumsum(total)[:-1])) if faces else np.zeros(0, int)
    return np.asarray(v, float), fv, start, total


def box(x0, y0, x1, y1, z0=0.0, z1=2.0):
    return prism(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]), z0, z1, [(0, 1, 2), (0, 2, 3)])


def env_of(polys, radius=0.25):
    env = Environment(2.0, 8, radius)
    for k, p in enumerate(polys):
        env.place(Obstacle(f"part {k}", p))
    return env


def test_a_box_is_its_convex_hull():
    parts = fp.parts(*box(0, 0, 1, 2))
    assert len(parts) == 1
    assert np.isclose(fp.area(parts[0]), 2.0)


def test_a_vertical_plane_wall_is_a_board_of_the_minimum_thickness():
    # A 4 m long, 2 m high plane: one quad standing on the ground along x.
    v = [(0, 0, 0), (4, 0, 0), (4, 0, 2), (0, 0, 2)]
    parts = fp.parts(*mesh(v, [(0, 1, 2, 3)]))
    assert len(parts) == 1
    assert np.isclose(fp.width(parts[0]), fp.MIN_THICKNESS)
    env = env_of(parts)
    # Points on either side of the wall are free; the wall's line is blocked along its length.
    assert not env.blocked(np.array([[2.0, 1.0], [2.0, -1.0]])).any()
    assert env.blocked(np.array([[x, 0.0] for x in np.linspace(0, 4, 41)])).all()


def test_a_line_of_loose_vertices_blocks_along_the_line():
    v = [(x, 1.0, 1.0) for x in np.linspace(0, 3, 7)]
    parts = fp.parts(np.array(v))
    assert len(parts) == 1
    assert np.isclose(fp.width(parts[0]), fp.MIN_THICKNESS)
    assert env_of(parts).blocked(np.array([[1.25, 1.0]]))[0]


def test_an_l_shaped_wall_leaves_its_inner_corner_open():
    ell = np.array([[0, 0], [3, 0], [3, 0.2], [0.2, 0.2], [0.2, 3], [0, 3]], float)
    parts = fp.parts(*prism(ell, 0, 2, [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)]))
    assert len(parts) > 1
    env = env_of(parts)
    assert not env.blocked(np.array([[2.0, 2.0]]))[0]  # the hull's corner, open ground
    assert env.blocked(np.array([[1.5, 0.1], [0.1, 1.5]])).all()


def room_of_planes(door=True):
    """Four 2 m high plane walls of a 6 x 4 m room joined at the corners, one mesh; the
    front wall has a 1.2 m door from x = 2.4 to 3.6 (two quads beside it)."""
    corners = [(0, 0), (6, 0), (6, 4), (0, 4)]
    v = [(x, y, z) for x, y in corners for z in (0.0, 2.0)]  # 2k: bottom, 2k + 1: top
    faces = [(2, 4, 5, 3), (4, 6, 7, 5), (6, 0, 1, 7)]  # right, back, left walls
    if door:
        v += [(2.4, 0, 0), (2.4, 0, 2), (3.6, 0, 0), (3.6, 0, 2)]  # 8, 9, 10, 11
        faces += [(0, 8, 9, 1), (10, 2, 3, 11)]
    else:
        faces += [(0, 2, 3, 1)]
    return mesh(v, faces)


def test_a_room_of_four_walls_as_one_mesh_is_open_inside():
    parts = fp.parts(*room_of_planes())
    assert len(parts) == 5
    env = env_of(parts)
    assert not env.blocked(np.array([[3.0, 2.0], [3.0, 0.0]])).any()  # inside; the door
    assert env.blocked(np.array([[1.0, 0.0], [6.0, 2.0], [3.0, 4.0]])).all()


def test_a_floor_joined_to_the_walls_does_not_fill_the_room():
    v, fv, fs, ft = room_of_planes()
    faces = [tuple(fv[s : s + t]) for s, t in zip(fs, ft)] + [(0, 2, 4, 6)]  # the floor
    parts = fp.parts(*mesh(v, faces))
    assert not env_of(parts).blocked(np.array([[3.0, 2.0]]))[0]


def test_a_closed_tall_box_keeps_its_inside_blocked():
    # 3 m high: both caps are outside the body band, yet the solid's plan is the hull.
    parts = fp.parts(*box(0, 0, 4, 4, 0.0, 3.0))
    assert len(parts) == 1
    assert env_of(parts).blocked(np.array([[2.0, 2.0]]))[0]


def test_meshes_under_or_over_the_body_band_are_no_obstacles():
    assert fp.parts(*box(0, 0, 5, 5, -0.1, 0.0)) == []  # a floor slab
    assert fp.parts(*box(0, 0, 5, 5, 2.5, 2.7)) == []  # a ceiling


def test_separate_islands_are_separate_parts():
    a, b = box(0, 0, 1, 1), box(3, 0, 4, 1)
    v = np.vstack((a[0], b[0]))
    parts = fp.parts(
        v,
        np.concatenate((a[1], b[1] + len(a[0]))),
        np.concatenate((a[2], b[2] + len(a[1]))),
        np.concatenate((a[3], b[3])),
    )
    assert len(parts) == 2
    assert not env_of(parts).blocked(np.array([[2.0, 0.5]]))[0]


def test_a_finely_divided_room_is_grouped_into_at_most_the_cell_count():
    # 8 x 8 m room of plane walls, each wall split into 200 quads: 800 faces, grouped.
    faces, v = [], []
    for (x0, y0), (x1, y1) in (
        ((0, 0), (8, 0)),
        ((8, 0), (8, 8)),
        ((8, 8), (0, 8)),
        ((0, 8), (0, 0)),
    ):
        for t0, t1 in zip(np.linspace(0, 1, 201)[:-1], np.linspace(0, 1, 201)[1:]):
            k = len(v)
            a = (x0 + (x1 - x0) * t0, y0 + (y1 - y0) * t0)
            b = (x0 + (x1 - x0) * t1, y0 + (y1 - y0) * t1)
            v += [(*a, 0.0), (*b, 0.0), (*b, 2.0), (*a, 2.0)]
            faces.append((k, k + 1, k + 2, k + 3))
    m = mesh(v, faces)
    # The quads do not share vertices: join them as one island by edges along the walls.
    edges = np.array([(4 * i + 1, 4 * (i + 1)) for i in range(len(faces) - 1)])
    parts = fp.parts(*m, edges=edges)
    assert 4 <= len(parts) <= (fp.GROUP_CELLS + 1) ** 2
    env = env_of(parts)
    assert not env.blocked(np.array([[4.0, 4.0]]))[0]
    assert env.blocked(np.array([[4.0, 0.0], [8.0, 4.0]])).all()


def test_outline_of_nothing_is_none_and_of_a_point_a_small_square():
    assert fp.outline(np.zeros((0, 2))) is None
    sq = fp.outline(np.array([[1.0, 1.0]]))
    assert len(sq) == 4 and np.isclose(fp.area(sq), fp.MIN_THICKNESS**2)


# -- the hull fast path against the rule as it was --------------------------------------------


def parts_before(vertices, fv=(), fs=(), ft=(), edges=(), band=fp.BODY_BAND):
    """:func:`fp.parts` as it was before islands were grouped by one sort and a hull bounded
    by its faces was taken without sampling the cover: the reference the new code must
    match, polygon for polygon."""
    v = np.asarray(vertices, float).reshape(-1, 3)
    n = len(v)
    fv = np.asarray(fv, np.int64).ravel()
    fs = np.asarray(fs, np.int64).ravel()
    ft = np.asarray(ft, np.int64).ravel()
    first = np.repeat(fs, ft)
    ed = np.asarray(edges, np.int64).reshape(-1, 2)
    pairs = [np.column_stack((fv[first], fv)), ed]
    used = np.zeros(n, bool)
    used[fv] = True
    used[ed.ravel()] = True
    loose = np.flatnonzero(~used)
    if len(loose) > 1:
        pairs.append(np.column_stack((np.full(len(loose) - 1, loose[0]), loose[1:])))
    label = fp._components(n, np.concatenate(pairs))
    z = v[:, 2]
    zmin = np.minimum.reduceat(z[fv], fs) if len(fs) else np.zeros(0)
    zmax = np.maximum.reduceat(z[fv], fs) if len(fs) else np.zeros(0)
    open_islands = set()
    if len(fs):
        pos = np.arange(len(fv)) - first
        nxt = fv[first + (pos + 1) % np.repeat(ft, ft)]
        e = np.sort(np.column_stack((fv, nxt)), axis=1)
        _, inverse, counts = np.unique(e, axis=0, return_inverse=True, return_counts=True)
        open_islands = set(label[e[counts[inverse.ravel()] != 2, 0]].tolist())
    in_band_face = (zmax >= band[0]) & (zmin <= band[1])
    out = []
    for isl in np.unique(label):
        verts = np.flatnonzero(label == isl)
        if z[verts].max() < band[0] or z[verts].min() > band[1]:
            continue
        faces = np.flatnonzero(label[fv[fs]] == isl) if len(fs) else np.zeros(0, np.int64)
        if isl in open_islands:
            faces = faces[in_band_face[faces]]
        if len(faces):
            elements = [fv[fs[f] : fs[f] + ft[f]] for f in faces]
        else:
            elements = [verts[(z[verts] >= band[0]) & (z[verts] <= band[1])]]
            if not len(elements[0]):
                elements = [verts]
        xy = v[:, :2]
        hull = fp.outline(xy[np.concatenate(elements)])
        if len(elements) == 1:
            out.append(hull)
            continue
        if len(elements) > fp.MAX_PARTS:
            lo, hi = hull.min(axis=0), hull.max(axis=0)
            cell = np.maximum((hi - lo) / fp.GROUP_CELLS, 1e-6)
            centre = np.array([xy[e].mean(axis=0) for e in elements])
            key = np.floor((centre - lo) / cell).astype(np.int64)
            key = key[:, 0] * (fp.GROUP_CELLS + 1) + key[:, 1]
            elements = [
                np.concatenate([elements[i] for i in np.flatnonzero(key == k)])
                for k in np.unique(key)
            ]
        polys = [fp.outline(xy[e]) for e in elements]
        out += [hull] if fp._covered(polys, hull) else polys
    return out


def cylinder(sides=32, r=0.25, z0=0.0, z1=2.0, x=0.0, y=0.0):
    """Blender's cylinder: ``sides`` quads round, each cap one n-gon (triangulated as a fan,
    as Blender's loop triangles are)."""
    a = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    ring = np.column_stack((x + r * np.cos(a), y + r * np.sin(a)))
    return prism(ring, z0, z1, [(0, i, i + 1) for i in range(1, sides - 1)])


def l_prism(x=0.0, y=0.0):
    ell = np.array([[0, 0], [3, 0], [3, 0.2], [0.2, 0.2], [0.2, 3], [0, 3]], float) + (x, y)
    return prism(ell, 0, 2, [(0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)])


def joined(*meshes):
    """One mesh of several (its islands)."""
    v, fv, fs, ft, shift, offset = [], [], [], [], 0, 0
    for mv, mfv, mfs, mft in meshes:
        v.append(mv)
        fv.append(mfv + shift)
        fs.append(mfs + offset)
        ft.append(mft)
        shift, offset = shift + len(mv), offset + len(mfv)
    return np.vstack(v), np.concatenate(fv), np.concatenate(fs), np.concatenate(ft)


def placed(m, turn=0.0, scale=(1.0, 1.0, 1.0), tilt=(0.0, 0.0), at=(0.0, 0.0, 0.0)):
    """The mesh as an object's matrix puts it in the world: scaled, tilted about x then y,
    turned about z, moved."""
    c, s = np.cos(turn), np.sin(turn)
    cx, sx, cy, sy = np.cos(tilt[0]), np.sin(tilt[0]), np.cos(tilt[1]), np.sin(tilt[1])
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return (m[0] * scale) @ (rz @ ry @ rx).T + at, *m[1:]


def flipped(m):
    """The mesh with every face's winding reversed (normals pointing in)."""
    v, fv, fs, ft = m
    return v, np.concatenate([fv[a : a + t][::-1] for a, t in zip(fs, ft)]), fs, ft


MESHES = {
    "box": box(0, 0, 1, 2),
    "cylinder": cylinder(),
    "cylinder, n-gon caps": (
        lambda v, fv, fs, ft: mesh(
            v,
            [tuple(fv[a : a + t]) for a, t in zip(fs, ft)][: 2 * 32]
            + [tuple(range(31, -1, -1)), tuple(range(32, 64))],
        )
    )(*cylinder()),
    "cylinder of 200 sides (grouped)": cylinder(200, r=1.0),
    "tall closed box (caps out of the band)": box(0, 0, 4, 4, 0.0, 3.0),
    "box, normals in": flipped(box(0, 0, 1, 2)),
    "open tube (no caps)": prism(cylinder()[0][:32, :2], 0.0, 2.0, [], caps=False),
    "L-shaped wall": l_prism(),
    "room of planes": room_of_planes(),
    "two boxes": joined(box(0, 0, 1, 1), box(3, 0, 4, 1)),
    "a box and an L": joined(box(-3, -3, -2, -2), l_prism(1, 1)),
    "cylinder turned and scaled": placed(cylinder(), 0.7, (1.5, 0.4, 1.1), at=(3, -2, 0)),
    "box turned, scaled and tilted": placed(box(0, 0, 1, 2), 0.3, (2.0, 0.5, 1.0), (0.4, 0.2)),
    "box tilted about x": placed(box(0, 0, 1, 2), 0.3, tilt=(0.4, 0.0)),
    # the top cut in two: its boundary has a corner on the hull's edges, where the hull has none
    "box, top in two halves": mesh(
        [(0, 0, 0), (1, 0, 0), (1, 2, 0), (0, 2, 0), (0, 0, 2), (0.5, 0, 2), (1, 0, 2)]
        + [(1, 2, 2), (0.5, 2, 2), (0, 2, 2)],
        [(0, 3, 2, 1), (4, 5, 8, 9), (5, 6, 7, 8), (0, 1, 6, 5, 4), (1, 2, 7, 6)]
        + [(2, 3, 9, 8, 7), (3, 0, 4, 9)],
    ),
    "L turned and scaled": placed(l_prism(), -1.1, (0.8, 1.3, 1.0), at=(-1, 4, 0)),
    "cylinder tilted on its side": placed(
        cylinder(r=0.5), 0.2, tilt=(np.pi / 2, 0.0), at=(0, 0, 0.6)
    ),
}


@pytest.mark.parametrize("name", list(MESHES))
def test_footprints_are_the_polygons_the_rule_made_before(name):
    got = fp.parts(*MESHES[name])
    want = parts_before(*MESHES[name])
    assert len(got) == len(want) > 0
    for g, w in zip(got, want):
        np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize(
    "name, sampled",
    [
        ("box", False),
        ("cylinder", False),
        ("cylinder, n-gon caps", False),
        ("cylinder of 200 sides (grouped)", False),
        ("box, normals in", False),
        ("cylinder turned and scaled", False),
        ("box turned, scaled and tilted", False),
        ("two boxes", False),
        ("box tilted about x", False),
        ("box, top in two halves", True),
        ("L-shaped wall", True),
        ("a box and an L", True),
    ],
)
def test_a_convex_solid_is_its_hull_without_sampling_the_cover(monkeypatch, name, sampled):
    calls = []
    covered = fp._covered
    monkeypatch.setattr(fp, "_covered", lambda *a: calls.append(1) or covered(*a))
    fp.parts(*MESHES[name])
    assert bool(calls) == sampled


def test_random_prisms_convex_or_not_keep_their_footprints(monkeypatch):
    """Prisms on random outlines (convex ones, and stars: concave), each placed by a
    random matrix: the same polygons as before, the cover sampled for none of the convex."""
    rng = np.random.default_rng(3)
    calls, sampled = [], []
    covered = fp._covered
    monkeypatch.setattr(fp, "_covered", lambda *a: calls.append(1) or covered(*a))
    for k in range(40):
        n = int(rng.integers(3, 24))
        a = np.sort(rng.uniform(0.0, 2 * np.pi, n))
        r = rng.uniform(0.2, 1.5) * (1.0 if k % 2 else rng.uniform(0.4, 1.0, n))
        ring = np.column_stack((r * np.cos(a), r * np.sin(a)))
        m = prism(ring, 0.0, rng.uniform(0.3, 2.5), [(0, i, i + 1) for i in range(1, n - 1)])
        m = placed(m, rng.uniform(-3, 3), rng.uniform(0.3, 2.0, 3), rng.uniform(-0.5, 0.5, 2))
        calls.clear()
        got = fp.parts(*m)
        sampled += [k] if calls else []
        want = parts_before(*m)
        assert len(got) == len(want)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)
    assert not [k for k in sampled if k % 2] and len(sampled) >= 10
