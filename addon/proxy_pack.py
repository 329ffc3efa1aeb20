# SPDX-License-Identifier: GPL-3.0-or-later
"""Pack islands with Blender's packer run on a small stand-in mesh: one face per island.

Blender's ``uv.pack_islands`` costs time per face of the mesh it runs on (about 1.5 s for a
single island of 840k triangles, whatever its settings), and it needs the mesh in edit mode,
which is another BMesh build of the whole mesh. Its result is one similarity per island
(uniform scale, rotation, translation), chosen from each island's shape only:

* ``AABB``: the island's bounding box, or with rotation the smallest box of any angle (or of
  quarter turns), which is the smallest box of its convex hull;
* ``CONVEX``: its convex hull;
* ``CONCAVE`` (exact shape): for a single island with nothing to pack around there is no
  other shape to fit against, and the result is the one of its convex hull.

So in those cases Blender's packer, run on a temporary mesh holding one convex polygon per
island (the island's convex hull, same UVs), chooses the same similarities; they are read
back from two hull vertices and applied to every corner of the real island. The real meshes
are never put in edit mode for it and their selection and pins are never touched.

The hull of an island is the hull of all its corners' UVs, computed by the core
(``uvflat.island_hulls``) for every island of a mesh in one call.

:func:`islands` returns ``None`` where this does not hold (islands packed around locked ones,
a non-square texture aspect, several islands with the exact shape, degenerate islands, very
many islands) and the caller runs Blender's packer on the meshes themselves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import mesh_io

# Above this many islands the per-island hulls (a Python loop) would cost more than they save.
MAX_ISLANDS = 2000
# Below this many faces in the meshes Blender's packer on the meshes themselves is as quick
# (building the stand-in costs some 30 ms).
MIN_FACES = 20000
PROXY_NAME = "uvflat pack proxy"


@dataclass
class PackedCorners:
    """The packed corners of one mesh and the island (index in the list of :func:`islands`)
    of each: shared by all the islands of that mesh."""

    corners: np.ndarray   # (K,) corner indices in the mesh
    island: np.ndarray    # (K,) island of each


@dataclass
class Island:
    """One island to pack: its mesh, its convex hull in UV (counter-clockwise) and its
    mesh's packed corners."""

    job: object
    hull: np.ndarray      # (H,2) float64, H >= 3, positive area
    members: PackedCorners


def applicable(settings, n_islands: int, locked: bool, aspects, n_faces: int) -> bool:
    """Whether the stand-in mesh packs exactly like the meshes themselves (module doc) and
    is worth building (meshes of ``n_faces`` >= :data:`MIN_FACES` faces in all)."""
    if locked or any(a != 1.0 for a in aspects) or n_islands == 0 or n_islands > MAX_ISLANDS:
        return False
    if n_faces < MIN_FACES:
        return False
    return settings.shape_method in ("AABB", "CONVEX") or n_islands == 1


def islands(core, jobs_faces, uvs):
    """The islands of ``jobs_faces`` (pairs ``(job, packed faces mask)``) with their hulls,
    from the UVs in ``uvs`` (job id -> (C,2) float32 as written); ``None`` if any island is
    degenerate or there are more than :data:`MAX_ISLANDS`. ``core``: the uvflat module, whose
    ``island_hulls`` computes every island's hull (of all its corners' UVs, as Blender's
    packer does) in one call per mesh."""
    out = []
    for job, faces in jobs_faces:
        if not faces.any():
            continue
        face_sizes = job.face_sizes.astype(np.int64)
        chart = np.asarray(job.result.chart, dtype=np.int64)
        ids, face_island = np.unique(chart[faces], return_inverse=True)
        if len(out) + len(ids) > MAX_ISLANDS:
            return None
        island = np.zeros(len(chart), dtype=np.int64)
        island[faces] = face_island
        offsets, points = core.island_hulls(uvs[id(job)], face_sizes, island, selected=faces)
        if np.any(np.diff(offsets) < 3):
            return None
        corners = np.flatnonzero(np.repeat(faces, face_sizes))
        members = PackedCorners(corners, np.repeat(island, face_sizes)[corners] + len(out))
        out.extend(Island(job, points[offsets[k]:offsets[k + 1]], members) for k in range(len(ids)))
    return out


def pack(context, islands_, settings, enter_edit_mode, leave_edit_mode):
    """Pack ``islands_`` with Blender's packer on a temporary mesh; returns one ``(a, b)``
    per island, complex numbers of the similarity ``z -> a z + b`` (``z = u + i v``).

    ``enter_edit_mode(view_layer, objects, active)`` / ``leave_edit_mode(objects)``: the
    engine's mode switches. The temporary object and mesh are removed in every case."""
    import bpy

    sizes = np.array([len(isl.hull) for isl in islands_], dtype=np.int64)
    points = np.concatenate([isl.hull for isl in islands_])
    positions = np.column_stack([points, np.zeros(len(points))])
    corners = np.arange(len(points), dtype=np.int32)
    mesh = mesh_io.new_mesh(PROXY_NAME, positions, corners, sizes)
    obj = None
    try:
        if len(mesh.polygons) != len(islands_) or len(mesh.loops) != len(points):
            raise RuntimeError("the packing stand-in mesh could not be built")
        name, _ = mesh_io.ensure_uv_map(mesh)
        mesh_io.write_uv(mesh, name, points)
        mesh_io.select_all_faces(mesh)
        obj = bpy.data.objects.new(PROXY_NAME, mesh)
        context.scene.collection.objects.link(obj)
        view_layer = context.view_layer
        tool_settings = context.scene.tool_settings
        sync = tool_settings.use_uv_select_sync
        select_mode = tuple(tool_settings.mesh_select_mode)
        tool_settings.mesh_select_mode = (False, False, True)
        try:
            enter_edit_mode(view_layer, [obj], obj)
            try:
                tool_settings.use_uv_select_sync = True
                result = bpy.ops.uv.pack_islands(
                    margin=settings.margin, margin_method=settings.margin_method,
                    shape_method=settings.shape_method, rotate=settings.rotate,
                    rotate_method=getattr(settings, "rotate_method", "ANY"), pin=False)
            finally:
                tool_settings.use_uv_select_sync = sync
                leave_edit_mode([obj])
        finally:
            tool_settings.mesh_select_mode = select_mode
        if "FINISHED" not in result:
            raise RuntimeError(f"Blender's island packing returned {set(result)}")
        packed = mesh_io.read_uv(obj.data, name).astype(np.float64)
    finally:
        if obj is not None:
            context.scene.collection.objects.unlink(obj)
            bpy.data.objects.remove(obj)
            context.view_layer.update()  # drop the removed object's base from the view layer
        bpy.data.meshes.remove(mesh)
    transforms = []
    start = 0
    for isl, n in zip(islands_, sizes):
        before = isl.hull[:, 0] + 1j * isl.hull[:, 1]
        after = packed[start:start + n, 0] + 1j * packed[start:start + n, 1]
        start += n
        far = int(np.argmax(np.abs(before - before[0])))
        a = (after[far] - after[0]) / (before[far] - before[0])
        transforms.append((a, after[0] - a * before[0]))
    return transforms


def apply(islands_, transforms, uvs):
    """Move every island's corners in ``uvs`` (job id -> (C,2) float32, changed in place),
    all islands of a mesh in one vectorised step (in float64)."""
    a_all = np.array([t[0] for t in transforms], dtype=np.complex128)
    b_all = np.array([t[1] for t in transforms], dtype=np.complex128)
    per_job = {}
    for isl in islands_:
        per_job.setdefault(id(isl.job), isl.members)
    for key, members in per_job.items():
        uv = uvs[key]
        corners = members.corners
        a, b = a_all[members.island], b_all[members.island]
        u = uv[corners, 0].astype(np.float64)
        v = uv[corners, 1].astype(np.float64)
        uv[corners, 0] = a.real * u - a.imag * v + b.real
        uv[corners, 1] = a.imag * u + a.real * v + b.imag
