# SPDX-License-Identifier: GPL-3.0-or-later
"""What the CLI hands back and how: exit codes, :class:`Result`, JSON, a quiet stdout while
a command works, and console progress."""

import contextlib
import io
import json
import math
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

COMMAND_ID = "motion_patches"
PROG = "blender -c " + COMMAND_ID

OK, FAILED, BAD_INPUT = 0, 1, 2
INTERNAL = getattr(os, "EX_SOFTWARE", 70)
UNAVAILABLE = getattr(os, "EX_UNAVAILABLE", 69)  # the Dask cluster was lost mid-run
INTERRUPTED = 130  # Ctrl-C, as shells report it


class CLIError(Exception):
    code = BAD_INPUT


class BadInput(CLIError):
    code = BAD_INPUT


class Failed(CLIError):
    code = FAILED


class Result:
    """What a command hands back: a JSON document, its exit code and a text summary."""

    def __init__(self, doc, code=OK, text=()):
        self.doc, self.code, self.text = doc, code, list(text)


def jsonable(value):
    """Plain JSON values (numpy scalars and arrays unwrapped, NaN/inf as null)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    return value


def count(n, noun, plural=None):
    """'1 piece', '3 pieces' (``plural`` when not ``noun`` + s)."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"


def dump(doc):
    return json.dumps(jsonable(doc), indent=2, allow_nan=False)


def error_line(message):
    print(f"{COMMAND_ID}: error: {message}", file=sys.stderr)


def _fflush_c():
    """Flush C stdio buffers, so text Blender printed lands where fd 1 points now."""
    try:
        import ctypes

        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError, TypeError):  # no libc by that name (Windows)
        pass


@contextlib.contextmanager
def quiet_stdout(verbose=False):
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


HEARTBEAT_S = 5.0  # seconds between the lines of a long call without a fraction to show


class Heartbeat:
    """While a call without a fraction to show runs (one long plan), a line on ``stream``
    every :data:`HEARTBEAT_S` seconds saying it still works and for how long; nothing
    when disabled (``--json``) or when the call ends first."""

    def __init__(self, label, stream=None, enabled=True):
        self.label, self.stream, self.enabled = label, stream, enabled
        self._stop = threading.Event()
        self._thread = None

    def _beat(self):
        t0 = time.monotonic()
        out = self.stream if self.stream is not None else sys.stderr
        while not self._stop.wait(HEARTBEAT_S):
            out.write(f"{self.label}: still working, {time.monotonic() - t0:.0f} s\n")
            out.flush()

    def __enter__(self):
        if self.enabled:
            self._thread = threading.Thread(target=self._beat, daemon=True)
            self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        return False
