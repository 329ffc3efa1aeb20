# SPDX-License-Identifier: GPL-3.0-or-later
"""Meshes without seams: uvflat's automatic seams against Smart UV Project and xatlas.

    .venv/bin/python blender_scripts/benchmark.py --closed [--open] [--meshes bunny,suzanne] \
        [--repeat 3] [--dump-uv DIR]

``--closed``: the closed meshes of ../shared/meshes (bunny, cow, decimated-max, 3holes,
fertility). ``--open``: open and multi-part meshes made here, deterministically, from a shared
mesh or Blender's primitives:

* ``bunny_open``: the bunny with its base open (the faces whose centroid lies in the lowest 3%
  of its bounding box height, the file's Y axis, deleted, and with them the patch of the
  base's floor they leave apart from the body);
* ``suzanne``: Blender's monkey with a Subdivision Surface modifier of one level applied, no
  seams (open at the eyes; the eyes are separate parts);
* ``teapot_parts``: a teapot of four open parts in one object (a UV sphere without its top
  cap as the body, a cylinder without caps as the spout, half a torus as the handle, a cone
  without its base as the lid);
* ``three_parts``: three separate primitives in one object (an ico sphere, a torus, a
  cylinder without caps).

Both flags together measure all of them. ``--meshes`` takes any of these names (or the path of
a .off/.obj/.ply file) whichever flag is given. Every unwrap starts from the same mesh without
seams and with all UVs at the origin, in one process:

* ``uvflat abf`` / ``uvflat slim`` / ``uvflat bff``: the operator with Auto Seams (its
  default), packing on;
* ``smart+ABF``: Blender's Smart UV Project (66°), seams from its islands, then Blender's
  ANGLE_BASED unwrap on those seams (time of both operators);
* ``xatlas``: an xatlas atlas (``pip install xatlas``; the row is left out without it).

Columns: islands, total seam length / √(3D area), flipped triangles, overlapping islands
(outline crossing itself), conformal and mean area distortion, the share of the surface whose
texel density is outside [½, 2] of its island's own, the area-weighted 5th–95th percentiles of
that density ratio (``uvflat.metrics``, docs/design.md's definitions: every map is measured by
the same code), and seconds (median of ``--repeat``).

Under the table, one target line per uvflat row: 0 flips, 0 overlapping islands, at most 5% of
the surface outside [½, 2], mean area distortion at most 1.35, at most a quarter of xatlas's
islands (never fewer than the mesh's separate parts) and at most 0.6× xatlas's seam length;
each missed target is marked ``MISSED``. ``--dump-uv DIR`` writes every row's map to
``DIR/<mesh>__<row>.npz`` (positions, corner_verts, face_sizes, uv).
"""

from __future__ import annotations

import math
import statistics
import time
from pathlib import Path

import numpy as np

import common

CLOSED = ("bunny.off", "cow.off", "decimated-max.obj", "3holes.off", "fertility.off")
OPEN = ("bunny_open", "suzanne", "teapot_parts", "three_parts")
MESH_SUFFIXES = (".off", ".obj", ".ply")

# Targets of the uvflat rows.
DENSITY_BOUND = 2.0  # texel density within [1/2, 2] of the island's own
MAX_OUTSIDE = 0.05  # share of the surface outside those bounds
MAX_AREA = 1.35  # mean area distortion
ISLANDS_OF_XATLAS = 0.25  # islands at most this share of xatlas's (never fewer than the parts)
SEAM_OF_XATLAS = 0.6  # seam length at most this share of xatlas's


# ---------------------------------------------------------------------------------------------
# Measures (numpy only)


def _starts(face_sizes):
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    return starts


def _next_corner(face_sizes):
    """The next corner of every corner around its face."""
    starts = _starts(face_sizes)
    face = np.repeat(np.arange(len(face_sizes)), face_sizes)
    nxt = np.arange(int(np.sum(face_sizes))) + 1
    last = starts + face_sizes - 1
    nxt[last] = starts
    return nxt, face


def _fan_corners(face_sizes):
    """Corner triples of a fan triangulation of every face, and the face of each triangle."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    starts = _starts(face_sizes)
    n_tris = face_sizes - 2
    face = np.repeat(np.arange(len(face_sizes)), n_tris)
    k = np.arange(int(n_tris.sum())) - np.repeat(np.cumsum(n_tris) - n_tris, n_tris)
    first = starts[face]
    return np.stack([first, first + k + 1, first + k + 2], axis=1), face


def seam_length(positions, corner_verts, face_sizes, uv, tol=1e-7):
    """Total 3D length of edges whose two sides have different UVs, over √(3D area)."""
    corner_verts = np.asarray(corner_verts, dtype=np.int64)
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    corner = np.arange(len(corner_verts))
    nxt, _ = _next_corner(face_sizes)
    a, b = corner_verts[corner], corner_verts[nxt]
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
    tri, _ = _fan_corners(face_sizes)
    p0, p1, p2 = (positions[corner_verts[tri[:, j]]] for j in range(3))
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1).sum()
    return float(length / math.sqrt(area))


def mesh_parts(corner_verts, face_sizes):
    """Number of separate parts (faces connected through shared vertices)."""
    corner_verts = np.asarray(corner_verts, dtype=np.int64)
    nxt, _ = _next_corner(np.asarray(face_sizes, dtype=np.int64))
    label = common.components(int(corner_verts.max()) + 1, corner_verts, corner_verts[nxt])
    return len(np.unique(label[corner_verts]))


def density_spread(positions, corner_verts, face_sizes, uv, bound=DENSITY_BOUND):
    """``(outside, p5, p95)`` of the texel-density ratio, computed here with numpy.

    Islands are the faces connected through edges of exactly two faces whose UVs agree at both
    ends. Per triangle (a fan of every face), ``r = (UV area / 3D area) / (island UV area /
    island 3D area)``, the island's UV area counting only the triangles of its own orientation
    (the sign of its total signed UV area); flipped or zero-area UV triangles have ``r = 0``.
    ``outside`` is the share of 3D area with ``r`` outside ``[1/bound, bound]``; ``p5`` and
    ``p95`` are area-weighted percentiles of ``r``. The same definition as
    ``uvflat.metrics(...).density_outside`` (used where the module has no such attribute)."""
    positions = np.asarray(positions, dtype=np.float64)
    corner_verts = np.asarray(corner_verts, dtype=np.int64)
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    uv = np.asarray(uv, dtype=np.float64)
    nxt, face = _next_corner(face_sizes)
    a, b = corner_verts, corner_verts[nxt]
    key = np.minimum(a, b) * (int(corner_verts.max()) + 1) + np.maximum(a, b)
    order = np.argsort(key, kind="stable")
    ks = key[order]
    uniq, first, count = np.unique(ks, return_index=True, return_counts=True)
    two = first[count == 2]
    c1, c2 = order[two], order[two + 1]
    # match the ends of the two sides by vertex
    same_dir = a[c1] == a[c2]
    m1 = np.where(same_dir, c2, nxt[c2])
    m2 = np.where(same_dir, nxt[c2], c2)
    agree = (uv[c1] == uv[m1]).all(axis=1) & (uv[nxt[c1]] == uv[m2]).all(axis=1)
    island = common.components(len(face_sizes), face[c1[agree]], face[c2[agree]])
    tri, tri_face = _fan_corners(face_sizes)
    p = [positions[corner_verts[tri[:, j]]] for j in range(3)]
    q = [uv[tri[:, j]] for j in range(3)]
    a3 = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]), axis=1)
    e1, e2 = q[1] - q[0], q[2] - q[0]
    a2 = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    _, isl = np.unique(island[tri_face], return_inverse=True)
    n = int(isl.max()) + 1 if len(isl) else 0
    total3 = np.bincount(isl, weights=a3, minlength=n)
    sign = np.where(np.bincount(isl, weights=a2, minlength=n) < 0, -1.0, 1.0)
    oriented = np.maximum(a2 * sign[isl], 0.0)
    total2 = np.bincount(isl, weights=oriented, minlength=n)
    valid = (total3 > 0) & (total2 > 0) & np.isfinite(total2)
    mean = np.where(valid, total2 / np.where(total3 > 0, total3, 1.0), 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(a3 > 0, oriented / a3 / mean[isl], 1.0)
    r = np.where(valid[isl] & np.isfinite(r), r, 0.0)
    total = a3.sum()
    if not total > 0:
        return 1.0, 0.0, 0.0
    out = ~((r >= 1.0 / bound) & (r <= bound))
    outside = float(a3[out].sum() / total)
    o = np.argsort(r, kind="stable")
    acc = np.cumsum(a3[o])

    def quantile(x):
        i = min(int(np.searchsorted(acc, x * total, side="left")), len(o) - 1)
        return float(r[o][i])

    return outside, quantile(0.05), quantile(0.95)


def quality(uvflat, positions, corner_verts, face_sizes, uv):
    m = uvflat.metrics(positions, corner_verts, face_sizes, uv)
    outside = getattr(m, "density_outside", None)
    if outside is None:
        outside, p5, p95 = density_spread(positions, corner_verts, face_sizes, uv)
    else:
        p5, p95 = m.density_p5, m.density_p95
    return dict(islands=m.charts, seam=seam_length(positions, corner_verts, face_sizes, uv),
                flips=m.flips, overlapping=m.overlapping_charts, conformal=m.conformal,
                area=m.area, outside=float(outside) + 0.0, p5=float(p5), p95=float(p95))


# ---------------------------------------------------------------------------------------------
# Meshes


def mesh_name(item):
    """The name a mesh goes by in ``--meshes`` and in the table: the file's stem or its name."""
    return Path(item).stem if Path(item).suffix.lower() in MESH_SUFFIXES else item


def select(names, closed=True, open_=False):
    """The meshes to measure: ``names`` (any closed or open mesh's name, or a mesh file's
    path) or, without names, the closed and/or open ones."""
    known = {mesh_name(f): f for f in CLOSED}
    known.update({n: n for n in OPEN})
    if not names:
        return (list(CLOSED) if closed else []) + (list(OPEN) if open_ else [])
    chosen, missing = [], []
    for n in names:
        if n in known:
            chosen.append(known[n])
        elif Path(n).suffix.lower() in MESH_SUFFIXES and Path(n).is_file():
            chosen.append(str(Path(n).resolve()))
        else:
            missing.append(n)
    if missing:
        raise SystemExit(f"unknown mesh(es) {missing}; available: {', '.join(known)} "
                         f"or the path of a {'/'.join(MESH_SUFFIXES)} file")
    return chosen


def _keep_faces(name, positions, corner_verts, face_sizes, keep):
    """A mesh object of the kept faces (unused vertices dropped)."""
    face = np.repeat(np.arange(len(face_sizes)), face_sizes)
    used, cv = np.unique(corner_verts[keep[face]], return_inverse=True)
    mesh = common.mesh_io().new_mesh(name, positions[used], cv, face_sizes[keep])
    return common.link_mesh_object(name, mesh)


def bunny_open():
    """The bunny with its base open: the faces whose centroid lies in the lowest 3% of the
    bounding box height (the file's Y axis) are deleted, and so is every part but the
    largest one they leave (a flat patch of the base's floor)."""
    positions, corner_verts, face_sizes = common.read_off(common.SHARED_MESHES / "bunny.off")
    corner_verts, face_sizes, _ = common.repair_repeated_corners(corner_verts, face_sizes)
    face = np.repeat(np.arange(len(face_sizes)), face_sizes)
    centroid_y = np.bincount(face, weights=positions[corner_verts, 1]) / face_sizes
    lo, hi = positions[:, 1].min(), positions[:, 1].max()
    keep = centroid_y > lo + 0.03 * (hi - lo)
    # what is left of the base's floor apart from the body (a flat patch) goes with it
    nxt, face = _next_corner(face_sizes)
    kept = keep[face]
    label = common.components(len(positions), corner_verts[kept], corner_verts[nxt][kept])
    body = np.bincount(label[corner_verts[kept]]).argmax()
    keep &= label[corner_verts[_starts(face_sizes)]] == body
    return _keep_faces("bunny_open", positions, corner_verts, face_sizes, keep)


def _delete_faces(obj, drop):
    """Delete the faces of ``obj`` whose local centroid ``drop(x, y, z)`` is true."""
    import bmesh

    bm = bmesh.new()
    bm.from_mesh(obj.data)
    faces = [f for f in bm.faces if drop(*f.calc_center_median())]
    bmesh.ops.delete(bm, geom=faces, context="FACES")
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def _subdivide_rings(obj, cuts):
    """Cut every edge of ``obj`` along its local Z axis ``cuts`` times (rings on a tube)."""
    import bmesh

    bm = bmesh.new()
    bm.from_mesh(obj.data)
    edges = [e for e in bm.edges
             if abs(e.verts[0].co.z - e.verts[1].co.z) > 1e-6]
    bmesh.ops.subdivide_edges(bm, edges=edges, cuts=cuts, use_grid_fill=True)
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()


def _join(objects, name):
    """One new object of the faces of ``objects`` (world transforms applied), which are
    removed. (Built from the arrays: Blender's join can leave the selection attributes of
    the joined mesh with a wrong type.)"""
    import bpy

    common.object_mode()
    bpy.context.view_layer.update()
    io = common.mesh_io()
    positions, corner_verts, face_sizes, offset = [], [], [], 0
    for o in objects:
        p, cv, fs = io.read_topology(o.data)
        m = np.array(o.matrix_world, dtype=np.float64)
        positions.append(p.astype(np.float64) @ m[:3, :3].T + m[:3, 3])
        corner_verts.append(cv.astype(np.int64) + offset)
        face_sizes.append(fs.astype(np.int64))
        offset += len(p)
    for o in objects:
        mesh = o.data
        bpy.data.objects.remove(o)
        bpy.data.meshes.remove(mesh)
    mesh = io.new_mesh(name, np.concatenate(positions), np.concatenate(corner_verts),
                       np.concatenate(face_sizes))
    return common.link_mesh_object(name, mesh)


def _active(name):
    import bpy

    obj = bpy.context.active_object
    obj.name = name
    return obj


def suzanne_open():
    """Blender's monkey, one Subdivision Surface level applied, no seams."""
    import bpy

    bpy.ops.mesh.primitive_monkey_add()
    obj = _active("suzanne")
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = 1
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    return obj


def teapot_parts():
    """Four open parts in one object: body, spout, handle, lid."""
    import bpy

    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=1.0,
                                         scale=(1.0, 1.0, 0.75))
    body = _active("body")
    _delete_faces(body, lambda x, y, z: z > 0.85)  # the top cap: an opening of radius ~0.4
    bpy.ops.mesh.primitive_cylinder_add(vertices=16, radius=0.12, depth=0.9,
                                        end_fill_type="NOTHING", location=(1.4, 0.0, 0.3),
                                        rotation=(0.0, math.radians(50.0), 0.0))
    spout = _active("spout")
    _subdivide_rings(spout, 5)
    bpy.ops.mesh.primitive_torus_add(major_segments=32, minor_segments=12, major_radius=0.45,
                                     minor_radius=0.07, location=(-1.05, 0.0, 0.0),
                                     rotation=(math.radians(90.0), 0.0, 0.0))
    handle = _active("handle")
    _delete_faces(handle, lambda x, y, z: x > 0.05)  # keep the outer half: a bent open tube
    bpy.ops.mesh.primitive_cone_add(vertices=32, radius1=0.45, radius2=0.0, depth=0.25,
                                    end_fill_type="NOTHING", location=(0.0, 0.0, 0.75))
    lid = _active("lid")
    return _join([body, spout, handle, lid], "teapot_parts")


def three_parts():
    """Three separate primitives in one object: an ico sphere, a torus, an open tube."""
    import bpy

    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=3, radius=1.0, location=(-2.5, 0.0, 0.0))
    ico = _active("ico")
    bpy.ops.mesh.primitive_torus_add(major_segments=48, minor_segments=16, major_radius=1.0,
                                     minor_radius=0.3, location=(0.0, 0.0, 0.0))
    torus = _active("torus")
    bpy.ops.mesh.primitive_cylinder_add(vertices=24, radius=0.6, depth=2.0,
                                        end_fill_type="NOTHING", location=(2.5, 0.0, 0.0))
    tube = _active("tube")
    _subdivide_rings(tube, 11)
    return _join([ico, torus, tube], "three_parts")


BUILDERS = {"bunny_open": bunny_open, "suzanne": suzanne_open, "teapot_parts": teapot_parts,
            "three_parts": three_parts}


def load(item):
    """The mesh object of ``item`` (a shared file, an open mesh's name, a file path) in an
    empty scene, with no seams."""
    common.reset_scene()
    common.load_addon()
    if item in BUILDERS:
        obj = BUILDERS[item]()
    else:
        path = Path(item)
        obj = common.load_mesh_object(path if path.is_absolute() else common.SHARED_MESHES / item)
    common.object_mode()
    return obj


# ---------------------------------------------------------------------------------------------
# Unwraps


def _clear(obj, mesh_io):
    mesh = obj.data
    mesh_io.write_seams(mesh, np.zeros(len(mesh.edges), dtype=bool))
    n_c = len(mesh.loops)
    mesh_io.write_uv(mesh, mesh_io.ensure_uv_map(mesh)[0], np.zeros((n_c, 2), dtype=np.float32))


def _run_uvflat(obj, method):
    import bpy

    op = bpy.ops.uv.uvflat_unwrap
    # the method itself, not a preset's (where the operator has presets)
    preset = {"preset": "ADVANCED"} if "preset" in op.get_rna_type().properties else {}
    common.edit_mode([obj])
    t0 = time.perf_counter()
    op(method=method, pack="ALL", margin=0.001, **preset)
    seconds = time.perf_counter() - t0
    common.object_mode()
    return seconds


def _run_smart(obj):
    import bpy

    common.edit_mode([obj])
    t0 = time.perf_counter()
    bpy.ops.uv.smart_project(angle_limit=math.radians(66.0), island_margin=0.001)
    bpy.ops.uv.seams_from_islands()
    bpy.ops.uv.unwrap(method="ANGLE_BASED", margin=0.001)
    seconds = time.perf_counter() - t0
    common.object_mode()
    return seconds


ROWS = (("uvflat_abf", "uvflat abf (auto seams)"), ("uvflat_slim", "uvflat slim (auto seams)"),
        ("uvflat_bff", "uvflat bff (auto seams)"), ("smart_abf", "Smart UV 66° + ANGLE_BASED"),
        ("xatlas", "xatlas"))


def rows_for(uvflat, mesh_io, obj, repeat):
    """One row per unwrap: ``key``, ``label``, ``seconds``, the quality columns, and the map
    measured (``corner_verts``, ``face_sizes``, ``uv``; xatlas's is a triangle mesh)."""
    positions, corner_verts, face_sizes = mesh_io.read_topology(obj.data)
    positions = positions.astype(np.float64)
    labels = dict(ROWS)
    rows = []
    for key, run in (("uvflat_abf", lambda: _run_uvflat(obj, "abf")),
                     ("uvflat_slim", lambda: _run_uvflat(obj, "slim")),
                     ("uvflat_bff", lambda: _run_uvflat(obj, "bff")),
                     ("smart_abf", lambda: _run_smart(obj))):
        times = []
        for _ in range(repeat):
            _clear(obj, mesh_io)
            times.append(run())
        uv = mesh_io.read_uv(obj.data).astype(np.float64)
        rows.append(dict(key=key, label=labels[key], seconds=statistics.median(times),
                         corner_verts=corner_verts, face_sizes=face_sizes, uv=uv,
                         **quality(uvflat, positions, corner_verts, face_sizes, uv)))
    try:
        import xatlas
    except ImportError:
        return rows
    tri = _fan_corners(np.asarray(face_sizes, dtype=np.int64))[0]
    tri = np.asarray(corner_verts, dtype=np.int64)[tri]
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        vmapping, indices, uvs = xatlas.parametrize(positions.astype(np.float32),
                                                    tri.astype(np.uint32))
        times.append(time.perf_counter() - t0)
    cv = vmapping[indices].reshape(-1).astype(np.int64)
    uv = uvs[indices].reshape(-1, 2).astype(np.float64)
    fs = np.full(len(indices), 3, dtype=np.int64)
    rows.append(dict(key="xatlas", label=labels["xatlas"], seconds=statistics.median(times),
                     corner_verts=cv, face_sizes=fs, uv=uv,
                     **quality(uvflat, positions, cv, fs, uv)))
    return rows


# ---------------------------------------------------------------------------------------------
# Table and targets


HEADER = ("| mesh | unwrap | islands | seam length / √area | flips | overlapping | conformal | "
          "area | outside [½, 2] | density p5–p95 | s |")


def row_line(name, n_faces, r):
    return (f"| {name} {n_faces:,} | {r['label']} | {r['islands']} | {r['seam']:.2f} | "
            f"{r['flips']} | {r['overlapping']} | {r['conformal']:.4f} | {r['area']:.4f} | "
            f"{100.0 * r['outside']:.2f}% | {r['p5']:.2f}–{r['p95']:.2f} | {r['seconds']:.3f} |")


def targets(r, xatlas_row, parts):
    """``(line, missed)`` of a uvflat row against the targets (see the module docs)."""
    checks = [
        (f"flips {r['flips']} (0)", r["flips"] == 0),
        (f"overlapping {r['overlapping']} (0)", r["overlapping"] == 0),
        (f"outside [½, 2] {100.0 * r['outside']:.2f}% (≤ {100.0 * MAX_OUTSIDE:.0f}%)",
         r["outside"] <= MAX_OUTSIDE),
        (f"area {r['area']:.4f} (≤ {MAX_AREA})", r["area"] <= MAX_AREA),
    ]
    if xatlas_row is not None:
        limit = max(ISLANDS_OF_XATLAS * xatlas_row["islands"], parts)
        checks.append((f"islands {r['islands']} (≤ {limit:g}: ¼ of xatlas's "
                       f"{xatlas_row['islands']}, parts {parts})", r["islands"] <= limit))
        seam_limit = SEAM_OF_XATLAS * xatlas_row["seam"]
        checks.append((f"seam {r['seam']:.2f} (≤ {seam_limit:.2f}: 0.6× xatlas's "
                       f"{xatlas_row['seam']:.2f})", r["seam"] <= seam_limit))
    else:
        checks.append((f"islands {r['islands']} (parts {parts}; no xatlas: not judged)", True))
    missed = [text for text, ok in checks if not ok]
    cells = [(f"{text} MISSED" if not ok else f"{text} ok") for text, ok in checks]
    return "; ".join(cells), len(missed)


def phase_line(uvflat, name, method, positions, corner_verts, face_sizes, xatlas_row):
    """The core's pipeline phases of one direct ``uvflat.unwrap`` of the mesh (auto seams on,
    the operator's defaults): seconds per step (per-chart steps summed over threads) and the
    repair counts, and the whole call against the xatlas row's seconds."""
    t0 = time.perf_counter()
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method=method)
    seconds = time.perf_counter() - t0
    p = r.phases
    ratio = f", {seconds / xatlas_row['seconds']:.2f}× xatlas" if xatlas_row else ""
    return (f"- {name} · uvflat {method} phases: build charts {p['build_charts']:.3f} s, "
            f"plan cuts {p['plan_cuts']:.3f} s ({p.get('predicted_rounds', 0)} predicted rounds; "
            f"cutting state {p.get('cut_state', 0):.3f}, cone placement {p.get('cone_placement', 0):.3f}, "
            f"split plans {p.get('split_plans', 0):.3f}, cut graphs {p.get('cut_graphs', 0):.3f}), "
            f"first solves {p['solve']:.3f} s, repair solves "
            f"{p['repair_solve']:.3f} s ({p['repair_rounds']} rounds, {p['repair_pieces']} pieces, "
            f"{p['splits']} splits ({p.get('predicted_splits', 0)} before any solve, "
            f"{p.get('far_splits', 0)} after one), "
            f"{p.get('peels', 0)} peels, "
            f"{p.get('last_resort', 0)} last-resort solves), "
            f"{p.get('glued', 0)} small islands glued, measure {p['measure']:.3f} s; whole call {seconds:.3f} s"
            f"{ratio}, {len(r.charts)} islands")


def run(meshes, repeat, dump_uv=None, phases=False):
    """Measure ``meshes`` (items of ``select``) and return the table and target lines (and,
    with ``phases``, one line per uvflat method with the core's pipeline phases)."""
    import uvflat

    addon = common.load_addon()
    mesh_io = addon.mesh_io
    lines = [HEADER, "|" + "---|" * (HEADER.count("|") - 1)]
    target_lines = []
    phase_lines = []
    if dump_uv is not None:
        dump_uv = Path(dump_uv)
        dump_uv.mkdir(parents=True, exist_ok=True)
    for item in meshes:
        name = mesh_name(item)
        obj = load(item)
        n_f = len(obj.data.polygons)
        positions, corner_verts, face_sizes = mesh_io.read_topology(obj.data)
        parts = mesh_parts(corner_verts, face_sizes)
        rows = rows_for(uvflat, mesh_io, obj, repeat)
        for r in rows:
            lines.append(row_line(name, n_f, r))
            print(lines[-1], flush=True)
            if dump_uv is not None:
                np.savez(dump_uv / f"{name}__{r['key']}.npz", positions=positions.astype(np.float64),
                         corner_verts=r["corner_verts"], face_sizes=r["face_sizes"], uv=r["uv"])
        xatlas_row = next((r for r in rows if r["key"] == "xatlas"), None)
        for r in rows:
            if r["key"].startswith("uvflat"):
                text, missed = targets(r, xatlas_row, parts)
                verdict = "all targets met" if not missed else f"{missed} target(s) MISSED"
                target_lines.append(f"- {name} · {r['label']}: {verdict}: {text}")
                print(target_lines[-1], flush=True)
        if phases:
            for method in ("abf", "slim", "bff"):
                phase_lines.append(phase_line(uvflat, name, method, positions.astype(np.float64),
                                              corner_verts, face_sizes, xatlas_row))
                print(phase_lines[-1], flush=True)
    text = "\n".join(lines) + "\n\nTargets of the uvflat rows:\n\n" + "\n".join(target_lines)
    if phase_lines:
        text += ("\n\nPipeline phases (one direct uvflat.unwrap per method; per-chart steps summed "
                 "over threads):\n\n" + "\n".join(phase_lines))
    return text
