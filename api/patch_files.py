# SPDX-License-Identifier: GPL-3.0-or-later
"""Patch files (export / import) and the bone map that puts a patch on a character."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from ..adapter import rig as rig_io
from ..adapter import storage
from .common import _check_character, _patch_for_planning
from .errors import MotionPatchesError

if TYPE_CHECKING:
    import bpy


def export_patch(
    scene: bpy.types.Scene, path: str | os.PathLike, patch_name: str | None = None
) -> str:
    """Write a baked patch (the active one by default) to a file another scene can import;
    returns the name of the patch written."""
    path = Path(path).expanduser()
    if not path.parent.is_dir():
        raise MotionPatchesError(f"cannot write {path}: folder {path.parent} does not exist")
    try:
        name = patch_name or storage.active_name(scene)
        storage.export_patch(scene, name, path)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    except OSError as exc:
        raise MotionPatchesError(f"cannot write {path}: {exc.strerror or exc}") from None
    return name


class ImportedPatch(str):
    """The name a patch file was stored under (a str), with what happened to a patch
    already in the way: ``kept`` (its name, left as it was) or ``replaced``."""

    kept: str | None = None
    replaced: bool = False


def import_patch(
    scene: bpy.types.Scene,
    path: str | os.PathLike,
    name: str | None = None,
    replace: bool = False,
) -> ImportedPatch:
    """Store a patch file written by :func:`export_patch` in ``scene`` and make it the
    active patch (the one planning uses next); returns the name it is stored under.

    A patch already in the scene is never overwritten unless ``replace``: without a
    ``name`` the file's patch takes its own name, or Blender's next free copy name
    (``walk.001``) when that is taken; a ``name`` that is taken is refused."""
    path = Path(path).expanduser()
    if not path.is_file():
        raise MotionPatchesError(f"patch file not found: {path}")
    if name is not None and not name.strip():
        raise MotionPatchesError("the patch name is empty")
    taken = name is not None and storage.patch_items(scene).get(name) is not None
    if taken and not replace:
        raise MotionPatchesError(
            f"this scene already has a patch '{name}': import under another name, or "
            "replace it (replace=True, the CLI's --replace)"
        )
    try:
        patch = storage.read_patch_file(path)
    except OSError as exc:
        raise MotionPatchesError(f"cannot read {path}: {exc.strerror or exc}") from None
    except ValueError as exc:
        raise MotionPatchesError(f"{path}: {exc}") from None
    wanted = patch.layer if name is None else name
    if name is None and not replace:
        name = storage.free_patch_name(scene, patch.layer)
    replaced = storage.patch_items(scene).get(name or wanted) is not None
    stored = ImportedPatch(storage.store_patch(scene, patch, name or wanted).name)
    stored.kept = wanted if stored != wanted else None
    stored.replaced = replaced
    storage.make_active(scene, stored)
    return stored


def bone_map(
    scene: bpy.types.Scene, character: bpy.types.Object, patch_name: str | None = None
) -> dict[str, str]:
    """{patch bone: bone of ``character`` that plays it ('' = none)}: what planning the
    character with the patch uses (its stored bone map over the names' pairing).
    :class:`MotionPatchesError` naming the patch bones that cannot be mapped."""
    patch = _patch_for_planning(scene, patch_name)
    rig = _check_character(character, patch)
    names = patch.gait.skeleton.names
    mapping = {n: n for n in names} if rig is None else rig.mapping
    return {n: mapping.get(n, "") for n in names}


def fill_bone_map(
    scene: bpy.types.Scene, character: bpy.types.Object, patch_name: str | None = None
) -> dict[str, str]:
    """Store on ``character``'s armature a bone map listing every patch bone with the rig
    bone the names give ('' where none), for an animator to correct; returns it. Works
    even when the names leave the legs unmapped (that is what the map is for)."""
    patch = _patch_for_planning(scene, patch_name)
    if character is None or character.type != "ARMATURE":
        raise MotionPatchesError("choose an armature")
    try:
        mapping = rig_io.guessed_map(character, patch.gait.skeleton)
    except ValueError as exc:
        raise MotionPatchesError(str(exc)) from None
    rig_io.set_bone_map(character, mapping)
    return mapping


def set_bone_map(character: bpy.types.Object, mapping: dict[str, str]) -> None:
    """Store ``mapping`` ({patch bone: rig bone, '' = left out}) as the bone map of the
    armature of ``character`` (shared by every object using that armature); an empty
    mapping clears it (bones are then paired by their names)."""
    if character is None or character.type != "ARMATURE":
        raise MotionPatchesError("choose an armature")
    bones = {b.name for b in character.data.bones}
    wrong = [r for r in mapping.values() if r and r not in bones]
    if wrong:
        raise MotionPatchesError(f"armature '{character.name}' has no bones {', '.join(wrong[:6])}")
    rig_io.set_bone_map(character, dict(mapping))
