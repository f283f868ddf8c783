# SPDX-License-Identifier: GPL-3.0-or-later
"""What the planner saw, as geometry for the viewport overlay (``panels/overlay.py`` draws
it): each planned path with its strips and the lattice, occluded cells and props it was
planned against, and where the tagged props' clips start and end."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import bpy
import numpy as np

from ..adapter import props_io, storage
from ..motion_patches.planning.plan_frame import (
    lattice_frame,
    local_environment,
    to_local,
    to_world,
)
from ..motion_patches.props import footprint as fp
from .common import object_patches
from .errors import MotionPatchesError

MAX_FOOTPRINT_VERTICES = 20000  # above this the panel does not compute the footprint area


@dataclass
class PlanDrawing:
    """One planned character's path as the planner laid it (world x, y)."""

    ground: np.ndarray  # (N, 3) x, y, heading per frame
    kinds: list  # per step (frame i to i + 1): "segment", "traversal" or "interaction"
    parity: np.ndarray  # per step: the index of its strip, mod 2 (strips alternate)
    stitches: list  # frames (from the first) where a strip starts
    grid: list = field(default_factory=list)  # [(p, q)] tile edges of its lattice
    occluded: list = field(default_factory=list)  # [(4, 2) corners] cells occluded there
    obstacles: list = field(default_factory=list)  # (K, 2) polygons it walked round
    radius: float = 0.0


def _tagged(scene):
    return (ob for ob in scene.objects if props_io.is_tagged(ob))


def plan_fingerprints(scene: bpy.types.Scene) -> list:
    """What changes when any character's plan record does (cheap: no record is read)."""
    return [storage.plan_fingerprint(ob) for ob in scene.objects if ob.type == "ARMATURE"]


# The drawings of the last call by (character, plan fingerprint, lattice drawn): the
# overlay asks again whenever the active character changes, and reading every plan record
# of a crowd of 1,000 took 1.7 s of its 2.2.
_drawn: dict = {}


def plan_drawings(
    scene: bpy.types.Scene, lattice_of: Iterable[str] | None = None
) -> list[PlanDrawing]:
    """:class:`PlanDrawing` of every visible planned character (a hidden one, or one in a
    hidden collection, is not drawn). With a patch baked, for the characters named in
    ``lattice_of`` (None: all), it also holds the plan's lattice (anchored at the start, +x
    towards the goal, as the planner laid it), the cells the planner's bitmask marks
    occluded (a cell touched by the grown footprint counts as occluded there, though a
    segment through a partly covered cell is then tested exactly against the footprint)
    and the props it walked round. A character whose plan record is the one of the call
    before gets the same drawing back (not to be changed)."""
    global _drawn
    out, drawn = [], {}
    try:
        patch = storage.load_patch(scene)
    except ValueError:
        patch = None
    lattice_of = None if lattice_of is None else set(lattice_of)
    # what a lattice drawn is made of besides the record
    grid = None if patch is None else (patch.side, patch.cells, patch.cell_size, patch.nodes)
    for ob in scene.objects:
        if ob.type != "ARMATURE" or not storage.has_plan(ob) or not ob.visible_get():
            continue
        lattice = grid if lattice_of is None or ob.name in lattice_of else None
        key = (ob.name, storage.plan_fingerprint(ob), lattice)
        d = _drawn.get(key)
        if d is None:
            d = _plan_drawing(ob, patch if lattice else None)
        drawn[key] = d
        out.append(d)
    _drawn = drawn
    return out


def _plan_drawing(ob, patch):
    """The :class:`PlanDrawing` of one planned character, with its lattice when ``patch``."""
    meta, arrays = storage.load_plan(ob)
    g = arrays["ground"]
    kinds = np.full(g.shape[0] - 1, "segment", dtype=object)
    strip_starts = [meta["frame_start"]] + list(meta["boundaries"])
    parity = np.zeros(g.shape[0] - 1, int)
    for n, s in enumerate(strip_starts):
        parity[s - meta["frame_start"] :] = n % 2
    for key in ("traversals", "interactions"):
        for a, b in meta.get(key, []):
            kinds[a - meta["frame_start"] : b - meta["frame_start"]] = key[:-1]
    drawing = PlanDrawing(g, list(kinds), parity, [s - meta["frame_start"] for s in strip_starts])
    if patch is None:
        return drawing
    env = storage.plan_environment(meta, patch.side, patch.cells, meta["radius"])
    frame = lattice_frame(g[0], meta["goal"], patch.side, patch.nodes)
    local = to_local(frame, g[:, :2])
    lo = np.floor(local.min(axis=0) / patch.side).astype(int) - 1
    hi = np.floor(local.max(axis=0) / patch.side).astype(int) + 1
    lenv = local_environment(env, frame, lo * patch.side, (hi + 1) * patch.side)
    c = patch.cell_size

    def world(*pts):
        return [(float(x), float(y)) for x, y in to_world(frame, np.array(pts, float))]

    for i in range(lo[0], hi[0] + 2):
        x = i * patch.side
        drawing.grid.append(world((x, lo[1] * patch.side), (x, (hi[1] + 1) * patch.side)))
    for j in range(lo[1], hi[1] + 2):
        y = j * patch.side
        drawing.grid.append(world((lo[0] * patch.side, y), ((hi[0] + 1) * patch.side, y)))
    for i in range(lo[0], hi[0] + 1):
        for j in range(lo[1], hi[1] + 1):
            free = int(lenv.free_cells((i, j)))
            for cell in range(patch.cells * patch.cells):
                if not free >> cell & 1:
                    x0 = i * patch.side + (cell % patch.cells) * c
                    y0 = j * patch.side + (cell // patch.cells) * c
                    drawing.occluded.append(
                        world((x0, y0), (x0 + c, y0), (x0 + c, y0 + c), (x0, y0 + c))
                    )
    drawing.obstacles = [np.array(poly) for poly in meta["obstacles"].values()]
    drawing.radius = meta["radius"]
    return drawing


def clip_ends(scene: bpy.types.Scene, depsgraph: bpy.types.Depsgraph | None = None) -> list[tuple]:
    """[(x, y, heading, entry)] of every tagged prop's clips: for each (copy of a) clip its
    first ground frame (``entry`` True) and its last. Empty when no patch is baked, or when
    a tagged prop cannot be read (a clip without an action): planning would refuse that
    scene too, and says why."""
    out = []
    try:
        patch = storage.load_patch(scene)
    except ValueError:
        patch = None
    if patch is not None and any(_tagged(scene)):
        if depsgraph is None:
            depsgraph = bpy.context.evaluated_depsgraph_get()
        try:
            props = object_patches(scene, depsgraph, patch)
        except MotionPatchesError:
            props = []
        for prop in props:
            for clip in prop.clips:
                g = prop.world_clip(clip).ground
                for (x, y, h), entry in ((g[0], True), (g[-1], False)):
                    out.append((float(x), float(y), float(h), entry))
    return out


def footprint_info(ob: bpy.types.Object) -> tuple[int, float | None]:
    """(vertex count, plan-view area in m² of the mesh's footprint as a tagged prop's
    (:func:`motion_patches.props.footprint.outline`), or None when the mesh is too large to
    measure while drawing). Modifiers are not applied here."""
    me = ob.data
    n = len(me.vertices)
    if n == 0 or n > MAX_FOOTPRINT_VERTICES:
        return n, None
    co = np.empty(n * 3)
    me.vertices.foreach_get("co", co)
    m = np.array(ob.matrix_world)
    outline = fp.outline(co.reshape(n, 3) @ m[:2, :3].T + m[:2, 3])
    return n, None if outline is None else fp.area(outline)
