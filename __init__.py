# SPDX-License-Identifier: GPL-3.0-or-later
"""Dynamic Motion Patches: tilable locomotion patches, object patches and path planning.

The extension entry point only registers classes; all logic lives in the pure-numpy
core (``motion_patches``), the Blender adapter (``adapter``) and the thin ``operators``.
"""

from . import cli, operators, panels, props


def register():
    props.register()
    operators.register()
    panels.register()
    cli.register()


def unregister():
    cli.unregister()
    panels.unregister()
    operators.unregister()
    props.unregister()
