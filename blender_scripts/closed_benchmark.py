# SPDX-License-Identifier: GPL-3.0-or-later
"""Closed meshes, no seams: uvflat's automatic seams against Smart UV Project and xatlas.

    .venv/bin/python blender_scripts/benchmark.py --closed [--meshes bunny,cow] [--repeat 3]

For every closed mesh of ../shared/meshes (bunny, cow, decimated-max, 3holes, fertility), in one
process, each from the same seamless mesh:

* ``uvflat abf`` / ``uvflat slim``: the operator with Auto Seams (its default), packing on;
* ``smart+ABF``: Blender's Smart UV Project (66°), seams from its islands, then Blender's
  ANGLE_BASED unwrap on those seams (time of both operators);
* ``xatlas``: an xatlas atlas (``pip install xatlas``; the row is left out without it).

Columns: seconds (median of ``--repeat``), islands, total seam length / √(3D area), flipped
triangles, overlapping islands (outline crossing itself), conformal and area distortion
(``uvflat.metrics``, DESIGN.md's definitions: every map is measured by the same code).
"""

from __future__ import annotations

import math
import statistics
import time

import bpy
import numpy as np

import common

CLOSED = ("bunny.off", "cow.off", "decimated-max.obj", "3holes.off", "fertility.off")


def seam_length(positions, corner_verts, face_sizes, uv, tol=1e-7):
    """Total 3D length of edges whose two sides have different UVs, over √(3D area)."""
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    corner = np.arange(len(corner_verts))
    face = np.repeat(np.arange(len(face_sizes)), face_sizes)
    nxt = corner + 1
    last = starts + face_sizes - 1
    wrap = np.isin(corner, last)
    nxt[wrap] = starts[face[wrap]]
    a, b = corner_verts[corner].astype(np.int64), corner_verts[nxt].astype(np.int64)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    # UVs of the edge's low and high vertex on this side
    uv_lo = np.where((a == lo)[:, None], uv[corner], uv[nxt])
    uv_hi = np.where((a == lo)[:, None], uv[nxt], uv[corner])
    key = lo * (int(corner_verts.max()) + 1) + hi
    order = np.argsort(key, kind="stable")
    key, uv_lo, uv_hi, lo, hi = key[order], uv_lo[order], uv_hi[order], lo[order], hi[order]
    same = key[1:] == key[:-1]
    i = np.flatnonzero(same)
    differ = (np.abs(uv_lo[i] - uv_lo[i + 1]).max(axis=1) > tol) | (
        np.abs(uv_hi[i] - uv_hi[i + 1]).max(axis=1) > tol)
    seam = i[differ]
    length = np.linalg.norm(positions[hi[seam]] - positions[lo[seam]], axis=1).sum()
    # 3D area by fan triangulation
    tri_a = corner_verts[np.repeat(starts, face_sizes - 2)]
    k = np.concatenate([np.arange(1, s - 1) for s in face_sizes]) + np.repeat(starts, face_sizes - 2)
    p0, p1, p2 = positions[tri_a], positions[corner_verts[k]], positions[corner_verts[k + 1]]
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1).sum()
    return float(length / math.sqrt(area))


def _quality(uvflat, positions, corner_verts, face_sizes, uv):
    m = uvflat.metrics(positions, corner_verts, face_sizes, uv)
    return dict(islands=m.charts, seam=seam_length(positions, corner_verts, face_sizes, uv),
                flips=m.flips, overlapping=m.overlapping_charts, conformal=m.conformal,
                area=m.area)


def _clear(obj, mesh_io):
    mesh = obj.data
    mesh_io.write_seams(mesh, np.zeros(len(mesh.edges), dtype=bool))
    n_c = len(mesh.loops)
    mesh_io.write_uv(mesh, mesh_io.ensure_uv_map(mesh)[0], np.zeros((n_c, 2), dtype=np.float32))


def _run_uvflat(obj, method):
    common.edit_mode([obj])
    t0 = time.perf_counter()
    bpy.ops.uv.uvflat_unwrap(method=method, pack="ALL", margin=0.001)
    seconds = time.perf_counter() - t0
    common.object_mode()
    return seconds


def _run_smart(obj):
    common.edit_mode([obj])
    t0 = time.perf_counter()
    bpy.ops.uv.smart_project(angle_limit=math.radians(66.0), island_margin=0.001)
    bpy.ops.uv.seams_from_islands()
    bpy.ops.uv.unwrap(method="ANGLE_BASED", margin=0.001)
    seconds = time.perf_counter() - t0
    common.object_mode()
    return seconds


def rows_for(uvflat, mesh_io, obj, repeat):
    positions, corner_verts, face_sizes = mesh_io.read_topology(obj.data)
    rows = []
    for label, run in (("uvflat abf (auto seams)", lambda: _run_uvflat(obj, "abf")),
                       ("uvflat slim (auto seams)", lambda: _run_uvflat(obj, "slim")),
                       ("Smart UV 66° + ANGLE_BASED", lambda: _run_smart(obj))):
        times = []
        for _ in range(repeat):
            _clear(obj, mesh_io)
            times.append(run())
        uv = mesh_io.read_uv(obj.data).astype(np.float64)
        rows.append(dict(label=label, seconds=statistics.median(times),
                         **_quality(uvflat, positions, corner_verts, face_sizes, uv)))
    try:
        import xatlas
    except ImportError:
        return rows
    tri = _fan(corner_verts, face_sizes)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        vmapping, indices, uvs = xatlas.parametrize(positions.astype(np.float32), tri.astype(np.uint32))
        times.append(time.perf_counter() - t0)
    cv = vmapping[indices].reshape(-1).astype(np.int64)
    uv = uvs[indices].reshape(-1, 2).astype(np.float64)
    fs = np.full(len(indices), 3, dtype=np.int64)
    rows.append(dict(label="xatlas", seconds=statistics.median(times),
                     **_quality(uvflat, positions, cv, fs, uv)))
    return rows


def _fan(corner_verts, face_sizes):
    out = []
    start = 0
    for s in face_sizes:
        f = corner_verts[start:start + s]
        out.extend([f[0], f[k], f[k + 1]] for k in range(1, s - 1))
        start += s
    return np.array(out, dtype=np.int64)


def run(meshes, repeat):
    import uvflat

    addon = common.load_addon()
    mesh_io = addon.mesh_io
    lines = ["| mesh | unwrap | s | islands | seam length / √area | flips | overlapping | "
             "conformal | area |", "|---|---|---|---|---|---|---|---|---|"]
    for name in meshes:
        common.reset_scene()
        common.load_addon()
        obj = common.load_mesh_object(common.SHARED_MESHES / name)
        n_f = len(obj.data.polygons)
        for r in rows_for(uvflat, mesh_io, obj, repeat):
            lines.append(f"| {name} {n_f:,} | {r['label']} | {r['seconds']:.3f} | {r['islands']} | "
                         f"{r['seam']:.2f} | {r['flips']} | {r['overlapping']} | "
                         f"{r['conformal']:.4f} | {r['area']:.4f} |")
            print(lines[-1], flush=True)
    return "\n".join(lines)
