# SPDX-License-Identifier: GPL-3.0-or-later
"""Command line: ``blender [-b] [scene.blend] -c motion_patches <command> ...``.

The handler :func:`main` is a plain function of ``argv`` (every argument after the
command id) returning an exit code; it is registered with
``bpy.utils.register_cli_command`` while the extension is enabled, and tests call it
directly. Everything it does goes through :mod:`api`, as the operators do.

Exit codes: 0 ok; 1 a check failed or no path was found; 2 bad input (usage error, missing
file, unknown object or action, no patch baked: nothing is written and the scene is left
as it was); 70 an internal error (a bug: the traceback is printed).
"""

import argparse
import contextlib
import io
import json
import math
import os
import sys
import tempfile
import time
import traceback
from pathlib import Path

import bpy
import numpy as np

from . import api

COMMAND_ID = "motion_patches"
PROG = "blender -c " + COMMAND_ID

OK, FAILED, BAD_INPUT = 0, 1, 2
INTERNAL = getattr(os, "EX_SOFTWARE", 70)

INVOCATION = f"""\
how to run it:
  blender -b scene.blend -c {COMMAND_ID} plan --character Walker --goal Goal --save out.blend

  Blender enables the extension, loads the .blend named BEFORE -c, then runs this command
  with every argument after "-c {COMMAND_ID}" (-c implies background mode, so -b is
  optional). Blender's own options (-S SCENE, --python-exit-code, ...) also go before -c.
  --blend FILE opens a file from inside the command instead. The extension must be enabled
  in the user preferences ("blender -c help" lists the commands that exist; with
  --factory-startup it is not).

exit codes: 0 ok, 1 a check failed / no path found, 2 bad input (nothing written),
  70 internal error. --json prints one JSON document on stdout and nothing else.
"""

SPEC_HELP = """\
layout spec (JSON or TOML), every key optional but "pairs":
  {"patch": "walk", "radius": 0.25, "alpha": 1.0, "beta": 0.5, "gamma": 0.2,
   "margin_tiles": 3,
   "limits": {"must_reach": true, "max_seconds": 30},      # defaults for every pair
   "pairs": [
     {"name": "door to desk", "character": "Walker", "goal": "Desk"},
     {"start": [0, 0, 90], "goal": [6, 6, 0], "max_seconds": 12},
     {"start": "SpawnA", "goal": "Exit", "must_reach": false}]}

  start / goal: an object name (an armature starts from its root and rest facing, any
  other object from its location and -Y axis) or [x, y, heading_deg] (heading counter-
  clockwise from +X). "character" is an armature start.
  limits: must_reach (default true), max_seconds (of motion), max_length (metres),
  max_cost (Eq. 5), allow_traversal (default true).
  goal_facing (per pair): "exact" (default: arrive facing the goal's heading) or "any".
  exclude (top level or per pair): object names that are not obstacles; the start and
  goal objects and their children (a character's body mesh) never are.

Nothing is written to the scene. For an unreachable pair, "blocked_by" names the props
that close it off, read from the planner's own occluded cells (footprints grown by the
radius) over the tiles it may search: the props that wall the start's open area off from
the goal's ("separated"); when that area is connected for a point, the props within two
cells of the shortest open cell path ("narrow": the walk does not fit or turn through);
or the props within the radius of the start or the goal ("start" / "goal").
"""


class CLIError(Exception):
    code = BAD_INPUT


class BadInput(CLIError):
    code = BAD_INPUT


class Failed(CLIError):
    code = FAILED


class _UsageError(Exception):
    def __init__(self, prog, message):
        super().__init__(message)
        self.prog, self.message = prog, message


class _Parser(argparse.ArgumentParser):
    """argparse that raises on usage errors instead of printing usage and exiting."""

    def error(self, message):
        raise _UsageError(self.prog, message)


class Result:
    """What a command hands back: a JSON document, its exit code and a text summary."""

    def __init__(self, doc, code=OK, text=()):
        self.doc, self.code, self.text = doc, code, list(text)


# --- output ---------------------------------------------------------------------------------


def _jsonable(value):
    """Plain JSON values (numpy scalars and arrays unwrapped, NaN/inf as null)."""
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    return value


def _dump(doc):
    return json.dumps(_jsonable(doc), indent=2, allow_nan=False)


def _error_line(message):
    print(f"{COMMAND_ID}: error: {message}", file=sys.stderr)


def _fflush_c():
    """Flush C stdio buffers, so text Blender printed lands where fd 1 points now."""
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no libc by that name (Windows)
        pass


@contextlib.contextmanager
def _quiet_stdout(verbose=False):
    """Keep stdout for the command's result: whatever gets printed while it works (Blender's
    own reports such as "Info: Saved", the BVH importer's log) is caught at the Python and
    the file-descriptor level and dropped, or sent to stderr with ``verbose``."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    sink = None if verbose else tempfile.TemporaryFile()
    saved = None
    try:
        _fflush_c()
        saved = os.dup(1)
        os.dup2(2 if verbose else sink.fileno(), 1)
    except OSError:
        saved = None
    try:
        with contextlib.redirect_stdout(sys.stderr if verbose else io.StringIO()):
            yield
    finally:
        if saved is not None:
            _fflush_c()
            os.dup2(saved, 1)
            os.close(saved)
        if sink is not None:
            sink.close()


class Progress:
    """Console progress for long work on ``stream``: a redrawn bar on a terminal, a line
    every 10 % otherwise, nothing when disabled (``--json``)."""

    def __init__(self, label, stream=None, enabled=True, width=30):
        self.label, self.stream, self.enabled, self.width = label, stream, enabled, width
        self.tty = False
        self._last = -1
        self._drawn = False

    def _out(self):
        return self.stream if self.stream is not None else sys.stderr

    def __call__(self, fraction):
        if not self.enabled:
            return
        out = self._out()
        if self._last < 0:
            self.tty = bool(getattr(out, "isatty", lambda: False)())
        pct = int(round(100 * min(max(float(fraction), 0.0), 1.0)))
        if self.tty:
            if pct == self._last:
                return
            n = pct * self.width // 100
            out.write(f"\r{self.label} [{'#' * n}{'-' * (self.width - n)}] {pct:3d}%")
            self._drawn = True
        else:
            if self._last >= 0 and pct // 10 == self._last // 10:
                return
            out.write(f"{self.label}: {pct}%\n")
        out.flush()
        self._last = pct

    def close(self):
        if self.enabled and self.tty and self._drawn:
            self._out().write("\n")
            self._out().flush()


# --- look-ups (all raise BadInput) -----------------------------------------------------------


def _names(coll, pred=lambda x: True, limit=8):
    names = sorted(x.name for x in coll if pred(x))
    if not names:
        return "none"
    return ", ".join(names[:limit]) + (", ..." if len(names) > limit else "")


def _object(name, what, types=None):
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


def _open_blend(args):
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


def _save_target(args):
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


def _save(path):
    if path is None:
        return None
    try:
        bpy.ops.wm.save_as_mainfile(filepath=str(path))
    except RuntimeError as exc:
        raise BadInput(f"could not save {path}: {str(exc).strip().splitlines()[-1]}") from None
    return str(path)


def _settings(args):
    """The planning settings given as flags (None: not given, the scene's is used)."""
    return {k: getattr(args, k, None) for k in api.DEFAULTS}


# --- bake ------------------------------------------------------------------------------------


def cmd_bake(args):
    """Import (optionally), bake and remember the clips: all in api.bake_locomotion_patch,
    which checks every argument first and undoes what it made when the bake fails."""
    scene = bpy.context.scene
    save = _save_target(args)
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
    saved = _save(save)
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
        "saved": saved,
    }
    text = [
        f"baked '{res.name}' ({res.layer}) in {res.seconds:.1f} s: {st.get('kept')} "
        f"segments kept, {st.get('culled')} culled"
    ]
    text += ["  " + n for n in res.notes]
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


# --- plan ------------------------------------------------------------------------------------


def _goal_of(args, scene):
    """(goal for api.plan_path, goal object or None) from --goal / --goal-xyh; neither:
    None, which api.plan_path reads as the scene's goal."""
    if args.goal:
        ob = _object(args.goal, "goal")
        return ob, ob
    if args.goal_xyh:
        x, y, h = args.goal_xyh
        return (x, y, math.radians(h)), None
    return None, scene.motion_patches.goal


def _plan_doc(res, fps):
    return {
        "character": res.character,
        "frame_start": res.frame_start,
        "frame_end": res.frame_end,
        "frames": res.frame_end - res.frame_start + 1,
        "seconds_of_motion": (res.frame_end - res.frame_start) / fps,
        "length_m": res.length_m,
        "cost": res.cost,
        "plan_seconds": res.seconds,
        "expansions": res.expansions,
        "pieces": res.pieces,
        "strips": len(res.strips),
        "stashed_action_track": res.stashed_action_track,
        "stats": res.stats,
    }


def _plan_line(res, fps):
    return (
        f"planned '{res.character}': {len(res.pieces)} pieces, frames {res.frame_start}-"
        f"{res.frame_end} ({(res.frame_end - res.frame_start) / fps:.1f} s of motion, "
        f"{res.length_m:.1f} m), cost {res.cost:.2f}, {res.seconds * 1000:.0f} ms"
    )


def cmd_plan(args):
    scene = bpy.context.scene
    char = _object(args.character, "character", {"ARMATURE"})
    goal, goal_obj = _goal_of(args, scene)
    w = api.planning_settings(scene, **_settings(args))  # what is used: the flags over the scene's
    save = _save_target(args)
    try:
        res = api.plan_path(
            scene,
            char,
            goal,
            patch_name=args.patch,
            frame_start=args.frame_start,
            gait=args.gait,
            **w,
        )
    except api.PathNotFound as exc:
        raise Failed(str(exc)) from None
    fps = api.scene_fps(scene)
    saved = _save(save)
    doc = _plan_doc(res, fps)
    if args.gait:
        doc.update(layer=res.stats.get("layer"), layer_costs=res.stats.get("layers"))
    doc.update(
        goal=api.state_dict(res.goal, goal_obj and goal_obj.name),
        patch=args.patch or api.active_patch_name(scene),
        weights=w,
        saved=saved,
    )
    text = [_plan_line(res, fps)]
    if args.gait:
        text.append(
            f"  layer '{res.stats.get('layer')}' (Eq. 5 cost per layer: "
            + ", ".join(
                f"{k} {'no path' if v is None else f'{v:.2f}'}"
                for k, v in res.stats.get("layers", {}).items()
            )
            + ")"
        )
    if res.stashed_action_track:
        text.append(
            f"  its active action was moved to the muted track '{res.stashed_action_track}'"
        )
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


# --- crowd -----------------------------------------------------------------------------------


def _crowd_pairs(args, scene):
    """--pair CHARACTER GOAL as given; else the crowd the API makes of --character (or of
    the scene, none given): api.crowd_members, the rule the Plan Crowd button follows."""
    if args.pair and args.character:
        raise BadInput("give either --pair or --character, not both")
    if args.pair:
        return [(_object(c, "character", {"ARMATURE"}), _object(g, "goal")) for c, g in args.pair]
    if args.character:
        return api.crowd_members(
            scene, [_object(c, "character", {"ARMATURE"}) for c in args.character]
        )
    return api.crowd_members(scene)


def cmd_crowd(args):
    scene = bpy.context.scene
    pairs = _crowd_pairs(args, scene)
    w = api.planning_settings(scene, **_settings(args))
    save = _save_target(args)
    progress = Progress("crowd", enabled=not args.json)
    wait = {} if args.max_wait is None else {"max_wait_seconds": args.max_wait}
    try:
        res = api.plan_crowd(
            scene,
            pairs,
            patch_name=args.patch,
            frame_start=args.frame_start,
            progress=progress,
            spacing=args.spacing,
            **wait,
            **w,
        )
    finally:
        progress.close()
    fps = api.scene_fps(scene)
    moving = list(getattr(res, "moving_conflicts", []))
    ok = not res.failed and not res.conflicts and not moving
    saved = _save(save) if ok else None
    doc = {
        "characters": len(pairs),
        "planned": [_plan_doc(p, fps) for p in res.plans],
        "failed": [{"character": c, "error": e} for c, e in res.failed],
        "conflicts": res.conflicts,
        "moving_prop_conflicts": moving,
        "delays_frames": res.delays,
        "rerouted": res.rerouted,
        "seconds": res.seconds,
        "patch": args.patch or api.active_patch_name(scene),
        "weights": w,
        "saved": saved,
    }
    text = [
        f"crowd: {len(res.plans)} of {len(pairs)} characters planned in "
        f"{res.seconds:.1f} s, {len(res.conflicts)} conflict(s)"
    ]
    for p in res.plans:
        wait = res.delays[p.character]
        text.append(
            "  "
            + _plan_line(p, fps)
            + (f", waits {wait} frames" if wait else "")
            + (", re-routed round the others" if p.character in res.rerouted else "")
        )
    for c, e in res.failed:
        text.append(f"  FAILED {e}")
    for c in res.conflicts:
        text.append(
            f"  CONFLICT '{c['a']}' and '{c['b']}' come {c['distance_m'] * 100:.0f} cm "
            f"apart at frame {c['frame']}"
        )
    for c in moving:
        text.append(
            f"  CONFLICT '{c['character']}' meets the moving prop '{c['prop']}' at frame "
            f"{c['frame']} ({c['distance_m'] * 100:.0f} cm from its footprint)"
        )
    if saved:
        text.append(f"saved {saved}")
    elif save is not None:
        text.append("not saved: the crowd has failures or conflicts")
    return Result(doc, OK if ok else FAILED, text)


# --- patch files -----------------------------------------------------------------------------


def cmd_export(args):
    out = Path(args.file).expanduser()
    name = api.export_patch(bpy.context.scene, out, args.patch)
    return Result({"patch": name, "file": str(out.resolve())}, OK, [f"exported '{name}' to {out}"])


def cmd_import(args):
    src = Path(args.file).expanduser()
    save = _save_target(args)
    name = api.import_patch(bpy.context.scene, src, args.name)  # and makes it the active one
    saved = _save(save)
    text = [f"imported '{name}' from {src}"] + ([f"saved {saved}"] if saved else [])
    return Result({"patch": name, "file": str(src.resolve()), "saved": saved}, OK, text)


# --- analyse ---------------------------------------------------------------------------------


def cmd_analyse(args):
    char = _object(args.character, "character", {"ARMATURE"})
    try:
        figures = api.analyse(bpy.context, char)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    f = figures
    sk = f["foot_skate"]
    text = [
        f"'{char.name}': {f['frames']} frames ({f['seconds']:.1f} s), evaluated",
        f"  foot skate while planted: {sk.get('mean_cm_per_frame', float('nan')):.2f} "
        f"cm/frame mean, {sk.get('p95_cm_per_frame', float('nan')):.2f} p95",
        f"  goal error: {f['goal_position_error_cm']:.1f} cm, "
        f"{f['goal_heading_error_deg']:.1f} deg "
        f"(hips {f['goal_root_position_error_cm']:.1f} cm)",
        f"  root from plan: max {f['root_from_plan_cm']['max']:.2f} cm; frames inside an "
        f"obstacle: {f['frames_root_inside_obstacle']}",
        f"  largest joint jump at a strip boundary: "
        f"{f['boundary_pop'].get('max_boundary_jump_deg', float('nan')):.1f} deg",
    ]
    return Result({"character": char.name, "figures": figures}, OK, text)


# --- check -----------------------------------------------------------------------------------


def _load_spec(path):
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
        [_object(c, "character", {"ARMATURE"}) for c in characters],
        [_object(g, "goal") for g in goals],
    )


def cmd_check(args):
    scene = bpy.context.scene
    if args.spec and (args.character or args.goal):
        raise BadInput("give either --spec or --character/--goal, not both")
    spec = (
        _load_spec(args.spec)
        if args.spec
        else {"pairs": _planned_pairs(scene, args.character or [], args.goal or [])}
    )
    if isinstance(spec, dict):
        spec = dict(spec)
        if args.patch:
            spec["patch"] = args.patch
        for k in ("alpha", "beta", "gamma", "radius"):
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


# --- parser ----------------------------------------------------------------------------------


def build_parser():
    common = _Parser(add_help=False)
    common.add_argument(
        "--json",
        action="store_true",
        help="print one JSON document on stdout (and nothing else there)",
    )
    common.add_argument(
        "--verbose",
        action="store_true",
        help="pass on what Blender prints while working (to stderr)",
    )
    common.add_argument(
        "--blend",
        metavar="FILE",
        help="open this .blend first (the file given to Blender before -c is already open)",
    )
    fmt = argparse.RawDescriptionHelpFormatter
    p = _Parser(
        prog=PROG,
        formatter_class=fmt,
        description="Dynamic Motion Patches: bake locomotion patches, plan characters "
        "and check layouts without the UI.",
        epilog=INVOCATION,
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)

    b = sub.add_parser(
        "bake",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="bake a locomotion patch from actions (optionally import BVH first)",
        description="Bake a locomotion patch from a straight action and turn "
        "actions on an armature and store it in the .blend.",
    )
    b.add_argument(
        "--armature",
        required=True,
        metavar="NAME",
        help="armature holding the clips (created by --import-bvh if missing)",
    )
    b.add_argument("--straight", required=True, metavar="ACTION", help="straight clip")
    b.add_argument(
        "--turn",
        action="append",
        metavar="ACTION",
        help="turn clip (repeat for several; mirrored turns are added)",
    )
    b.add_argument("--layer", default="walk", help="gait of the patch (default: walk)")
    b.add_argument("--name", help="patch name (default: the layer)")
    b.add_argument(
        "--import-bvh",
        action="append",
        metavar="FILE",
        help="import this BVH file first (repeat); its action is named after the "
        "file, e.g. 16_15.bvh -> 16_15",
    )
    b.add_argument(
        "--fps",
        type=int,
        help="set the scene frame rate first (the patch is baked at the scene rate)",
    )
    b.add_argument(
        "--cells",
        type=int,
        default=8,
        metavar="2..8",
        help="cells per side of the patch (default 8)",
    )
    b.add_argument(
        "--nodes", type=int, default=8, metavar="2..8", help="entry/exit nodes per edge (default 8)"
    )
    _save_options(b)
    b.set_defaults(run=cmd_bake)

    pl = sub.add_parser(
        "plan",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="plan a character to a goal and write it as NLA strips",
        description="Plan an armature's walk to a goal object or position "
        "and write it as NLA strips.",
    )
    pl.add_argument("--character", required=True, metavar="NAME", help="armature to plan")
    g = pl.add_mutually_exclusive_group()
    g.add_argument(
        "--goal",
        metavar="OBJECT",
        help="goal object: its location and -Y axis (default: the scene's goal)",
    )
    g.add_argument(
        "--goal-xyh",
        nargs=3,
        type=float,
        metavar=("X", "Y", "HEADING_DEG"),
        help="goal position (m) and facing (degrees counter-clockwise from +X)",
    )
    pl.add_argument("--patch", metavar="NAME", help="locomotion patch (default: the active one)")
    pl.add_argument(
        "--gait",
        metavar="walk|run|auto",
        help="plan in the patch of this layer, or 'auto': in every layer baked, "
        "keeping the cheapest (default: the --patch or active patch)",
    )
    _weight_options(pl)
    _planning_options(pl)
    pl.add_argument(
        "--frame-start",
        type=int,
        metavar="N",
        help="first frame of the motion (default: the current frame)",
    )
    _save_options(pl)
    pl.set_defaults(run=cmd_plan)

    a = sub.add_parser(
        "analyse",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="figures of a planned character's evaluated motion",
        description="Evaluate a planned character through the depsgraph frame "
        "by frame and print figures (foot skate, goal error, ...).",
    )
    a.add_argument("--character", required=True, metavar="NAME")
    a.set_defaults(run=cmd_analyse)

    c = sub.add_parser(
        "check",
        parents=[common],
        formatter_class=fmt,
        epilog=SPEC_HELP + "\n" + INVOCATION,
        help="layout test: plan start/goal pairs without writing anything",
        description="Plan every start/goal pair without writing to the scene and "
        "report reachable or not, path length, seconds of motion, "
        "cost and the blocking props; exit 1 when a pair fails its "
        "limits. Pairs come from --spec, from --character/--goal, or "
        "(neither given) from every character with a planned path "
        "and its planned goal.",
    )
    c.add_argument("--spec", metavar="FILE", help="JSON or TOML file of pairs and limits")
    c.add_argument(
        "--character",
        action="append",
        metavar="NAME",
        help="check this armature (repeat); with no --goal, against its planned goal",
    )
    c.add_argument(
        "--goal",
        action="append",
        metavar="OBJECT",
        help="goal object for the --character at the same position (repeat)",
    )
    c.add_argument("--patch", metavar="NAME")
    _weight_options(c)
    c.add_argument(
        "--max-seconds",
        type=float,
        metavar="S",
        help="default limit for every pair (a pair's own limit wins): at most S seconds of motion",
    )
    c.add_argument("--max-length", type=float, metavar="M", help="limit: at most M metres")
    c.add_argument("--max-cost", type=float, metavar="C", help="limit: at most this cost")
    c.set_defaults(run=cmd_check)

    cr = sub.add_parser(
        "crowd",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="plan several characters, each to its goal, kept apart in time",
        description="Plan every character to its goal against the props, then "
        "let later characters wait at their start until they keep "
        "--spacing from the earlier ones at every frame; exit 1 when "
        "a character finds no path or a conflict remains (then "
        "nothing is saved).",
    )
    cr.add_argument(
        "--pair",
        nargs=2,
        action="append",
        metavar=("CHARACTER", "GOAL"),
        help="an armature and its goal object (repeat; the order is the priority)",
    )
    cr.add_argument(
        "--character",
        action="append",
        metavar="NAME",
        help="an armature of the crowd (repeat), walking to its own goal, else to "
        "the scene's (as Plan Crowd does with the selected armatures); "
        "neither --pair nor --character: every armature with its own goal",
    )
    cr.add_argument("--patch", metavar="NAME", help="locomotion patch (default: the active one)")
    _weight_options(cr)
    _planning_options(cr)
    cr.add_argument(
        "--frame-start",
        type=int,
        metavar="N",
        help="first frame of the motion (default: the current frame)",
    )
    cr.add_argument(
        "--max-wait",
        type=float,
        metavar="S",
        help="longest wait at the start, in seconds (default 4)",
    )
    cr.add_argument(
        "--spacing",
        type=float,
        metavar="M",
        help="closest two characters' roots may come, in metres (default: two radii)",
    )
    _save_options(cr)
    cr.set_defaults(run=cmd_crowd)

    ex = sub.add_parser(
        "export",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="write a baked patch to a file",
        description="Write a baked locomotion patch to a file that 'import' (or "
        "the panel) reads into another .blend.",
    )
    ex.add_argument("file", metavar="FILE", help="patch file to write (e.g. walk.mpatch)")
    ex.add_argument("--patch", metavar="NAME", help="patch to export (default: the active one)")
    ex.set_defaults(run=cmd_export)

    im = sub.add_parser(
        "import",
        parents=[common],
        formatter_class=fmt,
        epilog=INVOCATION,
        help="store a patch file in the .blend",
        description="Store a locomotion patch file written by 'export' in the "
        "open .blend (replacing a patch of the same name).",
    )
    im.add_argument("file", metavar="FILE", help="patch file to read")
    im.add_argument("--name", help="name to store it under (default: its layer)")
    _save_options(im)
    im.set_defaults(run=cmd_import)
    return p


def _weight_options(p):
    p.add_argument("--alpha", type=float, help="cost per metre (default: the scene's setting)")
    p.add_argument("--beta", type=float, help="cost per radian turned (default: the scene's)")
    p.add_argument("--gamma", type=float, help="cost per unit of effort (default: the scene's)")
    p.add_argument("--radius", type=float, help="character radius in metres (default: the scene's)")


def _planning_options(p):
    """Flags over the scene's Planning settings; a setting not given is the scene's."""
    p.add_argument(
        "--stitching",
        choices=("dynamic", "static"),
        help="stitch traversal clips lazily (dynamic, the paper's method) or all "
        "before the search (static, Lee 2006); default: the scene's setting",
    )
    _either(
        p,
        "foot_lock",
        ("--foot-lock", True, "pin planted feet with leg IK (default: the scene's setting)"),
        ("--no-foot-lock", False, "leave planted feet as synthesised (no leg IK track)"),
    )
    _either(
        p,
        "goal_facing",
        (
            "--any-facing",
            "any",
            "end facing whichever way is cheapest (the goal's own facing is "
            "ignored); default: the scene's Goal Facing",
        ),
        ("--exact-facing", "exact", "end facing the goal's facing"),
    )
    _either(
        p,
        "turn_in_place",
        (
            "--turn-in-place",
            True,
            "turn on the spot where a walk would loop to leave the start or reach the "
            "goal facing its way (a turn derived from the walk's sharpest turn loop); "
            "default: the scene's Turn on the Spot",
        ),
        ("--no-turn-in-place", False, "walk the loops instead of turning on the spot"),
    )


def _either(p, dest, *flags):
    """Mutually exclusive flags [(flag, value, help)] setting ``dest`` (None when none is
    given: the scene's setting)."""
    g = p.add_mutually_exclusive_group()
    for flag, value, text in flags:
        g.add_argument(flag, dest=dest, action="store_const", const=value, help=text)


def _save_options(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--save", metavar="OUT.blend", help="save the .blend here on success")
    g.add_argument(
        "--save-in-place", action="store_true", help="save over the open .blend on success"
    )


# --- entry point -----------------------------------------------------------------------------


def main(argv):
    """The ``-c motion_patches`` handler: run one command, return its exit code."""
    argv = [str(a) for a in argv]
    want_json = "--json" in argv
    command = next((a for a in argv if not a.startswith("-")), None)
    try:
        args = build_parser().parse_args(argv)
    except _UsageError as exc:
        return _fail(BAD_INPUT, f"{exc.prog}: {exc.message} (see --help)", want_json, command)
    except SystemExit as exc:  # --help (0); argparse exits for nothing else here
        return OK if exc.code in (0, None) else BAD_INPUT
    t0 = time.perf_counter()
    try:
        with _quiet_stdout(args.verbose):
            _open_blend(args)
            result = args.run(args)
    except CLIError as exc:
        return _fail(exc.code, str(exc), args.json, args.command)
    except api.PathNotFound as exc:
        return _fail(FAILED, str(exc), args.json, args.command)
    except api.MotionPatchesError as exc:
        return _fail(BAD_INPUT, str(exc), args.json, args.command)
    except Exception:
        traceback.print_exc()
        return _fail(
            INTERNAL, "internal error (a bug; the traceback is above)", args.json, args.command
        )
    if args.json:
        doc = {
            "command": args.command,
            "ok": result.code == OK,
            "exit_code": result.code,
            "blender": bpy.app.version_string,
            "file": bpy.data.filepath or None,
            "wall_seconds": time.perf_counter() - t0,
        }
        doc.update(result.doc)
        print(_dump(doc))
    else:
        for line in result.text:
            print(line)
    sys.stdout.flush()
    return result.code


def _fail(code, message, want_json, command):
    _error_line(message)
    if want_json:
        print(_dump({"command": command, "ok": False, "exit_code": code, "error": message}))
        sys.stdout.flush()
    return code


# --- registration ----------------------------------------------------------------------------

_handle = None


def register():
    global _handle
    if _handle is None and hasattr(bpy.utils, "register_cli_command"):
        _handle = bpy.utils.register_cli_command(COMMAND_ID, main)


def unregister():
    global _handle
    if _handle is not None:
        try:
            bpy.utils.unregister_cli_command(_handle)
        finally:
            _handle = None
