# SPDX-License-Identifier: GPL-3.0-or-later
"""Per-face quality of an unwrap, stored on the mesh so the artist can see it.

After an unwrap, every solved face gets (faces not unwrapped keep their previous values, NaN
on a mesh that never had them):

* ``uvflat_conformal`` and ``uvflat_area`` (FACE, FLOAT): the conformal and area distortion of
  the face as measured by ``uvflat.metrics`` (docs/design.md definitions; 1 is perfect);
* ``uvflat_flipped`` (FACE, BOOLEAN): the face holds a flipped or zero-area UV triangle as
  the core's report counts them (the unwrap's ``face_flips``: Blender's render triangles, a
  quad folded on either diagonal);
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


def measure(job, solved):
    """``(conformal, area, flipped)`` per face of ``job``'s mesh for the ``solved`` faces.

    All three come with the unwrap's result: the core measures every chart on the UVs it
    returns, with the render triangulation, and ``face_flips`` holds the flips of every face
    exactly as the chart reports count them (so the flipped faces are the ones holding the
    report's flips)."""
    result = job.result
    keep = np.asarray(solved, dtype=bool)
    conformal = np.where(keep, np.asarray(result.face_conformal), np.nan)
    area = np.where(keep, np.asarray(result.face_area), np.nan)
    flipped = keep & (np.asarray(result.face_flips) > 0)
    return conformal, area, flipped


def flipped_faces(uvflat, mesh, uv_name=None):
    """Faces of ``mesh`` whose UVs (map ``uv_name``, default the active one) hold a flipped
    or zero-area triangle, ``(F,)`` bool, as the core counts them in a report
    (``uvflat.metrics(...).face_flips`` on Blender's render triangles; islands are the faces
    joined by equal UVs). Faces with a non-finite UV are not measured; a mesh without a UV
    map has none. The mesh must not be in edit mode."""
    n_f = len(mesh.polygons)
    if not n_f or not mesh.uv_layers:
        return np.zeros(n_f, dtype=bool)
    positions, corner_verts, face_sizes = mesh_io.read_topology(mesh)
    uv = mesh_io.read_uv(mesh, uv_name).astype(np.float64)
    bad_corner = ~np.isfinite(uv).all(axis=1)
    measured = ~np.logical_or.reduceat(bad_corner, np.cumsum(face_sizes) - face_sizes)
    m = uvflat.metrics(positions, corner_verts, face_sizes, uv, selected=measured,
                       triangles=mesh_io.read_loop_triangles(mesh, face_sizes))
    return np.asarray(m.face_flips) > 0


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
