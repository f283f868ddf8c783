# SPDX-License-Identifier: GPL-3.0-or-later
"""Analysis panel: the Analyse button and the last figures measured on the active
character (stored on it by the operator), in the numbers an animator checks."""

import bpy

from .. import api
from .sidebar import SidebarPanel, wrapped_label


def figure_lines(f):
    """The panel's lines for a figures dict of :func:`api.analyse`."""
    sk, pop = f["foot_skate"], f["boundary_pop"]
    return [
        f"Foot skate: {sk['mean_cm_per_frame']:.2f} cm/frame ({sk['mean_cm_per_s']:.1f} cm/s)",
        f"Goal error: {f['goal_position_error_cm']:.1f} cm, {f['goal_heading_error_deg']:.1f}°",
        f"Frames inside props: root {f['frames_root_inside_obstacle']}, "
        f"body {f.get('frames_body_inside_prop', '-')}",
        f"Boundary pop: {pop['max_boundary_jump_deg']:.1f}° "
        f"(elsewhere p99 {pop['p99_step_deg']:.1f}°)",
    ]


class MOTION_PATCHES_PT_analysis(SidebarPanel, bpy.types.Panel):
    bl_label = "Analysis"
    bl_idname = "MOTION_PATCHES_PT_analysis"

    def draw(self, context):
        layout = self.layout
        layout.operator("motion_patches.analyse_motion", icon="GRAPH")
        ob = context.active_object
        figures = api.last_analysis(ob) if ob is not None and ob.type == "ARMATURE" else None
        if figures is None:
            wrapped_label(layout, context, "Select a planned character and analyse it", icon="INFO")
            return
        col = layout.column(align=True)
        for line in figure_lines(figures):
            wrapped_label(col, context, line)


classes = (MOTION_PATCHES_PT_analysis,)
