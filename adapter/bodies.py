# SPDX-License-Identifier: GPL-3.0-or-later
"""Proxy bodies in the scene: a capsule object per bone of an armature, parented to that
bone, so it follows the evaluated pose (NLA strips, actions, constraints) with nothing
baked.

Bone parenting puts a child at its bone's *tail*, in the bone's axes (Y along the bone):
each capsule's mesh runs from ``-length`` to 0 along Y, so the object itself sits at the
identity under its bone and nothing depends on a parent inverse a user may clear.

Meshes are shared: a capsule is keyed by its length and radius (``SHAPE_KEY``), so every
character of one rig (a crowd's linked copies), and a rig's left and right bones of one
size, use the same mesh datablock. The colour is per character: a material on each part
through an object-linked slot (the shared mesh only carries the empty slot).

What this module made is marked: parts with ``BODY_KEY`` (the bone's name), meshes with
``SHAPE_KEY``, materials with ``MATERIAL_KEY``. Removal touches only marked parts parented
to the character, and meshes and materials of ours that nothing uses any more.
"""

import bpy
import numpy as np

from ..motion_patches.kinematics import proxy_body
from . import compat

BODY_KEY = "motion_patches_body"  # on a body part: the name of the bone it is parented to
SHAPE_KEY = "motion_patches_body_shape"  # on a shared capsule mesh: its length x radius
MATERIAL_KEY = "motion_patches_body_of"  # on a body material: the character it colours


def is_part(obj):
    """Whether ``obj`` is a body part this module made."""
    return obj is not None and BODY_KEY in obj.keys()


def parts(character):
    """The body parts of ``character`` (its children marked as parts)."""
    return [c for c in character.children if is_part(c)]


def owner(obj):
    """The character a body part belongs to, or None for any other object."""
    return obj.parent if is_part(obj) and obj.parent is not None else None


def metres_per_unit(obj):
    """The armature's world scale (the mean over its axes: a body only needs its size)."""
    m = np.array(obj.matrix_world)[:3, :3]
    return float(np.linalg.norm(m, axis=0).mean()) or 1.0


def body_bones(obj):
    """The bones a body is made of: the deform bones (a Rigify rig's DEF- bones, not its
    controls), or every bone when none deforms."""
    bones = list(obj.data.bones)
    return [b for b in bones if b.use_deform] or bones


def shapes_in_file():
    """{shape key: mesh} of the capsule meshes already in the file, to share."""
    return {m[SHAPE_KEY]: m for m in bpy.data.meshes if SHAPE_KEY in m.keys()}


def remove(characters):
    """Remove the bodies of ``characters`` and whatever of ours only they used; the number
    of parts removed."""
    n, meshes, materials = take_off(characters)
    purge(meshes, materials)
    return n


def take_off(characters):
    """Remove the characters' parts, all in one batch (one at a time, a crowd's thousands
    of removals each scan the file); (how many, their meshes, their materials), left in
    the file for :func:`make` to use again and :func:`purge` to clear."""
    owners = set(characters)  # one pass over the file (Object.children is a pass each)
    old = [o for o in bpy.data.objects if o.parent in owners and BODY_KEY in o.keys()]
    meshes = {p.data for p in old}
    materials = {s.material for p in old for s in p.material_slots if s.material is not None}
    bpy.data.batch_remove(old)
    return len(old), meshes, materials


def purge(meshes, materials):
    """Remove the meshes and materials of ours among these that nothing uses any more."""
    unused = [m for m in meshes if m.users == 0 and SHAPE_KEY in m.keys()]
    unused += [m for m in materials if m.users == 0 and MATERIAL_KEY in m.keys()]
    bpy.data.batch_remove(unused)


def make(character, colour, shapes, materials=None):
    """A body for the armature ``character`` (with none: :func:`take_off` first): a
    capsule part per :func:`body_bones` bone in the character's collections, sized by
    :func:`proxy_body.bone_radii` in the rig's own units, coloured ``colour`` (linear RGB)
    in its old material when ``materials`` ({character name: material}) holds one.
    ``shapes`` (:func:`shapes_in_file`, kept across characters) gains the meshes made.
    Returns the parts."""
    bones = body_bones(character)
    index = {b.name: i for i, b in enumerate(bones)}
    parents = []
    for b in bones:  # the nearest ancestor among the body's bones
        p = b.parent
        while p is not None and p.name not in index:
            p = p.parent
        parents.append(index[p.name] if p is not None else -1)
    world = character.matrix_world
    heights = np.array([(world @ b.tail_local).z for b in bones])
    lengths = np.array([b.length for b in bones])
    radii = proxy_body.bone_radii(parents, lengths, heights, metres_per_unit(character))
    material = _material(character, colour, (materials or {}).get(character.name))
    made = []
    colls = character.users_collection  # a search of every collection: once
    for b, length, r in zip(bones, lengths, radii):
        part = bpy.data.objects.new(f"{character.name} body {b.name}", _mesh(length, r, shapes))
        for coll in colls:
            coll.objects.link(part)
        part.parent = character
        part.parent_type = "BONE"
        part.parent_bone = b.name
        part[BODY_KEY] = b.name
        slot = part.material_slots[0]
        slot.link = "OBJECT"
        slot.material = material
        part.hide_select = True  # a click goes to the character, not its body
        made.append(part)
    return made


def _mesh(length, radius, shapes):
    """The shared capsule mesh of this length and radius (made once), running from
    ``-length`` to 0 along Y: from the bone's head to its tail, seen from the tail."""
    key = f"{length:.6g}x{radius:.6g}x{proxy_body.SIDES}"
    mesh = shapes.get(key)
    if mesh is not None:
        return mesh
    verts, faces = proxy_body.capsule(float(length), float(radius))
    verts[:, 1] -= length
    mesh = bpy.data.meshes.new(f"MP body {length:.3g}x{radius:.3g}")
    mesh.from_pydata(verts.tolist(), [], faces)
    if hasattr(mesh, "shade_smooth"):  # Blender 4.1 and later
        mesh.shade_smooth()
    mesh.materials.append(None)  # the slot each part fills with its character's colour
    mesh.update()
    mesh[SHAPE_KEY] = key
    shapes[key] = mesh
    return mesh


def _material(character, colour, mat=None):
    """The character's body material (``mat``, its old one, or a new one) in ``colour``
    (linear RGB): viewport colour (Solid mode) and base colour (renders)."""
    if mat is None:
        mat = bpy.data.materials.new(f"MP body {character.name}")
        mat[MATERIAL_KEY] = character.name
    rgba = (*(float(c) for c in colour[:3]), 1.0)
    mat.diffuse_color = rgba
    mat.roughness = 0.6
    bsdf = next((n for n in compat.material_nodes(mat).nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = rgba
        bsdf.inputs["Roughness"].default_value = 0.6
    return mat
