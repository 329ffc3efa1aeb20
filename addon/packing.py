# SPDX-License-Identifier: GPL-3.0-or-later
"""What the unwrap does to the new islands around Blender's packer (numpy only, no bpy).

* **UDIM tiles**: every new island is packed into the UDIM tile its faces were in before the
  unwrap (:func:`island_tiles`); the islands already in that tile are the ones it is packed
  around (:func:`face_tiles`). Blender's packer packs into the 0-1 tile, so the engine moves
  each tile's islands there for the packer and back afterwards.
* **Texel density**: packed around existing islands, the new islands get the density of the
  existing map (UV area per surface area of the faces left alone, :func:`density`), and the
  packer is told not to scale: the islands left alone keep theirs, and a re-unwrapped part
  matches them (:func:`scale_islands`).
* **Orientation**: :func:`rotate_islands` turns every island by its angle, the one that turns
  it to the smallest bounding box of its convex hull (``uvflat.island_box_angles``, computed
  in the core: ``rust/uvflat-core/src/geometry/min_box.rs``). Used where the packer may not
  rotate (a non-square texture the islands were not corrected for: Blender's packer rotates
  in the texture's pixels, which would shear such islands) and by the *Orient* option.
"""

from __future__ import annotations

import numpy as np

# UDIM tiles are numbered 1001 + u + 10 v with u in 0..9 (and v >= 0).
UDIM_COLUMNS = 10
UDIM_ROWS = 100


def _starts(face_sizes):
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    return starts


def face_areas(positions, corner_verts, face_sizes, triangles, uv):
    """``(surface area, UV area)`` of every face, from its triangles (corner triples; the UV
    area of a triangle taken unsigned)."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    n_f = len(face_sizes)
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    corner_faces = np.repeat(np.arange(n_f), face_sizes)
    tri_face = corner_faces[tris[:, 0]]
    p = np.asarray(positions, dtype=np.float64)[np.asarray(corner_verts, dtype=np.int64)[tris]]
    area3 = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    q = np.asarray(uv, dtype=np.float64)[tris]
    area2 = 0.5 * np.abs((q[:, 1, 0] - q[:, 0, 0]) * (q[:, 2, 1] - q[:, 0, 1])
                         - (q[:, 1, 1] - q[:, 0, 1]) * (q[:, 2, 0] - q[:, 0, 0]))
    return (np.bincount(tri_face, weights=area3, minlength=n_f),
            np.bincount(tri_face, weights=area2, minlength=n_f))


def density(area3, area_uv, faces):
    """UV area per surface area of ``faces`` (the faces with some UV area; an unmapped face,
    all its corners on one point, says nothing of the map's density); ``None`` when there is
    no such face."""
    faces = np.asarray(faces, dtype=bool) & (area_uv > 0) & (area3 > 0) & np.isfinite(area_uv)
    if not faces.any():
        return None
    total3, total_uv = float(area3[faces].sum()), float(area_uv[faces].sum())
    if not (total3 > 0 and total_uv > 0):
        return None
    return total_uv / total3


def _tile_of(points):
    """UDIM tile ``(column, row)`` of UV points (one per row); points outside the UDIM range
    (negative, or beyond ten columns) are in tile (0, 0)."""
    tile = np.floor(np.nan_to_num(points, nan=0.0, posinf=0.0, neginf=0.0)).astype(np.int64)
    valid = ((tile[:, 0] >= 0) & (tile[:, 0] < UDIM_COLUMNS)
             & (tile[:, 1] >= 0) & (tile[:, 1] < UDIM_ROWS))
    tile[~valid] = 0
    return tile


def face_tiles(uv, face_sizes):
    """UDIM tile ``(F, 2)`` of every face: the tile of the centre of its corners' UVs."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    uv = np.asarray(uv, dtype=np.float64)
    if not len(face_sizes):
        return np.zeros((0, 2), dtype=np.int64)
    starts = _starts(face_sizes)
    centre = np.column_stack([np.add.reduceat(uv[:, k], starts) for k in range(2)])
    return _tile_of(centre / face_sizes[:, None])


def island_tiles(old_uv, face_sizes, island, n_islands):
    """UDIM tile ``(n_islands, 2)`` of every island: the tile of the centre of its faces'
    previous UVs. ``island``: island of every face, -1 for faces of no island."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    island = np.asarray(island, dtype=np.int64)
    corner_island = np.repeat(island, face_sizes)
    inside = corner_island >= 0
    uv = np.nan_to_num(np.asarray(old_uv, dtype=np.float64)[inside])
    count = np.bincount(corner_island[inside], minlength=n_islands).astype(np.float64)
    centre = np.column_stack([np.bincount(corner_island[inside], weights=uv[:, k],
                                          minlength=n_islands) for k in range(2)])
    return _tile_of(centre / np.maximum(count, 1.0)[:, None])


def island_bounds(uv, face_sizes, island, n_islands):
    """``(low, high)`` corners ``(n_islands, 2)`` of the UV bounding box of every island."""
    corner_island = np.repeat(np.asarray(island, dtype=np.int64), face_sizes)
    inside = corner_island >= 0
    ci = corner_island[inside]
    uv = np.asarray(uv, dtype=np.float64)[inside]
    low = np.full((n_islands, 2), np.inf)
    high = np.full((n_islands, 2), -np.inf)
    for k in range(2):
        np.minimum.at(low[:, k], ci, uv[:, k])
        np.maximum.at(high[:, k], ci, uv[:, k])
    return low, high


def scale_islands(uv, face_sizes, island, factors):
    """Scale every island's UVs by ``factors[island]`` about the centre of its bounding box,
    in place (``uv``: (C,2) float array; faces of island -1 untouched)."""
    factors = np.asarray(factors, dtype=np.float64)
    corners, ci, centre, d = _about_centres(uv, face_sizes, island, len(factors))
    uv[corners] = centre + d * factors[ci][:, None]
    return uv


def _about_centres(uv, face_sizes, island, n_islands):
    """The corners of islands ``>= 0``, their island, their island's bounding-box centre and
    their offset from it (float64)."""
    island = np.asarray(island, dtype=np.int64)
    low, high = island_bounds(uv, face_sizes, island, n_islands)
    corner_island = np.repeat(island, face_sizes)
    corners = np.flatnonzero(corner_island >= 0)
    ci = corner_island[corners]
    centre = 0.5 * (low[ci] + high[ci])   # islands without corners (inf - inf) left out
    return corners, ci, centre, uv[corners].astype(np.float64) - centre


def rotate_islands(uv, face_sizes, island, angles):
    """Rotate every island's UVs by ``angles[island]`` (radians, counter-clockwise) about the
    centre of its bounding box, in place."""
    angles = np.asarray(angles, dtype=np.float64)
    corners, ci, centre, d = _about_centres(uv, face_sizes, island, len(angles))
    c, s = np.cos(angles[ci]), np.sin(angles[ci])
    uv[corners, 0] = centre[:, 0] + c * d[:, 0] - s * d[:, 1]
    uv[corners, 1] = centre[:, 1] + s * d[:, 0] + c * d[:, 1]
    return uv
