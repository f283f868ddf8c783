# SPDX-License-Identifier: GPL-3.0-or-later
"""Reading back what Blender actually plays: the depsgraph-evaluated armature per frame."""

import numpy as np


def sample_armature(context, obj, frames, bone_names):
    """World positions (F, B, 3) of bone heads, object ground states (F, 3) and local
    rotations (F, J, 4) of every pose bone, evaluated through the depsgraph."""
    scene = context.scene
    keep = scene.frame_current
    pos = np.empty((len(frames), len(bone_names), 3))
    ground = np.empty((len(frames), 3))
    names = [pb.name for pb in obj.pose.bones]
    rot = np.empty((len(frames), len(names), 4))
    try:
        for i, f in enumerate(frames):
            scene.frame_set(int(f))
            dg = context.evaluated_depsgraph_get()
            ev = obj.evaluated_get(dg)
            mw = np.array(ev.matrix_world)
            for b, name in enumerate(bone_names):
                head = np.array(ev.pose.bones[name].matrix)[:, 3]
                pos[i, b] = (mw @ head)[:3]
            ground[i] = (mw[0, 3], mw[1, 3], np.arctan2(mw[1, 0], mw[0, 0]))
            for j, pb in enumerate(ev.pose.bones):
                rot[i, j] = np.array(pb.matrix_basis.to_quaternion())
    finally:
        scene.frame_set(keep)
    return pos, ground, rot, names
