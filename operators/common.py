# SPDX-License-Identifier: GPL-3.0-or-later
"""What several operators share: the window manager's progress indicator, the add /
remove buttons beside the add-on's lists (turn clips of a bake, a prop's clips), and the
guard that turns an unexpected exception into a report."""

import functools
import traceback
from contextlib import contextmanager

import bpy


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


def report_conflicts(op, result):
    """A warning per pair of a crowd that still comes too close, and per walk meeting a prop
    that moves (Plan Crowd, Duplicate Crowd)."""
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


def guarded(cls):
    """``cls`` with its ``execute`` reporting an unexpected exception (a bug: not a
    :class:`api.MotionPatchesError`, which the operator reports itself) as an error and
    cancelling, the traceback printed to the console, instead of a Python traceback in the
    user's face. The API puts back what it changed before the exception reaches here."""
    execute = cls.__dict__.get("execute")
    if execute is None or getattr(execute, "_guarded", False):
        return cls

    @functools.wraps(execute)
    def run(self, context):
        try:
            return execute(self, context)
        except Exception as exc:
            traceback.print_exc()
            self.report(
                {"ERROR"},
                f"Internal error ({type(exc).__name__}: {exc}); the scene "
                f"was left as it was. Please report this bug with the "
                f"console output",
            )
            return {"CANCELLED"}

    run._guarded = True
    cls.execute = run
    return cls
