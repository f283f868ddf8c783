# SPDX-License-Identifier: GPL-3.0-or-later
"""Operators: read properties and context, call :mod:`api`, report. Nothing else."""

import bpy

from . import analyse, bake, bodies, crowd, mocap, object_patch, patch_files, plan
from .common import guarded

classes = tuple(
    guarded(c)
    for c in mocap.classes
    + bake.classes
    + patch_files.classes
    + object_patch.classes
    + plan.classes
    + analyse.classes
    + crowd.classes
    + bodies.classes
)

register, unregister = bpy.utils.register_classes_factory(classes)
