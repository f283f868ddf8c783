# SPDX-License-Identifier: GPL-3.0-or-later
"""A windowed Blender under Xvfb, driven with real input events (xdotool) and read through
the agent (tools/gui/agent.py). Used by tools/gui/suite.py inside the GUI root
(tools/gui/gui-root); needs Xvfb, xdotool, ImageMagick and numpy there.

Coordinates are X screen pixels, y downwards; Blender's window fills the screen at (0, 0).
"""

import json
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


class GuiError(RuntimeError):
    """A step of the GUI suite failed (the message says which and why)."""


def free_display(first=90):
    for n in range(first, first + 100):
        if not (Path(f"/tmp/.X{n}-lock").exists() or Path(f"/tmp/.X11-unix/X{n}").exists()):
            return n
    raise GuiError("no free X display number between :90 and :189")


class Session:
    """Xvfb + Blender (started by :meth:`start`), stopped by :meth:`stop` (also on errors)."""

    def __init__(self, workdir, user_dir, size=(1920, 1200), log=print):
        self.workdir = Path(workdir)
        self.user_dir = Path(user_dir)
        self.size = size
        self.log = log
        self.channel = self.workdir / "channel"
        self.blender_log = self.workdir / "blender.log"
        self.xvfb = self.blender = None
        self.display = None
        self._n = 0

    # --- processes ----------------------------------------------------------------------

    def env(self):
        env = dict(os.environ)
        env.update(
            DISPLAY=f":{self.display}",
            BLENDER_USER_RESOURCES=str(self.user_dir),
            HOME=str(self.workdir / "home"),
            TMPDIR=str(self.workdir / "tmp"),
        )
        # Mesa's software rasteriser, whatever the machine has.
        env.update(LIBGL_ALWAYS_SOFTWARE="1", GALLIUM_DRIVER="llvmpipe")
        return env

    def start_x(self):
        self.display = free_display()
        (self.workdir / "home").mkdir(parents=True, exist_ok=True)
        (self.workdir / "tmp").mkdir(parents=True, exist_ok=True)
        w, h = self.size
        self.xvfb = subprocess.Popen(
            [
                "Xvfb",
                f":{self.display}",
                "-screen",
                "0",
                f"{w}x{h}x24",
                "-nolisten",
                "tcp",
                "-noreset",
                "+extension",
                "GLX",
            ],
            stdout=subprocess.DEVNULL,
            stderr=open(self.workdir / "xvfb.log", "w"),
        )
        t0 = time.monotonic()
        while time.monotonic() - t0 < 20:
            if self.xvfb.poll() is not None:
                raise GuiError(f"Xvfb exited ({self.xvfb.returncode}); see {self.workdir}/xvfb.log")
            if (
                subprocess.run(
                    ["xdpyinfo"],
                    env=self.env(),
                    stdout=subprocess.DEVNULL,
                    stderr=subprocess.DEVNULL,
                ).returncode
                == 0
            ):
                return
            time.sleep(0.1)
        raise GuiError("Xvfb did not answer within 20 s")

    def start_blender(self, extra_args=()):
        if self.channel.exists():
            shutil.rmtree(self.channel)
        self.channel.mkdir(parents=True)
        w, h = self.size
        # --log-level info: the log says which operators started, finished or were cancelled.
        cmd = [
            "blender",
            "--window-geometry",
            "0",
            "0",
            str(w),
            str(h),
            "-noaudio",
            "--log-level",
            "info",
            *extra_args,
            "--python",
            str(HERE / "agent.py"),
            "--",
            "--channel",
            str(self.channel),
        ]
        self.blender = subprocess.Popen(
            cmd,
            env=self.env(),
            stdin=subprocess.DEVNULL,
            stdout=open(self.blender_log, "w"),
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )
        t0 = time.monotonic()
        while not (self.channel / "ready").exists():
            if self.blender.poll() is not None:
                raise GuiError(
                    f"Blender exited ({self.blender.returncode}) before its window "
                    f"was ready; see {self.blender_log}"
                )
            if time.monotonic() - t0 > 90:
                raise GuiError("Blender's window was not ready within 90 s")
            time.sleep(0.1)

    def start(self, extra_args=()):
        self.start_x()
        self.start_blender(extra_args)

    def stop(self):
        if self.blender is not None and self.blender.poll() is None:
            try:
                self.py(
                    "bpy.app.timers.register(lambda: bpy.ops.wm.quit_blender() and None, "
                    "first_interval=0.1)",
                    timeout=10,
                )
                self.blender.wait(timeout=20)
            except Exception:
                pass
            if self.blender.poll() is None:
                os.killpg(self.blender.pid, signal.SIGTERM)
                try:
                    self.blender.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    os.killpg(self.blender.pid, signal.SIGKILL)
                    self.blender.wait()
        if self.xvfb is not None and self.xvfb.poll() is None:
            self.xvfb.terminate()
            try:
                self.xvfb.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.xvfb.kill()
                self.xvfb.wait()

    # --- the agent ----------------------------------------------------------------------

    def py(self, code, timeout=120):
        """Run ``code`` in Blender's main loop; returns its variable ``result`` (JSON)."""
        n = self._n
        self._n += 1
        cmd = self.channel / f"cmd-{n}.py"
        tmp = self.channel / f".cmd-{n}.tmp"
        tmp.write_text(code)
        os.replace(tmp, cmd)
        res = self.channel / f"res-{n}.json"
        t0 = time.monotonic()
        while not res.exists():
            if self.blender.poll() is not None:
                raise GuiError(
                    f"Blender exited ({self.blender.returncode}) while running: "
                    f"{code.strip().splitlines()[0][:100]}"
                )
            if time.monotonic() - t0 > timeout:
                raise GuiError(
                    f"Blender did not answer within {timeout} s (busy or hung) to: "
                    f"{code.strip().splitlines()[0][:100]}"
                )
            time.sleep(0.005)
        out = json.loads(res.read_text())
        if time.monotonic() - t0 > 2 and self.log:
            self.log(
                f"  (Blender answered after {time.monotonic() - t0:.1f} s: "
                f"{code.strip().splitlines()[0][:60]})"
            )
        if not out["ok"]:
            raise GuiError("Python in Blender failed:\n" + out["error"])
        return out["result"]

    def wait_idle(self, timeout=120):
        """Returns once Blender's main loop runs again (after a long operator)."""
        self.py("result = 1", timeout=timeout)

    # --- input --------------------------------------------------------------------------

    def xdo(self, *args):
        r = subprocess.run(
            ["xdotool", *map(str, args)], env=self.env(), capture_output=True, text=True
        )
        if r.returncode:
            raise GuiError(f"xdotool {' '.join(map(str, args))} failed: {r.stderr.strip()}")
        return r.stdout

    def move(self, x, y):
        # No --sync: it waits 15 s when the pointer is already there; the X server keeps the
        # order of events anyway.
        self.xdo("mousemove", int(x), int(y))

    def click(self, x, y, button=1, modifiers=()):
        """Pointer to (x, y), then the press, then the release, each once Blender's main
        loop has taken what came before, as a hand does (a press lasts a tenth of a
        second). Pressed at once, a checkbox was toggled without an undo step (Ctrl+Z then
        undid the step before it): Blender records a toggle's undo step on release for the
        button under where its drag began, and a press taken before the move can begin it
        elsewhere; with press and release sent together it was still missed once in many
        runs."""
        self.move(x, y)
        self.wait_idle()
        for m in modifiers:
            self.xdo("keydown", m)
        self.xdo("mousedown", button)
        self.wait_idle()
        self.xdo("mouseup", button)
        self.wait_idle()
        for m in reversed(modifiers):
            self.xdo("keyup", m)

    def key(self, keys, at=None):
        if at is not None:
            self.move(*at)
        self.xdo("key", keys)

    # --- screen -------------------------------------------------------------------------

    def grab(self):
        """The screen as an (H, W, 3) uint8 array (ImageMagick's import: Blender's own
        screenshot operator gives a black image under llvmpipe)."""
        r = subprocess.run(
            ["import", "-window", "root", "-depth", "8", "ppm:-"],
            env=self.env(),
            capture_output=True,
        )
        if r.returncode:
            raise GuiError(f"import -window root failed: {r.stderr.decode(errors='replace')}")
        return read_ppm(r.stdout)

    def save(self, img, path, crop=None, scale=None, palette=False):
        """Write ``img`` (or its ``crop`` = (x, y, w, h)) as a PNG, optionally scaled, or
        with at most 256 colours (``palette``: a small file for the docs)."""
        if crop is not None:
            x, y, w, h = crop
            img = img[y : y + h, x : x + w]
        args = ["convert", "ppm:-"]
        if scale is not None and scale != 1:
            args += ["-filter", "Lanczos", "-resize", f"{scale * 100:g}%"]
        if palette:
            args += ["-dither", "None", "-colors", "256"]
        args += [
            "-strip",
            "-define",
            "png:compression-level=9",
            f"png{'8' if palette else ''}:{path}",
        ]
        h, w = img.shape[:2]
        data = f"P6\n{w} {h}\n255\n".encode() + np.ascontiguousarray(img).tobytes()
        r = subprocess.run(args, input=data, capture_output=True)
        if r.returncode:
            raise GuiError(f"convert failed: {r.stderr.decode(errors='replace')}")
        return path


def read_ppm(data):
    """A binary PPM (P6, maxval 255) as an (H, W, 3) uint8 array."""
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos : pos + 1].isspace():
            pos += 1
        if data[pos : pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end : end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    pos += 1
    magic, w, h, maxval = fields[0], int(fields[1]), int(fields[2]), int(fields[3])
    if magic != b"P6" or maxval != 255:
        raise GuiError(f"unexpected screenshot format {magic!r} maxval {maxval}")
    return np.frombuffer(data, np.uint8, w * h * 3, pos).reshape(h, w, 3)
