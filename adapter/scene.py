# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene objects -> core obstacles, and goal/start states of objects.

A mesh object blocks walking where its evaluated geometry overlaps the body's height band
(0.05 m to 1.8 m above the ground): floors and ceilings do not. Its footprint is made of
convex parts by :func:`motion_patches.props.footprint.parts` (thin walls grown to a board, open
rooms kept open); an object of several parts gives one obstacle per part, named
:func:`part_name`.
"""

import re

import numpy as np

from ..motion_patches.props import footprint as fp
from ..motion_patches.props.environment import Environment, Obstacle
from . import rig as rig_io

BODY_BAND = fp.BODY_BAND
_PART = re.compile(r" \(part \d+\)$")


def mesh_arrays(obj, depsgraph):
    """(world vertices (N, 3), triangle vertex indices (3T,), edges (E, 2)) of a mesh
    object's evaluated geometry (modifiers applied): what :mod:`motion_patches.props.footprint`
    reads. Triangles, not polygons: every face part is then convex in plan."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        n = len(mesh.vertices)
        co = np.empty(n * 3)
        mesh.vertices.foreach_get("co", co)
        mesh.calc_loop_triangles()
        tris = np.empty(len(mesh.loop_triangles) * 3, np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris)
        edges = np.empty(len(mesh.edges) * 2, np.int64)
        mesh.edges.foreach_get("vertices", edges)
    finally:
        ev.to_mesh_clear()
    m = np.array(ev.matrix_world)
    world = co.reshape(n, 3) @ m[:3, :3].T + m[:3, 3]
    return world, tris, edges.reshape(-1, 2)


def footprint_parts(obj, depsgraph, band=BODY_BAND):
    """Convex world footprint parts [(P, 2)] of a mesh object ([] when it blocks nothing)."""
    world, tris, edges = mesh_arrays(obj, depsgraph)
    t = len(tris) // 3
    return fp.parts(world, tris, np.arange(t) * 3, np.full(t, 3), edges, band)


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
    """Obstacles of every visible mesh object in the scene but ``exclude``."""
    out = []
    skip = {o.name for o in exclude}
    for obj in scene.objects:
        if obj.type != "MESH" or obj.name in skip or not obj.visible_get():
            continue
        polys = footprint_parts(obj, depsgraph)
        out += [Obstacle(part_name(obj.name, k, len(polys)), p) for k, p in enumerate(polys)]
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
