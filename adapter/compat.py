# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender version differences in one place (4.5 LTS, 5.0; 5.2 handled here too).

Since 4.4 actions are layered with slots; 5.0 removed ``Action.fcurves``. Everything
here goes through layers -> strip -> channelbag(slot) and assigns slots explicitly, so
the rest of the add-on never branches on the version. 5.0 gives every material its node
tree and deprecates ``Material.use_nodes``.
"""

import bpy

OWNER_KEY = "motion_patches_owner"  # custom property marking data this add-on created


def stored_settings(owner, name):
    """The add-on's settings group ``name`` (a ``bpy.props`` PointerProperty) of ``owner``,
    or None where it was never set, asked without creating it: reading it creates an empty
    one (on 4.5 among the owner's custom properties, which exporters write out; from 5.0
    with the system properties, which ``keys()`` does not list), so a plan, a check or the
    overlay looking at a mesh or rig would change it. None too for no owner or a group
    not registered."""
    try:
        if not owner.is_property_set(name):
            return None
    except (AttributeError, TypeError):
        return None
    return getattr(owner, name)


def new_action(name, id_type="OBJECT"):
    """A new layered action with one slot, one layer and one keyframe strip."""
    act = bpy.data.actions.new(name)
    slot = act.slots.new(id_type=id_type, name=name[:60])
    layer = act.layers.new("Layer")
    layer.strips.new(type="KEYFRAME")
    return act, slot


def action_slot(action, id_type="OBJECT"):
    """The action's first slot for ``id_type`` (or its first slot)."""
    for s in action.slots:
        if s.target_id_type in (id_type, "UNSPECIFIED"):
            return s
    return action.slots[0] if len(action.slots) else None


def channelbag(action, slot, create=False):
    if not action.layers:
        if not create:
            return None
        action.layers.new("Layer").strips.new(type="KEYFRAME")
    strip = action.layers[0].strips[0]
    if create:
        return strip.channelbag(slot, ensure=True)
    return strip.channelbag(slot)


def fcurves(action, slot=None):
    """F-curves of one slot of an action (empty list when it has none)."""
    slot = slot or action_slot(action)
    if slot is None:
        return []
    bag = channelbag(action, slot)
    return list(bag.fcurves) if bag else []


def new_fcurve(action, slot, data_path, index, group=None):
    bag = channelbag(action, slot, create=True)
    fc = bag.fcurves.new(data_path, index=index)
    if group:
        grp = bag.groups.get(group) or bag.groups.new(group)
        fc.group = grp
    return fc


def assign_action(id_block, action, slot):
    ad = id_block.animation_data or id_block.animation_data_create()
    ad.action = action
    ad.action_slot = slot


def set_strip_slot(strip, slot):
    strip.action_slot = slot


def material_nodes(mat):
    """The material's node tree, made on 4.5 (a new material has none there; 5.0 always
    has one and deprecates ``use_nodes``)."""
    if bpy.app.version < (5, 0, 0) and not mat.use_nodes:
        mat.use_nodes = True
    return mat.node_tree
