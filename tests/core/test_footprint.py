# SPDX-License-Identifier: GPL-3.0-or-later
"""Footprints of meshes as a user models them: thin walls block, rooms stay open."""

import numpy as np

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
