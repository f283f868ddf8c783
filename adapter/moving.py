# SPDX-License-Identifier: GPL-3.0-or-later
"""Keyframed props -> core prop tracks (:class:`~..motion_patches.moving_props.PropTrack`).

A prop moves when it (or an object it is parented to) has an action, drivers or
constraints. Its track is read through the depsgraph, frame by frame, from the plan's
first frame to the end of its keyframes (then it rests where they leave it), so parents,
constraints and every interpolation mode count; the scene's frame is put back afterwards.
The footprint is taken once, at the plan's first frame, and carried rigidly: a prop that
changes shape or scale while moving is followed by its rigid motion only.
"""

import math

import numpy as np

from ..motion_patches.planning.moving_props import PropTrack
from . import scene as scene_io

LONGEST_S = 600.0  # seconds of a prop's motion read at most (then it is held still)


def _moves(obj):
    """True when the object, or one it is parented to, is animated or constrained."""
    while obj is not None:
        ad = obj.animation_data
        if ad is not None and (ad.action is not None or len(ad.drivers) or len(ad.nla_tracks)):
            return True
        if len(obj.constraints):
            return True
        obj = obj.parent
    return False


def _last_frame(obj, scene):
    """The last frame at which the object's own (or a parent's) keyframes can move it; the
    scene's end when drivers or constraints make it unknowable."""
    end = None
    while obj is not None:
        ad = obj.animation_data
        if ad is not None:
            if len(ad.drivers) or len(obj.constraints):
                return scene.frame_end
            acts = [ad.action] if ad.action is not None else []
            acts += [s.action for t in ad.nla_tracks for s in t.strips if s.action is not None]
            for a in acts:
                hi = float(a.frame_range[1])
                end = hi if end is None else max(end, hi)
        elif len(obj.constraints):
            return scene.frame_end
        obj = obj.parent
    return scene.frame_end if end is None else int(math.ceil(end))


def _pose(obj):
    m = obj.matrix_world
    return m[0][3], m[1][3], math.atan2(m[1][0], m[0][0])


def moving_objects(scene, names):
    """The props that move among the objects ``names`` (obstacle names: objects, or their
    parts) stand for, in their order. The scene's objects are looked up in a dict made
    once: a lookup by name in ``scene.objects`` walks the scene (0.2 ms among 5,000)."""
    objects = {o.name: o for o in scene.objects}
    return [objects[n] for n in scene_io.owners(names) if n in objects and _moves(objects[n])]


def tracks(scene, depsgraph, names, frame_start, scale=1.0):
    """[PropTrack] of the moving props among obstacle ``names`` (one per footprint part, named
    as the obstacle), times in seconds from ``frame_start``, positions divided by ``scale``
    (the planner's world of a retargeted character)."""
    objs = moving_objects(scene, names)
    if not objs:
        return []
    fps = scene.render.fps / scene.render.fps_base
    ends = {
        o.name: min(max(_last_frame(o, scene), frame_start), frame_start + int(LONGEST_S * fps))
        for o in objs
    }
    last = max(ends.values())
    frame0, sub0 = scene.frame_current, scene.frame_subframe
    polygons, poses = {}, {o.name: [] for o in objs}
    try:
        for f in range(frame_start, last + 1):
            scene.frame_set(f)
            for o in objs:
                if f <= ends[o.name]:
                    poses[o.name].append(_pose(o))
            if f == frame_start:
                dg = depsgraph if depsgraph is not None else scene.view_layers[0].depsgraph
                for o in objs:
                    polygons[o.name] = scene_io.footprint_parts(o, dg)
    finally:
        scene.frame_set(frame0, subframe=sub0)
    out = []
    for o in objs:
        parts, p = polygons.get(o.name) or [], np.array(poses[o.name], float)
        if not parts or p.size == 0:
            continue
        x, y, yaw = p[0]
        c, s = math.cos(yaw), math.sin(yaw)
        p[:, :2] /= scale
        times = np.arange(len(p)) / fps
        if len(p) == 1:  # keyframes that end before the plan starts: held still
            times, p = np.array([0.0, 1.0]), np.vstack((p, p))
        for k, poly in enumerate(parts):
            d = poly - (x, y)
            local = np.column_stack((c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]))
            out.append(
                PropTrack(scene_io.part_name(o.name, k, len(parts)), local / scale, times, p)
            )
    return out
