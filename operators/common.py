# SPDX-License-Identifier: GPL-3.0-or-later
"""What several operators share: the window manager's progress indicator, long work run
a step at a time with a bar in the status bar and Esc to cancel (:class:`LongWork`), the
add / remove buttons beside the add-on's lists (turn clips of a bake, a prop's clips), and
the guard that turns an unexpected exception into a report."""

import functools
import threading
import traceback
from contextlib import contextmanager

import bpy

from .. import api


@contextmanager
def progress(context):
    """Show Blender's progress indicator for the block; yields ``update(fraction 0..1)``,
    the callable the API's ``progress`` argument takes. Always ended, even on error."""
    wm = context.window_manager
    wm.progress_begin(0, 100)
    try:
        yield lambda fraction: wm.progress_update(int(round(fraction * 100)))
    finally:
        wm.progress_end()


class Stepper:
    """``work(progress, cancelled)`` (an API call) run a step at a time: each :meth:`step`
    runs it until its next ``progress(fraction)`` report, or its end.

    The work runs in a thread of its own, but only ever while the caller waits in
    :meth:`step`: the two take turns, so Blender's data is never touched by two threads at
    once, and between steps Blender's event loop redraws the window and sees Esc. (The API
    cannot yield between its steps itself: it reports progress from deep inside, and it is
    the one function scripts and the CLI call in one go.)"""

    def __init__(self, work):
        self.fraction = 0.0
        self.stop = False  # what the work's ``cancelled()`` answers
        self.done = False
        self.result = self.error = None
        self._work = work
        self._thread = None
        self._go, self._back = threading.Semaphore(0), threading.Semaphore(0)

    def _run(self):
        self._go.acquire()
        try:
            self.result = self._work(self._progress, lambda: self.stop)
        except BaseException as exc:  # handed to the caller's thread
            self.error = exc
        finally:
            self.done = True
            self._back.release()

    def _progress(self, fraction):
        self.fraction = float(fraction)
        self._back.release()  # the caller's turn
        self._go.acquire()

    def step(self):
        """Run the work up to its next progress report (or its end), here and now."""
        if self.done:
            return
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="motion-patches", daemon=True)
            self._thread.start()
        self._go.release()
        self._back.acquire()

    def cancel(self):
        """Ask the work to stop and run it to its end: the API stops at its next check
        and puts back what it had written."""
        self.stop = True
        while not self.done:
            self.step()


class LongWork:
    """Mixin of an operator whose work is one long API call. ``prepare(context)`` reads the
    arguments (may raise :class:`api.MotionPatchesError`) and returns ``run(progress,
    cancelled)``, the API call; ``finish(context, result)`` reports and returns the
    operator's result; ``undo(context)`` removes what ``prepare`` made, on failure or cancel.

    From a button (invoke) the call runs a step at a time under a timer (:class:`Stepper`),
    its progress a bar in the status bar, Esc cancelling it with the scene left as it was;
    from a script or in background Blender (execute) it runs at once."""

    progress_label = "Working"

    def prepare(self, context):
        raise NotImplementedError

    def finish(self, context, result):
        return {"FINISHED"}

    def undo(self, context):
        pass

    def execute(self, context):
        try:
            run = self.prepare(context)
            with progress(context) as update:
                result = run(update, None)
        except api.MotionPatchesError as exc:
            self.undo(context)
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        except Exception:
            self.undo(context)
            raise
        return self.finish(context, result)

    def invoke(self, context, event):
        if bpy.app.background or context.window is None:
            return self.execute(context)
        return self.start(context)

    def start(self, context):
        """Begin the stepped run (from invoke, or from execute after a dialog)."""
        try:
            run = self.prepare(context)
        except api.MotionPatchesError as exc:
            self.undo(context)
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        except Exception as exc:
            self.undo(context)
            report_bug(self, exc)
            return {"CANCELLED"}
        self._stepper = Stepper(run)
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.02, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context):
        label, stepper = self.progress_label, self._stepper

        def draw(header, _context):
            row = header.layout.row(align=True)
            row.ui_units_x = 16  # the label and the percentage in full
            row.progress(
                factor=stepper.fraction,
                type="BAR",
                text=f"{label} {round(100 * stepper.fraction)} %",
            )
            header.layout.label(text="Cancel", icon="EVENT_ESC")

        if context.workspace is not None:
            context.workspace.status_text_set(draw)  # also redraws the status bar

    def modal(self, context, event):
        stepper = self._stepper
        try:
            if event.type == "ESC" and event.value == "PRESS":
                stepper.cancel()
            elif event.type == "TIMER":  # ours, or another's: a step either way
                stepper.step()
                self._status(context)
        except Exception as exc:  # a bug here: stop the work, the scene put back
            stepper.error = stepper.error or exc
            if not stepper.done:
                stepper.cancel()
        if not stepper.done:
            return {"RUNNING_MODAL"}  # the rest of the input waits: the scene is in use
        self._end(context)
        error = stepper.error
        if error is not None:
            self.undo(context)
            if isinstance(error, api.Cancelled):
                self.report({"INFO"}, str(error))
            elif isinstance(error, api.MotionPatchesError):
                self.report({"ERROR"}, str(error))
            else:
                report_bug(self, error)
            return {"CANCELLED"}
        try:
            return self.finish(context, stepper.result)
        except Exception as exc:
            report_bug(self, exc)
            return {"CANCELLED"}

    def cancel(self, context):
        """Blender ends the operator (a file loaded, Blender quit): stop the work."""
        self._stepper.cancel()
        self._end(context)
        self.undo(context)

    def _end(self, context):
        if getattr(self, "_timer", None) is not None:
            context.window_manager.event_timer_remove(self._timer)
            self._timer = None
        if context.workspace is not None:
            context.workspace.status_text_set(None)


def report_conflicts(op, result):
    """A warning per pair of a crowd that still comes too close, and per walk meeting a prop
    that moves (Plan Crowd, Duplicate Crowd), then where to find them again."""
    for c in result.conflicts:
        op.report(
            {"WARNING"},
            f"'{c['a']}' and '{c['b']}' come within {c['distance_m']:.2f} m at frame {c['frame']}",
        )
    for c in getattr(result, "moving_conflicts", ()):
        op.report(
            {"WARNING"},
            f"'{c['character']}' meets the moving prop '{c['prop']}' at frame {c['frame']} "
            f"({c['distance_m']:.2f} m from its footprint)",
        )
    if result.conflicts or getattr(result, "moving_conflicts", ()):
        op.report(
            {"WARNING"},
            "What was planned is written; Select Conflicts (Planning panel) selects the "
            "characters and goes to the first frame",
        )


def list_operators(name, noun, where, owner, items, index):
    """The Add and Remove operators (``motion_patches.<name>_add`` / ``_remove``) of the
    list ``owner(context).<items>`` whose active row is ``<index>``; ``owner`` returns None
    when there is no list to edit (the buttons are then greyed out)."""

    def has_list(context):
        return owner(context) is not None

    def add(self, context):
        data = owner(context)
        getattr(data, items).add()
        setattr(data, index, len(getattr(data, items)) - 1)
        return {"FINISHED"}

    def has_active(context):
        data = owner(context)
        return data is not None and 0 <= getattr(data, index) < len(getattr(data, items))

    def remove(self, context):
        data = owner(context)
        i = getattr(data, index)
        getattr(data, items).remove(i)
        setattr(data, index, max(0, min(i, len(getattr(data, items)) - 1)))
        return {"FINISHED"}

    def operator(verb, description, poll, execute):
        return type(
            f"MOTION_PATCHES_OT_{name}_{verb.lower()}",
            (bpy.types.Operator,),
            {
                "bl_idname": f"motion_patches.{name}_{verb.lower()}",
                "bl_label": f"{verb} {noun}",
                "bl_description": description,
                # INTERNAL: a list's + / - button, not a command to find in F3 search.
                "bl_options": {"REGISTER", "UNDO", "INTERNAL"},
                "poll": classmethod(lambda cls, context: poll(context)),
                "execute": execute,
            },
        )

    return (
        operator("Add", f"Add a {noun.lower()} to {where}", has_list, add),
        operator(
            "Remove",
            f"Remove the selected {noun.lower()} from {where} (the action itself is kept)",
            has_active,
            remove,
        ),
    )


def report_bug(op, exc):
    """An unexpected exception reported as an error, its traceback to the console."""
    traceback.print_exception(exc)
    op.report(
        {"ERROR"},
        f"Internal error ({type(exc).__name__}: {exc}); the scene "
        f"was left as it was. Please report this bug with the "
        f"console output",
    )


def guarded(cls):
    """``cls`` with its ``execute`` reporting an unexpected exception (a bug: not a
    :class:`api.MotionPatchesError`, which the operator reports itself) as an error and
    cancelling, the traceback printed to the console, instead of a Python traceback in the
    user's face. The API puts back what it changed before the exception reaches here."""
    execute = cls.__dict__.get("execute") or getattr(cls, "execute", None)
    if execute is None or getattr(execute, "_guarded", False):
        return cls

    @functools.wraps(execute)
    def run(self, context):
        try:
            return execute(self, context)
        except Exception as exc:
            report_bug(self, exc)
            return {"CANCELLED"}

    run._guarded = True
    cls.execute = run
    return cls
