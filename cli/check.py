# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``check`` command: a layout test that plans start/goal pairs without writing anything."""

import json
from pathlib import Path

import bpy

from .. import api
from .flags import WEIGHTS
from .lookup import object_named
from .output import FAILED, OK, BadInput, Result


def load_spec(path):
    p = Path(path).expanduser()
    if not p.is_file():
        raise BadInput(f"layout spec not found: {p}")
    if p.suffix.lower() in (".yaml", ".yml"):
        raise BadInput(
            f"layout spec {p.name}: specs are JSON or TOML (.json, .toml), not "
            f"YAML; see --help for the keys"
        )
    try:
        if p.suffix.lower() == ".toml":
            import tomllib

            with open(p, "rb") as fh:
                return tomllib.load(fh)
        with open(p, encoding="utf-8") as fh:
            return json.load(fh)
    except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError, TOMLDecodeError
        kind = "TOML" if p.suffix.lower() == ".toml" else "JSON"
        raise BadInput(
            f"cannot read layout spec {p.name} as {kind} (specs are JSON, or TOML "
            f"with a .toml name): {exc}"
        ) from None


def _planned_pairs(scene, characters, goals):
    """Spec pairs from --character/--goal, or from the stored plans (api.planned_pairs)."""
    return api.planned_pairs(
        scene,
        [object_named(c, "character", {"ARMATURE"}) for c in characters],
        [object_named(g, "goal") for g in goals],
    )


def cmd_check(args):
    scene = bpy.context.scene
    if args.spec and (args.character or args.goal):
        raise BadInput("give either --spec or --character/--goal, not both")
    spec = (
        load_spec(args.spec)
        if args.spec
        else {"pairs": _planned_pairs(scene, args.character or [], args.goal or [])}
    )
    if isinstance(spec, dict):
        spec = dict(spec)
        if args.patch:
            spec["patch"] = args.patch
        for k in WEIGHTS:
            if getattr(args, k, None) is not None:
                spec[k] = getattr(args, k)
        for k in ("max_seconds", "max_length", "max_cost"):
            v = getattr(args, k)
            if v is not None:
                spec["limits"] = dict(spec.get("limits") or {})
                spec["limits"][k] = v
    try:
        results = api.check_layout(scene, spec)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    failed = [r for r in results if not r["passed"]]
    doc = {
        "ok": not failed,
        "pairs": results,
        "passed": len(results) - len(failed),
        "failed": len(failed),
    }
    text = [
        f"check: {len(results)} pair(s), {len(results) - len(failed)} passed, {len(failed)} failed"
    ]
    for r in results:
        if r["reachable"]:
            what = (
                f"reachable, {r['length_m']:.1f} m, {r['seconds']:.1f} s of motion, "
                f"cost {r['cost']:.2f}"
            )
        else:
            what = "UNREACHABLE" + (
                f", blocked by {', '.join(r['blocked_by'][:6])}"
                + (", ..." if len(r["blocked_by"]) > 6 else "")
                + f" ({r['blocked_reason']})"
                if r["blocked_by"]
                else f" ({r['error']})"
            )
        text.append(f"  {'PASS' if r['passed'] else 'FAIL'}  {r['name']}: {what}")
        for f in r["failures"] if r["reachable"] else ():
            text.append(f"        {f}")
    return Result(doc, FAILED if failed else OK, text)
