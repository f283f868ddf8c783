# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene objects -> core obstacles, and goal/start states of objects.

A mesh object blocks walking where its evaluated geometry overlaps the body's height band
(0.05 m to 1.8 m above the ground): floors and ceilings do not. Its footprint is made of
convex parts by :func:`motion_patches.props.footprint.parts` (thin walls grown to a board, open
rooms kept open); an object of several parts gives one obstacle per part, named
:func:`part_name`.
"""

import hashlib
import re
from collections import OrderedDict
from itertools import chain

import numpy as np

from ..motion_patches.props import footprint as fp
from ..motion_patches.props.environment import Environment, Obstacle
from . import bodies
from . import rig as rig_io

BODY_BAND = fp.BODY_BAND
_PART = re.compile(r" \(part \d+\)$")


def mesh_arrays(obj, depsgraph, with_xy=True):
    """(world vertices (N, 3), triangle vertex indices (3T,), edges (E, 2)) of a mesh
    object's evaluated geometry (modifiers applied): what :mod:`motion_patches.props.footprint`
    reads. Triangles, not polygons: every face part is then convex in plan. ``with_xy``
    False: the world matrix's x, y translation left out (its height kept)."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        # Read in Blender's own types (float32, int32): foreach_get then copies the buffer
        # at once instead of converting item by item (the vertices 3x faster).
        n = len(mesh.vertices)
        co = np.empty(n * 3, np.float32)
        mesh.vertices.foreach_get("co", co)
        mesh.calc_loop_triangles()
        tris = np.empty(len(mesh.loop_triangles) * 3, np.int32)
        mesh.loop_triangles.foreach_get("vertices", tris)
        edges = np.empty(len(mesh.edges) * 2, np.int32)
        mesh.edges.foreach_get("vertices", edges)
    finally:
        ev.to_mesh_clear()
    m = matrix_array(ev.matrix_world)
    offset = m[:3, 3] if with_xy else np.array([0.0, 0.0, m[2, 3]])
    world = co.astype(float).reshape(n, 3) @ m[:3, :3].T + offset
    return world, tris.astype(np.int64), edges.astype(np.int64).reshape(-1, 2)


def matrix_array(matrix):
    """A 4x4 mathutils matrix as a float array (row by row: a quarter of ``np.array``'s
    time, which reads it through the sequence protocol)."""
    return np.fromiter(chain.from_iterable(matrix), float, 16).reshape(4, 4)


SHAPES_KEPT = 4096  # footprints of this many shapes are kept (a few kB each)
_shapes: OrderedDict = OrderedDict()  # shape key -> parts about the object's own x, y
_placed: dict = {}  # object name -> (shape key, x, y, world parts): the last footprint made


def footprint_parts(obj, depsgraph, band=BODY_BAND):
    """Convex world footprint parts [(P, 2)] of a mesh object ([] when it blocks nothing).

    Hulling a footprint costs tens of milliseconds for a cylinder, and a layout check asks
    for every prop's after each edit of one of them. The parts are made about the object's
    own x, y (its translation taken off) and kept under a key of the evaluated geometry
    (vertices as the matrix's rotation, scale and height place them, triangles, edges):
    any edit of the mesh, its modifiers or its matrix other than a move on the ground
    changes the key, and a move only shifts the parts. Copies of one prop (40 pillars)
    share one hull."""
    world, tris, edges, xy = _placed_arrays(obj, depsgraph)
    h = hashlib.blake2b(digest_size=20)
    for a in (world, tris, edges, np.asarray(band, float)):
        h.update(np.ascontiguousarray(a).tobytes())
    key = h.digest()
    last = _placed.get(obj.name)
    if last is not None and last[0] == key and last[1] == xy:
        return [p.copy() for p in last[2]]
    rel = _shapes.get(key)
    if rel is None:
        t = len(tris) // 3
        rel = fp.parts(world, tris, np.arange(t) * 3, np.full(t, 3), edges, band)
        _shapes[key] = rel
        if len(_shapes) > SHAPES_KEPT:
            _shapes.popitem(last=False)
    else:
        _shapes.move_to_end(key)
    parts = [p + xy for p in rel]
    _placed[obj.name] = (key, xy, parts)
    return [p.copy() for p in parts]


def forget_footprints():
    """Drop every kept footprint (a benchmark's cold check; a process that wants its memory
    back)."""
    _shapes.clear()
    _placed.clear()


def _placed_arrays(obj, depsgraph):
    """:func:`mesh_arrays` with the world matrix's x, y translation left out, and that
    translation ((x, y) as a float pair)."""
    world, tris, edges = mesh_arrays(obj, depsgraph, with_xy=False)
    m = obj.evaluated_get(depsgraph).matrix_world
    return world, tris, edges, (float(m[0][3]), float(m[1][3]))


def part_name(name, k, count):
    """Obstacle name of part ``k`` (from 0) of an object of ``count`` parts: the object's
    own name when it has one part, else "name (part k+1)"."""
    return name if count == 1 else f"{name} (part {k + 1})"


def owner(obstacle_name):
    """The object name an obstacle name (:func:`part_name`) belongs to."""
    return _PART.sub("", obstacle_name)


def owners(obstacle_names):
    """Object names of obstacle names, each once, in their first order."""
    return list(dict.fromkeys(owner(n) for n in obstacle_names))


def obstacles(scene, depsgraph, exclude=()):
    """Obstacles of every visible mesh object in the scene but ``exclude`` and the
    characters' proxy bodies (:mod:`.bodies`: display only, they walk with their owner)."""
    return [ob for _, obs in obstacles_of_objects(scene, depsgraph, exclude) for ob in obs]


def obstacles_of_objects(scene, depsgraph, exclude=()):
    """:func:`obstacles` object by object: [(object, its obstacles)] (a layout check reads
    them once and leaves out each pair's own objects)."""
    out = []
    skip = {o.name for o in exclude}
    for obj in scene.objects:
        if obj.type != "MESH" or obj.name in skip or not obj.visible_get():
            continue
        if bodies.is_part(obj):
            continue
        polys = footprint_parts(obj, depsgraph)
        parts = [Obstacle(part_name(obj.name, k, len(polys)), p) for k, p in enumerate(polys)]
        out.append((obj, parts))
    return out


def environment(scene, depsgraph, patch, radius, exclude=(), scale=1.0):
    """The scene's obstacles on the patch's tile grid. ``scale``: the character's size
    relative to the patch's skeleton (a retargeted rig's hip-height ratio); the planner
    then works in a world shrunk by it (footprints and radius divided by ``scale``), where
    the patch's steps are the character's steps."""
    env = Environment(patch.side, patch.cells, radius / scale)
    for ob in obstacles(scene, depsgraph, exclude):
        env.place(Obstacle(ob.name, ob.polygon / scale) if scale != 1.0 else ob)
    return env


def ground_state(obj):
    """(x, y, heading) of a goal or start object: its location and the heading of its -Y
    axis (Blender's convention: an object's front faces -Y, as a BVH rig's rest pose does)."""
    m = np.array(obj.matrix_world)
    fwd = -m[:3, 1]
    return np.array([m[0, 3], m[1, 3], np.arctan2(fwd[1], fwd[0])])


def character_state(obj, skel, matrix=None):
    """(x, y, heading) of a character: its root's ground position and its rest facing
    turned by the object's rotation (``matrix``: its world matrix, default the current;
    ``skel`` in metres and stood up, :func:`.rig.skeleton_in_metres`: the object's own
    scale and tilt are not applied again)."""
    from ..motion_patches.kinematics.inplace import rest_facing

    m = np.array(obj.matrix_world if matrix is None else matrix)
    turn = m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0).mean()  # ``skel`` is in metres
    tilt = rig_io.world_tilt(obj) if obj.type == "ARMATURE" else None
    if tilt is not None:  # ``skel`` is stood up already (rig.skeleton_in_metres)
        turn = turn @ tilt.T
    f = turn @ rest_facing(skel)
    root = m[:3, 3] + turn @ skel.rest[skel.root, :3, 3]
    return np.array([root[0], root[1], np.arctan2(f[1], f[0])])
