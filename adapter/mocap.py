# SPDX-License-Identifier: GPL-3.0-or-later
"""Importing motion capture through Blender's bundled BVH importer.

Every file becomes one action on a single armature (the first file's, or the one given),
in metres, with keys scaled to the scene frame rate. The importer makes an armature per
file; the extra ones are ours and are removed once their action is moved across. A file
whose skeleton is not the armature's (another subject: other bone lengths; another naming
convention: 3ds Max, Mixamo, Rigify...) is retargeted onto it by
:mod:`motion_patches.kinematics.retarget`, the rule planning uses too.
"""

from pathlib import Path

import bpy

CMU_SCALE = 0.056444  # CMU units to metres
SOURCE_KEY = "motion_patches_source"


def import_bvh(paths, scale=CMU_SCALE, armature=None, name=None):
    """Import BVH files as actions on one armature; returns (armature object, actions).

    Raises ValueError naming the file when a file is missing or the importer fails, or when
    its joints cannot be mapped onto the armature's bones (naming the joints).
    """
    paths = [Path(p) for p in paths]
    if not paths:
        raise ValueError("no BVH files given")
    for p in paths:
        if not p.is_file():
            raise ValueError(f"BVH file not found: {p}")
        with open(p, "rb") as fh:
            head = fh.read(4096).split()
        if not head or head[0].upper() != b"HIERARCHY":
            what = "is empty" if not head else "does not start with HIERARCHY"
            raise ValueError(f"{p.name} is not a BVH file: it {what}")
    actions = []
    for p in paths:
        before = set(bpy.data.objects)
        try:
            result = bpy.ops.import_anim.bvh(
                filepath=str(p),
                global_scale=scale,
                rotate_mode="QUATERNION",
                use_fps_scale=True,
                update_scene_fps=False,
                update_scene_duration=False,
            )
        except RuntimeError as exc:
            # The importer's own error, not where Blender's operator code re-raised it.
            lines = [
                ln.strip()
                for ln in str(exc).splitlines()
                if ln.strip() and not ln.strip().startswith(("Location:", "File ", "^", "~"))
            ]
            raise ValueError(
                f"Blender's BVH importer could not read {p.name}: "
                f"{lines[-1] if lines else 'unknown error'} (a damaged or "
                f"truncated file?)"
            ) from None
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
            same_names = {b.name for b in ob.data.bones} == {b.name for b in armature.data.bones}
            try:
                if not (same_names and _same_rest(ob, armature)):
                    act = _retargeted(act, ob, armature, p)
            except ValueError as exc:
                bpy.data.actions.remove(act)
                raise ValueError(
                    f"{p.name} cannot go on armature '{armature.name}': {exc}; "
                    f"import it on its own armature"
                ) from None
            finally:
                data = ob.data
                bpy.data.objects.remove(ob)
                bpy.data.armatures.remove(data)
        actions.append(act)
    return armature, actions


def _same_rest(a, b, tol=1e-3):
    """Whether two armatures with the same bone names have the same rest offsets."""
    ha = {bn.name: bn.head_local for bn in a.data.bones}
    return all(
        (ha[bn.name] - bn.head_local).length < tol
        and abs(
            (bn.tail_local - bn.head_local).length
            - (a.data.bones[bn.name].tail_local - a.data.bones[bn.name].head_local).length
        )
        < tol
        for bn in b.data.bones
    )


def _retargeted(action, source_obj, target_obj, path):
    """Another skeleton's clip (another subject, or other joint names) moved onto the
    target rig by :func:`motion_patches.kinematics.retarget.rig_map` (the target's stored bone map
    applies): rotations kept relative to each bone's rest, root motion scaled by hip
    height. ValueError naming the joints that cannot be mapped."""
    import numpy as np

    from ..motion_patches.kinematics.retarget import rig_map
    from ..motion_patches.kinematics.skeleton import root_position_to_location
    from . import actions as act_io
    from . import compat
    from . import rig as rig_io

    fps = bpy.context.scene.render.fps / bpy.context.scene.render.fps_base
    src = act_io.clip_from_action(action, source_obj, fps)
    target = act_io.skeleton_of(target_obj)
    stored = {s: t for s, t in rig_io.bone_map(target_obj).items() if s in src.skeleton.names}
    rm = rig_map(src.skeleton, target, stored, label="clip")
    clip = rm.clip(src)
    skel = rm.target
    name = action.name
    action.name = name + " (subject skeleton)"
    new, slot = compat.new_action(name)
    frames = np.arange(clip.frames) * (fps / clip.fps) + 1.0
    modes = {pb.name: pb.rotation_mode for pb in target_obj.pose.bones}
    act_io.key_pose(
        new,
        slot,
        skel,
        frames,
        root_position_to_location(skel, clip.root_pos),
        clip.rotations,
        modes,
    )
    new[SOURCE_KEY] = str(path.name)
    new["motion_patches_retargeted"] = (
        f"from the skeleton of {path.name}, root scaled by hip height: {rm.note()}"
    )
    new.use_fake_user = True
    action.use_fake_user = False
    bpy.data.actions.remove(action)
    return new
