# SPDX-License-Identifier: GPL-3.0-or-later
"""Runs inside a windowed Blender for the GUI suite (``blender --python tools/gui/agent.py --
--channel DIR``): a timer that executes the Python snippets the suite drops into DIR and
answers with JSON. It is how the suite reads the scene, the screen layout and the clipboard,
and does what input events cannot (importing mocap, making objects).

Protocol: the suite writes ``DIR/cmd-<n>.py`` (atomically, by rename); the agent runs it in
one namespace shared by all commands, in Blender's main loop (a ``bpy.app.timers`` timer,
between event handling and drawing), and writes ``DIR/res-<n>.json``:
``{"ok": true, "result": <the snippet's variable "result">}`` or ``{"ok": false, "error":
<traceback>}``. ``DIR/ready`` appears once Blender has opened its window and the add-on
is enabled. Nothing here is part of the add-on; it is not in the built zip.
"""

import json
import os
import sys
import traceback

import bpy

POLL_S = 0.01


def _channel():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    return argv[argv.index("--channel") + 1]


CHANNEL = _channel()
NS = {"bpy": bpy, "__name__": "gui_agent"}
_state = {"next": 0, "ready": False, "seen": False}


def window():
    return bpy.context.window_manager.windows[0]


def area(kind="VIEW_3D"):
    return next(a for a in window().screen.areas if a.type == kind)


def region(kind="VIEW_3D", rtype="WINDOW"):
    return next(r for r in area(kind).regions if r.type == rtype)


def override(kind="VIEW_3D", rtype="WINDOW"):
    """A context override for operators that need an area (e.g. view3d.*, screen.*)."""
    a = area(kind)
    return bpy.context.temp_override(
        window=window(),
        screen=window().screen,
        area=a,
        region=next(r for r in a.regions if r.type == rtype),
    )


def rect(r):
    """A region's rectangle on the X screen: (left, top, width, height), y downwards
    (Blender's window coordinates start at the bottom left)."""
    win = window()
    return (r.x, win.height - (r.y + r.height), r.width, r.height)


def take_clipboard():
    """The clipboard's text, then empties it (the suite copies a button's identity into it)."""
    wm = bpy.context.window_manager
    text = wm.clipboard
    wm.clipboard = ""
    return text


def redraw_all():
    for a in window().screen.areas:
        a.tag_redraw()


NS.update(
    window=window,
    area=area,
    region=region,
    override=override,
    rect=rect,
    redraw_all=redraw_all,
    take_clipboard=take_clipboard,
)


def _write(n, payload):
    path = os.path.join(CHANNEL, f"res-{n}.json")
    with open(path + ".tmp", "w") as fh:
        json.dump(payload, fh, default=repr)
    os.replace(path + ".tmp", path)


def _tick():
    if not _state["ready"]:
        if bpy.context.window_manager.windows:
            open(os.path.join(CHANNEL, "ready"), "w").close()
            _state["ready"] = True
        return POLL_S
    n = _state["next"]
    path = os.path.join(CHANNEL, f"cmd-{n}.py")
    if not os.path.exists(path):
        return POLL_S
    if not _state["seen"]:
        # Run it on the next tick, not this one: input events the suite sent before writing
        # the command (xdotool returns once the X server has them) are then surely handled
        # by Blender first (events are read at the top of each pass of its main loop).
        _state["seen"] = True
        return 0.0
    _state["seen"] = False
    with open(path) as fh:
        code = fh.read()
    NS.pop("result", None)
    try:
        exec(compile(code, f"<gui command {n}>", "exec"), NS)
        payload = {"ok": True, "result": NS.get("result")}
    except Exception:  # reported to the suite, which fails the step
        payload = {"ok": False, "error": traceback.format_exc()}
    _state["next"] = n + 1
    _write(n, payload)
    return POLL_S


bpy.app.timers.register(_tick, first_interval=0.5, persistent=True)
