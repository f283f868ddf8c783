"""Importing motion capture through Blender's bundled BVH importer.

Every file becomes one action on a single armature (the first file's), in metres, with
keys scaled to the scene frame rate. The importer makes an armature per file; the extra
ones are ours and are removed once their action is moved across.
"""

from pathlib import Path

import bpy

CMU_SCALE = 0.056444  # CMU units to metres
SOURCE_KEY = "motion_patches_source"


def import_bvh(paths, scale=CMU_SCALE, armature=None, name=None):
    """Import BVH files as actions on one armature; returns (armature object, actions).

    Raises ValueError naming the file when a file is missing or the importer fails, or when
    its joints do not match the armature's bones.
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("no BVH files given")
    for p in paths:
        if not p.is_file():
            raise ValueError(f"BVH file not found: {p}")
    actions = []
    for p in paths:
        before = set(bpy.data.objects)
        try:
            result = bpy.ops.import_anim.bvh(
                filepath=str(p), global_scale=scale, rotate_mode="QUATERNION",
                use_fps_scale=True, update_scene_fps=False, update_scene_duration=False)
        except RuntimeError as exc:
            raise ValueError(f"Blender's BVH importer could not read {p.name}: {exc}") from None
        new = [o for o in bpy.data.objects if o not in before]
        if result != {"FINISHED"} or len(new) != 1 or new[0].type != "ARMATURE":
            for o in new:
                bpy.data.objects.remove(o)
            raise ValueError(f"Blender's BVH importer did not create an armature from {p.name}")
        ob = new[0]
        act = ob.animation_data.action
        act.name = p.stem
        act[SOURCE_KEY] = str(p.name)
        act.use_fake_user = True
        if armature is None:
            armature = ob
            if name:
                ob.name = name
                ob.data.name = name
        else:
            missing = set(b.name for b in ob.data.bones) ^ set(b.name for b in armature.data.bones)
            data = ob.data
            bpy.data.objects.remove(ob)
            bpy.data.armatures.remove(data)
            if missing:
                raise ValueError(f"{p.name} has joints {sorted(missing)[:5]} that do not match "
                                 f"armature '{armature.name}'; import it on its own armature")
        actions.append(act)
    return armature, actions
