"""Scene objects -> core obstacles, and goal/start states of objects.

A mesh object blocks walking when its evaluated geometry overlaps the body's height band
(0.05 m to 1.8 m above the ground): floors and ceilings do not. Its footprint is the
convex hull of its world-space vertices projected on the ground.
"""

import numpy as np

from ..motion_patches.environment import Environment, Obstacle, convex_hull

BODY_BAND = (0.05, 1.8)


def footprint(obj, depsgraph):
    """Convex footprint (P, 2) of a mesh object's evaluated geometry, or None."""
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        n = len(mesh.vertices)
        if n == 0:
            return None
        co = np.empty(n * 3)
        mesh.vertices.foreach_get("co", co)
    finally:
        ev.to_mesh_clear()
    co = co.reshape(n, 3)
    m = np.array(ev.matrix_world)
    world = co @ m[:3, :3].T + m[:3, 3]
    if world[:, 2].max() < BODY_BAND[0] or world[:, 2].min() > BODY_BAND[1]:
        return None
    hull = convex_hull(world[:, :2])
    return hull if len(hull) >= 3 else None


def obstacles(scene, depsgraph, exclude=()):
    """Obstacles of every visible mesh object in the scene but ``exclude``."""
    out = []
    skip = {o.name for o in exclude}
    for obj in scene.objects:
        if obj.type != "MESH" or obj.name in skip or not obj.visible_get():
            continue
        fp = footprint(obj, depsgraph)
        if fp is not None:
            out.append(Obstacle(obj.name, fp))
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


def character_state(obj, skel):
    """(x, y, heading) of a character: its root's ground position and its rest facing
    turned by the object's rotation."""
    from ..motion_patches.inplace import rest_facing
    m = np.array(obj.matrix_world)
    f = m[:3, :3] @ rest_facing(skel)
    root = m @ np.append(skel.rest[skel.root, :3, 3], 1.0)
    return np.array([root[0], root[1], np.arctan2(f[1], f[0])])
