# SPDX-License-Identifier: GPL-3.0-or-later
"""The ``check`` command: a layout test that plans start/goal pairs without writing anything."""

import argparse
import json
from pathlib import Path

import bpy

from .. import api
from . import junit
from .flags import WEIGHTS
from .lookup import object_named, open_blend
from .output import BAD_INPUT, FAILED, OK, BadInput, Result, error_line


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


SPEC_SUFFIXES = (".json", ".toml", ".yaml", ".yml")  # YAML is refused by load_spec, by name
SIDECARS = (".layout.toml", ".layout.json")  # a spec beside its .blend: office.layout.toml


def sidecar(blend):
    """The layout spec kept beside a .blend (``office.blend`` -> ``office.layout.toml`` or
    ``office.layout.json``), or None."""
    base = Path(blend)
    for suffix in SIDECARS:
        p = base.with_name(base.stem + suffix)
        if p.is_file():
            return p
    return None


def _inputs(args):
    """(.blend paths, spec paths): --blend first, then the files named after ``check``,
    told apart by their suffix; every --spec first among the specs."""
    blends, specs = [], list(args.spec or [])
    for f in args.files or []:
        suffix = Path(f).suffix.lower()
        if suffix == ".blend":
            blends.append(f)
        elif suffix in SPEC_SUFFIXES:
            specs.append(f)
        else:
            raise BadInput(f"{f}: check takes .blend files and layout specs (.json, .toml)")
    if args.blend:  # already open (main opened it): checked first, its own spec found
        blends.insert(0, args.blend)
    return blends, specs


def _jobs(args, blends, specs):
    """(blend or None: the open file, spec path or None) of every check to run: each .blend
    with each spec; without specs, with its own spec beside it (:func:`sidecar`) or the
    pairs of --character/--goal or of its planned characters."""
    out = []
    for blend in blends or [None]:
        if specs:
            out += [(blend, spec) for spec in specs]
        elif blend and not (args.character or args.goal) and sidecar(blend):
            out.append((blend, str(sidecar(blend))))
        else:
            out.append((blend, None))
    return out


def _spec_for(args, scene, spec_path):
    spec = (
        load_spec(spec_path)
        if spec_path
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
    return spec


def _check_one(args, blend, spec_path, executor):
    """The results of one .blend against one spec; BadInput when it cannot be checked."""
    if blend and (blend != args.blend or bpy.data.filepath != str(Path(blend).resolve())):
        open_blend(argparse.Namespace(blend=blend))
    scene = bpy.context.scene
    spec = _spec_for(args, scene, spec_path)
    try:
        return api.check_layout(scene, spec, executor=executor)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None


def _pair_line(r):
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
    out = [f"  {'PASS' if r['passed'] else 'FAIL'}  {r['name']}: {what}"]
    out += [f"        {f}" for f in (r["failures"] if r["reachable"] else ())]
    return out


def cmd_check(args):
    if (args.spec or any(Path(f).suffix.lower() in SPEC_SUFFIXES for f in args.files or [])) and (
        args.character or args.goal
    ):
        raise BadInput("give either --spec or --character/--goal, not both")
    blends, specs = _inputs(args)
    jobs = _jobs(args, blends, specs)
    if args.junit and not Path(args.junit).expanduser().resolve().parent.is_dir():
        raise BadInput(f"cannot write --junit {args.junit}: its folder does not exist")
    done = []
    with api.cluster_executor(args.workers, args.scheduler) as executor:
        for blend, spec in jobs:
            job = {"blend": blend, "spec": spec, "pairs": [], "error": None}
            try:
                job["pairs"] = _check_one(args, blend, spec, executor)
            except BadInput as exc:
                if len(jobs) == 1 and not args.junit:
                    raise
                job["error"] = str(exc)
                error_line(f"{blend or bpy.data.filepath or 'the open scene'}: {exc}")
            done.append(job)
    if args.junit:
        junit.write(Path(args.junit).expanduser(), done)
        if len(jobs) == 1 and done[0]["error"] is not None:
            raise BadInput(done[0]["error"])
    return _result(done)


def _result(done):
    pairs = [{**r, "blend": j["blend"], "spec": j["spec"]} for j in done for r in j["pairs"]]
    failed = [r for r in pairs if not r["passed"]]
    bad = [j for j in done if j["error"] is not None]
    checks = [
        {
            "blend": j["blend"],
            "spec": j["spec"],
            "error": j["error"],
            "passed": sum(r["passed"] for r in j["pairs"]),
            "failed": sum(not r["passed"] for r in j["pairs"]),
        }
        for j in done
    ]
    doc = {
        "ok": not failed and not bad,
        "pairs": pairs,
        "passed": len(pairs) - len(failed),
        "failed": len(failed),
        "bad_input": len(bad),
        "checks": checks,
    }
    text = []
    for j in done:
        if len(done) > 1:
            head = j["blend"] or "the open scene"
            text.append(f"{head}" + (f" with {j['spec']}" if j["spec"] else "") + ":")
            if j["error"] is not None:
                text.append(f"  ERROR  {j['error']}")
        for r in j["pairs"]:
            text += _pair_line(r)
    files = f"{len(done)} check(s), " if len(done) > 1 else ""
    text.append(
        f"check: {files}{len(pairs)} pair(s), {len(pairs) - len(failed)} passed, "
        f"{len(failed)} failed" + (f", {len(bad)} not checked (bad input)" if bad else "")
    )
    if len(done) == 1:  # one check: its summary first, as before batches
        text.insert(0, text.pop())
    code = BAD_INPUT if bad else FAILED if failed else OK
    return Result(doc, code, text)
