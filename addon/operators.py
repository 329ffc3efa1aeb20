# SPDX-License-Identifier: GPL-3.0-or-later
"""The unwrap operator.

An unwrap expected to take longer than ``engine.MODAL_AFTER_SECONDS`` runs the core on a
worker thread while the operator runs modal: progress in the status bar, Esc cancels and
leaves every UV map, seam and selection exactly as before. The meshes stay out of edit mode
while the core solves (the viewport shows object mode): going back to edit mode only to leave
it again when the solve ends would rebuild every edit mesh twice for nothing (half a second
per million faces). Without a window (background
mode) or for small selections it runs in one go.
"""

from __future__ import annotations

import bpy

from . import distortion, engine, mesh_io, methods

# Events let through to Blender while the modal unwrap runs (view navigation only: nothing
# that could edit the meshes being solved).
_PASS_THROUGH = {"MIDDLEMOUSE", "WHEELUPMOUSE", "WHEELDOWNMOUSE", "MOUSEMOVE",
                 "INBETWEEN_MOUSEMOVE", "TRACKPADPAN", "TRACKPADZOOM", "NDOF_MOTION"}


# Why the operators are greyed out (tooltip) or refused (scripts) outside mesh edit mode.
POLL_MESSAGE = "uvflat: enter Edit Mode and select faces"


def _report_summary(op, summary):
    engine.LAST_SUMMARY = summary
    op.report({"WARNING"} if summary.needs_attention else {"INFO"}, summary.line())


@methods.add_properties
class UV_OT_uvflat_unwrap(bpy.types.Operator):
    """Unwrap the selected faces with uvflat (seams, pins and n-gons respected)"""

    bl_idname = "uv.uvflat_unwrap"
    bl_label = "uvflat Unwrap"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode == "EDIT_MESH":
            return True
        cls.poll_message_set(POLL_MESSAGE)
        return False

    def invoke(self, context, event):
        defaults = getattr(context.scene, "uvflat", None)
        if defaults is not None:
            methods.apply_defaults(self.properties, defaults)
        if getattr(context, "window", None) is None or engine.estimated_seconds(
                methods.chosen_method(self.properties), engine.selected_face_count(context),
                methods.pack_settings(self.properties),
                engine.face_count(context)) < engine.MODAL_AFTER_SECONDS:
            return self.execute(context)
        return self.start_modal(context)

    def execute(self, context):
        engine.LAST_SUMMARY = None
        methods.settle_preset(self)
        method = methods.chosen_method(self)
        try:
            summary = engine.unwrap_edit_objects(
                context,
                method,
                methods.core_options(self, method),
                auto_seams=methods.auto_seam_options(self),
                mark_seams=self.mark_seams,
                seams_only=self.auto_seams and self.seams_only,
                avoid_group=self.avoid_group,
                pack=engine.PackSettings(**methods.pack_settings(self)),
                correct_aspect=self.correct_aspect,
            )
        except engine.UnwrapError as ex:
            self.report({"ERROR"}, f"uvflat: {ex}")
            return {"CANCELLED"}
        except Exception as ex:  # anything else: UVs were restored by the engine
            self.report({"ERROR"}, f"uvflat: unwrap failed, UVs unchanged: {type(ex).__name__}: {ex}")
            return {"CANCELLED"}
        _report_summary(self, summary)
        return {"FINISHED"}

    # -- modal: the solve on a worker thread ---------------------------------------------------

    def start_modal(self, context):
        engine.LAST_SUMMARY = None
        methods.settle_preset(self)
        method = methods.chosen_method(self)
        run = engine.Run(method, methods.core_options(self, method),
                         engine.PackSettings(**methods.pack_settings(self)), self.correct_aspect,
                         auto_seams=methods.auto_seam_options(self), mark_seams=self.mark_seams,
                         seams_only=self.auto_seams and self.seams_only,
                         avoid_group=self.avoid_group)
        try:
            run.prepare(context, stay_out=True)
        except engine.UnwrapError as ex:
            self.report({"ERROR"}, f"uvflat: {ex}")
            return {"CANCELLED"}
        self._run = run
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 1000)
        self._status(context)
        run.start_thread()
        return {"RUNNING_MODAL"}

    def _status(self, context):
        done_objects, objects, charts_done, charts = self._run.progress
        fraction = (done_objects + (charts_done / charts if charts else 0.0)) / max(objects, 1)
        context.window_manager.progress_update(int(1000 * fraction))
        text = (f"uvflat {self._run.method}: {100 * fraction:.0f}%"
                + (f", chart {charts_done} of {charts}" if charts else "")
                + (f", object {done_objects + 1} of {objects}" if objects > 1 else "")
                + " (Esc to cancel)")
        context.workspace.status_text_set(text)

    def _end_ui(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        run = self._run
        if event.type == "ESC":
            run.cancel()
        elif event.type != "TIMER":
            return {"PASS_THROUGH"} if event.type in _PASS_THROUGH else {"RUNNING_MODAL"}
        if run.running:
            self._status(context)
            return {"RUNNING_MODAL"}
        self._end_ui(context)
        if run.cancel_requested.is_set() or run.cancelled:
            run.abort(context)
            self.report({"INFO"}, "uvflat: cancelled, UVs unchanged")
            return {"CANCELLED"}
        try:
            summary = run.finish(context)
        except engine.UnwrapError as ex:
            run.abort(context)
            self.report({"ERROR"}, f"uvflat: {ex}")
            return {"CANCELLED"}
        except Exception as ex:  # UVs were restored by the engine
            run.abort(context)
            self.report({"ERROR"}, f"uvflat: unwrap failed, UVs unchanged: {type(ex).__name__}: {ex}")
            return {"CANCELLED"}
        _report_summary(self, summary)
        return {"FINISHED"}

    def draw(self, context):
        methods.draw_settings(self.layout, self)


class UV_OT_uvflat_select_flipped(bpy.types.Operator):
    """Select exactly the faces whose UVs are flipped (or have zero UV area) in the active UV
    map, as uvflat's reports count them"""

    bl_idname = "uv.uvflat_select_flipped"
    bl_label = "Select Flipped Faces"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.mode == "EDIT_MESH":
            return True
        cls.poll_message_set(POLL_MESSAGE)
        return False

    def execute(self, context):
        in_mode = [o for o in context.objects_in_mode if o.type == "MESH"]
        active = context.active_object if context.active_object in in_mode else in_mode[0]
        try:
            uvflat = engine.import_core()
        except engine.UnwrapError as ex:
            self.report({"ERROR"}, f"uvflat: {ex}")
            return {"CANCELLED"}
        engine._leave_edit_mode(in_mode)
        count = 0
        try:
            for obj in {o.data.name: o for o in in_mode}.values():
                # the active UV map measured by the core, as a report counts flips
                try:
                    flipped = distortion.flipped_faces(uvflat, obj.data)
                except uvflat.UvflatError as ex:
                    self.report({"ERROR"}, f"uvflat: {obj.name}: {ex}")
                    return {"CANCELLED"}
                flipped &= ~mesh_io.read_hidden_faces(obj.data)
                mesh_io.select_faces(obj.data, flipped)
                count += int(flipped.sum())
        finally:
            engine._enter_edit_mode(context.view_layer, in_mode, active)
        self.report({"INFO"}, f"uvflat: {count} flipped face{'s' * (count != 1)} selected")
        return {"FINISHED"}


classes = (UV_OT_uvflat_unwrap, UV_OT_uvflat_select_flipped)
