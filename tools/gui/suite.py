# SPDX-License-Identifier: GPL-3.0-or-later
"""The GUI suite: the extension in a real, windowed Blender, used as an animator would.

Run by ``./dev gui`` inside the GUI root (tools/gui/gui-root), with Xvfb and Mesa's software
OpenGL. It builds the extension zip with that Blender's ``--command extension build``,
installs it with ``extension install-file -r user_default -e``, starts Blender with its window
and drives one scene through the sidebar:

* real input (xdotool): open the sidebar (N), pick the Motion Patches tab (a click on it),
  + on the turn list, Bake, collapse the Locomotion panel (a click on its header), + on the
  prop's clip list, Tag Object Patch, Plan Path, Analyse Motion, Plan Path again, Show
  Planner Overlay, top view (numpad 7), the overlay unticked then Ctrl+Z, Ctrl+Shift+Z,
  Ctrl+Z, Plan Crowd with Esc while it runs, then to its end, Add Body on the eight walkers,
  Duplicate Crowd to twenty (Return in its dialog), Every Character's Grid ticked and
  unticked, Ctrl+O and Return in the file browser (samples/props.blend), there Plan Path,
  Analyse Motion and Add Body;
* Python, where input cannot reach (tools/gui/agent.py): importing the mocap (a file
  browser), making the walker, the goal and the chair, choosing actions in the lists,
  placing the views, pointing the file browser at the sample, opening the preferences at
  the add-on.

Buttons are found on screen by their identity, not by coordinates written here: the pointer
is moved over the sidebar and Ctrl+C (an operator button copies its Python command) or
Ctrl+Shift+C (a property copies its data path) says what is under it.

Checks: each operator did its job (read back from the scene: a patch with kept segments,
the prop tagged, NLA tracks and a plan record on the walker, the scene's frame range
covering the plan, analysis figures stored, the overlay on, a capsule per bone on each
walker's evaluated bones, the copies of a walker with a body given bodies); the chair, 0.5 m
high, tagged with a jump that clears 0.18 m: the tag's warning and Plan Path's name both
heights (read from Blender's log, the chair's height from its evaluated bounds) and the
walker goes round it, no bone of its evaluated rig inside it; Plan Path again clears the
walker's figures (the Analysis panel's hint instead, shot) and Analyse measures the new plan;
after each of untick, Ctrl+Z, Ctrl+Shift+Z, Ctrl+Z the checkbox, the overlay's draw handler
and the path's pixels agree, and the plan is as it was; Plan Crowd's fraction (read from the
running operator) is between 0 and 1 while the status bar shows its bar, and Esc leaves
every walker and action as it was; with twenty walkers the overlay draws every path and the
grid of the active walker only (the overlay's own buffers), every grid once ticked (more of
the picture covered); the sample, saved by 4.5, plans its walker over a hurdle with no bone
of the evaluated rig inside a prop on any frame (Analyse Motion's figures) and shows its
body mid-jump. No screenshot is blank; overlay pixels: where the planned path must be
(projected by Blender) the overlay's path colours appear, and inside the chair's outline
nothing of the overlay shows (depth test); body pixels: at each walker's chest (projected)
the picture changes when the bodies are hidden; and Blender's log has no traceback and no
error line. Screenshots of every state go to ``--out``; ``--docs DIR`` also writes the
README's small ones. The steps after the first plans are in steps_overlay.py and
steps_sample.py.

Exit status: 0 all passed, 1 something failed (the summary says what).
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from session import GuiError, Session  # noqa: E402
from steps_overlay import OverlaySteps  # noqa: E402
from steps_sample import SampleSteps  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
EXT_ID = "motion_patches"
MODULE = f"bl_ext.user_default.{EXT_ID}"
TAB = "Motion Patches"
# The overlay's path colours (panels/overlay.py COLOURS), 0-255: segments, traversal, connector.
PATH_COLOURS = np.array(
    [(41, 115, 217), (242, 153, 25), (217, 38, 38), (153, 153, 153), (26, 178, 77)], float
)
COLOUR_TOLERANCE = 40  # per channel (anti-aliasing, blending with what is below)
# Blender's log: lines that fail the run. Debian's build and Mesa print a few harmless lines.
LOG_BAD = re.compile(
    r"Traceback|^Error\b|\| Error\b|\bERROR\b|Exception|Segmentation fault|"
    r"Cancelled: bpy\.ops\.motion_patches|[Uu]nable to load|[Ff]ailed to"
)
LOG_ALLOWED = re.compile(
    r"Color management: .*|.*libdecor.*|.*pipewire.*|.*ALSA.*|"
    r".*Warning: .*|.*failed to open .*\.(ttf|otf).*",
    re.I,
)


class Step:
    """Record of one step of the scenario: name, status and detail."""

    def __init__(self, name):
        self.name, self.ok, self.detail, self.seconds = name, None, "", 0.0


class Suite(OverlaySteps, SampleSteps):
    def __init__(self, args):
        self.args = args
        self.out = Path(args.out).resolve()
        self.steps = []
        self.shots = {}
        self.facts = {}
        self.t0 = time.monotonic()
        self.cache = {}  # identity -> (x, y) of a button last found there
        self.doc_boxes = {}  # screenshot name -> (x0, y0, x1, y1) of the README's cut
        self.sidebar_panel_width = 270
        self.probes = 0
        self.expected_log = set()  # numbers of log lines a step caused on purpose (Esc)

    # --- bookkeeping --------------------------------------------------------------------

    def log(self, msg):
        print(f"[gui {time.monotonic() - self.t0:6.1f}s] {msg}", flush=True)

    def step(self, name, fn):
        st = Step(name)
        self.steps.append(st)
        t = time.monotonic()
        self.log(f"{name} ...")
        try:
            st.detail = fn() or ""
            st.ok = True
        except (GuiError, AssertionError) as exc:
            st.ok, st.detail = False, str(exc) or type(exc).__name__
        except Exception:
            st.ok, st.detail = False, traceback.format_exc()
        st.seconds = time.monotonic() - t
        self.log(
            f"{name}: {'ok' if st.ok else 'FAILED'} ({st.seconds:.1f} s)"
            + (f" {st.detail}" if st.detail else "")
        )
        return st.ok

    def check(self, cond, msg):
        if not cond:
            raise AssertionError(msg)

    # --- blender outside the window: build, install -------------------------------------

    def blender_cmd(self, *args, timeout=300):
        env = dict(
            os.environ, BLENDER_USER_RESOURCES=str(self.user_dir), HOME=str(self.work / "home")
        )
        r = subprocess.run(
            ["blender", *args],
            env=env,
            capture_output=True,
            text=True,
            timeout=timeout,
            stdin=subprocess.DEVNULL,
        )
        text = r.stdout + r.stderr
        (self.work / "blender-commands.log").open("a").write(
            f"$ blender {' '.join(args)}\n{text}\n"
        )
        if r.returncode or LOG_BAD.search(_without_allowed(text)):
            raise GuiError(
                f"blender {' '.join(args)} failed (exit {r.returncode}):\n{text[-2000:]}"
            )
        return text

    def build_and_install(self):
        version = self.blender_cmd("--background", "--factory-startup", "--version")
        self.facts["blender"] = re.search(r"Blender (\S+.*)", version).group(1).strip()
        dist = self.work / "dist"
        dist.mkdir()
        src = self.work / "src"
        # The extension's files as the builder sees them in a fresh clone (no caches, no venvs).
        shutil.copytree(
            REPO,
            src,
            ignore=shutil.ignore_patterns(
                ".git",
                ".venv",
                "__pycache__",
                ".pytest_cache",
                "dist",
                "sample_blends",
                "bench",
                "tests",
                "tools",
                "docs",
                "examples",
            ),
        )
        self.blender_cmd(
            "--command", "extension", "build", "--source-dir", str(src), "--output-dir", str(dist)
        )
        zips = list(dist.glob("*.zip"))
        self.check(len(zips) == 1, f"extension build made {len(zips)} zips in {dist}")
        self.facts["zip"] = f"{zips[0].name}, {zips[0].stat().st_size // 1024} KiB"
        self.blender_cmd(
            "--command", "extension", "install-file", "-r", "user_default", "-e", str(zips[0])
        )
        # No splash over the window; the add-on must be enabled in the saved preferences.
        out = self.blender_cmd(
            "--background",
            "--python-expr",
            "import bpy, addon_utils\n"
            "bpy.context.preferences.view.show_splash = False\n"
            "bpy.ops.wm.save_userpref()\n"
            f"print('ENABLED', addon_utils.check({MODULE!r}))\n",
        )
        self.check(
            "ENABLED (True, True)" in out,
            f"{MODULE} is not enabled after install-file -e: {out[-500:]}",
        )
        return f"Blender {self.facts['blender']}; {self.facts['zip']} installed and enabled"

    # --- screen helpers -----------------------------------------------------------------

    def sidebar(self):
        """(left, top, width, height) of the 3D view's sidebar, and the panels' x range."""
        r = self.s.py('result = rect(region("VIEW_3D", "UI"))')
        x, y, w, h = r
        self.sidebar_panel_width = w - 22  # without the tabs
        return r, (x + 8, x + w - 31)

    def settle(self):
        """Let a panel that grew after a scripted change be laid out again: Blender does it
        on the next redraw, which moving the pointer over the sidebar brings."""
        (x, y, w, h), (left, _right) = self.sidebar()
        self.s.py("redraw_all(); result = 1")
        self.s.move(left + 5, y + h // 2)
        self.s.move(left + 6, y + h // 2 + 3)
        self.s.wait_idle()
        time.sleep(0.2)
        self.s.wait_idle()

    def probe(self, x, y, kind):
        """What is under (x, y): an operator ("motion_patches.bake_locomotion_patch") for
        kind "op" (Ctrl+C), a data path ("motion_patches.show_overlay") for "prop"
        (Ctrl+Shift+C), or ""."""
        self.probes += 1
        self.s.move(x, y)
        self.s.xdo("key", "ctrl+c" if kind == "op" else "ctrl+shift+c")
        text = self.s.py("result = take_clipboard()") or ""
        if kind == "op":
            return text[len("bpy.ops.") :].split("(")[0] if text.startswith("bpy.ops.") else ""
        return text if re.fullmatch(r"[A-Za-z_][\w.\[\]\"']*", text) else ""

    def find(self, ident, kind="op", cols=(0.3, 0.7), step=9, below=None):
        """Screen position of the button ``ident`` in the sidebar, found by probing: first
        where it was last seen and outwards from there; else down from the button
        ``below`` (one drawn above it) when that was seen, else from the top. ``cols``:
        fractions of the panels' width, or (> 1) pixels from their right edge."""
        (x, top, w, h), (left, right) = self.sidebar()
        xs = [int(left + f * (right - left)) if f <= 1 else int(right - f) for f in cols]
        ys = list(range(top + 6, top + h - 6, step))
        if ident in self.cache:
            y0 = self.cache[ident][1]
            ys.sort(key=lambda y: abs(y - y0))
        elif below in self.cache:
            y0 = self.cache[below][1]
            ys = [y for y in ys if y > y0] + [y for y in ys if y <= y0]
        for y in ys:
            for px in xs:
                got = self.probe(px, y, kind)
                if got:
                    self.cache.setdefault(got, (px, y))
                    if got == ident:
                        self.cache[got] = (px, y)
                        return px, y
        raise GuiError(
            f"no button '{ident}' found in the sidebar (probed {len(ys) * len(xs)} "
            f"places with {'Ctrl+C' if kind == 'op' else 'Ctrl+Shift+C'})"
        )

    def press(self, ident, kind="op", cols=(0.3, 0.7), timeout=180, below=None):
        t = time.monotonic()
        n = self.probes
        x, y = self.find(ident, kind, cols, below=below)
        self.log(
            f"  {ident} found at ({x}, {y}) after {self.probes - n} probes, "
            f"{time.monotonic() - t:.1f} s"
        )
        since = len(self.log_lines())
        self.s.click(x, y)
        self.s.wait_idle(timeout=timeout)  # a long operator blocks Blender's loop until done
        self.wait_modal(timeout)  # or runs a step at a time (bake, crowd) until done
        if kind == "op":
            self.operator_ran(ident, since)
        return x, y

    def running(self):
        """The add-on's operators running a step at a time (modal) in the window."""
        return self.s.py(
            "result = [op.bl_idname for op in window().modal_operators "
            "if op.bl_idname.startswith('MOTION_PATCHES_OT')]"
        )

    def wait_modal(self, timeout=300):
        t0 = time.monotonic()
        while self.running():
            if time.monotonic() - t0 > timeout:
                raise GuiError(f"{self.running()} still running after {timeout} s")
            time.sleep(0.2)
        return time.monotonic() - t0

    def grab_checked(self, name, crop=None, min_colours=24, img=None):
        """A screenshot (the screen or a crop; ``img``: one just taken) saved as
        ``name``.png; fails when blank."""
        img = self.s.grab() if img is None else img
        part = (
            img if crop is None else img[crop[1] : crop[1] + crop[3], crop[0] : crop[0] + crop[2]]
        )
        flat = part.reshape(-1, 3)
        colours = len(np.unique(flat[:: max(1, len(flat) // 200000)], axis=0))
        self.check(
            colours >= min_colours and float(flat.std()) > 4.0,
            f"screenshot '{name}' is blank ({colours} colours, std {flat.std():.1f})",
        )
        path = self.out / f"{name}.png"
        self.s.save(img, path, crop)
        self.shots[name] = (path, crop, img)
        return img

    def sidebar_shot(self, name, y_range=None):
        (x, top, w, h), _ = self.sidebar()
        y0, y1 = y_range or (top, top + h)
        return self.grab_checked(name, (x, y0, w, y1 - y0))

    def reports(self):
        """Every report Blender showed in its window so far (the Info editor's text, types
        not included): the status bar's messages, errors included."""
        return self.s.py("""
a = area("DOPESHEET_EDITOR")
old = a.type, a.ui_type
a.type = "INFO"
with bpy.context.temp_override(window=window(), area=a,
                               region=next(r for r in a.regions if r.type == "WINDOW")):
    bpy.ops.info.select_all(action="SELECT")
    bpy.ops.info.report_copy()
text = take_clipboard()
a.type, a.ui_type = old
result = text.splitlines()""")

    def log_lines(self):
        return (self.work / "blender.log").read_text(errors="replace").splitlines()

    def operator_ran(self, ident, since):
        """Blender's log (--log-level info) since line ``since``: fails unless ``ident``
        was started and finished (a Cancelled operator reported an error in the window)."""
        lines = self.log_lines()[since:]
        op = f"bpy.ops.{ident}("
        started = [ln for ln in lines if "Started" in ln and op in ln]
        bad = [ln for ln in lines if "Cancelled" in ln and op in ln]
        if bad or not started:
            why = self.reports()[-3:]
            raise GuiError(
                f"{ident} {'was cancelled' if bad else 'never started'} after the "
                f"click; last reports: {why}"
            )

    # --- the scenario -------------------------------------------------------------------

    def run(self):
        self.work = Path(tempfile.mkdtemp(prefix="motion_patches-gui-", dir="/tmp"))
        self.user_dir = self.work / "user"
        (self.work / "home").mkdir(parents=True)
        if self.out.exists():
            for old in self.out.glob("*.png"):
                old.unlink()
        self.out.mkdir(parents=True, exist_ok=True)
        try:
            if not self.step("build and install the extension zip", self.build_and_install):
                return
            self.s = Session(self.work, self.user_dir, size=(1920, 1200), log=self.log)
            try:
                for name, fn in self.scenario():
                    # A failed check of the scene alone does not stop the scenario; a step
                    # that could not do what the next ones build on does.
                    if not self.step(name, fn) and fn not in self.non_blocking:
                        break
            finally:
                try:  # what the window showed as reports, for whoever reads a failure
                    (self.out / "reports.txt").write_text("\n".join(self.reports()) + "\n")
                except Exception as exc:
                    self.log(f"could not read the reports: {exc}")
                self.s.stop()
                self.step("Blender's log: no traceback, no error", self.check_log)
        finally:
            self.write_docs()
            self.summary()
            if not self.args.keep:
                shutil.rmtree(self.work, ignore_errors=True)

    def scenario(self):
        return [
            ("start Blender under Xvfb (llvmpipe)", self.start),
            ("scene: mocap, walker, goal, chair (Python)", self.make_scene),
            ("sidebar: N, then a click on the Motion Patches tab", self.open_tab),
            ("Locomotion Patches: + turn clip, Bake", self.bake),
            ("Object Patch: + clip, Tag Object Patch (warned: too high to jump)", self.tag),
            ("Planning: Plan Path (round the chair, saying why)", self.plan),
            ("scene frame range follows the plan", self.frame_range),
            ("Analysis: Analyse Motion", self.analyse),
            ("Analysis: Plan Path clears the figures, Analyse Motion again", self.reanalyse),
            ("Overlay: Show Planner Overlay, top view", self.overlay_top),
            ("Overlay: perspective view, depth", self.overlay_perspective),
            ("Overlay: untick, Ctrl+Z, Ctrl+Shift+Z, Ctrl+Z", self.overlay_undo),
            ("Planning: Plan Crowd, its progress, Esc, then to its end", self.crowd),
            ("Planning: Add Body on the eight walkers", self.bodies),
            ("Planning: Duplicate Crowd to twenty, Return in its dialog", self.duplicate),
            ("Overlay: a crowd of twenty, the active walker's grid", self.crowd_overlay),
            ("Sample: Ctrl+O props.blend, Plan Path over a hurdle, Add Body", self.sample),
            ("Preferences: the add-on's defaults", self.preferences),
        ]

    @property
    def non_blocking(self):
        """Steps whose failure leaves the scene as the next steps need it."""
        return (
            self.frame_range,
            self.reanalyse,
            self.overlay_top,
            self.overlay_perspective,
            self.overlay_undo,
            self.crowd_overlay,
            self.sample,
        )

    def start(self):
        self.s.start()
        info = self.s.py(
            """
import addon_utils, gpu, sys
result = dict(enabled=addon_utils.check(%r), gpu=gpu.platform.renderer_get(),
              version=bpy.app.version_string, size=[window().width, window().height])"""
            % MODULE
        )
        self.check(info["enabled"] == [True, True], f"add-on not enabled in the window: {info}")
        self.check(info["size"] == [1920, 1200], f"window is {info['size']}, not 1920x1200")
        self.facts["gpu"] = info["gpu"]
        self.s.py(f'import sys\nmp = sys.modules["{MODULE}"]\nresult = 1')
        return f"{info['version']}, {info['gpu']}, window {info['size'][0]}x{info['size'][1]}"

    def make_scene(self):
        mocap = Path(os.environ.get("MOTION_PATCHES_MOCAP") or REPO.parent / "shared" / "mocap")
        cmu = mocap / "cmu"
        for f in ("16_15", "16_18", "16_06"):
            self.check((cmu / f"{f}.bvh").exists(), f"mocap {cmu}/{f}.bvh not found")
        self.s.py(f"""
import numpy as np
scene = bpy.context.scene
for ob in list(scene.objects):
    if ob.type in ("MESH", "LIGHT"):  # the startup cube and light (its icon in the views)
        bpy.data.objects.remove(ob)
scene.render.fps = 30
arm, acts = mp.api.import_mocap([{str(cmu / "16_15.bvh")!r}, {str(cmu / "16_18.bvh")!r},
                                 {str(cmu / "16_06.bvh")!r}], name="Source")
s = scene.motion_patches
s.source_armature, s.straight_action = arm, acts[0]
arm.hide_set(True)
walker = arm.copy()
walker.name = "Walker"
walker.animation_data_clear()
scene.collection.objects.link(walker)
walker.location = (0.5, 1.5, 0.0)  # off the world's axes (red and green lines)
walker.rotation_euler = (0, 0, np.pi / 2)  # the rig's rest faces -Y: face +X
goal = bpy.data.objects.new("Goal", None)
goal.empty_display_type = "SINGLE_ARROW"
scene.collection.objects.link(goal)
goal.location = (6.5, 1.5, 0.0)
goal.rotation_euler = (0, 0, np.pi / 2)  # its -Y (the facing) along +X
s.goal = goal
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(3.5, 1.5, 0.25))
chair = bpy.context.active_object
chair.name = "Chair"
chair.scale = (0.4, 0.44, 0.5)
for ob in scene.objects:
    ob.select_set(False)
bpy.context.view_layer.objects.active = None
result = 1""")
        return (
            "Source (16_15, 16_18, 16_06 at 30 fps), Walker facing +X, Goal 6 m ahead, "
            "Chair 0.4 m half way"
        )

    def open_tab(self, shot="01-sidebar"):
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        if not self.s.py('result = area("VIEW_3D").spaces[0].show_region_ui'):
            self.s.key("n", at=(view[0] + view[2] // 2, view[1] + view[3] // 2))
            self.s.wait_idle()
            ok = self.s.py('result = area("VIEW_3D").spaces[0].show_region_ui')
            self.check(ok, "N over the viewport did not open the sidebar")
        (x, top, w, h), _ = self.sidebar()
        # The tabs run down the sidebar's outer edge; click down it until ours is active.
        for y in range(top + 10, top + h, 24):  # a tab is at least ~35 px long
            self.s.click(x + w - 13, y)
            cat = self.s.py('result = region("VIEW_3D", "UI").active_panel_category')
            if cat == TAB:
                break
        else:
            raise GuiError(f"clicking down the sidebar's tabs never made '{TAB}' active")
        self.settle()
        self.sidebar_shot(shot)
        return f"tab clicked at y={y}"

    def bake(self):
        self.press("motion_patches.turn_add", cols=(12,))
        n = self.s.py("result = len(bpy.context.scene.motion_patches.turn_actions)")
        self.check(n == 1, f"+ beside the turn list left {n} rows (want 1)")
        self.s.py(
            "s = bpy.context.scene.motion_patches\n"
            's.turn_actions[0].action = bpy.data.actions["16_18"]\nresult = 1'
        )
        self.settle()
        t = time.monotonic()
        self.press(
            "motion_patches.bake_locomotion_patch", timeout=300, below="motion_patches.turn_add"
        )
        secs = time.monotonic() - t
        stats = self.s.py("""
import json
s = bpy.context.scene.motion_patches
result = [len(s.patches), json.loads(s.patches[0].stats) if len(s.patches) else None]""")
        self.check(
            stats[0] == 1 and stats[1]["kept"] > 100,
            f"Bake did not leave a patch with kept segments: {stats}",
        )
        self.settle()
        self.sidebar_shot("02-locomotion-baked")
        # Collapse the Locomotion panel (a click on its header, the sidebar's first) so the
        # others fit below it.
        (x, top, w, h), (left, right) = self.sidebar()
        self.s.click(left + 60, top + 13)
        self.settle()
        return f"{stats[1]['kept']} segments kept, {stats[1]['culled']} culled, {secs:.0f} s"

    def tag(self):
        self.s.py("""
chair = bpy.data.objects["Chair"]
chair.select_set(True)
bpy.context.view_layer.objects.active = chair
result = 1""")
        self.settle()
        self.press("motion_patches.clip_add", cols=(12,))
        n = self.s.py('result = len(bpy.data.objects["Chair"].motion_patch.clips)')
        self.check(n == 1, f"+ beside the clip list left {n} rows (want 1)")
        self.s.py(
            'c = bpy.data.objects["Chair"].motion_patch.clips[0]\n'
            'c.action = bpy.data.actions["16_06"]\nc.kind = "TRAVERSAL"\nresult = 1'
        )
        self.settle()
        since = len(self.log_lines())
        self.press("motion_patches.tag_object_patch", below="motion_patches.clip_add")
        ok = self.s.py('result = bpy.data.objects["Chair"].motion_patch.enabled')
        self.check(ok, "Tag Object Patch did not tag the chair")
        # The jump clears less than the chair's 0.5 m: the tag warns, naming both heights.
        top = self.s.py("""
from mathutils import Vector
dg = bpy.context.evaluated_depsgraph_get()
ev = bpy.data.objects["Chair"].evaluated_get(dg)
result = max((ev.matrix_world @ Vector(c)).z for c in ev.bound_box)""")
        clears, high = self.too_low_warning(since, "Chair")
        self.check(
            clears < high and abs(high - top) < 0.006,
            f"the tag's warning says 16_06 clears {clears} m over a {high} m prop "
            f"(the chair's evaluated top is {top:.3f} m)",
        )
        self.facts["too_low"] = [clears, high]
        self.settle()
        self.sidebar_shot("03-object-patch")
        return f"warned: 16_06 clears {clears:.2f} m, the chair is {high:.2f} m high"

    def too_low_warning(self, since, prop, what="a tag"):
        """(clearance, height) from the WARNING Blender logged since line ``since`` that a
        traversal clip clears less than ``prop`` is high (the report the window showed)."""
        pat = re.compile(rf"clears ([\d.]+) m over '{prop}', which is ([\d.]+) m high")
        found = [
            pat.search(ln)
            for ln in self.log_lines()[since:]
            if "| WARNING" in ln and pat.search(ln)
        ]
        if not found:
            raise AssertionError(
                f"{what} gave no warning naming both heights; last reports: {self.reports()[-3:]}"
            )
        return float(found[0].group(1)), float(found[0].group(2))

    def select_walker(self):
        """Only the Walker selected, and active: what the Planning buttons then act on."""
        self.s.py("""
for ob in bpy.context.scene.objects:
    ob.select_set(False)
w = bpy.data.objects["Walker"]
w.select_set(True)
bpy.context.view_layer.objects.active = w
result = 1""")
        self.settle()

    def plan(self):
        self.select_walker()
        since = len(self.log_lines())
        self.press("motion_patches.plan_path", cols=(0.25,))
        res = self.s.py("""
import json
w = bpy.data.objects["Walker"]
ad = w.animation_data
tracks = [t.name for t in ad.nla_tracks] if ad else []
meta, arrays = mp.api.load_plan_record(w) if mp.api.PLAN_KEY in w else (None, None)
sc = bpy.context.scene
result = dict(tracks=tracks, strips=sum(len(t.strips) for t in ad.nla_tracks) if ad else 0,
              plan=[meta["frame_start"], meta["frame_end"]] if meta else None,
              traversals=meta.get("traversals") if meta else None,
              scene=[sc.frame_start, sc.frame_end])""")
        self.check(res["plan"] is not None, "Plan Path left no plan record on the Walker")
        self.check(
            "MP motion" in res["tracks"] and res["strips"] > 0,
            f"Plan Path wrote no NLA strips on the Walker: {res}",
        )
        self.facts["plan"] = res
        # Round the chair, not over it, and the status bar says why (both heights).
        self.check(not res["traversals"], f"the walker jumps the 0.5 m chair: {res}")
        said = self.too_low_warning(since, "Chair", "Plan Path")
        self.check(
            said == tuple(self.facts.get("too_low", said)),
            f"Plan Path's reason {said} is not the tag's {self.facts.get('too_low')}",
        )
        self.settle()
        self.sidebar_shot("04-planning")
        return (
            f"tracks {res['tracks']}, frames {res['plan'][0]}-{res['plan'][1]}, scene range "
            f"{res['scene'][0]}-{res['scene'][1]}, no traversal (reported: clears "
            f"{said[0]:.2f} m, {said[1]:.2f} m high)"
        )

    def frame_range(self):
        res = self.facts["plan"]
        self.check(
            res["scene"] == res["plan"],
            f"the scene's frame range {res['scene']} does not follow the plan "
            f"{res['plan']} (the scene's was Blender's default 1-250)",
        )
        return f"{res['scene'][0]}-{res['scene'][1]}"

    def analyse(self):
        self.press("motion_patches.analyse_motion", timeout=300, below="motion_patches.plan_path")
        fig = self.s.py("""
import json
w = bpy.data.objects["Walker"]
raw = w.get("motion_patches_analysis")
result = json.loads(raw) if raw else None""")
        self.check(
            fig is not None and "foot_skate" in fig,
            "Analyse Motion stored no figures on the Walker",
        )
        self.check(
            fig["frames_body_inside_prop"] == 0,
            f"a bone of the walker is inside the chair on {fig['frames_body_inside_prop']} frames",
        )
        self.settle()
        self.sidebar_shot("05-analysis")
        return (
            f"foot skate {fig['foot_skate']['mean_cm_per_frame']:.2f} cm/frame, goal error "
            f"{fig['goal_position_error_cm']:.1f} cm, no bone in the chair"
        )

    ANALYSIS = """
import json
w = bpy.data.objects["Walker"]
raw = w.get("motion_patches_analysis")
meta, arrays = mp.api.load_plan_record(w)
result = [json.loads(raw) if raw else None, meta["frame_end"] - meta["frame_start"] + 1]"""

    def reanalyse(self):
        """Plan Path again: the figures of the plan it replaced are gone from the Walker and
        its Analysis panel (the hint instead); Analyse Motion measures the new plan."""
        self.press("motion_patches.plan_path", cols=(0.25,))  # fails unless it ran
        fig, frames = self.s.py(self.ANALYSIS)
        self.check(fig is None, "the Walker kept the figures of the plan Plan Path replaced")
        self.settle()
        self.sidebar_shot("13-analysis-cleared")
        self.press("motion_patches.analyse_motion", timeout=300, below="motion_patches.plan_path")
        fig, frames = self.s.py(self.ANALYSIS)
        self.check(
            fig is not None and fig["frames"] == frames,
            f"Analyse Motion did not measure the new plan of {frames} frames: "
            f"{fig and fig['frames']}",
        )
        self.settle()
        self.sidebar_shot("14-analysis-refreshed")
        return f"cleared by Plan Path; {fig['frames']} frames measured again"

    # --- overlay ------------------------------------------------------------------------

    def view_state(self):
        """Projection of the planned path and of the chair into screen pixels, from Blender:
        {"path": [[x, y, hidden]], "chair": [[x, y]] (inside its outline), "view": rect}."""
        return self.s.py('''
import numpy as np
from bpy_extras.view3d_utils import location_3d_to_region_2d, region_2d_to_origin_3d
from mathutils import Vector
reg = region("VIEW_3D", "WINDOW")
r3d = area("VIEW_3D").spaces[0].region_3d
rx, ry, rw, rh = rect(reg)
w = bpy.data.objects["Walker"]
meta, arrays = mp.api.load_plan_record(w)
g = arrays["ground"]
dg = bpy.context.evaluated_depsgraph_get()
chair = bpy.data.objects["Chair"]
def screen(p):
    v = location_3d_to_region_2d(reg, r3d, Vector(p))
    return None if v is None else (rx + v.x, ry + rh - v.y)
def hidden(p):
    """True when something (the chair) lies between the eye and p."""
    p = Vector(p)
    v = location_3d_to_region_2d(reg, r3d, p)
    eye = region_2d_to_origin_3d(reg, r3d, v) if v is not None else None
    if eye is None:
        return True
    d = p - eye
    hit, loc, *_ = bpy.context.scene.ray_cast(dg, eye, d.normalized(), distance=d.length - 0.02)
    return bool(hit)
# What covers the viewport: the other regions of its area (the sidebar overlaps it), and
# the walker's bones at the start, the goal's arrow at the end (drawn over the ground).
covers = [rect(r) for r in area("VIEW_3D").regions if r.type != "WINDOW" and r.width > 1
          and r.height > 1]
def covered(x, y):
    return any(cx - 6 <= x < cx + cw + 6 and cy - 6 <= y < cy + ch + 6 for cx, cy, cw, ch in covers)
ends = [Vector(w.matrix_world.translation),
        Vector(bpy.data.objects["Goal"].matrix_world.translation)]
path = []
for k in np.linspace(0, len(g) - 1, 80).astype(int):
    p = (float(g[k, 0]), float(g[k, 1]), 0.01)
    s = screen(p)
    if (s and rx + 4 <= s[0] < rx + rw - 4 and ry + 4 <= s[1] < ry + rh - 4
            and not covered(*s) and min((Vector(p) - e).xy.length for e in ends) > 0.6):
        path.append([s[0], s[1], hidden(p)])
m = chair.matrix_world
inside = []
for u in np.linspace(-0.35, 0.35, 7):   # points on the chair's faces the eye sees
    for v in np.linspace(-0.35, 0.35, 7):
        for local, normal in (((u, v, 0.5), (0, 0, 1)), ((u, -0.5, 0.5 + v), (0, -1, 0)),
                              ((-0.5, u, 0.5 + v), (-1, 0, 0)), ((0.5, u, 0.5 + v), (1, 0, 0)),
                              ((u, 0.5, 0.5 + v), (0, 1, 0))):
            p = m @ Vector(local)
            s = screen(p)
            v2 = location_3d_to_region_2d(reg, r3d, p)
            eye = region_2d_to_origin_3d(reg, r3d, v2) if v2 is not None else None
            n = (m.to_3x3() @ Vector(normal)).normalized()
            if (s and eye is not None and n.dot((eye - p).normalized()) > 0.3
                    and not hidden(p) and not covered(*s)):
                inside.append(list(s))
result = dict(path=path, chair=inside, view=[rx, ry, rw, rh], covers=covers,
              ends=[list(p) for p in (screen(e) for e in ends) if p])''')

    @staticmethod
    def near_colour(img, x, y, r=3):
        """Whether one of the overlay's path colours is within ``r`` pixels of (x, y)."""
        patch = img[max(0, y - r) : y + r + 1, max(0, x - r) : x + r + 1].reshape(-1, 3)
        d = np.abs(patch.astype(float)[:, None, :] - PATH_COLOURS[None]).max(axis=2)
        return bool((d <= COLOUR_TOLERANCE).any())

    def overlay_pixels(self, img_off, img_on, st, name):
        """The overlay is where it must be and nowhere it must not: along the visible
        planned path a path colour appears (with the overlay, not without it), behind the
        chair and inside its outline the picture does not change with the overlay."""
        near_colour = self.near_colour
        visible = [(int(round(x)), int(round(y))) for x, y, hid in st["path"] if not hid]
        hidden = [(int(round(x)), int(round(y))) for x, y, hid in st["path"] if hid]
        self.check(len(visible) >= 10, f"{name}: only {len(visible)} path points in view")
        hits = [near_colour(img_on, x, y) for x, y in visible]
        before = [near_colour(img_off, x, y) for x, y in visible]
        frac = float(np.mean(hits))
        changed = float(np.mean([hits[i] and not before[i] for i in range(len(hits))]))
        self.check(
            frac >= 0.8,
            f"{name}: the path colour shows at only {frac:.0%} of "
            f"{len(visible)} visible path points (want >= 80 %)",
        )
        self.check(
            changed >= 0.6,
            f"{name}: the path colour was already there without the "
            f"overlay at {1 - changed:.0%} of the points",
        )
        diff = [
            float(np.abs(img_on[y, x].astype(int) - img_off[y, x].astype(int)).max())
            for x, y in (tuple(map(int, map(round, p))) for p in st["chair"])
        ]
        self.check(
            diff and max(diff) <= 12,
            f"{name}: the overlay shows through the chair (largest change inside its "
            f"outline {max(diff) if diff else 'n/a'} of 255; depth test?)",
        )
        through = [
            p for p in hidden if near_colour(img_on, *p, r=1) and not near_colour(img_off, *p, r=1)
        ]
        self.check(
            len(through) <= max(1, len(hidden) // 5),
            f"{name}: {len(through)} of {len(hidden)} path points behind the chair "
            f"show the path colour",
        )
        return (
            f"path colour at {frac:.0%} of {len(visible)} visible points; chair outline "
            f"unchanged (max {max(diff):.0f}); {len(hidden)} hidden points, "
            f"{len(through)} showing"
        )

    def overlay_top(self):
        self.press(
            "motion_patches.show_overlay",
            kind="prop",
            cols=(0.1, 0.3),
            below="motion_patches.analyse_motion",
        )
        on = self.s.py("result = bpy.context.scene.motion_patches.show_overlay")
        self.check(on, "the Show Planner Overlay checkbox did not turn the overlay on")
        self.settle()
        self.sidebar_shot("06-overlay-panel")
        # Nothing selected: a selected object's orange outline would pass for the path.
        self.s.py("for ob in bpy.context.scene.objects:\n    ob.select_set(False)\nresult = 1")
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        self.s.key("KP_7", at=(view[0] + view[2] // 3, view[1] + view[3] // 2))
        self.s.wait_idle()
        top = self.s.py("""
r3d = area("VIEW_3D").spaces[0].region_3d
r3d.view_perspective = "ORTHO"
r3d.view_location = (4.2, 1.5, 0.0)  # the whole path left of the sidebar
r3d.view_distance = 6.4
redraw_all()
result = r3d.view_rotation.to_euler()[:]""")
        self.check(max(abs(a) for a in top) < 1e-3, f"numpad 7 did not give the top view ({top})")
        return self.overlay_pair("07-overlay-top")

    def overlay_pair(self, name):
        """Screenshots of the viewport with the overlay off, then on; pixel checks."""
        self.s.move(5, 5)
        self.s.py("bpy.context.scene.motion_patches.show_overlay = False\nredraw_all()\nresult=1")
        self.s.wait_idle()
        time.sleep(0.3)
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        img_off = self.s.grab()
        self.s.py("bpy.context.scene.motion_patches.show_overlay = True\nredraw_all()\nresult=1")
        self.s.wait_idle()
        time.sleep(0.3)
        st = self.view_state()
        img_on = self.grab_checked(name, crop=tuple(view))
        (self.out / f"{name}.json").write_text(json.dumps(st))
        pts = np.array([p[:2] for p in st["path"]] + st["chair"] + st["ends"]) - np.array(view[:2])
        if len(pts):  # the README's cut: the plan with a margin, between toolbar and sidebar
            lo, hi = pts.min(axis=0) - 110, pts.max(axis=0) + 110
            left, right = 0, view[2]
            for cx, cy, cw, ch in st["covers"]:
                if ch > view[3] // 2:  # a region down the side: the toolbar or the sidebar
                    if cx - view[0] < view[2] // 2:
                        left = max(left, cx - view[0] + cw)
                    else:
                        right = min(right, cx - view[0])
            self.doc_boxes[name] = (
                max(int(lo[0]), left),
                max(int(lo[1]), 0),
                min(int(hi[0]), right),
                min(int(hi[1]), view[3]),
            )
        self.s.save(img_off, self.out / f"{name}-off.png", crop=tuple(view))
        return self.overlay_pixels(img_off, img_on, st, name)

    def overlay_perspective(self):
        # From the side, low, the path running across the view behind the chair: what
        # lies on the ground behind it (the far half of its blocked area, clip markers, the
        # traversal's ground line) must be hidden by it.
        self.s.py("""
from mathutils import Euler
import math
r3d = area("VIEW_3D").spaces[0].region_3d
r3d.view_perspective = "PERSP"
r3d.view_location = (3.9, 1.6, 0.2)
r3d.view_rotation = Euler((math.radians(72), 0.0, math.radians(-12)), "XYZ").to_quaternion()
r3d.view_distance = 3.6
redraw_all()
result = 1""")
        return self.overlay_pair("08-overlay-perspective")

    # --- preferences --------------------------------------------------------------------

    # --- a crowd: progress, Esc --------------------------------------------------------

    CROWD_STATE = """
import json
def state(ob):
    ad = ob.animation_data
    return [ob.name, ob.get(mp.api.PLAN_KEY, ""),
            [[t.name, [[s.name, s.frame_start, s.frame_end] for s in t.strips]]
             for t in ad.nla_tracks] if ad else None]
crowd = sorted((o for o in bpy.data.objects if o.name.startswith("Walker")), key=lambda o: o.name)
result = [json.dumps([state(o) for o in crowd]), sorted(a.name for a in bpy.data.actions)]"""

    STATUS_BAR = """
a = next((a for a in window().screen.areas if a.type == "STATUSBAR"), None)
result = rect(a) if a is not None else [0, window().height - 40, window().width, 40]"""
    PROGRESS = """
result = [op._stepper.fraction for op in window().modal_operators
          if op.bl_idname == "MOTION_PATCHES_OT_plan_crowd" and hasattr(op, "_stepper")]"""

    def crowd(self):
        """Plan Crowd from its button on the Walker and seven more: it runs with a bar in the
        status bar while Blender's loop goes on; Esc stops it with every walker as it was;
        clicked again, it plans them all."""
        self.s.py("""
import numpy as np
src = bpy.data.objects["Walker"]
for ob in bpy.context.scene.objects:
    ob.select_set(False)
src.select_set(True)
bpy.context.view_layer.objects.active = src
for k in range(1, 8):
    w = src.copy()
    w.name = f"Walker{k}"
    w.animation_data_clear()
    bpy.context.scene.collection.objects.link(w)
    w.location = (0.5, 1.5 - 1.2 * k, 0.0)
    g = bpy.data.objects.new(f"Goal{k}", None)
    bpy.context.scene.collection.objects.link(g)
    g.location = (6.5, 1.5 - 1.2 * ((k * 3) % 8 + 1), 0.0)  # crossing the others
    g.rotation_euler = (0, 0, np.pi / 2)
    w.motion_patches_character.goal = g
    w.select_set(True)
result = 1""")
        self.settle()
        before = self.s.py(self.CROWD_STATE)
        x, y = self.find(
            "motion_patches.plan_crowd", cols=(0.75,), below="motion_patches.plan_path"
        )
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        self.s.move(view[0] + view[2] // 2, view[1] + view[3] // 2)
        bar = self.s.py(self.STATUS_BAR)
        idle = self.s.grab()
        since = len(self.log_lines())
        self.s.click(x, y)
        # Its progress: the fraction the running operator shows in the status bar, read
        # from it (the operator itself, through the window's modal operators).
        t0, seen = time.monotonic(), []
        while time.monotonic() - t0 < 20 and not (seen and 0 < seen[-1] < 1):
            time.sleep(0.1)
            got = self.s.py(self.PROGRESS)
            if not got and seen:
                break  # ended before its progress was read
            seen += got
        self.check(
            seen and 0 < seen[-1] < 1,
            f"Plan Crowd showed no progress while it ran (fractions read: {seen})",
        )
        busy = self.grab_checked("10-plan-crowd-progress", crop=tuple(bar), min_colours=8)
        later = self.s.py(self.PROGRESS)
        bx, by, bw, bh = bar
        a, b = (i[by : by + bh, bx : bx + bw].astype(int) for i in (busy, idle))
        drawn = float((np.abs(a - b).max(axis=2) > 40).mean())
        self.check(
            drawn > 0.005, f"the status bar did not change while Plan Crowd ran ({drawn:.2%})"
        )
        self.s.key("Escape", at=(view[0] + view[2] // 2, view[1] + view[3] // 2))
        self.wait_modal(timeout=60)
        cancels = [
            since + k
            for k, ln in enumerate(self.log_lines()[since:])
            if "Cancelled: bpy.ops.motion_patches.plan_crowd(" in ln
        ]
        self.check(len(cancels) == 1, f"Blender logged {len(cancels)} cancels of Plan Crowd")
        self.expected_log.update(cancels)
        after = self.s.py(self.CROWD_STATE)
        self.check(after == before, "Esc left the walkers or the actions changed")
        said = self.reports()
        self.check(
            any("cancelled; the scene was left as it was" in r for r in said[-3:]),
            f"Esc did not report the cancel: {said[-3:]}",
        )
        self.s.click(x, y)
        time.sleep(0.3)
        secs = self.wait_modal()
        planned = self.s.py("""
crowd = [o for o in bpy.data.objects if o.name.startswith("Walker")]
result = [o.name for o in crowd if mp.api.PLAN_KEY in o and o.animation_data
          and len(o.animation_data.nla_tracks)]""")
        self.check(len(planned) == 8, f"Plan Crowd planned only {planned}")
        said = self.reports()
        self.check(
            any(r.startswith("Planned 8 of 8") for r in said[-12:]), f"no summary: {said[-12:]}"
        )
        shown = f"{round(seen[-1] * 100)} %" + (
            f" then {round(later[0] * 100)} %" if later and later[0] != seen[-1] else ""
        )
        return (
            f"progress {shown} in the status bar ({drawn:.1%} of it drawn), cancelled by Esc, "
            f"the scene kept; then 8 walkers planned in {secs:.1f} s"
        )

    # --- proxy bodies ------------------------------------------------------------------

    BODY_STATE = """
import numpy as np
io = mp.adapter.bodies
dg = bpy.context.evaluated_depsgraph_get()
walkers = sorted((o for o in bpy.data.objects
                  if o.name.startswith("Walker") and o.type == "ARMATURE"), key=lambda o: o.name)
off = 0.0  # the farthest a capsule's evaluated vertex lies from its bone's segment, less its radius
parts = {}
for w in walkers:
    ev = w.evaluated_get(dg)
    mw = np.array(ev.matrix_world)
    parts[w.name] = [len(io.parts(w)), len({p.data.name for p in io.parts(w)})]
    for p in io.parts(w):
        pb = ev.pose.bones[p.parent_bone]
        a, b = ((mw @ np.append(np.array(v), 1.0))[:3] for v in (pb.head, pb.tail))
        pe = p.evaluated_get(dg)
        me = pe.to_mesh()
        co = np.array([v.co[:] for v in me.vertices])
        pe.to_mesh_clear()
        m = np.array(pe.matrix_world)
        x = co @ m[:3, :3].T + m[:3, 3]
        d = b - a
        t = np.clip((x - a) @ d / max(float(d @ d), 1e-12), 0, 1)
        dist = np.linalg.norm(x - (a + t[:, None] * d), axis=1)
        off = max(off, float(dist.max() - dist.min()))
result = dict(parts=parts, off=off, meshes=len({m.name for m in bpy.data.meshes
                                               if io.SHAPE_KEY in m.keys()}))"""

    def bodies(self):
        """Add Body from its button with the eight walkers selected (the Walker active): each
        gets a capsule per bone, on its bones at the frame shown, the eight sharing the
        meshes; the viewport, in perspective at a frame mid-walk, shows them (the picture
        changes where the walkers stand when the bodies are hidden)."""
        self.s.py("""
w = bpy.data.objects["Walker"]
for ob in bpy.context.scene.objects:
    ob.select_set(ob.type == "ARMATURE" and ob.name.startswith("Walker"))
bpy.context.view_layer.objects.active = w
meta, arrays = mp.api.load_plan_record(w)
bpy.context.scene.frame_set((meta["frame_start"] + meta["frame_end"]) // 2)
result = 1""")
        self.settle()
        self.press("motion_patches.add_body")
        st = self.s.py(self.BODY_STATE)
        counts = sorted(set(map(tuple, st["parts"].values())))
        self.check(
            len(st["parts"]) == 8 and counts == [(31, 31)],
            f"Add Body did not give the eight walkers a capsule per bone: {st['parts']}",
        )
        self.check(st["meshes"] == 31, f"the walkers' bodies use {st['meshes']} meshes, not 31")
        self.check(st["off"] < 1e-4, f"a capsule is {st['off'] * 100:.2f} cm off its bone")
        said = self.reports()
        self.check(
            any(r.startswith("8 bodies made: 248 capsules") for r in said[-3:]),
            f"no summary: {said[-3:]}",
        )
        self.settle()
        self.sidebar_shot("11-body-panel")
        self.s.py("""
from mathutils import Euler
import math
for ob in bpy.context.scene.objects:
    ob.select_set(False)
bpy.context.scene.motion_patches.show_overlay = False  # the picture is of the bodies
r3d = area("VIEW_3D").spaces[0].region_3d
r3d.view_perspective = "PERSP"
r3d.view_location = (3.5, -2.6, 0.6)
r3d.view_rotation = Euler((math.radians(62), 0.0, math.radians(-28)), "XYZ").to_quaternion()
r3d.view_distance = 10.0
redraw_all()
result = 1""")
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        shots, hips = self.body_shots("Walker")
        self.grab_checked("12-bodies", crop=tuple(view))
        self.check(len(hips) >= 6, f"only {len(hips)} of the 8 walkers are in view")
        pts = np.array(hips) - np.array(view[:2])
        lo, hi = pts.min(axis=0) - (160, 220), pts.max(axis=0) + (160, 160)
        self.doc_boxes["12-bodies"] = (
            max(int(lo[0]), 0),
            max(int(lo[1]), 0),
            min(int(hi[0]), view[2]),
            min(int(hi[1]), view[3]),
        )
        shown = self.bodies_shown(shots, hips)
        return (
            f"8 walkers, 248 capsules sharing 31 meshes, on their bones within "
            f"{st['off'] * 1000:.3f} mm; bodies visible at {shown} of {len(hips)} chests"
        )

    def body_shots(self, prefix):
        """The screen with the bodies hidden, then shown, and where the chests (the Spine
        bone's head, evaluated, projected) of the armatures whose names start with
        ``prefix`` lie in view, clear of the viewport's edges and of the regions over it:
        ({False: img, True: img}, [[x, y]])."""
        self.s.move(5, 5)
        shots = {}
        for shown in (False, True):
            self.s.py(
                "for o in bpy.data.objects:\n"
                "    if mp.adapter.bodies.is_part(o):\n"
                f"        o.hide_viewport = {not shown}\n"
                "redraw_all()\nresult = 1"
            )
            self.s.wait_idle()
            time.sleep(0.3)
            shots[shown] = self.s.grab()
        chests = self.s.py(f"""
from bpy_extras.view3d_utils import location_3d_to_region_2d
reg = region("VIEW_3D", "WINDOW")
r3d = area("VIEW_3D").spaces[0].region_3d
rx, ry, rw, rh = rect(reg)
dg = bpy.context.evaluated_depsgraph_get()
covers = [rect(r) for r in area("VIEW_3D").regions if r.type != "WINDOW" and r.width > 1
          and r.height > 1]
out = []
for w in (o for o in bpy.data.objects if o.name.startswith({prefix!r}) and o.type == "ARMATURE"):
    ev = w.evaluated_get(dg)
    v = location_3d_to_region_2d(reg, r3d, ev.matrix_world @ ev.pose.bones["Spine"].head)
    if v is None:
        continue
    x, y = int(rx + v.x), int(ry + rh - v.y)
    if rx + 20 <= x < rx + rw - 20 and ry + 20 <= y < ry + rh - 20 and not any(
            cx - 20 <= x < cx + cw + 20 and cy - 20 <= y < cy + ch + 20
            for cx, cy, cw, ch in covers):
        out.append([x, y])
result = out""")
        return shots, chests

    def bodies_shown(self, shots, chests):
        """How many of the ``chests`` the bodies show at (the picture changes there when
        they are hidden); fails unless at all."""
        changed = []
        for x, y in chests:
            a = shots[False][y - 6 : y + 7, x - 6 : x + 7].astype(int)
            b = shots[True][y - 6 : y + 7, x - 6 : x + 7].astype(int)
            changed.append(float((np.abs(a - b).max(axis=2) > 30).mean()))
        shown = sum(c > 0.5 for c in changed)
        self.check(
            chests and shown == len(chests),
            f"the bodies show at only {shown} of {len(chests)} chests in the viewport "
            f"(changed pixel shares {[round(c, 2) for c in changed]})",
        )
        return shown

    def duplicate(self):
        """Duplicate Crowd from its button: the dialog (its values set beforehand as the
        operator's last ones), Return, then the copies planned a step at a time."""
        self.s.py("""
last = bpy.context.window_manager.operator_properties_last("motion_patches.duplicate_crowd")
last.count = 12  # with the eight walkers, a crowd of twenty
last.region_min, last.region_max = (-6.0, 3.5), (-2.5, 8.0)  # clear of the walkers
last.goal_min, last.goal_max = (8.0, 3.5), (11.5, 8.0)
for ob in bpy.context.scene.objects:
    ob.select_set(False)
w = bpy.data.objects["Walker"]
w.select_set(True)
bpy.context.view_layer.objects.active = w
result = 1""")
        self.settle()
        x, y = self.find("motion_patches.duplicate_crowd", below="motion_patches.plan_crowd")
        self.s.click(x, y)
        time.sleep(1.0)
        self.s.key("Return")
        time.sleep(0.5)
        running = self.running()  # the window answers while the copies are planned
        self.check(running, "Duplicate Crowd did not run a step at a time after its dialog")
        secs = self.wait_modal()
        made = self.s.py("""
coll = bpy.data.collections.get(mp.api.CROWD_COLLECTION)
obs = [o for o in coll.objects if o.type == "ARMATURE"] if coll else []
result = [len(obs), sum(1 for o in obs if mp.api.PLAN_KEY in o),
          sum(1 for o in obs if mp.api.has_body(o))]""")
        self.check(
            made == [12, 12, 12],
            f"Duplicate Crowd made / planned / gave bodies to {made} (want 12 each: the "
            f"Walker has a body)",
        )
        said = self.reports()
        self.check(
            any(r.startswith("Crowd of 12: 12 planned") for r in said[-8:]),
            f"no summary: {said[-8:]}",
        )
        return f"12 copies planned in {secs:.1f} s after the dialog: twenty walkers"

    def preferences(self):
        self.s.py("""
bpy.context.preferences.active_section = "ADDONS"
bpy.context.window_manager.addon_search = "Motion"
with override("VIEW_3D"):
    bpy.ops.screen.userpref_show()
result = 1""")
        self.s.wait_idle()
        time.sleep(0.5)
        win = self.s.py(f"""
import addon_utils
wins = bpy.context.window_manager.windows
pw = wins[-1]
result = None
if len(wins) > 1:
    with bpy.context.temp_override(window=pw, area=pw.screen.areas[0]):
        bpy.ops.preferences.addon_expand(module={MODULE!r})
    for a in pw.screen.areas:
        a.tag_redraw()
    result = [pw.x, pw.y, pw.width, pw.height, pw.screen.areas[0].type]""")
        self.check(
            win is not None and win[4] == "PREFERENCES",
            f"the Preferences window did not open: {win}",
        )
        self.s.wait_idle()
        # The window's own position on the X screen (Blender's x, y are from the bottom).
        x, y, w, h = win[:4]
        x, y = max(0, x), max(0, 1200 - (y + h))
        self.s.move(x + w // 2, y + h // 2)
        self.s.move(x + w // 2 + 5, y + h // 2 + 5)
        self.s.wait_idle()
        # Scroll (the wheel, over the add-on list) down to the add-on's own preferences.
        for _ in range(4):
            self.s.xdo("click", 5)
            self.s.wait_idle()
        time.sleep(0.5)
        self.grab_checked("09-preferences", crop=(x, y, min(w, 1920 - x), min(h, 1200 - y)))
        return f"window {w}x{h} at {x},{y}"

    # --- log, docs, summary -------------------------------------------------------------

    def check_log(self):
        text = (self.work / "blender.log").read_text(errors="replace")
        shutil.copy(self.work / "blender.log", self.out / "blender.log")
        bad = [
            ln
            for k, ln in enumerate(text.splitlines())
            if LOG_BAD.search(ln) and not LOG_ALLOWED.fullmatch(ln) and k not in self.expected_log
        ]
        self.check(not bad, "Blender's log has errors:\n  " + "\n  ".join(bad[:20]))
        return f"{len(text.splitlines())} lines, clean"

    def write_docs(self):
        """The README's screenshots (docs/gui): the sidebar in three states side by side,
        the overlay from the top and in perspective (cut to the plan), the preferences;
        256-colour PNGs, a few hundred KB in all."""
        if not self.args.docs or not hasattr(self, "s"):
            return
        need = (
            "02-locomotion-baked",
            "03-object-patch",
            "05-analysis",
            "07-overlay-top",
            "08-overlay-perspective",
            "09-preferences",
        )
        if not all(n in self.shots for n in need):
            self.log("docs not written: the suite did not get as far as every screenshot")
            return
        docs = Path(self.args.docs)
        docs.mkdir(parents=True, exist_ok=True)

        def cut(name, w=None):
            path, crop, img = self.shots[name]
            x, y, cw, ch = crop
            return img[y : y + ch, x : x + (w or cw)]

        panel_w = self.sidebar_panel_width
        parts = [cut(n, panel_w) for n in need[:3]]
        h = max(p.shape[0] for p in parts)
        gap = np.full((h, 6, 3), 255, np.uint8)
        row = [np.pad(p, ((0, h - p.shape[0]), (0, 0), (0, 0)), constant_values=255) for p in parts]
        sidebar = np.hstack([row[0], gap, row[1], gap, row[2]])
        written = [self.s.save(sidebar, docs / "sidebar.png", palette=True)]
        for name, out in (
            ("07-overlay-top", "overlay-top.png"),
            ("08-overlay-perspective", "overlay-perspective.png"),
        ):
            img = cut(name)
            box = self.doc_boxes.get(name)
            if box:
                x0, y0, x1, y1 = box
                img = img[max(0, y0) : y1, max(0, x0) : x1]
            written.append(self.s.save(img, docs / out, scale=0.75, palette=True))
        written.append(self.s.save(cut("09-preferences"), docs / "preferences.png", palette=True))
        if "12-bodies" in self.shots:  # the walkers with their proxy bodies
            img = cut("12-bodies")
            box = self.doc_boxes.get("12-bodies")
            if box:
                x0, y0, x1, y1 = box
                img = img[y0:y1, x0:x1]
            written.append(self.s.save(img, docs / "bodies.png", scale=0.75, palette=True))
        sizes = ", ".join(f"{p.name} {p.stat().st_size // 1024} KiB" for p in written)
        self.log(f"docs: {sizes}")

    def summary(self):
        ok = all(st.ok for st in self.steps) and self.steps
        total = time.monotonic() - self.t0
        print(
            "\n== GUI suite summary"
            + (f" (Blender {self.facts['blender']})" if "blender" in self.facts else "")
        )
        for st in self.steps:
            mark = "PASS" if st.ok else "FAIL"
            first = (st.detail.splitlines() or [""])[0]
            print(f"  {mark}  {st.name} ({st.seconds:.1f} s){': ' + first if first else ''}")
            if not st.ok and len(st.detail.splitlines()) > 1:
                print("        " + "\n        ".join(st.detail.splitlines()[1:40]))
        print(f"  screenshots: {self.out}")
        passed = sum(1 for st in self.steps if st.ok)
        print(f"\ngui: {passed} passed, {len(self.steps) - passed} failed")
        print(f"GUI suite: {'PASS' if ok else 'FAIL'} ({total:.0f} s)")
        (self.out / "summary.json").write_text(
            json.dumps(
                {
                    "ok": bool(ok),
                    "seconds": round(total, 1),
                    "facts": self.facts,
                    "steps": [
                        {
                            "name": s.name,
                            "ok": s.ok,
                            "detail": s.detail,
                            "seconds": round(s.seconds, 1),
                        }
                        for s in self.steps
                    ],
                },
                indent=1,
                default=str,
            )
        )
        self.ok = bool(ok)


def _without_allowed(text):
    return "\n".join(ln for ln in text.splitlines() if not LOG_ALLOWED.fullmatch(ln))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--out",
        default=str(REPO / "dist" / "gui"),
        help="where the screenshots, Blender's log and summary.json go",
    )
    ap.add_argument("--docs", default=None, help="also write the README's screenshots here")
    ap.add_argument("--keep", action="store_true", help="keep the temporary Blender home")
    args = ap.parse_args(argv)
    suite = Suite(args)
    suite.run()
    return 0 if suite.ok else 1


if __name__ == "__main__":
    sys.exit(main())
