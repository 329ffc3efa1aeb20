# SPDX-License-Identifier: GPL-3.0-or-later
"""Unwrap the selected faces of every mesh in edit mode through the uvflat core.

Order of work, so that a failure never leaves a UV map half written:

1. leave edit mode (Blender writes the edit meshes back to mesh data);
2. read every mesh in bulk (``mesh_io``) and solve every mesh with ``uvflat.unwrap``:
   nothing is written until every solve has succeeded;
3. write the new UVs of solved faces only (failed charts and unselected faces keep their
   old UVs bit for bit);
4. pack the new islands with Blender's own packer (``bpy.ops.uv.pack_islands``), skipping
   islands that hold pinned UVs, then put the selection back exactly as it was;
5. re-enter edit mode.

If anything raises after step 3 started, every UV map is restored from the copies taken in
step 2 (and UV maps created by step 3 are removed) before the error propagates.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import mesh_io


# Summary of the last successful run (for batch scripts and tests).
LAST_SUMMARY = None


class UnwrapError(Exception):
    """An error meant for the user (shown by the operator as is)."""


def import_core():
    try:
        import uvflat
    except ImportError as ex:  # pragma: no cover - depends on the installation
        raise UnwrapError(f"the uvflat module could not be imported ({ex}); "
                          "reinstall the extension for this platform") from ex
    return uvflat


@dataclass
class ChartProblem:
    object_name: str
    chart: int
    kind: str
    status: str
    reason: str


@dataclass
class Summary:
    method: str = ""
    objects: int = 0
    charts: int = 0
    faces: int = 0
    solve_seconds: float = 0.0
    seconds: float = 0.0
    failed: list[ChartProblem] = field(default_factory=list)
    fallback: list[ChartProblem] = field(default_factory=list)
    packed: bool = False
    results: dict = field(default_factory=dict)  # object name -> uvflat.UnwrapResult

    def line(self) -> str:
        text = (f"uvflat {self.method}: {self.charts} chart{'s' * (self.charts != 1)}, "
                f"{self.faces} face{'s' * (self.faces != 1)} in {self.seconds:.3f} s "
                f"(solve {self.solve_seconds:.3f} s)")
        if self.failed:
            shown = "; ".join(f"{p.object_name} chart {p.chart} ({p.kind}): {p.reason}"
                              for p in self.failed[:3])
            more = f"; and {len(self.failed) - 3} more" if len(self.failed) > 3 else ""
            text += (f"; {len(self.failed)} chart{'s' * (len(self.failed) != 1)} not solved, "
                     f"UVs kept: {shown}{more}")
        if self.fallback:
            text += f"; {len(self.fallback)} solved by fallback ({self.fallback[0].reason})"
        return text


@dataclass
class _Job:
    obj: bpy.types.Object
    positions: np.ndarray
    corner_verts: np.ndarray
    face_sizes: np.ndarray
    selected: np.ndarray
    uv_name: str | None
    old_uv: np.ndarray          # (C,2) float32, exactly as stored
    pins: np.ndarray            # (P,) corner indices
    result: object = None
    created_uv: bool = False
    written: bool = False
    selection: dict | None = None
    raw_selected: np.ndarray | None = None


# ---------------------------------------------------------------------------------------------
# Mode switching


def _leave_edit_mode(objects):
    if any(o.mode == "EDIT" for o in objects):
        bpy.ops.object.mode_set(mode="OBJECT")
    still = [o.name for o in objects if o.data.is_editmode]
    if still:
        raise UnwrapError(f"could not leave edit mode for {', '.join(still)}")


def _enter_edit_mode(view_layer, objects, active):
    """Enter edit mode for exactly ``objects`` (object selection is restored afterwards)."""
    saved = [(o, o.select_get(view_layer=view_layer)) for o in view_layer.objects]
    wanted = set(o.name for o in objects)
    for o, _ in saved:
        o.select_set(o.name in wanted, view_layer=view_layer)
    view_layer.objects.active = active
    try:
        bpy.ops.object.mode_set(mode="EDIT")
    finally:
        for o, was in saved:
            o.select_set(was, view_layer=view_layer)
        view_layer.objects.active = active


# ---------------------------------------------------------------------------------------------
# The work


def _read(obj) -> _Job:
    mesh = obj.data
    positions, corner_verts, face_sizes = mesh_io.read_topology(mesh)
    raw_selected = mesh_io.read_face_selection(mesh, include_hidden=True)
    selected = mesh_io.read_face_selection(mesh)
    uv_name = mesh_io.active_uv_name(mesh)
    if uv_name is not None:
        old_uv = mesh_io.read_uv(mesh, uv_name)
        pinned = mesh_io.read_pins(mesh, uv_name) & np.repeat(selected, face_sizes)
        pins = np.flatnonzero(pinned)
    else:
        old_uv = np.zeros((len(corner_verts), 2), dtype=np.float32)
        pins = np.zeros(0, dtype=np.int64)
    job = _Job(obj, positions, corner_verts, face_sizes, selected, uv_name, old_uv, pins)
    job.raw_selected = raw_selected
    return job


def _solve(core, job: _Job, method, options, use_fit):
    kwargs = dict(options)
    seams = mesh_io.read_seams(job.obj.data)
    if len(seams):
        kwargs["seams"] = seams.astype(np.int64)
    if len(job.pins):
        kwargs["pins"] = job.pins.astype(np.int64)
        kwargs["pin_uvs"] = job.old_uv[job.pins].astype(np.float64)
    if use_fit and job.uv_name is not None:
        corners = np.repeat(job.selected, job.face_sizes)
        old = job.old_uv[corners]
        if len(old) and np.all(np.isfinite(old)) and np.ptp(old, axis=0).min() > 0.0:
            kwargs["fit_to"] = job.old_uv.astype(np.float64)
    job.result = core.unwrap(
        job.positions,
        job.corner_verts.astype(np.int64),
        job.face_sizes.astype(np.int64),
        method=method,
        selected=job.selected,
        triangles=mesh_io.read_loop_triangles(job.obj.data),
        **kwargs,
    )


def _write(job: _Job):
    mesh = job.obj.data
    name, job.created_uv = mesh_io.ensure_uv_map(mesh)
    job.written = True  # from here on, _restore must undo this job
    if job.created_uv:
        job.uv_name = name
        job.old_uv = mesh_io.read_uv(mesh, name)
    new_uv = job.old_uv.copy()
    solved = np.asarray(job.result.face_solved, dtype=bool) & job.selected
    corners = np.repeat(solved, job.face_sizes)
    new_uv[corners] = np.asarray(job.result.uv)[corners]
    mesh_io.write_uv(mesh, job.uv_name, new_uv)


def _pack_faces(job: _Job):
    """Faces whose islands should be packed: solved, and not in a chart holding pins."""
    chart = np.asarray(job.result.chart)
    faces = np.asarray(job.result.face_solved, dtype=bool) & job.selected
    if len(job.pins):
        pinned_charts = np.unique(chart[mesh_io.corner_faces(job.face_sizes)[job.pins]])
        faces &= ~np.isin(chart, pinned_charts)
    return faces


def _restore(jobs):
    """Put every UV map and selection back as it was before this run."""
    for job in jobs:
        mesh = job.obj.data
        if job.written:
            if job.created_uv:
                mesh_io.remove_uv_map(mesh, job.uv_name)
            else:
                mesh_io.write_uv(mesh, job.uv_name, job.old_uv)
            job.written = False
        if job.selection is not None:
            mesh_io.restore_selection(mesh, job.selection)
            job.selection = None


def _pack(context, jobs, in_mode, active, margin, shape) -> bool:
    """Pack the islands of the solved, unpinned charts with Blender's packer.

    Returns True when the objects were left in edit mode (the selection did not have to be
    changed for packing, so there was nothing to put back).
    """
    pack_sets = [(job, _pack_faces(job)) for job in jobs]
    if not any(faces.any() for _, faces in pack_sets):
        return False
    change = [(job, faces) for job, faces in pack_sets if not np.array_equal(faces, job.raw_selected)]
    tool_settings = context.scene.tool_settings
    sync = tool_settings.use_uv_select_sync
    select_mode = tuple(tool_settings.mesh_select_mode)
    for job, faces in change:
        job.selection = mesh_io.save_selection(job.obj.data)
        mesh_io.select_faces(job.obj.data, faces)
    if change:
        # face select mode, so entering edit mode cannot grow the selection onto faces whose
        # vertices are all selected
        tool_settings.mesh_select_mode = (False, False, True)
    try:
        _enter_edit_mode(context.view_layer, in_mode, active)
        tool_settings.use_uv_select_sync = True  # pack by mesh face selection
        result = bpy.ops.uv.pack_islands(margin=margin, shape_method=shape)
    finally:
        tool_settings.use_uv_select_sync = sync
        if change:
            tool_settings.mesh_select_mode = select_mode
    if "FINISHED" not in result:
        raise UnwrapError(f"Blender's island packing returned {set(result)}")
    if not change:
        return True
    _leave_edit_mode(in_mode)
    for job, _ in change:
        mesh_io.restore_selection(job.obj.data, job.selection)
        job.selection = None
    return False


def unwrap_edit_objects(context, method, options, *, pack=True, margin=0.001,
                        pack_shape="AABB") -> Summary:
    """Unwrap the selected faces of every mesh object in edit mode; see the module docstring."""
    start = time.perf_counter()
    core = import_core()
    if method not in core.METHODS:
        raise UnwrapError(f"method '{method}' is not provided by this uvflat build "
                          f"(available: {', '.join(core.METHODS)})")

    view_layer = context.view_layer
    in_mode = [o for o in context.objects_in_mode if o.type == "MESH"]
    objects = [o for o in context.objects_in_mode_unique_data if o.type == "MESH"]
    if not objects:
        raise UnwrapError("no mesh object in edit mode")
    active = context.active_object if context.active_object in in_mode else in_mode[0]
    summary = Summary(method=method)
    jobs: list[_Job] = []

    _leave_edit_mode(in_mode)
    in_edit = False
    try:
        # 2. read and solve everything before writing anything
        for obj in objects:
            job = _read(obj)
            if not job.selected.any():
                continue
            t0 = time.perf_counter()
            try:
                _solve(core, job, method, options, use_fit=not pack)
            except core.UvflatError as ex:
                raise UnwrapError(f"{obj.name}: {ex}") from ex
            summary.solve_seconds += time.perf_counter() - t0
            jobs.append(job)
        if not jobs:
            raise UnwrapError("no faces selected")

        try:
            # 3. write
            for job in jobs:
                _write(job)
            # 4. pack the new islands only
            if pack:
                in_edit = _pack(context, jobs, in_mode, active, margin, pack_shape)
                summary.packed = True
        except BaseException:
            _leave_edit_mode(in_mode)
            in_edit = False
            _restore(jobs)
            raise
    finally:
        if not in_edit:
            _enter_edit_mode(view_layer, in_mode, active)

    for job in jobs:
        summary.results[job.obj.name] = job.result
        summary.faces += int((np.asarray(job.result.face_solved, dtype=bool) & job.selected).sum())
        for chart in job.result.charts:
            problem = ChartProblem(job.obj.name, chart.id, chart.kind, chart.status,
                                   chart.reason or "no reason given")
            if chart.status == "failed":
                summary.failed.append(problem)
            else:
                summary.charts += 1
                if chart.status == "fallback":
                    summary.fallback.append(problem)
    summary.objects = len(jobs)
    summary.seconds = time.perf_counter() - start
    return summary
