# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene-building helpers shared by the Blender tests."""

import bpy
import numpy as np

from rig_names import MIXAMO

CMU_SCALE = 0.056444  # the CMU BVH's units in metres


def pillar(name, x, y, r=0.25, h=2.0):
    bpy.ops.mesh.primitive_cylinder_add(radius=r, depth=h, location=(x, y, h / 2))
    bpy.context.object.name = name
    return bpy.context.object


def prop_box(name, x, y, size=(0.4, 0.44, 0.5)):
    """A box prop (a chair's bulk) standing on the ground at (x, y)."""
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(x, y, size[2] / 2))
    ob = bpy.context.object
    ob.name = name
    ob.scale = size
    return ob


def empty(name, x, y, heading):
    """An empty whose -Y axis (the add-on's facing convention) points along ``heading``."""
    ob = bpy.data.objects.new(name, None)
    bpy.context.scene.collection.objects.link(ob)
    ob.location = (x, y, 0)
    ob.rotation_euler = (0, 0, heading + np.pi / 2)
    return ob


def walker_from(source, name="Walker", location=(0.4, 0.3, 0.0)):
    """A copy of the source armature with no animation, linked to the scene."""
    walker = source.copy()
    walker.name = name
    walker.animation_data_clear()
    bpy.context.scene.collection.objects.link(walker)
    walker.location = location
    return walker


def native_rig(mocap_dir, rel, name, rename=None):
    """A rig from Blender's BVH importer at its defaults (Euler bones), animation cleared,
    its bones renamed by ``rename`` ({old: new})."""
    before = set(bpy.data.objects)
    assert bpy.ops.import_anim.bvh(
        filepath=str(mocap_dir / rel), global_scale=CMU_SCALE, update_scene_fps=False
    ) == {"FINISHED"}
    (ob,) = [o for o in bpy.data.objects if o not in before]
    ob.name = name
    ob.animation_data_clear()
    for old, new in (rename or {}).items():
        ob.data.bones[old].name = new
    ob.location = (0.4, 0.3, 0.0)
    return ob


def fbx_like_mixamo(
    mocap_dir, name, scale=(0.01, 0.01, 0.01), units=100.0, y_up=True, rel="cmu/16_15.bvh"
):
    """A CMU subject (``rel``: subject 16 by default) named as Mixamo names its bones, as
    Blender's FBX importer leaves a Mixamo character: centimetre bones (``units`` per
    metre: the BVH read at 100 times its metre scale), bones in quaternion mode, the
    armature's data Y-up under a 90 degree X rotation of the object (``y_up``), the object
    scaled by 0.01."""
    before = set(bpy.data.objects)
    assert bpy.ops.import_anim.bvh(
        filepath=str(mocap_dir / rel),
        global_scale=CMU_SCALE * units,
        update_scene_fps=False,
    ) == {"FINISHED"}
    (ob,) = [o for o in bpy.data.objects if o not in before]
    ob.name = name
    ob.animation_data_clear()
    for old, new in MIXAMO.items():
        ob.data.bones[old].name = new
    for pb in ob.pose.bones:
        pb.rotation_mode = "QUATERNION"
    if y_up:  # the data turned Y-up, the object turned back upright
        bpy.context.view_layer.objects.active = ob
        for o in bpy.context.selected_objects:
            o.select_set(False)
        ob.select_set(True)
        ob.rotation_euler = (-np.pi / 2, 0.0, 0.0)
        bpy.ops.object.transform_apply(location=False, rotation=True, scale=False)
        ob.rotation_euler = (np.pi / 2, 0.0, 0.0)
    ob.location = (0.4, 0.3, 0.0)
    ob.scale = scale
    bpy.context.view_layer.update()  # as an import leaves it: its world matrix current
    return ob


def world_bone_matrices(rigs, frames, names):
    """{rig name: (F, B, 4, 4)} world matrices of the evaluated bones (pose_bone.matrix of
    the evaluated object, times its matrix_world), one depsgraph evaluation per frame."""
    scene = bpy.context.scene
    out = {r.name: np.empty((len(frames), len(names), 4, 4)) for r in rigs}
    for i, f in enumerate(frames):
        scene.frame_set(int(f))
        dg = bpy.context.evaluated_depsgraph_get()
        for r in rigs:
            ev = r.evaluated_get(dg)
            mw = np.array(ev.matrix_world)
            for b, n in enumerate(names):
                out[r.name][i, b] = mw @ np.array(ev.pose.bones[n].matrix)
    return out


def spy_writes(mp, addon_module):
    """{character name: (patch skeleton, its plan's world bone matrices (F, B, 4, 4))},
    filled as plans are written while ``mp`` (a pytest MonkeyPatch) holds: the motion
    ``nla.write_plan`` is handed (the locked rotations with the foot lock), in float64: what
    the rig should play."""
    nla = addon_module.adapter.nla
    motion = addon_module.motion_patches.kinematics.motion.Motion
    write_plan, written = nla.write_plan, {}

    def spy(bpy_, obj, patch, key, plan, motions, world, frame_start, locked=None, *more):
        rot = world.rotations if locked is None else locked
        m = motion(world.ground, world.root_local, rot, world.contacts)
        skel = patch.gait.skeleton
        written[obj.name] = (skel, m.world_matrices(skel))
        return write_plan(bpy_, obj, patch, key, plan, motions, world, frame_start, locked, *more)

    mp.setattr(nla, "write_plan", spy)
    return written
