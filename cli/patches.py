# SPDX-License-Identifier: GPL-3.0-or-later
"""The patch commands: ``bake`` one from actions (optionally importing BVH first),
``export`` it to a file and ``import`` such a file into another .blend."""

from pathlib import Path

import bpy

from .. import api
from .lookup import save_blend, save_target
from .output import OK, Progress, Result


def cmd_bake(args):
    """Import (optionally), bake and remember the clips: all in api.bake_locomotion_patch,
    which checks every argument first and undoes what it made when the bake fails."""
    scene = bpy.context.scene
    save = save_target(args)
    progress = Progress("bake", enabled=not args.json)
    try:
        res = api.bake_locomotion_patch(
            scene,
            args.armature,
            args.straight,
            args.turn or (),
            layer=args.layer,
            name=args.name,
            cells=args.cells,
            nodes=args.nodes,
            progress=progress,
            bvh_files=args.import_bvh or (),
            fps=args.fps,
        )
    finally:
        progress.close()
    saved = save_blend(save)
    st = res.stats
    doc = {
        "patch": res.name,
        "layer": res.layer,
        "armature": res.armature,
        "straight": res.straight,
        "turns": res.turns,
        "imported": res.imported,
        "fps": api.scene_fps(scene),
        "seconds": res.seconds,
        "stats": st,
        "notes": res.notes,
        "warnings": res.warnings,
        "saved": saved,
    }
    text = [
        f"baked '{res.name}' ({res.layer}) in {res.seconds:.1f} s: {st.get('kept')} "
        f"segments kept, {st.get('culled')} culled"
    ]
    text += ["  " + n for n in res.notes]
    text += ["warning: " + w for w in res.warnings]
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


def cmd_export(args):
    out = Path(args.file).expanduser()
    name = api.export_patch(bpy.context.scene, out, args.patch)
    return Result({"patch": name, "file": str(out.resolve())}, OK, [f"exported '{name}' to {out}"])


def cmd_import(args):
    src = Path(args.file).expanduser()
    save = save_target(args)
    name = api.import_patch(bpy.context.scene, src, args.name, replace=args.replace)
    saved = save_blend(save)
    text = [f"imported '{name}' from {src}"]
    if name.kept:
        text.append(f"  the scene's own '{name.kept}' is kept (--replace replaces it)")
    elif name.replaced:
        text.append(f"  replaced the scene's '{name}'")
    text += [f"saved {saved}"] if saved else []
    doc = {"patch": str(name), "kept": name.kept, "replaced": name.replaced}
    return Result({**doc, "file": str(src.resolve()), "saved": saved}, OK, text)
