# SPDX-License-Identifier: GPL-3.0-or-later
"""Linked copies of an armature with their goal empties, in a collection of their own (a
crowd made from one character), and their removal."""

import bpy
import numpy as np

from ..motion_patches.kinematics import quat
from . import actions as act_io
from . import nla, storage
from . import rig as rig_io


def make_copies(scene, source, starts, goals, facing, collection):
    """[(copy, goal empty)]: a copy of ``source`` (object copied, armature data shared) on
    each start (x, y) facing its goal (``facing``: the skeleton's forward angle,
    :func:`nla.facing_angle`), without the source's animation or plan, and a goal empty on
    each goal facing the same way (its -Y), all linked in a new collection ``collection``
    under the scene's."""
    coll = bpy.data.collections.new(collection)
    scene.collection.children.link(coll)
    tilt = rig_io.world_tilt(source)
    pairs = []
    for k, (s, g) in enumerate(zip(starts, goals)):
        heading = float(np.arctan2(g[1] - s[1], g[0] - s[0]))
        ob = source.copy()  # object copy, armature data shared
        ob.name = f"{source.name}.crowd{k:03d}"
        ob.animation_data_clear()
        for key in (storage.PLAN_KEY, storage.PLAN_ID_KEY, nla.TRACKS_KEY, nla.ACTIONS_KEY):
            if key in ob:
                del ob[key]
        coll.objects.link(ob)
        ob.location = (s[0], s[1], source.location[2])
        ob.rotation_mode = "XYZ"
        ob.rotation_euler = _facing(tilt, heading - facing)
        goal = bpy.data.objects.new(f"{ob.name} goal", None)
        coll.objects.link(goal)
        goal.location = (g[0], g[1], 0.0)
        goal.rotation_euler = (0.0, 0.0, heading + np.pi / 2)  # its -Y along the heading
        ob.motion_patches_character.goal = goal
        pairs.append((ob, goal))
    return pairs


def _facing(tilt, turn):
    """XYZ Euler angles of the turn about Z ``turn`` over the source's ``tilt``
    (:func:`rig.world_tilt`, None: none): a copy of an FBX import stands as it does."""
    if tilt is None:
        return (0.0, 0.0, turn)
    q = quat.mul(quat.about_z(np.array(turn)), quat.from_matrix(tilt))
    return tuple(act_io.closest_channels(q[None], "XYZ", np.zeros((1, 3)))[0])


def remove_copies(pairs, collection):
    """Remove the copies and goals of :func:`make_copies`, the actions planning made for
    them (:func:`nla.made_for`) and their collections (named from ``collection``) when
    left empty."""
    colls, tagged, made, doomed = set(), nla.tagged_actions(bpy), [], []
    for ob, goal in pairs:
        for o in (ob, goal):
            colls.update(c for c in o.users_collection if c.name.startswith(collection))
        made += nla.actions_made_for(bpy, ob, tagged)
        if ob.animation_data is not None:
            ob.animation_data_clear()
        doomed += [ob, goal]
    # in batches: each removal on its own has Blender look through the whole file
    bpy.data.batch_remove(doomed)
    bpy.data.batch_remove([a for a in made if a.users == 0])
    for c in colls:
        if not c.objects and not c.children:
            bpy.data.collections.remove(c)
