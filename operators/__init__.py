"""Operators: read properties and context, call :mod:`api`, report. Nothing else."""

import bpy

from . import analyse, bake, mocap, plan

classes = mocap.classes + bake.classes + plan.classes + analyse.classes

register, unregister = bpy.utils.register_classes_factory(classes)
