# SPDX-License-Identifier: GPL-3.0-or-later
"""Footprints of Blender's own meshes as the planner reads them: read the same as before
(Blender's float32 and int32 buffers, every value as the float64 read gave it) and the
same polygons by the hull fast path as by the general rule, for convex solids (cubes,
cylinders, turned, scaled, tilted, arrayed into islands) and concave ones."""

import bpy
import numpy as np


def fp_of(addon_module):
    return addon_module.api.scene_io.fp


def l_wall(name):
    """An L-shaped wall 3 x 3 m, 0.2 m thick, 2 m high: one mesh, n-gon caps."""
    ell = [(0, 0), (3, 0), (3, 0.2), (0.2, 0.2), (0.2, 3), (0, 3)]
    v = [(x, y, z) for z in (0.0, 2.0) for x, y in ell]
    k = len(ell)
    faces = [tuple(range(k - 1, -1, -1)), tuple(range(k, 2 * k))]
    faces += [(i, (i + 1) % k, k + (i + 1) % k, k + i) for i in range(k)]
    me = bpy.data.meshes.new(name)
    me.from_pydata(v, [], faces)
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def primitives():
    """{name: (object, convex: each island its hull)} as a level designer adds them."""
    out = {}
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0, 0, 1))
    out["cube"] = (bpy.context.object, True)
    bpy.ops.mesh.primitive_cylinder_add(radius=0.25, depth=2, location=(3, 0, 1))
    out["cylinder"] = (bpy.context.object, True)
    bpy.ops.mesh.primitive_cylinder_add(
        radius=0.5, depth=1.5, location=(6, 1, 1), rotation=(0.3, 0.2, 0.7)
    )
    ob = bpy.context.object
    ob.scale = (1.5, 0.4, 1.1)
    out["cylinder turned, tilted and scaled"] = (ob, True)
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-4, 2, 1), rotation=(0, 0, 0.4))
    ob = bpy.context.object
    ob.scale = (3.0, 0.2, 2.0)
    out["wall (a scaled cube)"] = (ob, True)
    bpy.ops.mesh.primitive_cube_add(size=0.6, location=(0, -4, 0.3))
    ob = bpy.context.object
    array = ob.modifiers.new("Array", "ARRAY")
    array.count, array.relative_offset_displace = 3, (2.0, 0.0, 0.0)
    out["three cubes by an array modifier (islands)"] = (ob, True)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(-3, -3, 0.8))
    out["sphere"] = (bpy.context.object, True)
    out["L-shaped wall"] = (l_wall("Ell"), False)
    ell = l_wall("Ell turned")
    ell.location, ell.rotation_euler, ell.scale = (4, 4, 0), (0, 0, 2.0), (0.8, 1.3, 1.0)
    out["L-shaped wall turned and scaled"] = (ell, False)
    return out


def test_meshes_are_read_as_the_float64_read_gave_them(addon_module, clean_scene):
    scene_io = addon_module.api.scene_io
    objects = primitives()
    dg = bpy.context.evaluated_depsgraph_get()
    for name, (ob, _) in objects.items():
        world, tris, edges = scene_io.mesh_arrays(ob, dg)
        ev = ob.evaluated_get(dg)
        mesh = ev.to_mesh()
        co = np.empty(len(mesh.vertices) * 3)
        mesh.vertices.foreach_get("co", co)
        mesh.calc_loop_triangles()
        tris64 = np.empty(len(mesh.loop_triangles) * 3, np.int64)
        mesh.loop_triangles.foreach_get("vertices", tris64)
        edges64 = np.empty(len(mesh.edges) * 2, np.int64)
        mesh.edges.foreach_get("vertices", edges64)
        ev.to_mesh_clear()
        m = np.array(ev.matrix_world)
        np.testing.assert_array_equal(world, co.reshape(-1, 3) @ m[:3, :3].T + m[:3, 3], name)
        np.testing.assert_array_equal(tris, tris64, name)
        np.testing.assert_array_equal(edges, edges64.reshape(-1, 2), name)
        assert tris.dtype == edges.dtype == np.int64 and world.dtype == np.float64


def test_footprints_by_the_hull_fast_path_are_the_general_rules(
    addon_module, clean_scene, monkeypatch
):
    scene_io, fp = addon_module.api.scene_io, fp_of(addon_module)
    objects = primitives()
    dg = bpy.context.evaluated_depsgraph_get()
    covered, sampled = fp._covered, []
    monkeypatch.setattr(fp, "_covered", lambda *a: sampled.append(1) or covered(*a))
    for name, (ob, convex) in objects.items():
        world, tris, edges = scene_io.mesh_arrays(ob, dg, with_xy=False)
        t = len(tris) // 3
        mesh = (world, tris, np.arange(t) * 3, np.full(t, 3), edges)
        sampled.clear()
        got = fp.parts(*mesh)
        assert bool(sampled) != convex, name  # the convex ones never sample the cover
        with monkeypatch.context() as m:
            m.setattr(fp, "_bounds_hull", lambda *a: False)
            general = fp.parts(*mesh)
        assert len(got) == len(general) >= 1, name
        for g, w in zip(got, general):
            np.testing.assert_array_equal(g, w, name)
    assert len(fp.parts(*mesh)) > 1  # the L: its arms, not its hull


def test_a_checks_footprints_are_those_of_the_scene(addon_module, clean_scene):
    """What a layout check reads once for all its pairs, less a pair's own objects, is what
    that pair read on its own before."""
    scene_io = addon_module.api.scene_io
    primitives()
    dg = bpy.context.evaluated_depsgraph_get()
    parts = scene_io.obstacles_of_objects(bpy.context.scene, dg)
    assert [prop for prop, _ in parts] == list(bpy.context.scene.objects)
    for exclude in ((), (bpy.data.objects["Ell"],)):
        gone = {o.name for o in exclude}
        kept = [ob for prop, obs in parts if prop.name not in gone for ob in obs]
        read = scene_io.obstacles(bpy.context.scene, dg, exclude)
        assert [o.name for o in kept] == [o.name for o in read]
        for a, b in zip(kept, read):
            np.testing.assert_array_equal(a.polygon, b.polygon)
