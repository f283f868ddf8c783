"""Command line: ``blender [-b] [scene.blend] -c motion_patches <command> ...``.

The handler :func:`main` is a plain function of ``argv`` (every argument after the
command id) returning an exit code; it is registered with
``bpy.utils.register_cli_command`` while the extension is enabled, and tests call it
directly. Everything it does goes through :mod:`api` (and, for ``check``, the core
planner through :func:`check_layout`).

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
from .adapter import nla, scene as scene_io, storage
from .motion_patches.motion import concatenate
from .motion_patches.planner import PlanError, SegmentPlanner, plan_motions

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
    ob = bpy.data.objects.get(name)
    if ob is None or (types and ob.type not in types):
        kind = " / ".join(t.lower() for t in types) + " object" if types else "object"
        found = "" if ob is None else f" ('{name}' is a {ob.type.lower()})"
        raise BadInput(f"no {kind} named '{name}' for the {what}{found} (have: "
                       f"{_names(bpy.data.objects, lambda o: not types or o.type in types)})")
    return ob


def _action(name, imported=None):
    act = (imported or {}).get(name) or bpy.data.actions.get(name)
    if act is None:
        raise BadInput(f"no action named '{name}' (have: {_names(bpy.data.actions)})")
    return act


def _load_patch(scene, name):
    try:
        return storage.load_patch(scene, name)
    except ValueError as exc:
        raise BadInput(str(exc)) from None


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
            raise BadInput("--save-in-place needs a .blend that was opened from a file "
                           "(or use --save OUT.blend)")
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


def _active_patch_name(scene):
    """The patch used when none is named (as ``storage.load_patch``: active, else first)."""
    s = scene.motion_patches
    items = s.patches
    i = s.active_patch_index
    return items[i].name if 0 <= i < len(items) else items[0].name


def _nonneg(value, flag):
    if value is not None and (not math.isfinite(value) or value < 0):
        raise BadInput(f"{flag} must be a number >= 0, not {value:g}")
    return value


def _weights(scene, args):
    s = scene.motion_patches
    out = {}
    for key in ("alpha", "beta", "gamma", "radius"):
        v = getattr(args, key, None)
        out[key] = float(getattr(s, key) if v is None else _nonneg(v, "--" + key))
    if out["radius"] <= 0:
        raise BadInput("--radius must be > 0")
    return out


def _check_character(obj, patch):
    try:
        nla.check_rig(obj, patch.gait.skeleton)
    except ValueError as exc:
        raise BadInput(str(exc)) from None
    if obj.rotation_mode != "QUATERNION" and (abs(obj.rotation_euler[0]) > 1e-6
                                              or abs(obj.rotation_euler[1]) > 1e-6):
        raise BadInput(f"armature '{obj.name}' is tilted (X/Y rotation); the planned root "
                       f"turns about Z only")


def _state_json(state, obj=None):
    h = (float(np.degrees(state[2])) + 180.0) % 360.0 - 180.0
    d = {"x": round(float(state[0]), 6), "y": round(float(state[1]), 6),
         "heading_deg": round(h, 4) + 0.0}
    if obj is not None:
        d["object"] = obj
    return d


def _path_length(ground):
    return float(np.linalg.norm(np.diff(np.asarray(ground)[:, :2], axis=0), axis=1).sum())


# --- bake ------------------------------------------------------------------------------------


class _Rollback:
    """Remove the objects, armatures and actions made after it was taken; restore the rate."""

    COLLECTIONS = ("objects", "armatures", "actions")

    def __init__(self, scene):
        self.scene = scene
        self.before = {c: set(getattr(bpy.data, c)) for c in self.COLLECTIONS}
        self.fps = (scene.render.fps, scene.render.fps_base)

    def restore(self):
        for c in self.COLLECTIONS:
            coll = getattr(bpy.data, c)
            for item in [x for x in coll if x not in self.before[c]]:
                coll.remove(item)
        self.scene.render.fps, self.scene.render.fps_base = self.fps


def cmd_bake(args):
    scene = bpy.context.scene
    files = [Path(p).expanduser() for p in args.import_bvh or ()]
    for f in files:
        if not f.is_file():
            raise BadInput(f"BVH file not found: {f}")
    arm = bpy.data.objects.get(args.armature)
    if arm is None and not files:
        _object(args.armature, "clips", {"ARMATURE"})  # raises with the names there are
    if arm is not None and arm.type != "ARMATURE":
        _object(args.armature, "clips", {"ARMATURE"})
    stems = {f.stem for f in files}
    for name in [args.straight] + list(args.turn or ()):
        if name not in stems and bpy.data.actions.get(name) is None:
            raise BadInput(f"no action named '{name}' (have: {_names(bpy.data.actions)}"
                           + (f"; imported files give: {', '.join(sorted(stems))}" if stems else "")
                           + ")")
    if args.fps is not None and not 1 <= args.fps <= 1000:
        raise BadInput(f"--fps must be between 1 and 1000, not {args.fps}")
    if not args.layer.strip():
        raise BadInput("--layer must not be empty")
    save = _save_target(args)

    rollback = _Rollback(scene)
    progress = Progress("bake", enabled=not args.json)
    try:
        if args.fps is not None:
            scene.render.fps, scene.render.fps_base = int(args.fps), 1.0
        imported = {}
        if files:
            arm, acts = api.import_mocap(files, armature=arm,
                                         name=args.armature if arm is None else None)
            imported = {f.stem: a for f, a in zip(files, acts)}
        straight = _action(args.straight, imported)
        turns = [_action(n, imported) for n in args.turn or ()]
        try:
            res = api.bake_locomotion_patch(scene, arm, straight, turns, layer=args.layer,
                                            name=args.name, cells=args.cells, nodes=args.nodes,
                                            progress=progress)
        finally:
            progress.close()
    except api.MotionPatchesError as exc:
        rollback.restore()
        raise BadInput(str(exc)) from None
    except BaseException:
        rollback.restore()
        raise
    s = scene.motion_patches  # what the panel shows: the clips this patch came from
    s.source_armature = arm
    s.straight_action = straight
    s.turn_actions.clear()
    for t in turns:
        s.turn_actions.add().action = t
    s.active_patch_index = list(s.patches).index(s.patches[res.name])
    saved = _save(save)
    st = res.stats
    doc = {"patch": res.name, "layer": res.layer, "armature": arm.name,
           "straight": straight.name, "turns": [t.name for t in turns],
           "imported": [a.name for a in imported.values()], "fps": api.scene_fps(scene),
           "seconds": res.seconds, "stats": st, "notes": res.notes, "saved": saved}
    text = [f"baked '{res.name}' ({res.layer}) in {res.seconds:.1f} s: {st.get('kept')} "
            f"segments kept, {st.get('culled')} culled"]
    text += ["  " + n for n in res.notes]
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


# --- plan ------------------------------------------------------------------------------------


def cmd_plan(args):
    scene = bpy.context.scene
    char = _object(args.character, "character", {"ARMATURE"})
    if args.goal:
        goal_obj = _object(args.goal, "goal")
        goal = goal_obj
    elif args.goal_xyh:
        x, y, h = args.goal_xyh
        if not all(math.isfinite(v) for v in (x, y, h)):
            raise BadInput("--goal-xyh needs finite numbers")
        goal_obj, goal = None, (x, y, math.radians(h))
    elif scene.motion_patches.goal is not None:
        goal_obj = goal = scene.motion_patches.goal
    else:
        raise BadInput("no goal: give --goal OBJECT or --goal-xyh X Y HEADING_DEG")
    if goal_obj is not None and goal_obj == char:
        raise BadInput("the goal cannot be the character itself")
    patch = _load_patch(scene, args.patch)
    fps = api.scene_fps(scene)
    if abs(patch.gait.fps - fps) > 1e-3:
        raise BadInput(f"the patch was baked at {patch.gait.fps:g} fps but the scene runs at "
                       f"{fps:g} fps; re-bake or change the scene rate")
    _check_character(char, patch)
    w = _weights(scene, args)
    save = _save_target(args)
    # Evaluate first: api.plan_path reads the goal's world matrix before it evaluates, so a
    # goal moved by a script just before would be read where it was.
    bpy.context.evaluated_depsgraph_get()
    try:
        res = api.plan_path(scene, char, goal, patch_name=args.patch, frame_start=args.frame_start,
                            **w)
    except api.MotionPatchesError as exc:
        raise Failed(f"no path for '{char.name}': {exc}") from None
    meta, arrays = api.load_plan_record(char)
    length = _path_length(arrays["ground"])
    seconds = (res.frame_end - res.frame_start) / fps
    saved = _save(save)
    goal_state = np.asarray(meta["goal"], float)
    doc = {"character": char.name, "goal": _state_json(goal_state, goal_obj and goal_obj.name),
           "patch": args.patch or _active_patch_name(scene), "weights": w,
           "frame_start": res.frame_start, "frame_end": res.frame_end,
           "frames": res.frame_end - res.frame_start + 1, "seconds_of_motion": seconds,
           "length_m": length, "cost": res.cost, "plan_seconds": res.seconds,
           "expansions": res.expansions, "pieces": res.pieces, "strips": len(res.strips),
           "stashed_action_track": res.stashed_action_track, "stats": res.stats, "saved": saved}
    text = [f"planned '{char.name}': {len(res.pieces)} pieces, frames {res.frame_start}-"
            f"{res.frame_end} ({seconds:.1f} s of motion, {length:.1f} m), cost {res.cost:.2f}, "
            f"{res.seconds * 1000:.0f} ms"]
    if res.stashed_action_track:
        text.append(f"  its active action was moved to the muted track "
                    f"'{res.stashed_action_track}'")
    if saved:
        text.append(f"saved {saved}")
    return Result(doc, OK, text)


# --- analyse ---------------------------------------------------------------------------------


def cmd_analyse(args):
    char = _object(args.character, "character", {"ARMATURE"})
    try:
        figures = api.analyse(bpy.context, char)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    f = figures
    sk = f["foot_skate"]
    text = [f"'{char.name}': {f['frames']} frames ({f['seconds']:.1f} s), evaluated",
            f"  foot skate while planted: {sk.get('mean_cm_per_frame', float('nan')):.2f} "
            f"cm/frame mean, {sk.get('p95_cm_per_frame', float('nan')):.2f} p95",
            f"  goal error: {f['goal_position_error_cm']:.1f} cm, "
            f"{f['goal_heading_error_deg']:.1f} deg "
            f"(hips {f['goal_root_position_error_cm']:.1f} cm)",
            f"  root from plan: max {f['root_from_plan_cm']['max']:.2f} cm; frames inside an "
            f"obstacle: {f['frames_root_inside_obstacle']}",
            f"  largest joint jump at a strip boundary: "
            f"{f['boundary_pop'].get('max_boundary_jump_deg', float('nan')):.1f} deg"]
    return Result({"character": char.name, "figures": figures}, OK, text)


# --- check -----------------------------------------------------------------------------------

TOP_KEYS = {"patch", "alpha", "beta", "gamma", "radius", "margin_tiles", "limits", "exclude",
            "pairs"}
LIMIT_KEYS = {"must_reach", "max_seconds", "max_length", "max_cost", "allow_traversal"}
PAIR_KEYS = {"name", "character", "start", "goal", "exclude"} | LIMIT_KEYS
LIMIT_DEFAULTS = {"must_reach": True, "max_seconds": None, "max_length": None,
                  "max_cost": None, "allow_traversal": True}


def _spec_error(msg):
    return api.MotionPatchesError(f"layout spec: {msg}")


def _limits(d, where, base):
    out = dict(base)
    for k in LIMIT_KEYS & set(d):
        v = d[k]
        if k in ("must_reach", "allow_traversal"):
            if not isinstance(v, bool):
                raise _spec_error(f"{where}: {k} must be true or false")
        elif v is not None:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0:
                raise _spec_error(f"{where}: {k} must be a number >= 0")
            v = float(v)
        out[k] = v
    return out


def _place(value, where):
    if isinstance(value, str) and value:
        return value
    if (isinstance(value, (list, tuple)) and len(value) == 3
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)):
        return [float(v) for v in value]
    raise _spec_error(f"{where} must be an object name or [x, y, heading_deg]")


def normalise_spec(spec):
    """A validated copy of a layout spec (see ``SPEC_HELP``); MotionPatchesError if bad."""
    if not isinstance(spec, dict):
        raise _spec_error("the top level must be a table / object")
    unknown = set(spec) - TOP_KEYS
    if unknown:
        raise _spec_error(f"unknown key(s) {', '.join(sorted(unknown))} (known: "
                          f"{', '.join(sorted(TOP_KEYS))})")
    out = {"patch": spec.get("patch")}
    if out["patch"] is not None and not isinstance(out["patch"], str):
        raise _spec_error("patch must be a name")
    for k in ("alpha", "beta", "gamma", "radius", "margin_tiles"):
        v = spec.get(k)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)) or v < 0):
            raise _spec_error(f"{k} must be a number >= 0")
        out[k] = v
    limits = spec.get("limits", {})
    if not isinstance(limits, dict) or set(limits) - LIMIT_KEYS:
        raise _spec_error(f"limits must be a table of {', '.join(sorted(LIMIT_KEYS))}")
    base = _limits(limits, "limits", LIMIT_DEFAULTS)
    out["exclude"] = _names_list(spec.get("exclude"), "top level")
    pairs = spec.get("pairs")
    if not isinstance(pairs, list) or not pairs:
        raise _spec_error("'pairs' must be a non-empty list of start/goal pairs")
    out["pairs"] = []
    for n, p in enumerate(pairs):
        where = f"pair {n + 1}"
        if not isinstance(p, dict):
            raise _spec_error(f"{where} must be a table / object")
        unknown = set(p) - PAIR_KEYS
        if unknown:
            raise _spec_error(f"{where}: unknown key(s) {', '.join(sorted(unknown))} (known: "
                              f"{', '.join(sorted(PAIR_KEYS))})")
        if ("character" in p) == ("start" in p):
            raise _spec_error(f"{where}: give either 'character' or 'start'")
        if "goal" not in p:
            raise _spec_error(f"{where}: 'goal' is missing")
        start = p["character"] if "character" in p else p["start"]
        start = _place(start, f"{where}: {'character' if 'character' in p else 'start'}")
        if "character" in p and not isinstance(start, str):
            raise _spec_error(f"{where}: 'character' must be an armature's name")
        goal = _place(p["goal"], f"{where}: goal")
        name = p.get("name") or f"{_label(start)} -> {_label(goal)}"
        out["pairs"].append({"name": str(name), "start": start, "goal": goal,
                             "exclude": _names_list(p.get("exclude"), where),
                             "limits": _limits(p, where, base)})
    return out


def _names_list(value, where):
    if value is None:
        return []
    if not isinstance(value, list) or not all(isinstance(v, str) and v for v in value):
        raise _spec_error(f"{where}: exclude must be a list of object names")
    return list(value)


def _label(place):
    if isinstance(place, str):
        return place
    return f"({place[0]:g}, {place[1]:g}, {place[2]:g} deg)"


def _resolve(place, what, skel):
    """(state, object or None) for an object name or [x, y, heading_deg]."""
    if what == "exclude":
        ob = bpy.data.objects.get(place)
        if ob is None:
            raise api.MotionPatchesError(f"layout spec: no object named '{place}' to exclude")
        return None, ob
    if not isinstance(place, str):
        return np.array([place[0], place[1], math.radians(place[2])]), None
    ob = bpy.data.objects.get(place)
    if ob is None:
        raise api.MotionPatchesError(f"layout spec: no object named '{place}' for a {what} "
                                     f"(have: {_names(bpy.data.objects)})")
    if what == "start" and ob.type == "ARMATURE":
        try:
            nla.check_rig(ob, skel)
        except ValueError as exc:
            raise api.MotionPatchesError(str(exc)) from None
        return scene_io.character_state(ob, skel), ob
    return scene_io.ground_state(ob), ob


def check_layout(scene, spec, context=None):
    """Plan every start/goal pair of a layout ``spec`` WITHOUT writing to the scene.

    Returns one dict per pair: reachable, seconds of motion, length, cost, the props
    blocking it when it is not reachable, and whether it passed its limits. Raises
    :class:`api.MotionPatchesError` for a bad spec (unknown object or patch), before planning.
    (A layout check is a Python API function: this belongs in ``api.py``.)
    """
    spec = normalise_spec(spec)
    try:
        patch = storage.load_patch(scene, spec["patch"])
    except ValueError as exc:
        raise api.MotionPatchesError(str(exc)) from None
    skel = patch.gait.skeleton
    s = scene.motion_patches
    w = {k: float(getattr(s, k) if spec[k] is None else spec[k])
         for k in ("alpha", "beta", "gamma", "radius")}
    if w["radius"] <= 0:
        raise _spec_error("radius must be > 0")
    margin = 3 if spec["margin_tiles"] is None else int(spec["margin_tiles"])
    # Evaluate first: it also brings the objects' world matrices up to date.
    depsgraph = (context or bpy.context).evaluated_depsgraph_get()
    jobs = []
    for p in spec["pairs"]:
        start, sob = _resolve(p["start"], "start", skel)
        goal, gob = _resolve(p["goal"], "goal", skel)
        # Not obstacles: the start and goal objects with their children (a character's own
        # body mesh) and whatever the spec excludes.
        exclude = {}
        for ob in [sob, gob] + [_resolve(n, "exclude", skel)[1]
                                for n in spec["exclude"] + p["exclude"]]:
            if ob is not None:
                for o in (ob, *ob.children_recursive):
                    exclude[o.name] = o
        jobs.append((p, start, sob, goal, gob, exclude))
    envs, results = {}, []
    props = api.object_patches(scene, depsgraph, patch)  # tagged props offer traversals
    for p, start, sob, goal, gob, exclude in jobs:
        allow = bool(p["limits"]["allow_traversal"])
        key = (tuple(sorted(exclude)), allow)
        if key not in envs:
            env = scene_io.environment(scene, depsgraph, patch, w["radius"],
                                       tuple(exclude.values()))
            usable = [pr for pr in props if pr.name not in exclude] if allow else []
            try:
                planner = SegmentPlanner(patch, env, w["alpha"], w["beta"], w["gamma"],
                                         props=usable)
            except PlanError as exc:
                raise api.MotionPatchesError(str(exc)) from None
            envs[key] = env, planner
        env, planner = envs[key]
        r = {"name": p["name"], "start": _state_json(start, sob and sob.name),
             "goal": _state_json(goal, gob and gob.name), "reachable": False,
             "seconds": None, "frames": None, "length_m": None, "cost": None, "pieces": None,
             "traversals": 0, "expansions": None, "plan_seconds": None, "blocked_by": [],
             "blocked_reason": None, "error": None, "limits": p["limits"]}
        try:
            plan = planner.plan(start, goal, margin_tiles=margin)
        except PlanError as exc:
            r["error"] = str(exc)
            r["blocked_by"], r["blocked_reason"] = blocking_obstacles(env, start, goal, margin)
        else:
            world = concatenate(plan_motions(patch, plan))
            r.update(reachable=True, frames=int(world.frames),
                     seconds=(world.frames - 1) / patch.gait.fps,
                     length_m=_path_length(world.ground), cost=float(plan.cost),
                     pieces=len(plan.pieces), expansions=int(plan.expansions),
                     plan_seconds=float(plan.seconds),
                     traversals=sum(pc.kind == "traversal" for pc in plan.pieces))
        r["failures"] = _judge(r, p["limits"])
        r["passed"] = not r["failures"]
        results.append(r)
    return results


def _judge(r, lim):
    if not r["reachable"]:
        if not lim["must_reach"]:
            return []
        why = f"unreachable ({r['error']})"
        if r["blocked_by"]:
            why = f"unreachable: blocked by {', '.join(r['blocked_by'][:6])}" + (
                ", ..." if len(r["blocked_by"]) > 6 else "") + f" ({r['blocked_reason']})"
        return [why]
    out = []
    for key, value, unit in (("max_seconds", r["seconds"], " s of motion"),
                             ("max_length", r["length_m"], " m"), ("max_cost", r["cost"], "")):
        if lim[key] is not None and value > lim[key]:
            out.append(f"{value:.2f}{unit} exceeds {key} {lim[key]:g}")
    if not lim["allow_traversal"] and r["traversals"]:
        out.append(f"{r['traversals']} traversal(s) but allow_traversal is false")
    return out


# --- which props block an unreachable pair ---------------------------------------------------


def blocking_obstacles(env, start, goal, margin_tiles=3):
    """(names, reason) of the props that keep ``start`` from ``goal`` on ``env``.

    Read from the planner's own view: the free-cell bitfields ``B_t`` (footprints grown by
    the character's radius) of the tiles it may search (start and goal tiles plus the
    margin). Free cells are flood-filled (4-connected) from the start's cell and the goal's.

    * start or goal within the radius of props -> those props ("start" / "goal");
    * separate open areas -> the props whose occluded cells border both areas, i.e. the
      wall between them; if no single prop does (a barrier several props thick), the props
      bordering the smaller area ("separated");
    * one open area (a point could pass, the walk cannot fit or turn through) -> the props
      whose occluded cells lie within two cells of the shortest open cell path, those with
      most such cells first ("narrow");
    * nothing found -> ([], "unknown") (e.g. start and goal too close to join the graph).
    """
    from .motion_patches.environment import distance_to_polygon
    for what, pt in (("start", start), ("goal", goal)):
        near = [n for n, ob in env.obstacles.items()
                if distance_to_polygon(np.asarray(pt[:2])[None], ob.polygon)[0] < env.radius]
        if near:
            return sorted(near), what
    if not env.obstacles:
        return [], "unknown"
    side, cells = env.side, env.cells
    c = side / cells
    ts, tg = env.tile_of(start[:2]), env.tile_of(goal[:2])
    i0, j0 = min(ts[0], tg[0]) - margin_tiles, min(ts[1], tg[1]) - margin_tiles
    i1, j1 = max(ts[0], tg[0]) + margin_tiles, max(ts[1], tg[1]) + margin_tiles
    W, H = (i1 - i0 + 1) * cells, (j1 - j0 + 1) * cells
    free = np.ones((H, W), bool)
    bit = np.arange(cells * cells, dtype=np.uint64)
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            if not env.members((i, j)):
                continue
            f = np.uint64(env.free_cells((i, j)))
            block = ((f >> bit) & np.uint64(1)).astype(bool).reshape(cells, cells)  # [iy, ix]
            y0, x0 = (j - j0) * cells, (i - i0) * cells
            free[y0:y0 + cells, x0:x0 + cells] = block

    def cell_of(p):
        gx = int(np.clip(np.floor(p[0] / c) - i0 * cells, 0, W - 1))
        gy = int(np.clip(np.floor(p[1] / c) - j0 * cells, 0, H - 1))
        return gy, gx

    cs, cg = cell_of(start), cell_of(goal)
    free[cs] = free[cg] = True
    comp_s, parent = _flood(free, cs)

    def owners(cells_yx):
        """prop name -> number of the given occluded cells it occludes."""
        from .motion_patches.environment import polygons_within
        count = {}
        for gy, gx in cells_yx:
            x0, y0 = (gx + i0 * cells) * c, (gy + j0 * cells) * c
            box = np.array([[x0, y0], [x0 + c, y0], [x0 + c, y0 + c], [x0, y0 + c]])
            tile = env.tile_of((x0 + c / 2, y0 + c / 2))
            for n in env.members(tile):
                if polygons_within(box, env.obstacles[n].polygon, env.radius):
                    count[n] = count.get(n, 0) + 1
        return count

    if not comp_s[cg]:
        comp_g, _ = _flood(free, cg)
        bs, bg = owners(_border(comp_s, free)), owners(_border(comp_g, free))
        both = sorted(set(bs) & set(bg))
        if not both:
            both = sorted(bg if comp_g.sum() <= comp_s.sum() else bs)
        return both, "separated"
    path = []
    node = cg
    while node is not None:
        path.append(node)
        node = parent.get(node)
    touch = np.zeros_like(free)
    for gy, gx in path:
        touch[max(gy - 2, 0):gy + 3, max(gx - 2, 0):gx + 3] = True
    count = owners(zip(*np.nonzero(touch & ~free)))
    return sorted(count, key=lambda n: (-count[n], n)), ("narrow" if count else "unknown")


def _flood(free, seed):
    """Cells reachable from ``seed`` over free cells (4-connected) and BFS parents."""
    from collections import deque
    H, W = free.shape
    seen = np.zeros_like(free)
    seen[seed] = True
    parent = {seed: None}
    q = deque([seed])
    while q:
        y, x = q.popleft()
        for ny, nx in ((y - 1, x), (y + 1, x), (y, x - 1), (y, x + 1)):
            if 0 <= ny < H and 0 <= nx < W and free[ny, nx] and not seen[ny, nx]:
                seen[ny, nx] = True
                parent[(ny, nx)] = (y, x)
                q.append((ny, nx))
    return seen, parent


def _border(comp, free):
    """Occluded cells 4-adjacent to a component."""
    grow = comp.copy()
    grow[1:] |= comp[:-1]
    grow[:-1] |= comp[1:]
    grow[:, 1:] |= comp[:, :-1]
    grow[:, :-1] |= comp[:, 1:]
    return list(zip(*np.nonzero(grow & ~free)))


def _load_spec(path):
    p = Path(path).expanduser()
    if not p.is_file():
        raise BadInput(f"layout spec not found: {p}")
    try:
        if p.suffix.lower() == ".toml":
            import tomllib
            with open(p, "rb") as fh:
                return tomllib.load(fh)
        with open(p, encoding="utf-8") as fh:
            return json.load(fh)
    except (ValueError, UnicodeDecodeError) as exc:  # JSONDecodeError, TOMLDecodeError
        raise BadInput(f"cannot read layout spec {p.name}: {exc}") from None


def _planned_pairs(scene, characters, goals):
    """Spec pairs from --character/--goal, or from the stored plans of characters."""
    pairs = []
    if goals and len(goals) != len(characters):
        raise BadInput(f"give one --goal per --character ({len(characters)} characters, "
                       f"{len(goals)} goals), or no --goal to use each character's planned goal")
    if characters:
        for n, name in enumerate(characters):
            ob = _object(name, "character", {"ARMATURE"})
            if goals:
                _object(goals[n], "goal")
                pairs.append({"name": name, "character": name, "goal": goals[n]})
            else:
                pairs.append(_stored_pair(ob))
        return pairs
    for ob in scene.objects:
        if ob.type == "ARMATURE" and api.PLAN_KEY in ob:
            pairs.append(_stored_pair(ob))
    if not pairs:
        raise BadInput("nothing to check: no --spec, no --character, and no character in the "
                       "scene has a planned path")
    return pairs


def _stored_pair(ob):
    try:
        meta, arrays = api.load_plan_record(ob)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    g0 = arrays["ground"][0]
    goal = meta["goal"]
    return {"name": ob.name, "start": [float(g0[0]), float(g0[1]), math.degrees(g0[2])],
            "goal": [float(goal[0]), float(goal[1]), math.degrees(goal[2])],
            "exclude": [ob.name]}


def cmd_check(args):
    scene = bpy.context.scene
    if args.spec and (args.character or args.goal):
        raise BadInput("give either --spec or --character/--goal, not both")
    spec = _load_spec(args.spec) if args.spec else {
        "pairs": _planned_pairs(scene, args.character or [], args.goal or [])}
    if isinstance(spec, dict):
        spec = dict(spec)
        if args.patch:
            spec["patch"] = args.patch
        for k in ("alpha", "beta", "gamma", "radius"):
            if getattr(args, k, None) is not None:
                spec[k] = _nonneg(getattr(args, k), "--" + k)
        for k in ("max_seconds", "max_length", "max_cost"):
            v = getattr(args, k)
            if v is not None:
                _nonneg(v, "--" + k.replace("_", "-"))
                spec["limits"] = dict(spec.get("limits") or {})
                spec["limits"][k] = v
    try:
        results = check_layout(scene, spec)
    except api.MotionPatchesError as exc:
        raise BadInput(str(exc)) from None
    failed = [r for r in results if not r["passed"]]
    doc = {"ok": not failed, "pairs": results, "passed": len(results) - len(failed),
           "failed": len(failed)}
    text = [f"check: {len(results)} pair(s), {len(results) - len(failed)} passed, "
            f"{len(failed)} failed"]
    for r in results:
        if r["reachable"]:
            what = (f"reachable, {r['length_m']:.1f} m, {r['seconds']:.1f} s of motion, "
                    f"cost {r['cost']:.2f}")
        else:
            what = "UNREACHABLE" + (f", blocked by {', '.join(r['blocked_by'][:6])}"
                                    + (", ..." if len(r["blocked_by"]) > 6 else "")
                                    + f" ({r['blocked_reason']})" if r["blocked_by"] else
                                    f" ({r['error']})")
        text.append(f"  {'PASS' if r['passed'] else 'FAIL'}  {r['name']}: {what}")
        for f in r["failures"] if r["reachable"] else ():
            text.append(f"        {f}")
    return Result(doc, FAILED if failed else OK, text)


def cmd_crowd(args):
    raise BadInput("'crowd' is not implemented yet: plan characters one by one with 'plan'")


# --- parser ----------------------------------------------------------------------------------


def build_parser():
    common = _Parser(add_help=False)
    common.add_argument("--json", action="store_true",
                        help="print one JSON document on stdout (and nothing else there)")
    common.add_argument("--verbose", action="store_true",
                        help="pass on what Blender prints while working (to stderr)")
    common.add_argument("--blend", metavar="FILE",
                        help="open this .blend first (the file given to Blender before -c is "
                             "already open)")
    fmt = argparse.RawDescriptionHelpFormatter
    p = _Parser(prog=PROG, formatter_class=fmt,
                description="Dynamic Motion Patches: bake locomotion patches, plan characters "
                            "and check layouts without the UI.",
                epilog=INVOCATION)
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND",
                           parser_class=_Parser)

    b = sub.add_parser("bake", parents=[common], formatter_class=fmt, epilog=INVOCATION,
                       help="bake a locomotion patch from actions (optionally import BVH first)",
                       description="Bake a locomotion patch from a straight action and turn "
                                   "actions on an armature and store it in the .blend.")
    b.add_argument("--armature", required=True, metavar="NAME",
                   help="armature holding the clips (created by --import-bvh if missing)")
    b.add_argument("--straight", required=True, metavar="ACTION", help="straight clip")
    b.add_argument("--turn", action="append", metavar="ACTION",
                   help="turn clip (repeat for several; mirrored turns are added)")
    b.add_argument("--layer", default="walk", help="gait of the patch (default: walk)")
    b.add_argument("--name", help="patch name (default: the layer)")
    b.add_argument("--import-bvh", action="append", metavar="FILE",
                   help="import this BVH file first (repeat); its action is named after the "
                        "file, e.g. 16_15.bvh -> 16_15")
    b.add_argument("--fps", type=int,
                   help="set the scene frame rate first (the patch is baked at the scene rate)")
    b.add_argument("--cells", type=int, default=8, choices=range(2, 9), metavar="2..8")
    b.add_argument("--nodes", type=int, default=8, choices=range(2, 9), metavar="2..8")
    _save_options(b)
    b.set_defaults(run=cmd_bake)

    pl = sub.add_parser("plan", parents=[common], formatter_class=fmt, epilog=INVOCATION,
                        help="plan a character to a goal and write it as NLA strips",
                        description="Plan an armature's walk to a goal object or position "
                                    "and write it as NLA strips.")
    pl.add_argument("--character", required=True, metavar="NAME", help="armature to plan")
    g = pl.add_mutually_exclusive_group()
    g.add_argument("--goal", metavar="OBJECT",
                   help="goal object: its location and -Y axis (default: the scene's goal)")
    g.add_argument("--goal-xyh", nargs=3, type=float, metavar=("X", "Y", "HEADING_DEG"),
                   help="goal position (m) and facing (degrees counter-clockwise from +X)")
    pl.add_argument("--patch", metavar="NAME", help="locomotion patch (default: the active one)")
    _weight_options(pl)
    pl.add_argument("--frame-start", type=int, metavar="N",
                    help="first frame of the motion (default: the current frame)")
    _save_options(pl)
    pl.set_defaults(run=cmd_plan)

    a = sub.add_parser("analyse", parents=[common], formatter_class=fmt, epilog=INVOCATION,
                       help="figures of a planned character's evaluated motion",
                       description="Evaluate a planned character through the depsgraph frame "
                                   "by frame and print figures (foot skate, goal error, ...).")
    a.add_argument("--character", required=True, metavar="NAME")
    a.set_defaults(run=cmd_analyse)

    c = sub.add_parser("check", parents=[common], formatter_class=fmt,
                       epilog=SPEC_HELP + "\n" + INVOCATION,
                       help="layout test: plan start/goal pairs without writing anything",
                       description="Plan every start/goal pair without writing to the scene and "
                                   "report reachable or not, path length, seconds of motion, "
                                   "cost and the blocking props; exit 1 when a pair fails its "
                                   "limits. Pairs come from --spec, from --character/--goal, or "
                                   "(neither given) from every character with a planned path "
                                   "and its planned goal.")
    c.add_argument("--spec", metavar="FILE", help="JSON or TOML file of pairs and limits")
    c.add_argument("--character", action="append", metavar="NAME",
                   help="check this armature (repeat); with no --goal, against its planned goal")
    c.add_argument("--goal", action="append", metavar="OBJECT",
                   help="goal object for the --character at the same position (repeat)")
    c.add_argument("--patch", metavar="NAME")
    _weight_options(c)
    c.add_argument("--max-seconds", type=float, metavar="S",
                   help="default limit for every pair (a pair's own limit wins): at most S "
                        "seconds of motion")
    c.add_argument("--max-length", type=float, metavar="M", help="limit: at most M metres")
    c.add_argument("--max-cost", type=float, metavar="C", help="limit: at most this cost")
    c.set_defaults(run=cmd_check)

    cr = sub.add_parser("crowd", parents=[common], formatter_class=fmt,
                        help="(not implemented yet) plan several characters together",
                        description="Not implemented yet: exits with code 2.")
    cr.set_defaults(run=cmd_crowd)
    return p


def _weight_options(p):
    p.add_argument("--alpha", type=float, help="cost per metre (default: the scene's setting)")
    p.add_argument("--beta", type=float, help="cost per radian turned")
    p.add_argument("--gamma", type=float, help="cost per unit of effort")
    p.add_argument("--radius", type=float, help="character radius in metres")


def _save_options(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument("--save", metavar="OUT.blend", help="save the .blend here on success")
    g.add_argument("--save-in-place", action="store_true",
                   help="save over the open .blend on success")


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
    except api.MotionPatchesError as exc:
        return _fail(BAD_INPUT, str(exc), args.json, args.command)
    except Exception:
        traceback.print_exc()
        return _fail(INTERNAL, "internal error (a bug; the traceback is above)", args.json,
                     args.command)
    if args.json:
        doc = {"command": args.command, "ok": result.code == OK, "exit_code": result.code,
               "blender": bpy.app.version_string, "file": bpy.data.filepath or None,
               "wall_seconds": time.perf_counter() - t0}
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
