# SPDX-License-Identifier: GPL-3.0-or-later
"""Command line: ``blender [-b] [scene.blend] -c motion_patches <command> ...``.

The handler :func:`main` is a plain function of ``argv`` (every argument after the
command id) returning an exit code; it is registered with
``bpy.utils.register_cli_command`` while the extension is enabled, and tests call it
directly. Everything it does goes through :mod:`api`, as the operators do.

The package: :mod:`.parser` (a builder per command; the planning flags derived from the
settings table in :mod:`.flags`), a module per command family (:mod:`.patches`,
:mod:`.plan`, :mod:`.crowd`, :mod:`.check`), the scene look-ups (:mod:`.lookup`) and what is
handed back (:mod:`.output`).

Exit codes: 0 ok; 1 a check failed or no path was found; 2 bad input (usage error, missing
file, unknown object or action, no patch baked: nothing is written and the scene is left
as it was); 69 the Dask cluster was lost mid-run (nothing is written); 70 an internal
error (a bug: the traceback is printed).
"""

import sys
import time
import traceback

import bpy

from .. import api
from .check import load_spec
from .lookup import open_blend
from .output import (
    BAD_INPUT,
    COMMAND_ID,
    FAILED,
    INTERNAL,
    INTERRUPTED,
    OK,
    UNAVAILABLE,
    BadInput,
    CLIError,
    Failed,
    Progress,
    Result,
    dump,
    error_line,
    quiet_stdout,
)
from .parser import UsageError, build_parser

__all__ = (  # what scripts and tests reach as cli.X
    "BAD_INPUT",
    "COMMAND_ID",
    "FAILED",
    "INTERNAL",
    "OK",
    "UNAVAILABLE",
    "BadInput",
    "CLIError",
    "Failed",
    "Progress",
    "Result",
    "api",
    "build_parser",
    "load_spec",
    "main",
    "register",
    "unregister",
)


def main(argv):
    """The ``-c motion_patches`` handler: run one command, return its exit code."""
    argv = [str(a) for a in argv]
    want_json = "--json" in argv
    command = next((a for a in argv if not a.startswith("-")), None)
    try:
        args = build_parser().parse_args(argv)
    except UsageError as exc:
        return _fail(BAD_INPUT, f"{exc.prog}: {exc.message} (see --help)", want_json, command)
    except SystemExit as exc:  # --help (0); argparse exits for nothing else here
        return OK if exc.code in (0, None) else BAD_INPUT
    t0 = time.perf_counter()
    try:
        with quiet_stdout(args.verbose):
            open_blend(args)
            result = args.run(args)
    except CLIError as exc:
        return _fail(exc.code, str(exc), args.json, args.command)
    except api.PathNotFound as exc:
        return _fail(FAILED, str(exc), args.json, args.command)
    except api.ClusterLost as exc:
        return _fail(UNAVAILABLE, str(exc), args.json, args.command)
    except api.MotionPatchesError as exc:
        return _fail(BAD_INPUT, str(exc), args.json, args.command)
    except KeyboardInterrupt:  # Ctrl-C: the API puts back what it had begun to write
        return _fail(INTERRUPTED, "interrupted: nothing was saved", args.json, args.command)
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
        print(dump(doc))
    else:
        for line in result.text:
            print(line)
    sys.stdout.flush()
    return result.code


def _fail(code, message, want_json, command):
    error_line(message)
    if want_json:
        print(dump({"command": command, "ok": False, "exit_code": code, "error": message}))
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
