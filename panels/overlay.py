"""Viewport overlay: what the planner sees, drawn with the ``gpu`` module when enabled.

Tile grid and occluded cells around each planned path, the path coloured by piece kind
(segments alternate two colours, traversals red, interactions green, connectors grey) and
the stitch points between pieces. The geometry is computed by :func:`buffers` from the
plans stored on the characters, so it can be tested without a GPU; the draw handler is
added only while the overlay is enabled and always removed on unregister.
"""

import json

import numpy as np

from .. import api
from ..adapter import storage
from ..motion_patches.environment import Environment, Obstacle

COLOURS = {"segment": ((0.16, 0.45, 0.85, 1.0), (0.95, 0.6, 0.1, 1.0)),
           "part": ((0.16, 0.45, 0.85, 1.0), (0.95, 0.6, 0.1, 1.0)),
           "traversal": ((0.85, 0.15, 0.15, 1.0),), "interaction": ((0.1, 0.7, 0.3, 1.0),),
           "start": ((0.6, 0.6, 0.6, 1.0),), "goal": ((0.6, 0.6, 0.6, 1.0),)}
GRID = (0.5, 0.5, 0.5, 0.35)
OCCLUDED = (0.9, 0.35, 0.3, 0.35)
STITCH = (1.0, 1.0, 1.0, 1.0)
Z = 0.01  # drawn just above the ground

_handle = None
_cache = {"key": None, "buffers": None}


def buffers(scene):
    """{"lines": (coords, colours), "points": (...), "tris": (...)} in world space."""
    lines, lcol, points, pcol, tris, tcol = [], [], [], [], [], []
    try:
        patch = storage.load_patch(scene)
    except ValueError:
        patch = None
    for ob in scene.objects:
        if ob.type != "ARMATURE" or api.PLAN_KEY not in ob:
            continue
        meta, arrays = api.load_plan_record(ob)
        g = arrays["ground"]
        kinds = np.full(g.shape[0] - 1, "segment", dtype=object)
        strip_starts = [meta["frame_start"]] + list(meta["boundaries"])
        parity = np.zeros(g.shape[0] - 1, int)
        for n, s in enumerate(strip_starts):
            parity[s - meta["frame_start"]:] = n % 2
        for key in ("traversals", "interactions"):
            for a, b in meta.get(key, []):
                kinds[a - meta["frame_start"]:b - meta["frame_start"]] = key[:-1]
        for i in range(g.shape[0] - 1):
            lines += [(g[i, 0], g[i, 1], Z), (g[i + 1, 0], g[i + 1, 1], Z)]
            options = COLOURS.get(kinds[i], COLOURS["segment"])
            c = options[parity[i] % len(options)]
            lcol += [c, c]
        for s in strip_starts:
            k = s - meta["frame_start"]
            if 0 <= k < g.shape[0]:
                points.append((g[k, 0], g[k, 1], Z))
                pcol.append(STITCH)
        if patch is None:
            continue
        env = Environment(patch.side, patch.cells, meta["radius"])
        for name, poly in meta["obstacles"].items():
            env.place(Obstacle(name, np.array(poly)))
        lo = np.floor(g[:, :2].min(axis=0) / patch.side).astype(int) - 1
        hi = np.floor(g[:, :2].max(axis=0) / patch.side).astype(int) + 1
        c = patch.cell_size
        for i in range(lo[0], hi[0] + 2):
            x = i * patch.side
            lines += [(x, lo[1] * patch.side, Z), (x, (hi[1] + 1) * patch.side, Z)]
            lcol += [GRID, GRID]
        for j in range(lo[1], hi[1] + 2):
            y = j * patch.side
            lines += [(lo[0] * patch.side, y, Z), ((hi[0] + 1) * patch.side, y, Z)]
            lcol += [GRID, GRID]
        for i in range(lo[0], hi[0] + 1):
            for j in range(lo[1], hi[1] + 1):
                free = int(env.free_cells((i, j)))
                for cell in range(patch.cells * patch.cells):
                    if not free >> cell & 1:
                        x0 = i * patch.side + (cell % patch.cells) * c
                        y0 = j * patch.side + (cell // patch.cells) * c
                        quad = [(x0, y0, Z), (x0 + c, y0, Z), (x0 + c, y0 + c, Z),
                                (x0, y0, Z), (x0 + c, y0 + c, Z), (x0, y0 + c, Z)]
                        tris += quad
                        tcol += [OCCLUDED] * 6

    def arr(v, n):
        return np.array(v, np.float32).reshape(-1, n)
    return {"lines": (arr(lines, 3), arr(lcol, 4)), "points": (arr(points, 3), arr(pcol, 4)),
            "tris": (arr(tris, 3), arr(tcol, 4))}


def _scene_key(scene):
    return json.dumps([ob.get(api.PLAN_KEY, "")[:64] + str(len(ob.get(api.PLAN_KEY, "")))
                       for ob in scene.objects if ob.type == "ARMATURE"])


def draw():
    import bpy
    import gpu
    from gpu_extras.batch import batch_for_shader
    scene = bpy.context.scene
    if not scene.motion_patches.show_overlay:
        return
    key = _scene_key(scene)
    if _cache["key"] != key:
        _cache["key"], _cache["buffers"] = key, buffers(scene)
    flat = gpu.shader.from_builtin("FLAT_COLOR")
    gpu.state.blend_set("ALPHA")
    for prim, name in (("TRIS", "tris"), ("LINES", "lines"), ("POINTS", "points")):
        pos, col = _cache["buffers"][name]
        if not len(pos):
            continue
        shader = flat
        if prim == "POINTS":
            try:  # point shaders with a size uniform (4.x+, required on Metal/Vulkan)
                shader = gpu.shader.from_builtin("POINT_FLAT_COLOR")
                shader.uniform_float("size", 6.0)
            except (ValueError, KeyError):
                gpu.state.point_size_set(6.0)
        batch_for_shader(shader, prim, {"pos": pos, "color": col}).draw(shader)
    gpu.state.blend_set("NONE")


def enable():
    global _handle
    import bpy
    if _handle is None:
        _handle = bpy.types.SpaceView3D.draw_handler_add(draw, (), "WINDOW", "POST_VIEW")


def disable():
    global _handle
    import bpy
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    _cache["key"] = _cache["buffers"] = None


def is_enabled():
    return _handle is not None
