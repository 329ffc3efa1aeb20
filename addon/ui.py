# SPDX-License-Identifier: GPL-3.0-or-later
"""Scene defaults, the UV editor sidebar panel and the menu entries."""

from __future__ import annotations

import bpy

from . import distortion, engine, mesh_io, methods
from .operators import UV_OT_uvflat_select_flipped, UV_OT_uvflat_unwrap

# Viewport shading of each 3D view before the heat map replaced it (by space pointer):
# (shading type, colour type).
_previous_shading: dict[int, tuple[str, str]] = {}


def attribute_color_type() -> str:
    """The identifier of the solid-shading colour type that shows the active colour attribute
    (labelled "Attribute"; ``VERTEX`` in Blender 4.2 to 5.0), read from Blender's own enum."""
    items = bpy.types.View3DShading.bl_rna.properties["color_type"].enum_items
    for item in items:
        if item.name == "Attribute":
            return item.identifier
    for identifier in ("VERTEX", "ATTRIBUTE"):
        if identifier in items.keys():
            return identifier
    raise RuntimeError("this Blender has no viewport colour type for attributes")


def _screens(context):
    """The screens whose 3D views show the heat map: the context's and every window's."""
    window_manager = getattr(context, "window_manager", None)
    candidates = [getattr(context, "screen", None)]
    candidates += [w.screen for w in (window_manager.windows if window_manager else ())]
    screens = []
    for screen in candidates:
        if screen is not None and screen not in screens:
            screens.append(screen)
    return screens


def show_heat_map(context, show, kind):
    """Show (or stop showing) the distortion heat map: the meshes in edit mode (or the
    selected ones) get the heat colours of ``kind`` written from their stored per-face
    measure as active colour attribute (``distortion.write_colors``; meshes in edit mode leave
    it for the write and enter it again), and every 3D view of the screens (the context's and
    the windows') shades solid with attribute colours. Hiding it puts back each view's own
    shading and leaves the colours on the meshes (the next unwrap removes them)."""
    objects = [o for o in (getattr(context, "objects_in_mode", None) or
                           getattr(context, "selected_objects", None) or []) if o.type == "MESH"]
    if show and objects:
        _write_heat_colors(context, objects, kind)
    color_type = attribute_color_type() if show else None
    for screen in _screens(context):
        for area in screen.areas:
            if area.type != "VIEW_3D":
                continue
            for space in area.spaces:
                if space.type != "VIEW_3D":
                    continue
                shading = space.shading
                key = space.as_pointer()
                if show:
                    _previous_shading.setdefault(key, (shading.type, shading.color_type))
                    if shading.type != "SOLID":
                        shading.type = "SOLID"  # only solid shading colours faces by attribute
                    shading.color_type = color_type
                elif key in _previous_shading:
                    shading.type, shading.color_type = _previous_shading.pop(key)
            area.tag_redraw()


def _write_heat_colors(context, objects, kind):
    editing = [o for o in objects if o.mode == "EDIT"]
    view_layer = getattr(context, "view_layer", None) or bpy.context.view_layer
    active = view_layer.objects.active
    if editing:
        engine._leave_edit_mode(editing)
    try:
        for obj in objects:
            mesh = obj.data
            distortion.write_colors(mesh, mesh_io.read_face_sizes(mesh), kind)
            mesh.update()
    finally:
        if editing:
            engine._enter_edit_mode(view_layer, editing, active)


def _update_heat_map(self, context):
    show_heat_map(context, self.show_distortion, self.distortion_kind)


@methods.add_properties
class UVFLAT_PG_defaults(bpy.types.PropertyGroup):
    """Scene-level defaults copied into the unwrap operator when it is invoked, and the
    sidebar's display settings (not operator settings)."""

    show_distortion: bpy.props.BoolProperty(
        name="Show Distortion",
        description="Colour the faces by the distortion of the last unwrap (blue 1, red at "
                    f"{distortion.RED_AT:g} or more, grey not measured) in the 3D viewport",
        default=False, update=_update_heat_map)
    distortion_kind: bpy.props.EnumProperty(
        name="Distortion",
        description="Which distortion the heat map shows",
        items=(("conformal", "Conformal", "Angle distortion, sigma1/sigma2"),
               ("area", "Area", "Area distortion, max(J, 1/J)")),
        default="conformal", update=_update_heat_map)


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


# Charts listed by the result panel (the ones needing attention first).
CHART_ROWS = 12


def _fmt(x):
    return "-" if x != x else ("inf" if x == float("inf") else f"{x:.3f}")


def _fmt_density(x):
    """Pixels per metre, to four significant digits (``-`` where not measured)."""
    return "-" if not x == x or x in (float("inf"), float("-inf")) else f"{x:.4g}"


class UVFLAT_PT_result(bpy.types.Panel):
    bl_label = "Last Unwrap"
    bl_space_type = "IMAGE_EDITOR"
    bl_region_type = "UI"
    bl_category = "uvflat"

    @classmethod
    def poll(cls, context):
        return UVFLAT_PT_defaults.poll(context)

    def draw(self, context):
        layout = self.layout
        settings = context.scene.uvflat
        row = layout.row(align=True)
        row.prop(settings, "show_distortion", toggle=True, icon="COLOR")
        row.prop(settings, "distortion_kind", text="")
        col = layout.column()
        col.enabled = context.mode == "EDIT_MESH"
        col.operator(UV_OT_uvflat_select_flipped.bl_idname, icon="RESTRICT_SELECT_OFF")
        summary = engine.LAST_SUMMARY
        if summary is None:
            layout.label(text="No unwrap yet")
            return
        box = layout.box()
        box.label(text=f"{summary.method}: {summary.charts} charts, {summary.faces} faces, "
                       f"{summary.seconds:.3f} s", icon="INFO")
        if summary.coverage is not None:
            shapes = ", ".join(engine.SHAPE_NAMES[s] for s in summary.pack_shapes)
            box.label(text=f"Tile coverage {100 * summary.coverage:.0f}%"
                           + (f", packed as {shapes}" if shapes else ""))
        if summary.non_manifold_edges:
            box.label(text=f"{summary.non_manifold_edges} non-manifold edges cut as seams",
                      icon="ERROR")
        if summary.inconsistent_edges:
            box.label(text=f"{summary.inconsistent_edges} edges between opposite normals cut "
                           "as seams", icon="ERROR")
        if summary.stretched:
            box.label(text="Unwrapped as scaled (non-uniform scale): "
                           + ", ".join(summary.stretched), icon="INFO")
        rows = engine.chart_rows(summary)
        if summary.density == "FIXED":
            box.label(text=f"Texel density {summary.texel_density:g} px/m at "
                           f"{summary.texture_size} px"
                           + (": islands larger than their tile" if summary.density_overflow
                              else ""), icon="ERROR" if summary.density_overflow else "NONE")
        grid = box.grid_flow(row_major=True, columns=9, even_columns=False, align=True)
        for heading in ("Chart", "Method", "Faces", "Flips", "Overlap", "Conformal", "Area",
                        f"px/m ({summary.texture_size})", "Time"):
            grid.label(text=heading)
        for r in rows[:CHART_ROWS]:
            grid.label(text=f"{r['object']}:{r['chart']}",
                       icon="ERROR" if r["status"] == "failed" else "NONE")
            grid.label(text=r["method"] if r["status"] != "failed" else "failed")
            grid.label(text=str(r["faces"]))
            grid.label(text=str(r["flips"]))
            grid.label(text="yes" if r["overlap"] else "no")
            grid.label(text=_fmt(r["conformal"]))
            grid.label(text=_fmt(r["area"]))
            grid.label(text=_fmt_density(r["density"]))
            grid.label(text=f"{r['seconds']:.3f}")
        reasons = [r for r in rows[:CHART_ROWS] if r["reason"]]
        for r in reasons:
            box.label(text=f"{r['object']}:{r['chart']} {r['status']}: {r['reason']}")
        if len(rows) > CHART_ROWS:
            box.label(text=f"... and {len(rows) - CHART_ROWS} more charts")


def menu_entry(self, context):
    self.layout.separator()
    self.layout.operator(UV_OT_uvflat_unwrap.bl_idname, text="uvflat Unwrap")


# (menu class name in bpy.types, function). Only the UV editor's Unwrap menu: the 3D
# Viewport's UV menu (VIEW3D_MT_uv_map) inlines it with ``menu_contents``, so an entry there as
# well would show the operator twice.
MENUS = (("IMAGE_MT_uvs_unwrap", menu_entry),)

# Default shortcut, rebindable in Preferences > Keymap: (keymap name, space type, key, modifiers).
# Shift+Alt+U: free in both the mesh edit mode and the UV editor keymaps.
KEYMAP_ITEMS = (
    ("Mesh", "EMPTY", "U", {"shift": True, "alt": True}),
    ("UV Editor", "EMPTY", "U", {"shift": True, "alt": True}),
)
_addon_keymaps: list = []

class UVFLAT_PT_result_3d(UVFLAT_PT_result):
    """The same panel in the 3D Viewport's sidebar, where the heat map shows."""

    bl_space_type = "VIEW_3D"

    @classmethod
    def poll(cls, context):
        return context.mode == "EDIT_MESH"


classes = (UVFLAT_PG_defaults, UVFLAT_PT_defaults, UVFLAT_PT_result, UVFLAT_PT_result_3d)


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


def register_keymaps():
    """Add the default shortcut to the add-on keyconfig (absent in background mode)."""
    keyconfig = bpy.context.window_manager.keyconfigs.addon
    if keyconfig is None:
        return
    for km_name, space_type, key, modifiers in KEYMAP_ITEMS:
        km = keyconfig.keymaps.new(name=km_name, space_type=space_type)
        kmi = km.keymap_items.new(UV_OT_uvflat_unwrap.bl_idname, key, "PRESS", **modifiers)
        _addon_keymaps.append((km, kmi))


def unregister_keymaps():
    for km, kmi in _addon_keymaps:
        try:
            km.keymap_items.remove(kmi)
        except (ReferenceError, RuntimeError):  # keyconfig already freed
            pass
    _addon_keymaps.clear()
