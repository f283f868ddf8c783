"""Where every panel of the add-on lives: the 3D viewport's sidebar, "Motion Patches" tab."""


class SidebarPanel:
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "Motion Patches"


def list_with_buttons(layout, listtype, owner, items, index, add, remove, rows=3):
    """A UIList of ``owner.<items>`` with add / remove buttons beside it."""
    row = layout.row()
    row.template_list(listtype, "", owner, items, owner, index, rows=rows)
    col = row.column(align=True)
    col.operator(add, icon='ADD', text="")
    col.operator(remove, icon='REMOVE', text="")
