# SPDX-License-Identifier: GPL-3.0-or-later
"""The command line's parser: one builder per command; the planning flags come from the
settings table (:mod:`.flags`)."""

import argparse

from .check import cmd_check
from .crowd import cmd_crowd
from .flags import PLANNING, WEIGHTS, add_settings
from .output import COMMAND_ID, PROG
from .patches import cmd_bake, cmd_export, cmd_import
from .plan import cmd_analyse, cmd_plan

FMT = argparse.RawDescriptionHelpFormatter

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
  69 the Dask cluster was lost mid-run (nothing written), 70 internal error. --json
  prints one JSON document on stdout and nothing else.
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


class UsageError(Exception):
    def __init__(self, prog, message):
        super().__init__(message)
        self.prog, self.message = prog, message


class Parser(argparse.ArgumentParser):
    """argparse that raises on usage errors instead of printing usage and exiting."""

    def error(self, message):
        raise UsageError(self.prog, message)


def build_parser():
    common = Parser(add_help=False)
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
    p = Parser(
        prog=PROG,
        formatter_class=FMT,
        description="Dynamic Motion Patches: bake locomotion patches, plan characters "
        "and check layouts without the UI.",
        epilog=INVOCATION,
    )
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=Parser)
    _bake_parser(sub, common)
    _plan_parser(sub, common)
    _analyse_parser(sub, common)
    _check_parser(sub, common)
    _crowd_parser(sub, common)
    _export_parser(sub, common)
    _import_parser(sub, common)
    return p


def _bake_parser(sub, common):
    p = sub.add_parser(
        "bake",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="bake a locomotion patch from actions (optionally import BVH first)",
        description="Bake a locomotion patch from a straight action and turn "
        "actions on an armature and store it in the .blend.",
    )
    p.add_argument(
        "--armature",
        required=True,
        metavar="NAME",
        help="armature holding the clips (created by --import-bvh if missing)",
    )
    p.add_argument("--straight", required=True, metavar="ACTION", help="straight clip")
    p.add_argument(
        "--turn",
        action="append",
        metavar="ACTION",
        help="turn clip (repeat for several; mirrored turns are added)",
    )
    p.add_argument("--layer", default="walk", help="gait of the patch (default: walk)")
    p.add_argument("--name", help="patch name (default: the layer)")
    p.add_argument(
        "--import-bvh",
        action="append",
        metavar="FILE",
        help="import this BVH file first (repeat); its action is named after the "
        "file, e.g. 16_15.bvh -> 16_15",
    )
    p.add_argument(
        "--fps",
        type=int,
        help="set the scene frame rate first (the patch is baked at the scene rate)",
    )
    p.add_argument(
        "--cells",
        type=int,
        default=8,
        metavar="2..8",
        help="cells per side of the patch (default 8)",
    )
    p.add_argument(
        "--nodes", type=int, default=8, metavar="2..8", help="entry/exit nodes per edge (default 8)"
    )
    _save_options(p)
    p.set_defaults(run=cmd_bake)


def _plan_parser(sub, common):
    p = sub.add_parser(
        "plan",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="plan a character to a goal and write it as NLA strips",
        description="Plan an armature's walk to a goal object or position "
        "and write it as NLA strips.",
    )
    p.add_argument("--character", required=True, metavar="NAME", help="armature to plan")
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--goal",
        metavar="OBJECT",
        help="goal object: its location and -Y axis (default: the character's Own Goal, "
        "else the scene's goal)",
    )
    g.add_argument(
        "--goal-xyh",
        nargs=3,
        type=float,
        metavar=("X", "Y", "HEADING_DEG"),
        help="goal position (m) and facing (degrees counter-clockwise from +X)",
    )
    p.add_argument("--patch", metavar="NAME", help="locomotion patch (default: the active one)")
    p.add_argument(
        "--gait",
        metavar="walk|run|auto",
        help="plan in the patch of this layer, or 'auto': in every layer baked, "
        "keeping the cheapest (default: the --patch or active patch)",
    )
    add_settings(p, PLANNING)
    p.add_argument(
        "--frame-start",
        type=int,
        metavar="N",
        help="first frame of the motion (default: the current frame)",
    )
    p.add_argument(
        "--start-prop",
        metavar="OBJECT",
        help="a prop tagged with a stand-up clip the character starts seated on (default: "
        "the character's own Start Prop, if it has one)",
    )
    p.add_argument(
        "--from-here",
        action="store_true",
        help="start where the character is at the current frame (continue from here), not "
        "where it stood before it was planned",
    )
    _bodies_option(p, "the character")
    _save_options(p)
    p.set_defaults(run=cmd_plan)


def _analyse_parser(sub, common):
    p = sub.add_parser(
        "analyse",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="figures of a planned character's evaluated motion",
        description="Evaluate a planned character through the depsgraph frame "
        "by frame and print figures (foot skate, goal error, ...).",
    )
    p.add_argument("--character", required=True, metavar="NAME")
    p.set_defaults(run=cmd_analyse)


def _check_parser(sub, common):
    p = sub.add_parser(
        "check",
        parents=[common],
        formatter_class=FMT,
        epilog=SPEC_HELP + "\n" + INVOCATION,
        help="layout test: plan start/goal pairs without writing anything",
        description="Plan every start/goal pair without writing to the scene and "
        "report reachable or not, path length, seconds of motion, "
        "cost and the blocking props; exit 1 when a pair fails its "
        "limits. Pairs come from --spec, from --character/--goal, or "
        "(neither given) from every character with a planned path "
        "and its planned goal. Several .blend files and specs are "
        "checked in one process, with one exit status for all: 0 every "
        "pair passed, 1 a pair failed, 2 bad input (a file or spec that "
        "could not be checked).",
    )
    p.add_argument(
        "files",
        nargs="*",
        metavar="FILE",
        help=".blend files to check (each with every spec; a .blend without one uses the "
        "spec beside it, NAME.layout.toml or NAME.layout.json) and layout specs",
    )
    p.add_argument(
        "--spec",
        action="append",
        metavar="FILE",
        help="JSON or TOML file of pairs and limits (repeat: every .blend with each)",
    )
    p.add_argument(
        "--junit",
        metavar="FILE",
        help="also write the results as JUnit XML (one test case per pair), the report "
        "GitLab, Jenkins and GitHub Actions show",
    )
    p.add_argument(
        "--character",
        action="append",
        metavar="NAME",
        help="check this armature (repeat); with no --goal, against its planned goal",
    )
    p.add_argument(
        "--goal",
        action="append",
        metavar="OBJECT",
        help="goal object for the --character at the same position (repeat)",
    )
    p.add_argument("--patch", metavar="NAME")
    add_settings(p, WEIGHTS)
    p.add_argument(
        "--max-seconds",
        type=float,
        metavar="S",
        help="default limit for every pair (a pair's own limit wins): at most S seconds of motion",
    )
    p.add_argument("--max-length", type=float, metavar="M", help="limit: at most M metres")
    p.add_argument("--max-cost", type=float, metavar="C", help="limit: at most this cost")
    _cluster_options(p)
    p.set_defaults(run=cmd_check)


def _crowd_parser(sub, common):
    p = sub.add_parser(
        "crowd",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="plan several characters, each to its goal, kept apart in time",
        description="Plan every character to its goal against the props, then "
        "let later characters wait at their start until they keep "
        "--spacing from the earlier ones at every frame; exit 1 when "
        "a character finds no path or a conflict remains (then "
        "nothing is saved).",
    )
    p.add_argument(
        "--pair",
        nargs=2,
        action="append",
        metavar=("CHARACTER", "GOAL"),
        help="an armature and its goal object (repeat; the order is the priority)",
    )
    p.add_argument(
        "--character",
        action="append",
        metavar="NAME",
        help="an armature of the crowd (repeat), walking to its own goal, else to "
        "the scene's (as Plan Crowd does with the selected armatures); "
        "neither --pair nor --character: every armature with its own goal",
    )
    p.add_argument("--patch", metavar="NAME", help="locomotion patch (default: the active one)")
    add_settings(p, PLANNING)
    p.add_argument(
        "--frame-start",
        type=int,
        metavar="N",
        help="first frame of the motion (default: the current frame)",
    )
    p.add_argument(
        "--max-wait",
        type=float,
        metavar="S",
        help="longest wait at the start, in seconds (default 4)",
    )
    p.add_argument(
        "--spacing",
        type=float,
        metavar="M",
        help="closest two characters' roots may come, in metres (default: two radii)",
    )
    _cluster_options(p)
    _bodies_option(p, "every character of the crowd")
    _save_options(p)
    p.add_argument(
        "--save-anyway",
        action="store_true",
        help="with --save or --save-in-place: save what was planned even when characters "
        "found no path or conflicts remain (the exit status is still 1)",
    )
    p.set_defaults(run=cmd_crowd)


def _cluster_options(p):
    """--workers / --scheduler: where the independent work runs (Dask distributed)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="plan on a Dask LocalCluster of N worker processes (needs dask and "
        "distributed in Blender's Python; default: in this process)",
    )
    g.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="plan on the running Dask scheduler at ADDRESS (tcp://host:8786): any Dask "
        "cluster, e.g. SLURM through dask-jobqueue or Kubernetes",
    )


def _export_parser(sub, common):
    p = sub.add_parser(
        "export",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="write a baked patch to a file",
        description="Write a baked locomotion patch to a file that 'import' (or "
        "the panel) reads into another .blend.",
    )
    p.add_argument("file", metavar="FILE", help="patch file to write (e.g. walk.mpatch)")
    p.add_argument("--patch", metavar="NAME", help="patch to export (default: the active one)")
    p.set_defaults(run=cmd_export)


def _import_parser(sub, common):
    p = sub.add_parser(
        "import",
        parents=[common],
        formatter_class=FMT,
        epilog=INVOCATION,
        help="store a patch file in the .blend",
        description="Store a locomotion patch file written by 'export' in the "
        "open .blend. A patch already there is kept: without --name the file's patch "
        "takes its layer's name or the next free copy name (walk.001); a --name that is "
        "taken is refused unless --replace.",
    )
    p.add_argument("file", metavar="FILE", help="patch file to read")
    p.add_argument("--name", help="name to store it under (default: its layer)")
    p.add_argument(
        "--replace",
        action="store_true",
        help="replace a patch of the same name instead of keeping both",
    )
    _save_options(p)
    p.set_defaults(run=cmd_import)


def _bodies_option(p, who):
    p.add_argument(
        "--bodies",
        action="store_true",
        help=f"give {who} a proxy body: a low-poly capsule round each bone, parented to "
        "it, in a colour per character (made again: replaced)",
    )


def _save_options(p):
    g = p.add_mutually_exclusive_group()
    g.add_argument(
        "--save", metavar="OUT.blend", help="save the .blend here on success (compressed)"
    )
    g.add_argument(
        "--save-in-place",
        action="store_true",
        help="save over the open .blend on success (compressed)",
    )
