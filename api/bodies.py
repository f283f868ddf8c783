# SPDX-License-Identifier: GPL-3.0-or-later
"""Proxy bodies: low-poly capsules round a character's bones, so it reads as a figure and
not as bone sticks in the viewport and in renders. Display only: planning never sees them
(they are no obstacles, for their own character or any other)."""

from __future__ import annotations

import colorsys
import zlib
from collections.abc import Iterable, Sequence

import bpy

from ..adapter import bodies
from .errors import MotionPatchesError
from .results import BodiesResult

GOLDEN = 0.618033988749895  # hue step: neighbouring hash values land far apart on the wheel


def character_colour(name: str) -> tuple[float, float, float]:
    """The body colour of a character (linear RGB), from its name: the same each time it
    is made, and different hues for the names of a crowd (Walker.crowd000, ...)."""
    hue = (zlib.crc32(name.encode()) * GOLDEN) % 1.0
    rgb = colorsys.hsv_to_rgb(hue, 0.6, 0.85)
    r, g, b = (c**2.2 for c in rgb)  # sRGB to linear, roughly
    return r, g, b


def chosen_characters(objects: Iterable[bpy.types.Object | None]) -> list[bpy.types.Object]:
    """The characters among chosen objects (the selection and the active object): the
    armatures, and the character of a chosen body part; each once, in the order met.
    MotionPatchesError when there is none."""
    out: dict = {}
    for ob in objects:
        if ob is None:
            continue
        ob = bodies.owner(ob) or ob
        if ob.type == "ARMATURE":
            out.setdefault(ob.name, ob)
    if not out:
        raise MotionPatchesError("no character chosen: select the armatures to give a body")
    return list(out.values())


def _check(ob: bpy.types.Object | None) -> None:
    if ob is None:
        raise MotionPatchesError("no character given to make a body for")
    if ob.type != "ARMATURE":
        raise MotionPatchesError(
            f"'{ob.name}' is {'an' if ob.type[0] in 'AEIOU' else 'a'} {ob.type.lower()}, "
            f"not an armature: a body is made round an armature's bones"
        )
    if not len(ob.data.bones):
        raise MotionPatchesError(f"armature '{ob.name}' has no bones to make a body of")
    if not ob.users_collection:
        raise MotionPatchesError(f"'{ob.name}' is in no collection: link it to the scene first")


def add_bodies(
    characters: Iterable[bpy.types.Object],
    colour: Sequence[float] | None = None,
) -> BodiesResult:
    """Give each armature a proxy body: a low-poly capsule per deform bone, parented to the
    bone (it follows the pose, whatever plays it), sized from the bone's length in the
    rig's own units (a 0.01-scaled rig of centimetre bones gets a body of human size), in
    ``colour`` (linear RGB) or the character's own (:func:`character_colour`). Characters
    of one rig share the capsule meshes. Made again, a body replaces the old one; nothing
    but the extension's own body parts is ever removed. Everything is checked first: a
    non-armature, a rig with no bones, or a colour that is not three numbers from 0 to 1
    raise :class:`MotionPatchesError` with the scene unchanged."""
    chars = list(characters)
    if not chars:
        raise MotionPatchesError("no character given to make a body for")
    for ob in chars:
        _check(ob)
    if colour is not None:
        try:
            rgb = [float(c) for c in colour]
        except (TypeError, ValueError):
            rgb = []
        if len(rgb) not in (3, 4) or not all(0.0 <= c <= 1.0 for c in rgb):
            raise MotionPatchesError(
                f"a body colour is three numbers from 0 to 1 (red, green, blue), not {colour!r}"
            )
    chars = list(dict.fromkeys(chars))  # each once
    bpy.context.view_layer.update()  # world matrices current: a scale just set counts
    _, old_meshes, old_materials = bodies.take_off(chars)  # its meshes are made again
    shapes = bodies.shapes_in_file()
    mine = {m.get(bodies.MATERIAL_KEY): m for m in old_materials}  # each character's own
    made = []
    for ob in chars:
        made += bodies.make(ob, colour or character_colour(ob.name), shapes, mine)
    bodies.purge(old_meshes, old_materials)  # what the old bodies alone used
    return BodiesResult(
        characters=[ob.name for ob in chars],
        parts=len(made),
        meshes=len({p.data.name for p in made}),
    )


def remove_bodies(characters: Iterable[bpy.types.Object]) -> int:
    """Remove the proxy bodies of the characters (only the parts the extension made, and
    the meshes and materials nothing else uses); the number of parts removed."""
    return bodies.remove([ob for ob in characters if ob is not None])


def has_body(character: bpy.types.Object | None) -> bool:
    """Whether the character has a proxy body."""
    return character is not None and bool(bodies.parts(character))
