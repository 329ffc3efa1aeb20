# SPDX-License-Identifier: GPL-3.0-or-later
"""Per-face quality of an unwrap, stored on the mesh so the artist can see it.

After an unwrap, every solved face gets (faces not unwrapped keep their previous values, NaN
on a mesh that never had them):

* ``uvflat_conformal`` and ``uvflat_area`` (FACE, FLOAT): the conformal and area distortion of
  the face as measured by ``uvflat.metrics`` (docs/design.md definitions; 1 is perfect);
* ``uvflat_flipped`` (FACE, BOOLEAN): the face holds a flipped or zero-area UV triangle as
  the core's report counts them (:func:`face_flips`: Blender's render triangles, a quad
  folded on either diagonal);
* ``uvflat_conformal_color`` or ``uvflat_area_color`` (CORNER, FLOAT_COLOR): one of the
  same distortions as a heat map (blue 1, green, yellow, red at :data:`RED_AT` or more, grey
  where not measured), shown by the sidebar's toggle through the viewport's attribute colours.
  Float colours (stored linear, converted here from the sRGB heat colours) because Blender
  writes them with one copy, where byte colours convert element by element (a tenth of a
  second per million corners).

The colours exist only while the heat map is shown, and only for the distortion it shows
(:func:`write_colors`, from the stored per-face values): every corner layer of a mesh is
copied again each time it enters edit mode, and the two colour layers made entering edit mode
after an unwrap about a third slower (camelhead: 16.8 against 12.9 ms). An unwrap with the
heat map hidden removes them (:func:`drop_colors`); showing it writes them again.

Nothing here touches a mesh in edit mode; ``engine`` calls it between its mode switches.
"""

from __future__ import annotations

import numpy as np

from . import mesh_io

CONFORMAL, AREA, FLIPPED = "uvflat_conformal", "uvflat_area", "uvflat_flipped"
MEASURE = {"conformal": CONFORMAL, "area": AREA}   # heat-map kind -> its face attribute
COLOR = {"conformal": "uvflat_conformal_color", "area": "uvflat_area_color"}
ATTRIBUTES = (CONFORMAL, AREA, FLIPPED, *COLOR.values())
RED_AT = 2.0  # distortion shown fully red

_STOPS = np.array([0.0, 1 / 3, 2 / 3, 1.0])
_RGB = np.array([[0.15, 0.35, 1.0], [0.15, 0.85, 0.3], [1.0, 0.85, 0.1], [0.9, 0.1, 0.1]])
_GREY = (0.5, 0.5, 0.5)


def heat_colors(values):
    """RGBA in 0..1 for distortion ``values`` (>= 1): log scale from 1 (blue) to
    :data:`RED_AT` (red); NaN grey, infinity red."""
    values = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.log(np.maximum(values, 1.0)) / np.log(RED_AT), 0.0, 1.0)
    t = np.where(np.isposinf(values), 1.0, t)
    rgba = np.ones((len(values), 4))
    for k in range(3):
        rgba[:, k] = np.interp(t, _STOPS, _RGB[:, k])
    rgba[np.isnan(values), :3] = _GREY
    return rgba


# Signed UV areas at most this times the squared bounding-box diagonal of the chart's UVs (in
# a frame of half-size 1) count as zero, as in the core's flip definition.
ZERO_AREA_RELATIVE = 1e-15


def _fan_triangles(face_sizes):
    """Corner triples of a fan from every face's first corner."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    n_tris = np.maximum(face_sizes - 2, 0)
    face = np.repeat(np.arange(len(face_sizes)), n_tris)
    offset = np.arange(int(n_tris.sum())) - np.repeat(np.cumsum(n_tris) - n_tris, n_tris)
    first = starts[face]
    return np.column_stack([first, first + 1 + offset, first + 2 + offset])


def _two_face_quads(uv, face_sizes, starts, corner_faces, ok_corner, chart, corner_verts,
                    corner_edges):
    """Per face: the corner (0..3) of a quad at a vertex inside its chart shared by only two
    of the chart's faces, else -1. Such a quad cannot be strictly convex in UV (the two
    corner angles there sum to a full turn); the core splits it through that vertex and looks
    at that split only. Inside the chart: every edge at the vertex joins two solved faces of
    the chart and has the same UVs on both sides (seams and cuts part them)."""
    n_f = len(face_sizes)
    out = np.full(n_f, -1, dtype=np.int64)
    quads = np.flatnonzero((face_sizes == 4) & ok_corner[starts])
    if corner_verts is None or corner_edges is None or not len(quads):
        return out
    cv = np.asarray(corner_verts, dtype=np.int64)
    ce = np.asarray(corner_edges, dtype=np.int64)
    n_c = len(cv)
    nxt = np.arange(n_c) + 1
    nxt[starts + face_sizes - 1] = starts
    ch = chart[corner_faces]
    ok = np.flatnonzero(ok_corner)
    n_v = int(cv.max()) + 1
    n_e = int(ce.max()) + 1
    # corners of an edge joined inside a chart: exactly two corners of solved faces on the
    # edge, both in the chart, with the same UVs at both ends
    on_edge = np.bincount(ce[ok], minlength=n_e)
    order = ok[np.argsort(ch[ok] * n_e + ce[ok], kind="stable")]
    key = ch[order] * n_e + ce[order]
    joined = np.zeros(n_c, dtype=bool)
    first = np.flatnonzero((key[:-1] == key[1:]) & (on_edge[ce[order[:-1]]] == 2))
    c1, c2 = order[first], order[first + 1]
    same = ((np.all(uv[c1] == uv[nxt[c2]], axis=1) & np.all(uv[nxt[c1]] == uv[c2], axis=1))
            | (np.all(uv[c1] == uv[c2], axis=1) & np.all(uv[nxt[c1]] == uv[nxt[c2]], axis=1)))
    joined[c1[same]] = True
    joined[c2[same]] = True
    # (chart, vertex): faces around it, and whether an open edge of the chart touches it
    keys, inverse, count = np.unique(ch[ok] * n_v + cv[ok], return_inverse=True,
                                     return_counts=True)
    boundary = np.zeros(len(keys), dtype=bool)
    open_corner = ok[~joined[ok]]
    boundary[np.searchsorted(keys, ch[open_corner] * n_v + cv[open_corner])] = True
    boundary[np.searchsorted(keys, ch[open_corner] * n_v + cv[nxt[open_corner]])] = True
    two = np.zeros(n_c, dtype=bool)
    two[ok] = (count[inverse] == 2) & ~boundary[inverse]
    hit = two[starts[quads][:, None] + np.arange(4)]
    has = hit.any(axis=1)
    out[quads[has]] = np.argmax(hit[has], axis=1)
    return out


def face_flips(uv, face_sizes, chart, solved, triangles=None, corner_verts=None,
               corner_edges=None):
    """Flipped triangles of every face, counted as the core counts them in its report.

    The triangles are the ones Blender renders (``triangles``: the mesh's loop triangles as
    corner triples; default a fan of every face). A triangle is flipped when its signed UV area
    opposes the majority of its chart's triangles, or is zero (at most
    :data:`ZERO_AREA_RELATIVE` times the squared diagonal of the chart's UV bounding box, in a
    frame of half-size 1). A quad counts the flips of the worse of its two diagonal splits, so
    a quad folded on either diagonal is flipped; a quad at a vertex inside its chart shared by
    two faces only counts its split through that vertex (``corner_verts`` and ``corner_edges``
    find those vertices). Only ``solved`` faces of a chart (>= 0) are looked at; every other
    face counts 0."""
    uv = np.asarray(uv, dtype=np.float64)
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    n_f = len(face_sizes)
    counts = np.zeros(n_f, dtype=np.int64)
    if n_f == 0:
        return counts
    chart = np.asarray(chart, dtype=np.int64)
    ok_face = np.asarray(solved, dtype=bool) & (chart >= 0)
    if not ok_face.any():
        return counts
    starts = np.zeros(n_f, dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    corner_faces = np.repeat(np.arange(n_f), face_sizes)
    ok_corner = ok_face[corner_faces]
    tris = _fan_triangles(face_sizes) if triangles is None else np.asarray(triangles, np.int64)
    tris = tris.reshape(-1, 3)
    tri_face = corner_faces[tris[:, 0]]
    through = _two_face_quads(uv, face_sizes, starts, corner_faces, ok_corner, chart,
                              corner_verts, corner_edges)
    quad = (face_sizes == 4) & ok_face & (through < 0)
    # single triangles: every rendered triangle of a face that is not a (free) quad, and the
    # split through the two-face vertex of the other quads
    singles = tris[ok_face[tri_face] & ~quad[tri_face] & (through[tri_face] < 0)]
    tq = np.flatnonzero(through >= 0)
    if len(tq):
        k = through[tq]
        c = [starts[tq] + (k + j) % 4 for j in range(4)]
        singles = np.vstack([singles, np.column_stack([c[0], c[1], c[2]]),
                             np.column_stack([c[2], c[3], c[0]])])
    q = np.flatnonzero(quad)
    a, b, c, d = (starts[q] + j for j in range(4))
    splits = np.stack([np.column_stack(s) for s in ((a, b, c), (a, c, d), (a, b, d), (b, c, d))],
                      axis=1).reshape(-1, 3)
    every = np.vstack([singles, splits])
    every_face = corner_faces[every[:, 0]]
    every_chart = chart[every_face]
    # each chart's UVs in a frame of half-size 1 about the centre of their bounding box
    n_charts = int(chart[ok_face].max()) + 1
    ch_c = chart[corner_faces][ok_corner]
    uv_c = uv[ok_corner]
    lo = np.full((n_charts, 2), np.inf)
    hi = np.full((n_charts, 2), -np.inf)
    with np.errstate(invalid="ignore"):
        for k in range(2):
            np.minimum.at(lo[:, k], ch_c, uv_c[:, k])
            np.maximum.at(hi[:, k], ch_c, uv_c[:, k])
        centre = 0.5 * lo + 0.5 * hi
        size = np.max(0.5 * hi - 0.5 * lo, axis=1)
    good = np.isfinite(size) & (size > 0) & np.all(np.isfinite(centre), axis=1)
    centre = np.where(np.isfinite(centre), centre, 0.0)
    size = np.where(good, size, 1.0)
    with np.errstate(invalid="ignore", over="ignore"):
        lo_n = (lo - centre) / size[:, None]
        hi_n = (hi - centre) / size[:, None]
        diag2 = np.where(lo_n[:, 0] <= hi_n[:, 0], ((hi_n - lo_n) ** 2).sum(axis=1), 0.0)
        eps = ZERO_AREA_RELATIVE * diag2
        p = [(uv[every[:, j]] - centre[every_chart]) / size[every_chart][:, None] for j in range(3)]
        area = 0.5 * ((p[1][:, 0] - p[0][:, 0]) * (p[2][:, 1] - p[0][:, 1])
                      - (p[1][:, 1] - p[0][:, 1]) * (p[2][:, 0] - p[0][:, 0]))
        e = eps[every_chart]
        pos = np.bincount(every_chart, weights=area > e, minlength=n_charts)
        neg = np.bincount(every_chart, weights=area < -e, minlength=n_charts)
        majority = np.where(neg > pos, -1.0, 1.0)
        flipped = ~(area * majority[every_chart] > e)
    n_single = len(singles)
    counts += np.bincount(every_face[:n_single], weights=flipped[:n_single],
                          minlength=n_f).astype(np.int64)
    f = flipped[n_single:].reshape(-1, 4).astype(np.int64)
    counts[q] += np.maximum(f[:, 0] + f[:, 1], f[:, 2] + f[:, 3])
    return counts


def flipped_faces(uv, face_sizes, chart, solved, triangles=None, corner_verts=None,
                  corner_edges=None):
    """Faces with at least one flipped triangle by :func:`face_flips` (the core's count)."""
    return face_flips(uv, face_sizes, chart, solved, triangles, corner_verts, corner_edges) > 0


def measure(job, solved):
    """``(conformal, area, flipped)`` per face of ``job``'s mesh for the ``solved`` faces.

    The conformal and area values come with the unwrap's result (the core measures every
    chart on the UVs it returns, with the render triangulation); the flipped faces are the
    ones holding the flips the core's report counts (:func:`face_flips` on the same UVs and
    triangles). Reads the mesh's corner edges (out of edit mode)."""
    result = job.result
    keep = np.asarray(solved, dtype=bool)
    conformal = np.where(keep, np.asarray(result.face_conformal), np.nan)
    area = np.where(keep, np.asarray(result.face_area), np.nan)
    flipped = flipped_faces(np.asarray(result.uv), job.face_sizes, np.asarray(result.chart),
                            keep, job.triangles, job.corner_verts,
                            mesh_io.read_corner_edges(job.obj.data))
    return conformal, area, flipped


def srgb_to_linear(rgba):
    """The sRGB colours ``rgba`` ((N,4), alpha kept) as linear values (IEC 61966-2-1)."""
    out = np.array(rgba, dtype=np.float64)
    c = out[:, :3]
    out[:, :3] = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return out


_LEVELS = 1024  # steps of the heat scale in the stored colours (bytes held 256)
_LINEAR_TABLE = None


def _linear_heat_colors(values):
    """:func:`heat_colors` as linear float32 RGBA, from a table of :data:`_LEVELS` steps of
    the scale (the sRGB conversion's power is too slow per face on large meshes)."""
    global _LINEAR_TABLE
    if _LINEAR_TABLE is None:
        t = np.linspace(0.0, 1.0, _LEVELS)
        table = srgb_to_linear(heat_colors(np.exp(t * np.log(RED_AT))))
        grey = srgb_to_linear(heat_colors([np.nan]))
        _LINEAR_TABLE = np.vstack([table, grey]).astype(np.float32)
    values = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(np.log(np.maximum(values, 1.0)) / np.log(RED_AT), 0.0, 1.0)
    index = np.rint(np.nan_to_num(t, nan=0.0) * (_LEVELS - 1)).astype(np.int64)
    index[np.isposinf(values)] = _LEVELS - 1
    index[np.isnan(values)] = _LEVELS  # grey
    return _LINEAR_TABLE[index]


def write(mesh, face_sizes, solved, conformal, area, flipped, color_kind=None):
    """Store the measures of the ``solved`` faces (others keep theirs, see the module doc),
    and the heat colours of ``color_kind`` (``"conformal"`` or ``"area"``, the one the heat map
    shows; ``None`` when it is hidden: no colours)."""
    n_f = len(face_sizes)
    old_c = mesh_io.read_attribute(mesh, CONFORMAL)
    old_a = mesh_io.read_attribute(mesh, AREA)
    old_f = mesh_io.read_attribute(mesh, FLIPPED)
    c = np.where(solved, conformal, old_c if old_c is not None and len(old_c) == n_f else np.nan)
    a = np.where(solved, area, old_a if old_a is not None and len(old_a) == n_f else np.nan)
    f = np.where(solved, flipped, old_f if old_f is not None and len(old_f) == n_f else False)
    mesh_io.write_attribute(mesh, CONFORMAL, "FACE", "FLOAT", c)
    mesh_io.write_attribute(mesh, AREA, "FACE", "FLOAT", a)
    mesh_io.write_attribute(mesh, FLIPPED, "FACE", "BOOLEAN", f)
    if color_kind is None:
        drop_colors(mesh)
    else:
        write_colors(mesh, face_sizes, color_kind, c if color_kind == "conformal" else a)


def write_colors(mesh, face_sizes, kind, values=None):
    """Write the heat colours of distortion ``kind`` (from ``values`` per face, or the stored
    per-face measure; grey where there is none) as the mesh's active colour attribute (the one
    the viewport shows), and remove the other kind's colours. The mesh must not be in edit
    mode."""
    if values is None:
        values = mesh_io.read_attribute(mesh, MEASURE[kind])
        if values is None or len(values) != len(face_sizes):
            values = np.full(len(face_sizes), np.nan)
    rgba = np.repeat(_linear_heat_colors(values), face_sizes, axis=0)
    mesh_io.write_attribute(mesh, COLOR[kind], "CORNER", "FLOAT_COLOR", rgba)
    mesh.color_attributes.active_color_name = COLOR[kind]
    for other, name in COLOR.items():
        if other != kind:
            mesh_io.restore_attribute(mesh, name, None)


def drop_colors(mesh):
    """Remove both heat colour attributes (if present)."""
    for name in COLOR.values():
        mesh_io.restore_attribute(mesh, name, None)


def snapshot(mesh):
    """The stored state of every attribute of this module (restored on error)."""
    return {name: mesh_io.save_attribute(mesh, name) for name in ATTRIBUTES}


def restore(mesh, state):
    for name, saved in state.items():
        mesh_io.restore_attribute(mesh, name, saved)
