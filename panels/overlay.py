# SPDX-License-Identifier: GPL-3.0-or-later
"""Viewport overlay: what the planner sees, drawn with the ``gpu`` module when enabled.

Tile grid and occluded cells around each planned path, the path coloured by piece kind
(segments alternate two colours, traversals red, interactions green, connectors grey), the
stitch points between pieces, and for every tagged prop where its clips start (green) and
end (red) with a short tick along the heading there: the places the planner can stitch a
hurdle or a sit-down into the walk. The geometry is computed by :func:`buffers`, so it can
be tested without a GPU; the draw handler is added only while the overlay is enabled and
always removed on unregister.
"""

import json

import bpy
import numpy as np

from .. import api, props
from .sidebar import SidebarPanel, wrapped_label

COLOURS = {
    "segment": ((0.16, 0.45, 0.85, 1.0), (0.95, 0.6, 0.1, 1.0)),
    "part": ((0.16, 0.45, 0.85, 1.0), (0.95, 0.6, 0.1, 1.0)),
    "traversal": ((0.85, 0.15, 0.15, 1.0),),
    "interaction": ((0.1, 0.7, 0.3, 1.0),),
    "start": ((0.6, 0.6, 0.6, 1.0),),
    "goal": ((0.6, 0.6, 0.6, 1.0),),
}
GRID = (0.5, 0.5, 0.5, 0.35)
BLOCKED = (0.9, 0.35, 0.3, 0.35)  # fill: a prop's footprint grown by the radius
OCCLUDED = (0.9, 0.35, 0.3, 0.6)  # outline: a cell the planner's bitmask (B_t) occludes
ARC_STEP = np.radians(15.0)  # the grown footprint's rounded corners, in steps
LEGEND = (
    "Path: segments blue / orange, traversals red, interactions green",
    "Red fill: where the root cannot go (each prop grown by the radius); red squares: "
    "cells the planner marks occluded",
    "White points: stitches between pieces",
    "Props: green = a clip starts, red = it ends (tick: heading)",
)
STITCH = (1.0, 1.0, 1.0, 1.0)
ENTRY = (0.2, 0.9, 0.3, 1.0)
EXIT = (0.95, 0.2, 0.2, 1.0)
TICK = 0.2  # metres: the heading tick at a clip's entry / exit
Z = 0.01  # drawn just above the ground

_handle = None
_cache = {"plans": (None, None), "markers": (None, None)}


def _arr(v, n):
    return np.array(v, np.float32).reshape(-1, n)


def buffers(scene, depsgraph=None):
    """Everything the overlay draws, in world space, as (coords, colours) float32 arrays:
    "lines", "points", "tris" for the plans (paths, stitches, tile grid, occluded cells),
    "markers" (points) and "ticks" (lines) for the props' clip entries and exits."""
    out = plan_buffers(scene)
    out.update(marker_buffers(scene, depsgraph))
    return out


def marker_buffers(scene, depsgraph=None):
    """{"markers": (P, 3) points, "ticks": (2P, 3) line ends} of every tagged prop's clips
    (:func:`api.clip_ends`): for each (copy of a) clip its first ground frame (ENTRY
    colour) and last (EXIT colour), each with a TICK-long line along the heading there."""
    points, pcol, ticks, tcol = [], [], [], []
    for x, y, h, entry in api.clip_ends(scene, depsgraph):
        colour = ENTRY if entry else EXIT
        points.append((x, y, Z))
        ticks += [(x, y, Z), (x + TICK * np.cos(h), y + TICK * np.sin(h), Z)]
        pcol.append(colour)
        tcol += [colour, colour]
    return {"markers": (_arr(points, 3), _arr(pcol, 4)), "ticks": (_arr(ticks, 3), _arr(tcol, 4))}


def grown(polygon, radius, step=ARC_STEP):
    """(K, 2) outline of a convex footprint (3 or more points) grown by ``radius``: the
    points within the radius of it, edges pushed out and corners rounded; K is even."""
    poly = np.asarray(polygon, float)
    area2 = np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    if area2 < 0:  # counter-clockwise, so the edges' outward normals point right
        poly = poly[::-1]
    out = poly
    if radius > 0 and len(poly) >= 3:
        out = []
        for i in range(len(poly)):
            e0 = poly[i] - poly[i - 1]
            e1 = poly[(i + 1) % len(poly)] - poly[i]
            a0 = np.arctan2(-e0[0], e0[1])  # outward normal of the edge in, and out
            a1 = a0 + np.mod(np.arctan2(-e1[0], e1[1]) - a0, 2 * np.pi)
            for a in np.linspace(a0, a1, max(1, int(np.ceil((a1 - a0) / step))) + 1):
                out.append(poly[i] + radius * np.array([np.cos(a), np.sin(a)]))
        out = np.array(out)
    if len(out) % 2:  # fills are drawn as quads (pairs of triangles)
        out = np.vstack((out, out[-1:]))
    return out


def _fan_quads(outline, z):
    """Triangles (pairs per quad) filling a convex outline from its centre."""
    c = outline.mean(axis=0)
    tris = []
    n = len(outline)
    for i in range(0, n, 2):
        a, b, d = outline[i], outline[(i + 1) % n], outline[(i + 2) % n]
        for p, q in ((a, b), (b, d)):
            tris += [(c[0], c[1], z), (p[0], p[1], z), (q[0], q[1], z)]
    return tris


def _tagged(scene):
    return (ob for ob in scene.objects if api.is_tagged(ob))


def _lattice_of(scene):
    """Whose tile grid is drawn: the active character's, or every one's when asked."""
    if scene.motion_patches.overlay_all_lattices:
        return None
    active = bpy.context.view_layer.objects.active
    return [] if active is None else [active.name]


def plan_buffers(scene):
    """{"lines", "points", "tris"} of every visible planned character's path (see
    :func:`buffers`, :func:`api.plan_drawings`) and, for the active one (or all, by the
    Overlay panel's toggle), its lattice: the props it walked around grown by its radius are
    filled ("tris"): where its root cannot go; the cells the planner's bitmask marks
    occluded are outlined ("lines"). Each path in arrays at once (a crowd of 1,000 drawn
    point by point in Python took a second)."""
    chunks = {k: [] for k in ("lines", "lcol", "points", "pcol", "tris", "tcol")}

    def at_z(pts):
        return [(x, y, Z) for x, y in pts]

    for d in api.plan_drawings(scene, _lattice_of(scene)):
        for k, v in zip(("lines", "lcol", "points", "pcol"), _path_arrays(d)):
            chunks[k].append(v)
        lines, lcol, tris, tcol = [], [], [], []
        for edge in d.grid:
            lines += at_z(edge)
            lcol += [GRID, GRID]
        for cell in d.occluded:
            corners = at_z(cell)
            for k in range(4):
                lines += [corners[k], corners[(k + 1) % 4]]
            lcol += [OCCLUDED] * 8
        for poly in d.obstacles:
            outline = grown(poly, d.radius)
            tris += _fan_quads(outline, Z)
            tcol += [BLOCKED] * (3 * len(outline))
            for k in range(len(outline)):
                a, b = outline[k], outline[(k + 1) % len(outline)]
                lines += [(a[0], a[1], Z), (b[0], b[1], Z)]
                lcol += [OCCLUDED, OCCLUDED]
        for k, v, n in (
            ("lines", lines, 3),
            ("lcol", lcol, 4),
            ("tris", tris, 3),
            ("tcol", tcol, 4),
        ):
            if v:
                chunks[k].append(_arr(v, n))

    def joined(k, n):
        return np.concatenate(chunks[k]) if chunks[k] else np.zeros((0, n), np.float32)

    return {
        "lines": (joined("lines", 3), joined("lcol", 4)),
        "points": (joined("points", 3), joined("pcol", 4)),
        "tris": (joined("tris", 3), joined("tcol", 4)),
    }


def _path_arrays(d):
    """(lines (2S, 3), their colours (2S, 4), stitch points (K, 3), their colours (K, 4))
    of one drawing's path of S steps: each step a line coloured by its piece's kind
    (segments alternating two colours strip by strip), a point where each strip starts."""
    g = np.asarray(d.ground, float)
    n = max(g.shape[0] - 1, 0)
    lines = np.full((n, 2, 3), Z, np.float32)
    lines[:, 0, :2], lines[:, 1, :2] = g[:n, :2], g[1 : n + 1, :2]
    col = np.empty((n, 4), np.float32)
    kinds, parity = np.asarray(d.kinds[:n], dtype=object), np.asarray(d.parity[:n], int)
    for kind in set(kinds.tolist()):
        options = np.array(COLOURS.get(kind, COLOURS["segment"]), np.float32)
        at = kinds == kind
        col[at] = options[parity[at] % len(options)]
    stitches = [k for k in d.stitches if 0 <= k < g.shape[0]]
    points = np.full((len(stitches), 3), Z, np.float32)
    points[:, :2] = g[stitches, :2]
    return (
        lines.reshape(-1, 3),
        np.repeat(col, 2, axis=0),
        points,
        np.tile(np.array(STITCH, np.float32), (len(stitches), 1)),
    )


def _patch_key(scene):
    """Changes when another patch becomes active or one is re-baked (its bake report)."""
    s = scene.motion_patches
    return [s.active_patch_index] + [[p.name, p.stats] for p in s.patches]


def _plans_key(scene):
    """Changes with any plan, the patch, who is visible, and whose grid is drawn."""
    visible = [o.name for o in scene.objects if o.type == "ARMATURE" and o.visible_get()]
    return json.dumps(
        api.plan_fingerprints(scene) + _patch_key(scene) + [visible, _lattice_of(scene)]
    )


def _markers_key(scene):
    """Changes when a tagged prop moves, is (un)tagged or its clips change."""
    return json.dumps(
        [
            [
                ob.name,
                [list(r) for r in ob.matrix_world],
                ob.visible_get(),
                [
                    [c.action.name if c.action else "", c.kind, c.effort, c.copy_step]
                    for c in ob.motion_patch.clips
                ],
            ]
            for ob in _tagged(scene)
        ]
        + _patch_key(scene)
    )


def _cached(name, key, make):
    if _cache[name][0] != key:
        _cache[name] = (key, make())
    return _cache[name][1]


def draw():
    import gpu
    from gpu_extras.batch import batch_for_shader

    scene = bpy.context.scene
    if not scene.motion_patches.show_overlay:
        return
    buf = dict(_cached("plans", _plans_key(scene), lambda: plan_buffers(scene)))
    # The viewport's own (already evaluated) depsgraph: drawing never triggers evaluation.
    depsgraph = bpy.context.view_layer.depsgraph
    buf.update(_cached("markers", _markers_key(scene), lambda: marker_buffers(scene, depsgraph)))
    flat = gpu.shader.from_builtin("FLAT_COLOR")
    gpu.state.blend_set("ALPHA")
    # Depth-tested against the scene (a prop in front hides what lies behind it), drawn
    # without writing depth (the fills are see-through; the lines sit on the same plane).
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(False)
    for prim, name, size in (
        ("TRIS", "tris", 0),
        ("LINES", "lines", 0),
        ("LINES", "ticks", 0),
        ("POINTS", "points", 6.0),
        ("POINTS", "markers", 9.0),
    ):
        pos, col = buf[name]
        if not len(pos):
            continue
        shader = flat
        if prim == "POINTS":
            try:  # point shaders with a size uniform (4.x+, required on Metal/Vulkan)
                shader = gpu.shader.from_builtin("POINT_FLAT_COLOR")
                shader.uniform_float("size", size)
            except (ValueError, KeyError):
                gpu.state.point_size_set(size)
        batch_for_shader(shader, prim, {"pos": pos, "color": col}).draw(shader)
    gpu.state.depth_test_set("NONE")
    gpu.state.blend_set("NONE")


def enable():
    global _handle
    if _handle is None:
        _handle = bpy.types.SpaceView3D.draw_handler_add(draw, (), "WINDOW", "POST_VIEW")


def disable():
    global _handle
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    _cache.update(plans=(None, None), markers=(None, None))


def is_enabled():
    return _handle is not None


def sync():
    """Draw handler on exactly when some scene has the overlay ticked: the setting is saved
    with the .blend, the handler is not (a file opened, the add-on enabled again)."""
    try:
        wanted = any(sc.motion_patches.show_overlay for sc in bpy.data.scenes)
    except AttributeError:  # bpy.data not readable yet (add-on registering at start-up)
        return 0.1  # as a timer: try again shortly
    enable() if wanted else disable()
    return None


@bpy.app.handlers.persistent
def _on_load(*_args):
    # load_post, undo_post, redo_post: whatever Blender passes (a file path, a scene...).
    sync()


def _switch(on):
    enable() if on else disable()


# Undo and redo put the setting back without its update callback: sync after them too.
_HANDLERS = ("load_post", "undo_post", "redo_post")


def register_handlers():
    props.overlay_switch = _switch  # Show Planner Overlay ticked or unticked
    for name in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if _on_load not in handlers:
            handlers.append(_on_load)
    if sync() is not None:
        bpy.app.timers.register(sync, first_interval=0.1)


def unregister_handlers():
    props.overlay_switch = None
    for name in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if _on_load in handlers:
            handlers.remove(_on_load)
    if bpy.app.timers.is_registered(sync):
        bpy.app.timers.unregister(sync)
    disable()  # never leave a draw handler behind


class MOTION_PATCHES_PT_overlay(SidebarPanel, bpy.types.Panel):
    bl_label = "Overlay"
    bl_idname = "MOTION_PATCHES_PT_overlay"

    def draw(self, context):
        layout = self.layout
        layout.prop(context.scene.motion_patches, "show_overlay")
        layout.prop(context.scene.motion_patches, "overlay_all_lattices")
        col = layout.column(align=True)
        col.active = context.scene.motion_patches.show_overlay
        for text in LEGEND:
            wrapped_label(col, context, text)


classes = (MOTION_PATCHES_PT_overlay,)
