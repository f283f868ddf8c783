# SPDX-License-Identifier: GPL-3.0-or-later
"""The GUI suite's (tools/gui/suite.py) step on a committed sample scene: File > Open
samples/props.blend (saved by Blender 4.5), then its walker planned over a hurdle,
analysed on the evaluated rig, and given a body.

A mixin of :class:`suite.Suite`: it uses its session (``self.s``), its button finder and
its body-pixel helpers.
"""

import time
from pathlib import Path

import numpy as np

SAMPLES = Path(__file__).resolve().parents[2] / "samples"

# The file browser Ctrl+O opened, pointed at the sample (Python: typing a path into it is
# not what is tested here): [x, y, w, h] of its window (Blender's, from the bottom), or None.
POINT_BROWSER = """
import os
result = None
for w in bpy.context.window_manager.windows:
    for a in w.screen.areas:
        p = a.spaces[0].params if a.type == "FILE_BROWSER" else None
        if p is not None:
            try:
                p.directory = os.fsencode(%r)
            except TypeError:
                p.directory = %r
            p.filename = %r
            for r in a.regions:
                r.tag_redraw()
            result = [w.x, w.y, w.width, w.height]"""

# The sample as opened: [file, patches, characters with animation (the source armature with
# the mocap is hidden), tagged props, windows, the Blender that saved it].
OPENED = """
scene = bpy.context.scene
result = [bpy.path.basename(bpy.data.filepath), len(scene.motion_patches.patches),
          [o.name for o in scene.objects
           if o.type == "ARMATURE" and o.visible_get() and o.animation_data],
          sorted(o.name for o in scene.objects if o.type == "MESH" and o.motion_patch.enabled),
          len(bpy.context.window_manager.windows), list(bpy.data.version)]"""


class SampleSteps:
    def open_sample(self, name):
        """Ctrl+O over the viewport, the file browser pointed at ``samples/name``, Return
        over it: the file opened in this window (its own layout)."""
        # Nothing here is worth saving: no "save changes?" question before the browser.
        self.s.py("bpy.context.preferences.view.use_save_prompt = False\nresult = 1")
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        self.s.key("ctrl+o", at=(view[0] + view[2] // 2, view[1] + view[3] // 2))
        path = str(SAMPLES) + "/"
        t0, win = time.monotonic(), None
        while win is None and time.monotonic() - t0 < 20:
            self.s.wait_idle()
            win = self.s.py(POINT_BROWSER % (path, path, name))
        self.check(win is not None, "Ctrl+O over the viewport opened no file browser")
        self.s.wait_idle()
        time.sleep(0.5)
        x, y, w, h = win
        x, y = max(0, x), max(0, 1200 - (y + h))
        self.grab_checked("17-open-sample", crop=(x, y, min(w, 1920 - x), min(h, 1200 - y)))
        self.s.key("Return", at=(x + w // 2, y + h // 2))
        t0 = time.monotonic()
        while time.monotonic() - t0 < 60:
            self.s.wait_idle()
            opened = self.s.py(OPENED)
            if opened[0] == name and opened[4] == 1:
                break
            time.sleep(0.2)
        else:
            raise AssertionError(f"Return in the file browser did not open {name}: {opened}")
        self.cache.clear()  # another layout: the buttons are found again
        return opened

    def sample(self):
        """samples/props.blend opened with Ctrl+O (the file browser, Return); Plan Path on
        its Walker: over a hurdle (a 0.15 m prop its jump clears), and on no frame a bone
        of the evaluated rig inside a prop (Analyse Motion's figures); Add Body: the
        walker, mid-jump, with its body."""
        file, patches, animated, tagged, _, version = self.open_sample("props.blend")
        self.check(
            patches == 1 and not animated and tagged,
            f"props.blend opened with {patches} patches, {animated} planned, tagged {tagged}",
        )
        self.open_tab("18-sample-sidebar")
        (x, top, w, h), (left, right) = self.sidebar()
        self.s.click(left + 60, top + 13)  # fold the Locomotion panel, as before
        self.select_walker()
        self.press("motion_patches.plan_path", cols=(0.25,))
        self.press("motion_patches.analyse_motion", timeout=300, below="motion_patches.plan_path")
        fig = self.s.py("""
import json
w = bpy.data.objects["Walker"]
raw = w.get("motion_patches_analysis")
meta, arrays = mp.api.load_plan_record(w)
result = [json.loads(raw) if raw else None, meta.get("traversals", [])]""")
        fig, traversals = fig
        self.check(fig is not None, "Analyse Motion stored no figures on the sample's Walker")
        self.check(
            len(traversals) >= 1 and fig["traversals"] == len(traversals),
            f"the sample's Walker did not jump a hurdle: traversals {traversals}",
        )
        self.check(
            fig["frames_body_inside_prop"] == 0 and fig["frames_root_inside_obstacle"] == 0,
            f"inside a prop: a bone on {fig['frames_body_inside_prop']} frames, the root on "
            f"{fig['frames_root_inside_obstacle']}",
        )
        self.press("motion_patches.add_body")
        parts = self.s.py("""
w = bpy.data.objects["Walker"]
result = [len(mp.adapter.bodies.parts(w)), len(w.pose.bones)]""")
        self.check(parts[0] == parts[1] > 0, f"Add Body gave the Walker {parts[0]} of {parts[1]}")
        a, b = traversals[0]
        self.s.py(f"""
from mathutils import Euler
import math
scene = bpy.context.scene
scene.frame_set({(a + b) // 2})
for ob in scene.objects:
    ob.select_set(False)
dg = bpy.context.evaluated_depsgraph_get()
ev = bpy.data.objects["Walker"].evaluated_get(dg)
hips = ev.matrix_world @ ev.pose.bones["Hips"].head
r3d = area("VIEW_3D").spaces[0].region_3d
r3d.view_perspective = "PERSP"
r3d.view_location = (hips.x, hips.y, 0.5)
r3d.view_rotation = Euler((math.radians(68), 0.0, math.radians(-35)), "XYZ").to_quaternion()
r3d.view_distance = 5.0
redraw_all()
result = 1""")
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        shots, chests = self.body_shots("Walker")
        self.grab_checked("19-sample-body", crop=tuple(view))
        self.check(len(chests) == 1, f"the Walker's chest is not in view ({chests})")
        self.bodies_shown(shots, chests)
        body_px = float((np.abs(shots[True].astype(int) - shots[False]).max(axis=2) > 30).mean())
        return (
            f"{file} (saved by {version[0]}.{version[1]}) opened; {len(traversals)} traversal "
            f"(frames {a}-{b}), no bone inside a prop, root clear; body of {parts[0]} "
            f"capsules shown ({body_px:.1%} of the screen)"
        )
