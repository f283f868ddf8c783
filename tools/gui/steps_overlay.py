# SPDX-License-Identifier: GPL-3.0-or-later
"""Steps of the GUI suite (tools/gui/suite.py) on the overlay after the first plans: its
checkbox through undo and redo, and a crowd of twenty with the active walker's grid.

A mixin of :class:`suite.Suite`: it uses its session (``self.s``), its button finder and
its pixel helpers.
"""

import time

import numpy as np

# What the overlay drew last (the panel's cache of its buffers): {"grid": tile edges drawn,
# "lattice": whose grids (None: every one's)}.
DRAWN = """
import json
import numpy as np
ov = mp.panels.overlay
key, buf = ov._cache["plans"]
pos, col = buf["lines"]
grid = int(np.all(np.abs(col - np.array(ov.GRID, np.float32)) < 1e-4, axis=1).sum()) // 2
result = dict(grid=grid, lattice=json.loads(key)[-1] if key else "not drawn")"""

# {name: tile edges of its grid} of every visible planned character.
GRIDS = """
scene = bpy.context.scene
names = [o.name for o in scene.objects
         if o.type == "ARMATURE" and mp.adapter.storage.has_plan(o) and o.visible_get()]
result = {n: len(d.grid) for n, d in zip(names, mp.api.plan_drawings(scene, None))}"""

# Screen points inside each visible planned character's path (a quarter, half and three
# quarters along it), clear of the regions over the viewport: [[x, y]].
PATH_POINTS = """
from bpy_extras.view3d_utils import location_3d_to_region_2d
from mathutils import Vector
reg = region("VIEW_3D", "WINDOW")
r3d = area("VIEW_3D").spaces[0].region_3d
rx, ry, rw, rh = rect(reg)
covers = [rect(r) for r in area("VIEW_3D").regions if r.type != "WINDOW" and r.width > 1
          and r.height > 1]
out = []
for o in bpy.context.scene.objects:
    if o.type != "ARMATURE" or not mp.adapter.storage.has_plan(o) or not o.visible_get():
        continue
    g = mp.api.load_plan_record(o)[1]["ground"]
    for f in (0.25, 0.5, 0.75):
        k = int(f * (len(g) - 1))
        v = location_3d_to_region_2d(reg, r3d, Vector((g[k, 0], g[k, 1], 0.01)))
        if v is None:
            continue
        x, y = rx + v.x, ry + rh - v.y
        if rx + 6 <= x < rx + rw - 6 and ry + 6 <= y < ry + rh - 6 and not any(
                cx - 6 <= x < cx + cw + 6 and cy - 6 <= y < cy + ch + 6
                for cx, cy, cw, ch in covers):
            out.append([int(round(x)), int(round(y))])
result = out"""


class OverlaySteps:
    def overlay_seen(self, points, rest):
        """(Show Planner Overlay ticked, its draw handler on, the share of ``points`` (on
        the visible planned path) showing a path colour) now; the pointer at ``rest``."""
        self.s.move(*rest)
        self.s.py("redraw_all()\nresult = 1")
        self.s.wait_idle()
        time.sleep(0.3)
        img = self.s.grab()
        ticked, drawing = self.s.py(
            "result = [bpy.context.scene.motion_patches.show_overlay, "
            "mp.panels.overlay.is_enabled()]"
        )
        share = float(np.mean([self.near_colour(img, x, y) for x, y in points]))
        return ticked, drawing, share, img

    def overlay_undo(self):
        """Show Planner Overlay unticked with a click, then Ctrl+Z, Ctrl+Shift+Z and Ctrl+Z
        pressed over the viewport: after each, the checkbox, the draw handler and the
        pixels along the path agree (undo sets the property back without its update
        callback: the overlay follows it all the same), and nothing else was undone."""
        st = self.view_state()
        points = [(int(round(x)), int(round(y))) for x, y, hid in st["path"] if not hid]
        self.check(len(points) >= 10, f"only {len(points)} path points in view")
        vx, vy, vw, vh = st["view"]
        rest = (vx + 40, vy + vh - 40)  # a corner of the viewport, off the path
        plans = self.s.py(self.CROWD_STATE)
        seen = [("before", self.overlay_seen(points, rest))]
        x, y = self.find("motion_patches.show_overlay", kind="prop", cols=(0.1, 0.3))
        self.s.click(x, y)
        seen.append(("unticked", self.overlay_seen(points, rest)))
        for keys in ("ctrl+z", "ctrl+shift+z", "ctrl+z"):
            self.s.key(keys, at=rest)
            seen.append((keys, self.overlay_seen(points, rest)))
        self.grab_checked("15-overlay-undo", crop=tuple(st["view"]), img=seen[-1][1][3])
        wrong = []
        for name, (ticked, drawing, share, _) in seen:
            on = name in ("before", "ctrl+z")
            if ticked != on or drawing != on or (share < 0.8 if on else share > 0.2):
                wrong.append(f"{name}: ticked {ticked}, drawing {drawing}, path {share:.0%}")
        self.check(not wrong, "the checkbox and the overlay disagree: " + "; ".join(wrong))
        self.check(
            self.s.py(self.CROWD_STATE) == plans, "undo changed the plan (not only the checkbox)"
        )
        return ", ".join(
            f"{name} {'on' if t else 'off'} ({share:.0%} of {len(points)} path points)"
            for name, (t, _, share, _) in seen
        )

    def crowd_overlay(self):
        """The twenty walkers' paths from the top, the Walker active: every path drawn, the
        tile grid only the Walker's (Every Character's Grid off); ticked with a click, every
        grid, which covers much more of the picture; unticked again."""
        self.s.py("""
scene = bpy.context.scene
for ob in scene.objects:
    ob.select_set(False)
bpy.context.view_layer.objects.active = bpy.data.objects["Walker"]
s = scene.motion_patches
s.show_overlay, s.overlay_all_lattices = True, False
scene.frame_set(scene.frame_start)
r3d = area("VIEW_3D").spaces[0].region_3d
r3d.view_perspective = "ORTHO"
r3d.view_rotation = (1.0, 0.0, 0.0, 0.0)  # from the top
r3d.view_location = (4.9, 0.1, 0.0)  # the crowd between the toolbar and the sidebar
r3d.view_distance = 19.0
redraw_all()
result = 1""")
        self.settle()
        view = self.s.py('result = rect(region("VIEW_3D", "WINDOW"))')
        points = self.s.py(PATH_POINTS)
        grids = self.s.py(GRIDS)
        rest = (5, 5)
        self.s.py("bpy.context.scene.motion_patches.show_overlay = False\nresult = 1")
        *_, none = self.overlay_seen(points, rest)
        self.s.py("bpy.context.scene.motion_patches.show_overlay = True\nresult = 1")
        *_, share, active = self.overlay_seen(points, rest)
        self.grab_checked("16-crowd-overlay", crop=tuple(view), img=active)
        one = self.s.py(DRAWN)
        # The checkbox below Show Planner Overlay, found again (the panels above it changed
        # height since: the Walker's figures went with its re-plan).
        self.find("motion_patches.show_overlay", kind="prop", cols=(0.1, 0.3))
        x, y = self.find(
            "motion_patches.overlay_all_lattices",
            kind="prop",
            cols=(0.1, 0.3),
            below="motion_patches.show_overlay",
        )
        self.s.click(x, y)
        self.s.wait_idle()
        self.s.move(*rest)
        time.sleep(0.3)
        self.s.wait_idle()
        every = self.grab_checked("16-crowd-overlay-every-grid", crop=tuple(view))
        allg = self.s.py(DRAWN)
        self.s.click(x, y)  # back to the active one's
        self.s.wait_idle()
        still = self.s.py("result = bpy.context.scene.motion_patches.overlay_all_lattices")

        def covered(img):  # share of the viewport the overlay changes
            vx, vy, vw, vh = view
            a, b = (i[vy : vy + vh, vx : vx + vw].astype(int) for i in (img, none))
            return float((np.abs(a - b).max(axis=2) > 12).mean())

        c_one, c_all = covered(active), covered(every)
        total = sum(grids.values())
        self.check(len(grids) == 20, f"{len(grids)} planned walkers drawn, not 20")
        self.check(
            len(points) >= 45 and share >= 0.8,
            f"the path colour shows at {share:.0%} of {len(points)} points on the 20 paths",
        )
        self.check(
            one["lattice"] == ["Walker"] and one["grid"] == grids["Walker"] > 0,
            f"with Every Character's Grid off the overlay drew {one['grid']} grid edges for "
            f"{one['lattice']} (the Walker's grid has {grids['Walker']})",
        )
        self.check(
            allg["lattice"] is None and allg["grid"] == total > one["grid"],
            f"ticked, the overlay drew {allg['grid']} grid edges of {total}",
        )
        self.check(
            c_all > 1.2 * c_one,
            f"every grid covers {c_all:.1%} of the viewport, the Walker's alone {c_one:.1%}",
        )
        self.check(not still, "a second click did not untick Every Character's Grid")
        return (
            f"20 paths (colour at {share:.0%} of {len(points)} points); the Walker's grid: "
            f"{one['grid']} edges, {c_one:.1%} of the viewport; every grid: {allg['grid']} "
            f"edges, {c_all:.1%}"
        )
