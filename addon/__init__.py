# SPDX-License-Identifier: GPL-3.0-or-later
"""uvflat: UV unwrapping of selected faces through a Rust core.

UV Editor > UV > Unwrap > uvflat Unwrap, 3D Viewport (Edit Mode) > UV > uvflat Unwrap (the
same menu, inlined), Shift+Alt+U in mesh edit mode and the UV editor (rebindable), and the
"uvflat" tab of the UV Editor sidebar for the defaults.
"""

from __future__ import annotations

if "bpy" in locals():  # reload support (F3 > Reload Scripts)
    import importlib

    for _name in ("mesh_io", "methods", "aspect", "distortion", "packing", "proxy_pack", "engine",
                  "operators", "ui"):
        if _name in locals():
            importlib.reload(locals()[_name])

import bpy

from . import aspect, distortion, engine, mesh_io, methods, operators, packing, proxy_pack, ui

classes = operators.classes + ui.classes


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.uvflat = bpy.props.PointerProperty(type=ui.UVFLAT_PG_defaults)
    ui.register_menus()
    ui.register_keymaps()


def unregister():
    ui.unregister_keymaps()
    ui.unregister_menus()
    del bpy.types.Scene.uvflat
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
