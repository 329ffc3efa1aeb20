# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene defaults, the UV editor sidebar panel and the menu entries."""

from __future__ import annotations

import bpy

from . import methods
from .operators import UV_OT_uvflat_unwrap


@methods.add_properties
class UVFLAT_PG_defaults(bpy.types.PropertyGroup):
    """Scene-level defaults copied into the unwrap operator when it is invoked."""


class UVFLAT_PT_defaults(bpy.types.Panel):
    bl_label = "uvflat"
    bl_space_type = "IMAGE_EDITOR"
    bl_region_type = "UI"
    bl_category = "uvflat"

    @classmethod
    def poll(cls, context):
        space = context.space_data
        return space is not None and getattr(space, "mode", "UV") == "UV"

    def draw(self, context):
        layout = self.layout
        methods.draw_settings(layout, context.scene.uvflat)
        col = layout.column()
        col.enabled = context.mode == "EDIT_MESH"
        col.operator(UV_OT_uvflat_unwrap.bl_idname, text="Unwrap", icon="UV")


def menu_entry(self, context):
    self.layout.separator()
    self.layout.operator(UV_OT_uvflat_unwrap.bl_idname, text="uvflat Unwrap")


# (menu class name in bpy.types, function) — both verified on Blender 4.2 and 5.0
MENUS = (("VIEW3D_MT_uv_map", menu_entry), ("IMAGE_MT_uvs_unwrap", menu_entry))

classes = (UVFLAT_PG_defaults, UVFLAT_PT_defaults)


def register_menus():
    for menu_name, func in MENUS:
        menu = getattr(bpy.types, menu_name, None)
        if menu is not None:
            menu.append(func)


def unregister_menus():
    for menu_name, func in reversed(MENUS):
        menu = getattr(bpy.types, menu_name, None)
        if menu is not None:
            menu.remove(func)
