# SPDX-License-Identifier: GPL-3.0-or-later
"""The unwrap operator."""

from __future__ import annotations

import bpy

from . import engine, methods


@methods.add_properties
class UV_OT_uvflat_unwrap(bpy.types.Operator):
    """Unwrap the selected faces with uvflat (seams, pins and n-gons respected)"""

    bl_idname = "uv.uvflat_unwrap"
    bl_label = "uvflat Unwrap"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.mode == "EDIT_MESH"

    def invoke(self, context, event):
        defaults = getattr(context.scene, "uvflat", None)
        if defaults is not None:
            for name in methods.SETTING_NAMES:
                setattr(self, name, getattr(defaults, name))
        return self.execute(context)

    def execute(self, context):
        engine.LAST_SUMMARY = None
        try:
            summary = engine.unwrap_edit_objects(
                context,
                self.method,
                methods.core_options(self),
                pack=self.pack,
                margin=self.margin,
                pack_shape=self.pack_shape,
                auto_seams=methods.auto_seam_options(self),
                mark_seams=self.mark_seams,
                avoid_group=self.avoid_group,
            )
        except engine.UnwrapError as ex:
            self.report({"ERROR"}, f"uvflat: {ex}")
            return {"CANCELLED"}
        except Exception as ex:  # anything else: UVs were restored by the engine
            self.report({"ERROR"}, f"uvflat: unwrap failed, UVs unchanged: {type(ex).__name__}: {ex}")
            return {"CANCELLED"}
        engine.LAST_SUMMARY = summary
        self.report({"WARNING"} if summary.failed else {"INFO"}, summary.line())
        return {"FINISHED"}

    def draw(self, context):
        methods.draw_settings(self.layout, self)


classes = (UV_OT_uvflat_unwrap,)
