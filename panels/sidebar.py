# SPDX-License-Identifier: GPL-3.0-or-later
"""Where every panel of the add-on lives: the 3D viewport's sidebar, "Motion Patches" tab."""


class SidebarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Motion Patches"


def list_with_buttons(layout, listtype, owner, items, index, add, remove, rows=3):
    """A UIList of ``owner.<items>`` with add / remove buttons beside it."""
    row = layout.row()
    row.template_list(listtype, "", owner, items, owner, index, rows=rows)
    col = row.column(align=True)
    col.operator(add, icon="ADD", text="")
    col.operator(remove, icon="REMOVE", text="")


# Where a label's text starts and ends inside the sidebar region, in unscaled pixels: the
# panel's margin and padding on the left, and on the right the padding, the category tabs
# and a few pixels to spare (measured on Blender 5.2 at the default 1920x1200 layout).
LABEL_INSET = 17 + 50
ICON_WIDTH = 22


def text_width(text, context):
    """Width of ``text`` in pixels as the UI draws it (Blender's UI font at the interface's
    widget size and scale), or an estimate when no font can be measured."""
    prefs = context.preferences
    scale = prefs.system.ui_scale if prefs is not None else 1.0
    try:
        import blf

        points = prefs.ui_styles[0].widget.points if prefs is not None else 11
        blf.size(0, points * scale)
        return blf.dimensions(0, text)[0]
    except Exception:  # no font (some headless builds): about 6.5 px per character
        return 6.5 * scale * len(text)


def wrap_text(text, context, icon=False):
    """``text`` broken at spaces into lines that fit the region's width (Blender cuts a
    label that does not fit and shows '...' instead of the end). Drawn with no region
    (off screen, e.g. into a test's recording layout) there is no width: one line."""
    region = getattr(context, "region", None)
    if region is None or region.width <= 1:
        return [text]
    prefs = context.preferences
    scale = prefs.system.ui_scale if prefs is not None else 1.0
    room = max(region.width - (LABEL_INSET + (ICON_WIDTH if icon else 0)) * scale, 60 * scale)
    lines, line = [], ""
    for word in text.split(" "):
        candidate = f"{line} {word}" if line else word
        if line and text_width(candidate, context) > room:
            lines.append(line)
            line = word
        else:
            line = candidate
    return lines + [line]


def wrapped_label(layout, context, text, icon="NONE"):
    """A label whose text wraps onto as many lines as the sidebar's width needs; the lines
    after the first are indented under the text when there is an icon."""
    col = layout.column(align=True)
    for i, line in enumerate(wrap_text(text, context, icon != "NONE")):
        col.label(text=line, icon=icon if i == 0 else ("BLANK1" if icon != "NONE" else "NONE"))
    return col
