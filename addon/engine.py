# SPDX-License-Identifier: GPL-3.0-or-later
"""Unwrap the selected faces of every mesh in edit mode through the uvflat core.

Order of work, so that a failure never leaves a UV map half written:

1. leave edit mode (Blender writes the edit meshes back to mesh data);
2. read every mesh in bulk (``mesh_io``) and solve every mesh with ``uvflat.unwrap``:
   nothing is written until every solve has succeeded;
3. write the new UVs of solved faces only (failed charts and unselected faces keep their
   old UVs bit for bit);
4. pack the new islands with Blender's own packer (``bpy.ops.uv.pack_islands``), skipping
   islands that hold pinned UVs, each into the UDIM tile its faces were in and, around
   existing islands, at their texel density (:func:`_pack`), then put the selection back
   exactly as it was;
5. re-enter edit mode.

If anything raises after step 3 started, every UV map is restored from the copies taken in
step 2 (and UV maps created by step 3 are removed) before the error propagates.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from dataclasses import dataclass, field

import bpy
import numpy as np

from . import aspect, distortion, mesh_io, packing, proxy_pack


# Summary of the last successful run (for batch scripts and tests).
LAST_SUMMARY = None

# Optional callable(objects_done, objects_total, charts_done, charts_total) told of the
# solve's progress (from the solving thread); the batch script draws a progress bar with it.
PROGRESS_HOOK = None


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
    seams_added: int = 0   # edges cut by automatic seams
    cones: int = 0         # cone singularities placed by automatic seams
    seams_marked: bool = False
    seams_only: bool = False  # Mark Seams Only: seams marked, no UVs written
    non_manifold_edges: int = 0  # edges of 3+ selected faces, treated as seams
    stretched: tuple = ()  # objects with a non-uniform scale, unwrapped as they look
    inconsistent_edges: int = 0  # edges between faces with opposite normals, treated as seams
    flipped_faces: int = 0  # faces holding the flipped triangles (what Select Flipped selects)
    pack_shapes: tuple = ()  # island shapes Blender's packer was given (see pack_shape)
    pack_shape: str = ""     # the shape asked for
    # UV area of the packed islands over the area of the squares bounding them (one per UDIM
    # tile packed into; with Around Others the tile's other islands count too); None when
    # nothing was packed
    coverage: float | None = None
    # texel density: the mode the new islands got (AUTO, MATCH, FIXED; MATCH with nothing
    # to match is AUTO), the FIXED px/m, the texture size of the per-chart px/m, and whether
    # FIXED islands did not fit in their UDIM tile
    density: str = "AUTO"
    texel_density: float = 0.0
    texture_size: int = 1024
    density_overflow: bool = False
    # object name -> UV units per metre of surface of every chart (NaN where not solved):
    # sqrt(UV area / world surface area)
    chart_density: dict = field(default_factory=dict)
    # object name -> the texture aspect (width / height) its new islands were corrected for
    # (1.0 without Correct Aspect): the texture is then texture_size by texture_size / aspect
    # pixels (see px_per_metre)
    chart_aspect: dict = field(default_factory=dict)
    results: dict = field(default_factory=dict)  # object name -> uvflat.UnwrapResult
    # Seconds per phase of the last run (for benchmarks); they add up to ``seconds``:
    # "read", "solve", "quality" (the core's measure of the per-face distortion), "write"
    # (UVs, seams, distortion attributes), "pack" (Blender's packer; with the stand-in mesh
    # of ``proxy_pack`` everything it does), "mode" (edit/object mode switches and selection
    # changes around them) and "other" (the rest: summaries, bookkeeping).
    phases: dict = field(default_factory=dict)

    def px_per_metre(self, name):
        """Texel density of every chart of object ``name`` in texture pixels per metre of
        surface: ``sqrt(pixel area / world area)`` on a texture of ``texture_size`` pixels along
        U and ``texture_size / aspect`` along V (Correct Aspect's aspect; a square texture
        without it). An island corrected for that aspect has this density along U and along
        V. ``None`` when the object's densities were not measured."""
        per_metre = self.chart_density.get(name)
        if per_metre is None:
            return None
        aspect_ = float(self.chart_aspect.get(name, 1.0))
        return np.asarray(per_metre, dtype=np.float64) * (self.texture_size / np.sqrt(aspect_))

    @property
    def needs_attention(self) -> bool:
        """Whether the operator should report a warning rather than info."""
        return bool(self.failed) or self.non_manifold_edges > 0 or self.inconsistent_edges > 0

    def line(self) -> str:
        """The short status line: counts, time, problems grouped by reason, and a pointer to
        the sidebar's chart list when something needs attention."""
        text = (f"uvflat {self.method}: {self.charts} chart{'s' * (self.charts != 1)}, "
                f"{self.faces} face{'s' * (self.faces != 1)} in {self.seconds:.3f} s")
        if self.seams_only:
            text += "; seams only: no UVs written"
        if self.seams_added:
            text += (f"; auto seams: {self.seams_added} edge{'s' * (self.seams_added != 1)} cut "
                     f"through {self.cones} cone{'s' * (self.cones != 1)}"
                     f"{' (marked as seams)' if self.seams_marked else ''}")
        if self.failed:
            text += (f"; {len(self.failed)} chart{'s' * (len(self.failed) != 1)} not solved, "
                     f"UVs kept: {_grouped(self.failed)}")
        if self.fallback:
            text += f"; {len(self.fallback)} solved by fallback ({_grouped(self.fallback)})"
        if self.non_manifold_edges:
            n = self.non_manifold_edges
            text += (f"; {n} non-manifold edge{'s' * (n != 1)} (3+ faces) treated as "
                     f"seam{'s' * (n != 1)}")
        if self.inconsistent_edges:
            n = self.inconsistent_edges
            text += (f"; {n} edge{'s' * (n != 1)} between faces with opposite normals treated as "
                     f"seam{'s' * (n != 1)} (Mesh > Normals > Recalculate Outside joins them)")
        if self.stretched:
            names = ", ".join(self.stretched[:2]) + (", ..." if len(self.stretched) > 2 else "")
            text += (f"; unwrapped as scaled ({names}: non-uniform object scale; the UVs stay "
                     f"right when it is applied)")
        flips = self.flipped_triangles
        if flips:
            text += f"; {flips} flipped triangle{'s' * (flips != 1)}"
            faces = self.flipped_faces
            if faces:
                text += f" in {faces} face{'s' * (faces != 1)} (Select Flipped)"
        if self.coverage is not None:
            text += f"; tile coverage {100 * self.coverage:.0f}%"
        if self.density == "FIXED":
            text += (f"; texel density {self.texel_density:g} px/m at {self.texture_size} px"
                     + (": islands larger than their tile" if self.density_overflow else ""))
        elif self.density == "MATCH":
            text += "; texel density of the islands left alone"
        cheaper = [s for s in self.pack_shapes if s != self.pack_shape]
        if self.pack_shape and cheaper:
            text += f"; many islands: packed as {' and '.join(SHAPE_NAMES[s] for s in cheaper)}"
        if self.needs_attention or self.fallback or flips:
            text += " - see the uvflat sidebar"
        return text

    @property
    def flipped_triangles(self) -> int:
        return sum(int(getattr(c, "flips", 0)) for r in self.results.values() for c in r.charts
                   if c.status != "failed")


SHAPE_NAMES = {"CONCAVE": "exact shapes", "CONVEX": "convex hulls", "AABB": "bounding boxes"}


def _grouped(problems, shown=2) -> str:
    """Reasons with their counts, most frequent first: 'closed surface (x3); ...'."""
    counts: dict[str, int] = {}
    for p in problems:
        counts[p.reason] = counts.get(p.reason, 0) + 1
    ranked = sorted(counts.items(), key=lambda kv: -kv[1])
    text = "; ".join(f"{reason} (x{n})" if n > 1 else reason for reason, n in ranked[:shown])
    if len(ranked) > shown:
        text += f"; {len(ranked) - shown} other reason{'s' * (len(ranked) - shown != 1)}"
    return text


def chart_rows(summary, limit=None):
    """One dict per chart of ``summary`` (object, chart, method, status, faces, flips, overlap,
    conformal, area, density: texel density in pixels per metre at the summary's texture size,
    see :meth:`Summary.px_per_metre` (NaN where not solved), seconds, reason), the ones needing attention first: failed,
    fallback, flipped, overlapping, then by conformal distortion."""
    rows = []
    for name, result in summary.results.items():
        px_per_metre = summary.px_per_metre(name)
        for c in result.charts:
            density = (float(px_per_metre[c.id]) if px_per_metre is not None
                       and c.id < len(px_per_metre) else float("nan"))
            rows.append({"object": name, "chart": c.id, "method": c.method, "status": c.status,
                         "faces": c.faces, "flips": c.flips, "overlap": bool(c.overlap),
                         "conformal": c.conformal, "area": c.area,
                         "density": density, "seconds": c.seconds,
                         "reason": c.reason or "", "code": getattr(c, "reason_code", "")})

    def attention(row):
        conformal = row["conformal"] if row["conformal"] == row["conformal"] else float("inf")
        return (row["status"] != "failed", row["status"] != "fallback", row["flips"] == 0,
                not row["overlap"], -conformal)

    rows.sort(key=attention)
    return rows if limit is None else rows[:limit]


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
    fitted: bool = False        # solved with fit_to (new islands placed where the old ones were)
    created_uv: bool = False
    written: bool = False
    selection: dict | None = None
    pin_state: tuple | None = None  # (saved pin attribute,) while packing around locked islands
    raw_selected: np.ndarray | None = None
    avoid: np.ndarray | None = None        # vertex indices where seams must not go
    old_seams: np.ndarray | None = None    # (E,) seam flags before marking new seams
    triangles: np.ndarray | None = None    # (T,3) Blender's render triangles (corner triples)
    seams: np.ndarray | None = None  # (S,2) seam vertex pairs
    quality: dict | None = None      # distortion attributes as they were before writing
    aspect: float = 1.0              # width / height of the texture (correct aspect)
    flipped_faces: int = 0           # faces holding flipped triangles (uvflat_flipped)
    # the object's stretch (see object_stretch) when it is not a uniform scale, else None;
    # the core then solves the surface as the viewport shows it
    stretch: np.ndarray | None = None

    @property
    def shape_positions(self) -> np.ndarray:
        """Vertex positions of the surface to unwrap: the mesh's own, stretched as the
        object's transform stretches them (``positions`` when it does not)."""
        return self.positions if self.stretch is None else self.positions @ self.stretch.T


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


def object_stretch(obj, tolerance=1e-5):
    """The symmetric positive definite ``(3, 3)`` stretch ``P`` of ``obj``'s world transform
    ``M = R P`` (polar decomposition: ``P = sqrt(Mᵀ M)``, ``R`` a rotation or reflection),
    in the object's own axes, or ``None`` when ``P`` is a uniform scale within ``tolerance``
    (rotation, mirroring and uniform scale change no angle or length ratio of the surface,
    so the unwrap would be the same). A non-uniform scale (the object scaled along one axis
    and not applied) stretches every face in the viewport: the unwrap is solved on the
    stretched surface, so the texture is not stretched on it."""
    m = np.array(obj.matrix_world, dtype=np.float64)[:3, :3]
    w, v = np.linalg.eigh(m.T @ m)
    if not np.all(np.isfinite(w)) or w.min() <= 0.0:
        return None   # a degenerate transform (a zero scale) has no surface to unwrap
    s = np.sqrt(w)
    if s.max() - s.min() <= tolerance * s.max():
        return None
    return (v * s) @ v.T


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
    job.stretch = object_stretch(obj)
    job.raw_selected = raw_selected
    job.seams = mesh_io.read_seams(mesh)
    # read here, on the main thread: the solve may run on a worker thread
    job.triangles = mesh_io.read_loop_triangles(mesh, face_sizes)
    return job


def _read_avoid_groups(context, objects, in_mode, active, group):
    """Vertices of vertex group ``group`` per object name, read in bulk: Blender's own
    *Select* of the group marks them, the selection is read as one array and then put back
    exactly as it was. Objects without the group are left out. Runs in object mode."""
    wanted = [o for o in objects if group and o.vertex_groups.get(group) is not None]
    if not wanted:
        return {}
    out = {}
    saved = {o.name: (mesh_io.save_selection(o.data), o.vertex_groups.active_index) for o in wanted}
    try:
        for o in wanted:
            _enter_edit_mode(context.view_layer, [o], o)
            try:
                bpy.ops.mesh.select_all(action="DESELECT")
                o.vertex_groups.active_index = o.vertex_groups[group].index
                bpy.ops.object.vertex_group_select()
            finally:
                _leave_edit_mode([o])
            out[o.name] = np.flatnonzero(mesh_io.read_vertex_selection(o.data))
    finally:
        for o in wanted:
            selection, index = saved[o.name]
            mesh_io.restore_selection(o.data, selection)
            o.vertex_groups.active_index = index
    return out


def _solved_faces(job: _Job):
    """Selected faces that received UVs."""
    return np.asarray(job.result.face_solved, dtype=bool) & job.selected


def _mark_new_seams(job: _Job) -> int:
    """Mark the edges cut by automatic seams as seams; returns how many were new. Only cuts
    along a face that received UVs are marked: a chart that failed keeps its UVs and its seams."""
    new = np.asarray(getattr(job.result, "new_seams", ()))
    if not len(new):
        return 0
    mesh = job.obj.data
    _, use_seam = mesh_io.read_edges(mesh)
    add = mesh_io.seam_mask_of_pairs(mesh, new) & ~use_seam
    solved_edges = np.zeros(len(use_seam), dtype=bool)
    corners = np.repeat(_solved_faces(job), job.face_sizes)
    solved_edges[mesh_io.read_corner_edges(mesh)[corners]] = True
    add &= solved_edges
    if not add.any():
        return 0
    job.old_seams = use_seam.copy()
    mesh_io.write_seams(mesh, use_seam | add)
    return int(add.sum())


def _solve(core, job: _Job, method, options, use_fit, progress=None):
    """Solve one job with the core; touches no Blender data (safe on a worker thread)."""
    kwargs = dict(options)
    if job.avoid is not None and len(job.avoid):
        kwargs["avoid_vertices"] = job.avoid.astype(np.int64)
    if len(job.seams):
        kwargs["seams"] = job.seams.astype(np.int64)
    if progress is not None:
        kwargs["progress"] = progress
    if len(job.pins):
        kwargs["pins"] = job.pins.astype(np.int64)
        kwargs["pin_uvs"] = job.old_uv[job.pins].astype(np.float64)
    if use_fit and job.uv_name is not None:
        corners = np.repeat(job.selected, job.face_sizes)
        old = job.old_uv[corners]
        if len(old) and np.all(np.isfinite(old)) and np.ptp(old, axis=0).min() > 0.0:
            kwargs["fit_to"] = job.old_uv.astype(np.float64)
            job.fitted = True
    job.result = core.unwrap(
        job.shape_positions,
        job.corner_verts.astype(np.int64),
        job.face_sizes.astype(np.int64),
        method=method,
        selected=job.selected,
        triangles=job.triangles,
        **kwargs,
    )


def _write(job: _Job, phases=None, color_kind=None):
    """Write the new UVs of the solved faces and their quality attributes. A job where no face
    was solved writes nothing at all (no UV map is created, no attribute changes)."""
    solved = _solved_faces(job)
    if not solved.any():
        return
    mesh = job.obj.data
    name, job.created_uv = mesh_io.ensure_uv_map(mesh)
    job.written = True  # from here on, _restore must undo this job
    if job.created_uv:
        job.uv_name = name
        job.old_uv = mesh_io.read_uv(mesh, name)
    new_uv = job.old_uv.copy()
    corners = np.repeat(solved, job.face_sizes)
    np.copyto(new_uv, np.asarray(job.result.uv), where=corners[:, None])
    # per-face quality of the returned UVs (before the aspect correction; packing moves
    # islands by similarities only, which changes none of it)
    t0 = time.perf_counter()
    quality = distortion.measure(job, solved)
    job.flipped_faces = int(np.count_nonzero(quality[2]))
    if phases is not None:
        _lap(phases, "quality", t0)
    if job.aspect != 1.0:
        chart = np.asarray(job.result.chart, dtype=np.int64)
        free = solved.copy()
        if len(job.pins):  # pinned UVs stay exactly where they are
            free &= ~np.isin(chart, chart[mesh_io.corner_faces(job.face_sizes)[job.pins]])
        aspect.correct(new_uv, np.repeat(free, job.face_sizes), np.repeat(chart, job.face_sizes),
                       job.aspect)
    mesh_io.write_uv(mesh, job.uv_name, new_uv)
    job.quality = distortion.snapshot(mesh)
    distortion.write(mesh, job.face_sizes, solved, *quality, color_kind=color_kind)
    mesh.update()


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
        if job.old_seams is not None:
            mesh_io.write_seams(mesh, job.old_seams)
            job.old_seams = None
        if job.written:
            if job.created_uv:
                mesh_io.remove_uv_map(mesh, job.uv_name)
            else:
                mesh_io.write_uv(mesh, job.uv_name, job.old_uv)
            if job.quality is not None:
                distortion.restore(mesh, job.quality)
                job.quality = None
                mesh.update()
            job.written = False
    _restore_selection_and_pins(jobs)


@dataclass(frozen=True)
class PackSettings:
    """How the new islands are packed (Blender's ``uv.pack_islands`` options).

    ``mode``: ``AROUND`` packs the new islands into the free space of the UDIM tile their
    faces were in, every other island of the UV map locked in place (Blender's packer with
    pinned islands locked) and its texel density kept; ``ALL`` packs the new islands over the
    whole tile, scaled to fill it, as Blender's own Unwrap does (other islands are not moved,
    but may be overlapped); ``OFF`` fits each new island to where its faces' previous UVs were.
    ``shape_method`` is the shape asked for (see :func:`pack_shape`); ``orient`` turns the
    new islands to their smallest bounding box first.

    ``density`` sets the new islands' texel density: ``AUTO`` as the packing mode does it
    (around others: theirs; whole tile: scaled to fill it; off: where the old UVs were);
    ``MATCH`` the density of the islands left alone in every packing mode (the packer scales
    nothing; as ``AUTO`` when there are none); ``FIXED`` ``texel_density`` pixels per metre of
    surface (world size, scene units) on a texture ``texture_size`` pixels wide, i.e.
    :attr:`uv_per_metre` UV units per metre along U, packed without scaling (islands may not
    fit in the tile: the summary says so). With Correct Aspect on a texture of aspect ``a``
    (width / height) the texture is ``texture_size / a`` pixels high, and the islands,
    corrected for it, get ``texel_density`` pixels per metre along U and along V (see
    :func:`_fixed_target`). ``texture_size`` also gives the pixels of the per-island densities
    the summary lists. Every density is per metre of world surface (the object's transform
    counts, see :func:`world_face_areas`).
    """

    mode: str = "AROUND"
    margin: float = 0.001
    margin_method: str = "SCALED"
    shape_method: str = "CONCAVE"
    rotate: bool = True
    orient: bool = True  # new islands turned to their smallest bounding box first
    density: str = "AUTO"          # AUTO, MATCH or FIXED
    texel_density: float = 1024.0  # pixels per metre (FIXED)
    texture_size: int = 1024       # texture width in pixels (FIXED; and the summary's px/m)

    @property
    def uv_per_metre(self) -> float:
        """UV units per metre of surface along U of the ``FIXED`` density."""
        return float(self.texel_density) / float(self.texture_size)

    @property
    def rotate_method(self) -> str:
        """How Blender's packer may rotate: oriented islands by quarter turns only."""
        return "CARDINAL" if self.orient else "ANY"


def _locked_faces(job: _Job, packed):
    """Faces whose islands stay where they are while packing around them: every visible face
    of an existing UV map that is not packed now (unselected, failed, pinned)."""
    if job.created_uv:
        return np.zeros_like(packed)
    return ~packed & ~mesh_io.read_hidden_faces(job.obj.data)


@dataclass
class _PackPlan:
    """The packing of one job's new islands (see :func:`_pack`)."""

    job: _Job
    faces: np.ndarray            # (F,) faces packed now
    locked: np.ndarray           # (F,) faces packed around (AROUND), in any tile
    island: np.ndarray           # (F,) island of every packed face, -1 elsewhere
    tiles: np.ndarray            # (n_islands, 2) UDIM tile of every island
    face_tile: np.ndarray        # (F, 2) UDIM tile of every face (current UVs)
    uv: np.ndarray               # (C, 2) float64: the UVs as they are being packed
    area3: np.ndarray            # (F,) world surface area of every face (world_face_areas)
    area_uv: np.ndarray          # (F,) UV area of every face (as written)
    matched: np.ndarray | None = None  # (F,) faces whose density the new islands take
    reference: float | None = None  # UV area per surface area of the matched faces
    keep_angle: bool = False     # the packer must not rotate these islands (see _pack)


def _plan(job: _Job, faces, locked, matched=None) -> _PackPlan:
    written = mesh_io.read_uv(job.obj.data, job.uv_name)
    chart = np.asarray(job.result.chart, dtype=np.int64)
    ids, inverse = np.unique(chart[faces], return_inverse=True)
    island = np.full(len(chart), -1, dtype=np.int64)
    island[faces] = inverse
    old = np.zeros_like(written) if job.created_uv else job.old_uv
    # densities are per metre of world surface: islands of objects of different scales (or of
    # one non-uniformly scaled object) are compared by the texels their world surface gets
    area3, area_uv = world_face_areas(job, written)
    plan = _PackPlan(job, faces, locked, island,
                     packing.island_tiles(old, job.face_sizes, island, len(ids)),
                     packing.face_tiles(written, job.face_sizes), written.astype(np.float64),
                     area3, area_uv)
    plan.matched = locked if matched is None else matched
    plan.reference = (packing.density(area3, area_uv, plan.matched) if plan.matched.any()
                      else None)
    return plan


def world_face_areas(job: _Job, uv=None):
    """Surface area of every face of ``job``'s mesh in square metres (the object's world
    transform and the scene's unit scale applied), and the UV area of ``uv`` (default the
    written map) per face; both over Blender's render triangles."""
    matrix = np.array(job.obj.matrix_world, dtype=np.float64)[:3, :3]
    scene = bpy.context.scene
    metres = float(scene.unit_settings.scale_length) if scene is not None else 1.0
    positions = job.positions @ matrix.T * metres
    if uv is None:
        uv = mesh_io.read_uv(job.obj.data, job.uv_name)
    return packing.face_areas(positions, job.corner_verts, job.face_sizes, job.triangles, uv)


def _scale_to_density(plans, settings) -> bool:
    """Scale the new islands of ``plans`` (their ``uv``) to the texel density ``settings``
    asks for (see :class:`PackSettings`); returns whether their size is now set (the packer
    must then scale nothing). ``AUTO`` and ``MATCH``: each mesh's matched faces' density,
    else all meshes' together, nothing when there are none; ``FIXED``: its UV units per
    metre, by world surface."""
    if settings.density == "FIXED":
        for plan in plans:
            _scale_plan(plan, _fixed_target(settings, plan.job.aspect), _island_ratio(plan))
        return True
    area3 = sum(float(p.area3[p.matched & (p.area_uv > 0)].sum()) for p in plans)
    area_uv = sum(float(p.area_uv[p.matched & (p.area3 > 0)].sum()) for p in plans)
    reference = area_uv / area3 if area3 > 0 and area_uv > 0 else None
    if reference is None:
        return False
    for plan in plans:
        target = plan.reference if plan.reference is not None else reference
        _scale_plan(plan, target, _island_ratio(plan))
    return True


def _fixed_target(settings, aspect_=1.0) -> float:
    """UV area per world surface area of the ``FIXED`` density for islands corrected for a
    texture of aspect ``aspect_`` (width / height; 1.0 without Correct Aspect).

    The texture is ``W = texture_size`` by ``H = W / aspect_`` pixels; ``D`` pixels per metre
    along U and along V are ``D / W`` and ``D / H`` UV units per metre: an area ratio of
    ``D^2 / (W H) = uv_per_metre^2 * aspect_``. The correction has made the islands ``aspect_``
    times narrower in U than in V already, so scaling them uniformly to that ratio gives both."""
    return settings.uv_per_metre ** 2 * float(aspect_)


def _scale_plan(plan: _PackPlan, target, ratio):
    """Scale every new island of ``plan`` from UV area per surface area ``ratio`` to
    ``target`` (islands without area unchanged)."""
    good = np.isfinite(ratio) & (ratio > 0)
    factors = np.where(good, np.sqrt(target / np.where(good, ratio, 1.0)), 1.0)
    packing.scale_islands(plan.uv, plan.job.face_sizes, plan.island, factors)


def _island_ratio(plan: _PackPlan):
    """UV area per world surface area of every new island."""
    n = len(plan.tiles)
    inside = plan.island >= 0
    area3 = np.bincount(plan.island[inside], weights=plan.area3[inside], minlength=n)
    area_uv = np.bincount(plan.island[inside], weights=plan.area_uv[inside], minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        return area_uv / area3


# Islands from which Blender's packer is given a cheaper shape than the one asked for. Its
# exact (concave) and convex shapes are searched island against island: a handful of
# islands takes it a fraction of a second, a few tens of them tens of seconds (30 one-face
# islands: 41 s), bounding boxes a millisecond whatever their number. Islands of one or two
# faces count several times (many same-sized tiny islands are its slowest case).
CONCAVE_MAX_ISLANDS = 8
CONVEX_MAX_ISLANDS = 16
TINY_ISLAND_FACES = 2
TINY_ISLAND_WEIGHT = 4


def pack_shape(shape_method, islands, tiny=0) -> str:
    """The island shape Blender's packer is given for ``islands`` new islands (``tiny`` of
    them of at most :data:`TINY_ISLAND_FACES` faces): the one asked for, or the first cheaper
    one (convex hulls, then bounding boxes) when there are too many islands for it."""
    pieces = islands + (TINY_ISLAND_WEIGHT - 1) * tiny
    shape = shape_method
    if shape == "CONCAVE" and pieces > CONCAVE_MAX_ISLANDS:
        shape = "CONVEX"
    if shape == "CONVEX" and pieces > CONVEX_MAX_ISLANDS:
        shape = "AABB"
    return shape


def _island_counts(plan, faces):
    """``(islands, tiny islands)`` among the islands of ``faces`` of ``plan``."""
    sizes = np.bincount(plan.island[faces])
    sizes = sizes[sizes > 0]
    return len(sizes), int(np.count_nonzero(sizes <= TINY_ISLAND_FACES))


def _plans(jobs, settings: PackSettings, only=None):
    """A :class:`_PackPlan` of every job (of ``only``, default all) with new islands to pack
    or scale: locked faces around others, matched faces around others or with Match
    Existing."""
    around = settings.mode == "AROUND"
    chosen = None if only is None else {id(job) for job in only}
    plans = []
    for job in jobs:
        if job.uv_name is None or not job.written or (chosen is not None and id(job) not in chosen):
            continue
        faces = _pack_faces(job)
        if not faces.any():
            continue
        left_alone = _locked_faces(job, faces)
        locked = left_alone if around else np.zeros_like(faces)
        plans.append(_plan(job, faces, locked,
                           left_alone if around or settings.density == "MATCH" else locked))
    return plans


def _scale_in_place(jobs, settings: PackSettings):
    """Packing off: the new islands of ``jobs``, where their old UVs were, scaled about their
    centres to the density ``settings`` asks for (Match Existing or Fixed)."""
    plans = _plans(jobs, settings)
    if _scale_to_density(plans, settings):
        _PACK_REPORT.density = settings.density
        for plan in plans:
            mesh_io.write_uv(plan.job.obj.data, plan.job.uv_name, plan.uv)
    return plans


def _pack(context, jobs, in_mode, active, settings: PackSettings, only=None, phases=None) -> bool:
    """Pack the islands of the solved, unpinned charts with Blender's packer (of the jobs in
    ``only``, default all), around the locked islands when ``settings.mode == "AROUND"``.

    Every new island goes into the UDIM tile its faces were in (``packing``), packed around
    that tile's locked islands; around existing islands (or with Match Existing) the new ones
    get the texel density of the islands left alone, with a Fixed density that one, and the
    packer scales nothing. Blender's packer rotates in the
    pixels of the object's texture: islands not corrected for a non-square one would be
    sheared, so they are turned to their smallest bounding box here and packed unrotated.

    Islands are turned to their smallest bounding box first with ``settings.orient``. The
    selection (and, around locked islands, the pin flags) are changed for the packer and put
    back exactly afterwards. Runs from object mode and returns to it (returns False: the
    objects are not left in edit mode).
    """
    plans = _plans(jobs, settings, only)
    if not plans:
        return False
    core = import_core()
    # texel density: around others (or Match Existing) that of the map left alone, each
    # mesh's own, else all of them together; or the fixed one
    keep_density = _scale_to_density(plans, settings)
    _PACK_REPORT.density = settings.density if keep_density else "AUTO"
    transformed = keep_density
    for plan in plans:
        job = plan.job
        plan.keep_angle = (settings.rotate and aspect.material_aspect(job.obj) != 1.0
                           and job.aspect == 1.0)
        if plan.keep_angle or settings.orient:
            _orient(core, plan)
            transformed = True
    tiles = np.unique(np.vstack([p.tiles for p in plans]), axis=0)
    try:
        for tile in tiles:
            _pack_tile(context, core, jobs, plans, in_mode, active, settings, tile, keep_density,
                       phases)
    finally:
        _restore_selection_and_pins(jobs)
    for plan in plans:
        mesh_io.write_uv(plan.job.obj.data, plan.job.uv_name, plan.uv)
    _PACK_REPORT.coverage = _coverage(plans, tiles)
    return False


def _orient(core, plan: _PackPlan):
    """Turn every new island of ``plan`` to its smallest bounding box. Islands corrected for a
    non-square texture are turned in its pixels (U times the aspect), where they are
    undistorted: a turn in UV units would shear them."""
    job = plan.job
    corners = np.repeat(plan.faces, job.face_sizes)
    pixels = plan.uv.copy()
    pixels[corners, 0] *= job.aspect
    angles = core.island_box_angles(pixels, job.face_sizes.astype(np.int64), plan.island)
    if not len(angles):
        return
    # an island the core leaves as it lies (angle 0: no area, or its box already the least) is
    # not touched at all, so its UVs stay exactly as they were
    turned = (plan.island >= 0) & (angles[np.maximum(plan.island, 0)] != 0.0)
    if not turned.any():
        return
    packing.rotate_islands(pixels, job.face_sizes, np.where(turned, plan.island, -1), angles)
    plan.uv[corners, 0] = pixels[corners, 0] / job.aspect
    plan.uv[corners, 1] = pixels[corners, 1]


def _coverage(plans, tiles):
    """UV area over the area of the squares bounding the packed UVs, one square per UDIM tile
    packed into: the new islands and, packed around, that tile's locked islands."""
    area = 0.0
    squares = 0.0
    for tile in tiles:
        lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
        for plan in plans:
            faces = ((plan.faces & np.all(plan.tiles[np.maximum(plan.island, 0)] == tile, axis=1))
                     | (plan.locked & np.all(plan.face_tile == tile, axis=1)))
            if not faces.any():
                continue
            _, area_uv = packing.face_areas(plan.job.positions, plan.job.corner_verts,
                                            plan.job.face_sizes, plan.job.triangles, plan.uv)
            area += float(area_uv[faces].sum())
            pts = plan.uv[np.repeat(faces, plan.job.face_sizes)]
            lo, hi = np.minimum(lo, pts.min(axis=0)), np.maximum(hi, pts.max(axis=0))
        if np.all(hi >= lo):
            squares += float(np.max(hi - lo)) ** 2
    return area / squares if squares > 0 else None


class _PackReport:
    """What the packing of the current run did (the summary reports it)."""

    def __init__(self):
        self.shapes: list[str] = []   # island shapes Blender's packer was given
        self.coverage = None          # see _coverage
        self.density = "AUTO"         # the density the new islands were given (see _pack)


_PACK_REPORT = _PackReport()


def _note_shape(shape):
    if shape not in _PACK_REPORT.shapes:
        _PACK_REPORT.shapes.append(shape)


def _run_packer(context, settings, shape, rotate, scale, locked, phases):
    """Blender's packer on the selected faces of the meshes in edit mode (by mesh selection)."""
    tool_settings = context.scene.tool_settings
    sync = tool_settings.use_uv_select_sync
    try:
        tool_settings.use_uv_select_sync = True  # pack by mesh face selection
        t0 = time.perf_counter()
        result = bpy.ops.uv.pack_islands(
            margin=settings.margin, margin_method=settings.margin_method,
            shape_method=shape, rotate=rotate, rotate_method=settings.rotate_method, scale=scale,
            pin=locked, pin_method="LOCKED")
        if phases is not None:
            _lap(phases, "pack", t0)
    finally:
        tool_settings.use_uv_select_sync = sync
    if "FINISHED" not in result:
        raise UnwrapError(f"Blender's island packing returned {set(result)}")


def _pack_tile(context, core, jobs, plans, in_mode, active, settings, tile, keep_density,
               phases):
    """Pack the new islands of UDIM ``tile`` (of every plan) into it, around that tile's
    locked faces; updates each plan's ``uv``. Runs from object mode and returns to it."""
    tile = np.asarray(tile, dtype=np.int64)
    members = []  # (plan, new faces, locked faces) of this tile
    for plan in plans:
        new = plan.faces & np.all(plan.tiles[np.maximum(plan.island, 0)] == tile, axis=1)
        if new.any():
            members.append((plan, new, plan.locked & np.all(plan.face_tile == tile, axis=1)))
    if not members:
        return
    counts = [_island_counts(plan, new) for plan, new, _ in members]
    n_islands = sum(c[0] for c in counts)
    n_locked = sum(int(locked.sum()) for _, _, locked in members)
    shape = pack_shape(settings.shape_method, n_islands, sum(c[1] for c in counts))
    _note_shape(shape)
    rotate = settings.rotate and not any(plan.keep_angle for plan, _, _ in members)
    group_settings = dataclasses.replace(settings, shape_method=shape, rotate=rotate)
    offset = tile.astype(np.float64)
    if n_locked == 0 and not keep_density and _pack_tile_by_proxy(
            context, core, jobs, members, group_settings, n_islands, offset, phases):
        return
    in_tile = {id(plan.job): (plan, new, locked) for plan, new, locked in members}
    tool_settings = context.scene.tool_settings
    select_mode = tuple(tool_settings.mesh_select_mode)
    # every mesh selects exactly this tile's new and locked faces (the others nothing): the
    # packer packs the selection
    for job in jobs:
        plan, new, locked = in_tile.get(id(job), (None, None, None))
        if plan is None and not job.raw_selected.any() and job.selection is None:
            continue
        mesh = job.obj.data
        if job.selection is None:
            job.selection = mesh_io.save_selection(mesh)
        if plan is None:
            mesh_io.select_faces(mesh, np.zeros(len(job.face_sizes), dtype=bool))
            continue
        mesh_io.select_faces(mesh, new | locked)
        uv = plan.uv.copy()
        new_corners = np.repeat(new, job.face_sizes)
        locked_corners = np.repeat(locked, job.face_sizes)
        # into the 0-1 tile for the packer: the locked faces by the tile's offset, the new
        # islands together onto its centre (the packer then places them)
        uv[locked_corners] -= offset
        pts = uv[new_corners]
        uv[new_corners] += 0.5 - 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        mesh_io.write_uv(mesh, job.uv_name, uv)
        if locked.any():
            if job.pin_state is None:
                job.pin_state = (mesh_io.save_pins(mesh, job.uv_name),)
            mesh_io.write_pins(mesh, job.uv_name,
                               mesh_io.read_pins(mesh, job.uv_name) | locked_corners)
    # face select mode, so entering edit mode cannot grow the selection onto faces whose
    # vertices are all selected
    tool_settings.mesh_select_mode = (False, False, True)
    try:
        _enter_edit_mode(context.view_layer, in_mode, active)
        try:
            _run_packer(context, group_settings, shape, rotate, not keep_density, n_locked > 0,
                        phases)
        finally:
            _leave_edit_mode(in_mode)
    finally:
        tool_settings.mesh_select_mode = select_mode
    for plan, new, _ in members:
        job = plan.job
        packed = mesh_io.read_uv(job.obj.data, job.uv_name).astype(np.float64)
        corners = np.repeat(new, job.face_sizes)
        plan.uv[corners] = packed[corners] + offset
        # every other face (the locked ones were only moved for the packer) as before
        mesh_io.write_uv(job.obj.data, job.uv_name, plan.uv)


def _pack_tile_by_proxy(context, core, jobs, members, settings, n_islands, offset, phases):
    """Pack a tile's new islands on a stand-in mesh of one face per island when that packs
    exactly as the meshes themselves would (``proxy_pack``: nothing packed around, square
    texture, large meshes); updates the plans' ``uv``. Returns False, having changed nothing,
    when it does not apply."""
    t0 = time.perf_counter()
    n_faces = sum(len(job.face_sizes) for job in jobs)
    aspects = [aspect.image_aspect(context, plan.job.obj) for plan, _, _ in members]
    if not proxy_pack.applicable(settings, n_islands, False, aspects, n_faces):
        return False
    uvs = {id(plan.job): plan.uv for plan, _, _ in members}
    islands = proxy_pack.islands(core, [(plan.job, new) for plan, new, _ in members], uvs)
    if islands is None:
        return False
    transforms = proxy_pack.pack(context, islands, settings, _enter_edit_mode, _leave_edit_mode)
    proxy_pack.apply(islands, transforms, uvs)
    for plan, new, _ in members:
        plan.uv[np.repeat(new, plan.job.face_sizes)] += offset
    if phases is not None:
        _lap(phases, "pack", t0)
    return True


def _restore_selection_and_pins(jobs):
    for job in jobs:
        mesh = job.obj.data
        if job.selection is not None:
            mesh_io.restore_selection(mesh, job.selection)
            job.selection = None
        if job.pin_state is not None:
            mesh_io.restore_pins(mesh, job.uv_name, job.pin_state[0])
            job.pin_state = None


class Run:
    """One unwrap split in three steps, so that the solve can run on a worker thread while
    Blender keeps drawing: :meth:`prepare` (Blender data, main thread), :meth:`solve` (core
    only, any thread) and :meth:`finish` or :meth:`abort` (Blender data, main thread).

    Nothing is written before :meth:`finish`; :meth:`abort` leaves every UV map, seam and
    selection exactly as :meth:`prepare` found them.
    """

    def __init__(self, method, options, pack: PackSettings, correct_aspect=True, *,
                 auto_seams=None, mark_seams=True, seams_only=False, avoid_group=""):
        self.method = method
        # Mark Seams Only: mark the planned cuts, write no UVs and pack nothing
        self.seams_only = seams_only
        self.correct_aspect = correct_aspect
        # automatic-seams keywords of uvflat.unwrap first, the method's options after
        self.options = {**(auto_seams or {}), **dict(options)}
        self.mark_seams = mark_seams
        self.avoid_group = avoid_group
        self.pack = pack
        self.jobs: list[_Job] = []
        self.summary = Summary(method=method)
        self.start = time.perf_counter()
        self.cancel_requested = threading.Event()
        # (objects done, objects total, charts done, charts total), written by the solve
        self.progress = (0, 0, 0, 0)
        self.error: BaseException | None = None
        self.cancelled = False
        self._thread: threading.Thread | None = None
        self._core = None

    # -- main thread -------------------------------------------------------------------------

    def prepare(self, context, *, stay_out=False):
        """Leave edit mode, read every mesh; back in edit mode unless ``stay_out``."""
        core = import_core()
        if self.method not in core.METHODS:
            raise UnwrapError(f"method '{self.method}' is not provided by this uvflat build "
                              f"(available: {', '.join(core.METHODS)})")
        self._core = core
        self.view_layer = context.view_layer
        self.in_mode = [o for o in context.objects_in_mode if o.type == "MESH"]
        objects = [o for o in context.objects_in_mode_unique_data if o.type == "MESH"]
        if not objects:
            raise UnwrapError("no mesh object in edit mode")
        self.active = (context.active_object if context.active_object in self.in_mode
                       else self.in_mode[0])
        phases = self.summary.phases
        t0 = time.perf_counter()
        _leave_edit_mode(self.in_mode)
        _lap(phases, "mode", t0)
        t0 = time.perf_counter()
        try:
            avoid = {}
            if self.avoid_group and self.options.get("auto_seams", True):
                avoid = _read_avoid_groups(context, objects, self.in_mode, self.active,
                                           self.avoid_group)
            for obj in objects:
                job = _read(obj)
                job.avoid = avoid.get(obj.name)
                if job.selected.any():
                    if self.correct_aspect:
                        job.aspect = aspect.image_aspect(context, obj)
                    self.jobs.append(job)
            if not self.jobs:
                raise UnwrapError("no faces selected")
        except BaseException:
            _enter_edit_mode(self.view_layer, self.in_mode, self.active)
            raise
        _lap(phases, "read", t0)
        if not stay_out:
            t0 = time.perf_counter()
            _enter_edit_mode(self.view_layer, self.in_mode, self.active)
            _lap(phases, "mode", t0)
        self.progress = (0, len(self.jobs), 0, 0)
        return self

    def start_thread(self):
        """Run :meth:`solve` on a worker thread (see :attr:`running`)."""
        self._thread = threading.Thread(target=self._solve_catching, name="uvflat solve",
                                        daemon=True)
        self._thread.start()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def cancel(self):
        """Ask the solve to stop; :meth:`finish` will then refuse and :meth:`abort` is due."""
        self.cancel_requested.set()

    def finish(self, context, *, in_edit=True) -> Summary:
        """Write the solved UVs, pack, and return to edit mode (see the module docstring)."""
        if self.error is not None:
            raise self.error
        if self.cancel_requested.is_set() or self.cancelled:
            raise UnwrapError("cancelled")
        if in_edit:
            t0 = time.perf_counter()
            _leave_edit_mode(self.in_mode)
            _lap(self.summary.phases, "mode", t0)
        return _write_and_pack(context, self)

    def abort(self, context):
        """Nothing was written: make sure the objects are in edit mode as before."""
        if any(not o.data.is_editmode for o in self.in_mode):
            _enter_edit_mode(self.view_layer, self.in_mode, self.active)

    # -- any thread --------------------------------------------------------------------------

    def solve(self):
        """Solve every job with the core (no Blender data touched)."""
        core = self._core
        packing = self.pack.mode != "OFF"
        for k, job in enumerate(self.jobs):
            if self.cancel_requested.is_set():
                self.cancelled = True
                return
            t0 = time.perf_counter()

            def progress(done, total, k=k):
                self.progress = (k, len(self.jobs), done, total)
                hook = PROGRESS_HOOK
                if hook is not None:
                    hook(*self.progress)
                return not self.cancel_requested.is_set()

            try:
                _solve(core, job, self.method, self.options, use_fit=not packing,
                       progress=progress)
            except core.Cancelled:
                self.cancelled = True
                return
            except core.UvflatError as ex:
                raise UnwrapError(f"{job.obj.name}: {ex}") from ex
            self.summary.solve_seconds += time.perf_counter() - t0
            self.summary.phases["solve"] = self.summary.solve_seconds
            self.progress = (k + 1, len(self.jobs), 0, 0)

    def _solve_catching(self):
        try:
            self.solve()
        except BaseException as ex:  # handed to the main thread by finish()
            self.error = ex


def heat_map_kind(context):
    """The distortion the sidebar's heat map shows (``"conformal"`` or ``"area"``), or
    ``None`` while it is hidden (the unwrap then writes no heat colours, see ``distortion``)."""
    settings = getattr(getattr(context, "scene", None), "uvflat", None)
    if settings is None or not getattr(settings, "show_distortion", False):
        return None
    return settings.distortion_kind


def _lap(phases, name, t0):
    """Add the seconds since ``t0`` to phase ``name``."""
    phases[name] = phases.get(name, 0.0) + time.perf_counter() - t0


def _write_and_pack(context, run: Run) -> Summary:
    """Steps 3 to 5 of the module docstring, from object mode; restores everything on error."""
    jobs, pack, summary = run.jobs, run.pack, run.summary
    phases = summary.phases
    global _PACK_REPORT
    _PACK_REPORT = _PackReport()
    summary.pack_shape = pack.shape_method
    packing = pack.mode != "OFF"
    in_edit = False
    try:
        try:
            # 3. write (UVs, then the seams automatic seams cut)
            t0, quality = time.perf_counter(), phases.get("quality", 0.0)
            color_kind = heat_map_kind(context)
            for job in jobs:
                if run.seams_only:
                    # Mark Seams Only: the cuts are marked, every UV map stays as it was
                    summary.seams_added += _mark_new_seams(job)
                    continue
                _write(job, phases, color_kind)
                if run.mark_seams:
                    summary.seams_added += _mark_new_seams(job)
                else:
                    summary.seams_added += len(getattr(job.result, "new_seams", ()))
            summary.seams_marked = bool((run.mark_seams or run.seams_only) and summary.seams_added)
            summary.seams_only = run.seams_only
            # the core's quality measure is its own phase
            _lap(phases, "write", t0 + (phases.get("quality", 0.0) - quality))
            # 4. pack the new islands only. With packing off, islands without previous UVs
            # to keep them near (all area-scaled around the origin) are packed anyway, so
            # that they land inside the 0-1 tile without overlapping each other.
            only = None if packing else [job for job in jobs if not job.fitted]
            if run.seams_only:
                only = []
            elif not packing and pack.density != "AUTO":
                # where the old UVs were, at the density asked for
                _scale_in_place([job for job in jobs if job.fitted], pack)
            if only is None or only:
                settings = pack if packing else dataclasses.replace(pack, mode="AROUND")
                t0, packer = time.perf_counter(), phases.get("pack", 0.0)
                in_edit = _pack(context, jobs, run.in_mode, run.active, settings, only, phases)
                # the packer itself is "pack"; the selection and mode changes around it "mode"
                _lap(phases, "mode", t0 + (phases.get("pack", 0.0) - packer))
                summary.packed = packing
            # every chart's texel density on the UVs as written and packed
            summary.texel_density = float(pack.texel_density)
            summary.texture_size = int(pack.texture_size)
            summary.density = _PACK_REPORT.density
            if not run.seams_only:
                _measure_density(jobs, summary)
        except BaseException:
            _leave_edit_mode(run.in_mode)
            in_edit = False
            _restore(jobs)
            raise
    finally:
        if not in_edit:
            t0 = time.perf_counter()
            _enter_edit_mode(run.view_layer, run.in_mode, run.active)
            _lap(phases, "mode", t0)

    for job in jobs:
        summary.results[job.obj.name] = job.result
        summary.faces += int((np.asarray(job.result.face_solved, dtype=bool) & job.selected).sum())
        summary.non_manifold_edges += int(getattr(job.result, "non_manifold_edges", 0))
        if job.stretch is not None:
            summary.stretched += (job.obj.name,)
        summary.inconsistent_edges += int(getattr(job.result, "inconsistent_edges", 0))
        summary.flipped_faces += job.flipped_faces
        for chart in job.result.charts:
            summary.cones += getattr(chart, "cones", 0)
            problem = ChartProblem(job.obj.name, chart.id, chart.kind, chart.status,
                                   chart.reason or "no reason given")
            if chart.status == "failed":
                summary.failed.append(problem)
            else:
                summary.charts += 1
                if chart.status == "fallback":
                    summary.fallback.append(problem)
    summary.objects = len(jobs)
    summary.pack_shapes = tuple(_PACK_REPORT.shapes)
    summary.coverage = _PACK_REPORT.coverage
    summary.density = _PACK_REPORT.density
    summary.seconds = time.perf_counter() - run.start
    phases.pop("other", None)
    phases["other"] = max(0.0, summary.seconds - sum(phases.values()))
    return summary


def _measure_density(jobs, summary: Summary):
    """Every solved chart's texel density (UV units per metre of world surface, on the UVs as
    written and packed) into ``summary.chart_density``; with a Fixed density, whether a new
    island does not fit in its UDIM tile (``summary.density_overflow``)."""
    for job in jobs:
        if not job.written:
            continue
        uv = mesh_io.read_uv(job.obj.data, job.uv_name).astype(np.float64)
        area3, area_uv = world_face_areas(job, uv)
        chart = np.asarray(job.result.chart, dtype=np.int64)
        solved = _solved_faces(job)
        n = len(job.result.charts)
        summary.chart_aspect[job.obj.name] = float(job.aspect)
        with np.errstate(invalid="ignore", divide="ignore"):
            summary.chart_density[job.obj.name] = np.sqrt(
                np.bincount(chart[solved], weights=area_uv[solved], minlength=n)
                / np.bincount(chart[solved], weights=area3[solved], minlength=n))
        if summary.density == "FIXED":
            island = np.where(solved, chart, -1)
            low, high = packing.island_bounds(uv, job.face_sizes, island, n)
            mapped = np.isfinite(low).all(axis=1)
            tile = np.floor(0.5 * (low[mapped] + high[mapped]))
            if np.any((low[mapped] < tile - 1e-6) | (high[mapped] > tile + 1 + 1e-6)):
                summary.density_overflow = True


def selected_face_count(context) -> int:
    """Selected faces of the meshes in edit mode (from the edit meshes' statistics)."""
    total = 0
    for obj in context.objects_in_mode_unique_data:
        if obj.type == "MESH":
            total += getattr(obj.data, "total_face_sel", 0)
    return total


# Rough seconds per selected face of one solve, per method (linear methods are one sparse
# factorization; the iterative ones many): only to decide whether to show progress.
_SECONDS_PER_FACE = {"tutte": 2e-6, "harmonic": 2e-6, "mean_value": 3e-6, "lscm": 3e-6,
                     "spectral": 2e-5, "bff": 3e-6, "abf": 3e-5, "arap": 5e-5, "slim": 5e-5,
                     "mips": 5e-5, "scaffold": 2e-4}
# Above this estimate the operator solves on a worker thread and shows progress.
MODAL_AFTER_SECONDS = 0.5
# Seconds Blender's packer may take on a few islands of the exact or convex shape (searched
# island against island, see pack_shape); bounding boxes take a millisecond.
_PACK_SHAPE_SECONDS = {"CONCAVE": 0.6, "CONVEX": 0.6, "AABB": 0.0}
# Seconds per face of the meshes for packing's edit mode round trips and selection changes.
_PACK_SECONDS_PER_FACE = 2e-6


def face_count(context) -> int:
    """Faces of the meshes in edit mode."""
    return sum(len(obj.data.polygons) for obj in context.objects_in_mode_unique_data
               if obj.type == "MESH")


def estimated_seconds(method, faces, pack=None, mesh_faces=0) -> float:
    """What an unwrap of ``faces`` selected faces (of meshes of ``mesh_faces`` faces) with
    ``method`` may take, packing included (``pack``: ``methods.pack_settings`` keywords or a
    :class:`PackSettings`; ``None`` for no packing). Only to choose the modal path."""
    seconds = faces * _SECONDS_PER_FACE.get(method, 5e-5)
    if pack is not None:
        mode = pack["mode"] if isinstance(pack, dict) else pack.mode
        shape = pack["shape_method"] if isinstance(pack, dict) else pack.shape_method
        if mode != "OFF":
            seconds += _PACK_SHAPE_SECONDS.get(shape, 0.6) + _PACK_SECONDS_PER_FACE * mesh_faces
    return seconds


def unwrap_edit_objects(context, method, options, *, pack: PackSettings | None = None,
                        correct_aspect=True, auto_seams=None, mark_seams=True,
                        seams_only=False, avoid_group="") -> Summary:
    """Unwrap the selected faces of every mesh object in edit mode; see the module docstring.

    ``pack``: how the new islands are packed (default :class:`PackSettings`: around the
    other islands). ``correct_aspect``: scale the new islands for the texture's aspect ratio
    (see ``aspect.py``). ``auto_seams``: the automatic-seams keywords of ``uvflat.unwrap``
    (default: the core's); ``mark_seams``: mark the edges it cut as seams; ``seams_only``:
    mark them and nothing else (no UVs, no packing: *Mark Seams Only*); ``avoid_group``: a
    vertex group where new seams must not go."""
    run = Run(method, options, PackSettings() if pack is None else pack, correct_aspect,
              auto_seams=auto_seams, mark_seams=mark_seams, seams_only=seams_only,
              avoid_group=avoid_group)
    run.prepare(context, stay_out=True)
    try:
        run.solve()
    except BaseException:
        run.abort(context)
        raise
    return run.finish(context, in_edit=False)
