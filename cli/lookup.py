# SPDX-License-Identifier: GPL-3.0-or-later
"""What the flags name, looked up in the scene or on disk: objects, the .blend to open and
the one to save, the planning settings given. Each raises :class:`BadInput` on a bad name."""

from pathlib import Path

import bpy

from .. import api
from .output import BadInput


def _names(coll, pred=lambda x: True, limit=8):
    names = sorted(x.name for x in coll if pred(x))
    if not names:
        return "none"
    return ", ".join(names[:limit]) + (", ..." if len(names) > limit else "")


def object_named(name, what, types=None):
    """The object of the scene named ``name`` (a name is the CLI's way to point at one)."""
    objects = bpy.context.scene.objects
    ob = objects.get(name)
    if ob is None or (types and ob.type not in types):
        kind = " / ".join(t.lower() for t in types) + " object" if types else "object"
        found = "" if ob is None else f" ('{name}' is a {ob.type.lower()})"
        raise BadInput(
            f"no {kind} named '{name}' for the {what}{found} (have: "
            f"{_names(objects, lambda o: not types or o.type in types)})"
        )
    return ob


def open_blend(args):
    path = getattr(args, "blend", None)
    if not path:
        return
    p = Path(path)
    if not p.is_file():
        raise BadInput(f".blend file not found: {p}")
    try:
        bpy.ops.wm.open_mainfile(filepath=str(p.resolve()))
    except RuntimeError as exc:
        raise BadInput(f"could not open {p}: {str(exc).strip().splitlines()[-1]}") from None


def save_target(args):
    """The path to save to on success (checked now, written later), or None."""
    if getattr(args, "save", None):
        p = Path(args.save).expanduser()
        if p.suffix.lower() != ".blend":
            raise BadInput(f"--save needs a .blend path, not '{args.save}'")
        if not p.parent.is_dir():
            raise BadInput(f"cannot save to {p}: folder {p.parent} does not exist")
        return p.resolve()
    if getattr(args, "save_in_place", False):
        if not bpy.data.filepath:
            raise BadInput(
                "--save-in-place needs a .blend that was opened from a file "
                "(or use --save OUT.blend)"
            )
        return Path(bpy.data.filepath)
    return None


def save_blend(path):
    """Save the .blend to ``path`` (None: nothing), compressed: Blender 5.0 and later save
    compressed by default, 4.5 does not, and a crowd's file is then about six times larger
    (docs/benchmarks.md). Blender keeps a file's compression on later saves (File > Save As
    > Compress turns it off)."""
    if path is None:
        return None
    try:
        bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    except RuntimeError as exc:
        raise BadInput(f"could not save {path}: {str(exc).strip().splitlines()[-1]}") from None
    return str(path)


def settings_given(args):
    """The planning settings given as flags (None: not given, the scene's is used)."""
    return {s.name: getattr(args, s.name, None) for s in api.SETTINGS}
