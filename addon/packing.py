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
* **Orientation**: :func:`min_box_angles` turns an island to the smallest bounding box of its
  convex hull, by the smallest rotation that does it. Used where the packer may not rotate
  (a non-square texture the islands were not corrected for: Blender's packer rotates in the
  texture's pixels, which would shear such islands) and by the *Orient* option.
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
    centre = 0.5 * (low + high)[ci]
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


def min_box_angle(hull, chunk=512):
    """The rotation (radians) turning the convex polygon ``hull`` ((H,2), H >= 3) to its
    bounding box of least area, the smallest in size of the four that do (a quarter turn
    more or less gives the same box on its side)."""
    hull = np.asarray(hull, dtype=np.float64)
    edges = np.roll(hull, -1, axis=0) - hull
    keep = np.hypot(edges[:, 0], edges[:, 1]) > 0
    if not keep.any():
        return 0.0
    # the box of least area has a side along an edge of the hull: turning that edge to the
    # u axis is a rotation by minus its direction
    candidates = -np.arctan2(edges[keep, 1], edges[keep, 0])
    candidates = np.append(candidates, 0.0)
    centred = hull - hull.mean(axis=0)
    best_area, best = np.inf, 0.0
    for k in range(0, len(candidates), chunk):
        angle = candidates[k:k + chunk]
        c, s = np.cos(angle), np.sin(angle)
        x = np.outer(c, centred[:, 0]) - np.outer(s, centred[:, 1])
        y = np.outer(s, centred[:, 0]) + np.outer(c, centred[:, 1])
        area = np.ptp(x, axis=1) * np.ptp(y, axis=1)
        j = int(np.argmin(area))
        if area[j] < best_area * (1.0 - 1e-9):
            best_area, best = float(area[j]), float(angle[j])
    # the same box is reached by any quarter turn more: take the smallest rotation
    best = (best + np.pi / 4) % (np.pi / 2) - np.pi / 4
    # keep the island as it was when turning it saves (almost) nothing
    c0 = np.ptp(centred[:, 0]) * np.ptp(centred[:, 1])
    return 0.0 if c0 <= best_area * (1.0 + 1e-6) else best


# Hulls of at most this many points are turned in bulk (:func:`min_box_angles`); larger ones,
# rare, one by one.
_BULK_HULL = 64
# Candidate boxes measured per bulk block (islands x candidates x points), bounding memory.
_BULK_BLOCK = 1 << 21


def min_box_angles(offsets, points):
    """:func:`min_box_angle` of every hull ``points[offsets[k]:offsets[k + 1]]``.

    Hulls of up to ``_BULK_HULL`` points, grouped by size, are measured in blocks of whole
    arrays (a mesh of many small islands has tens of thousands of them), with the same
    candidates in the same order as :func:`min_box_angle`, so the same box wins."""
    offsets = np.asarray(offsets, dtype=np.int64)
    points = np.asarray(points, dtype=np.float64)
    sizes = np.diff(offsets)
    angles = np.zeros(len(sizes), dtype=np.float64)
    for k in np.flatnonzero(sizes > _BULK_HULL):
        angles[k] = min_box_angle(points[offsets[k]:offsets[k + 1]])
    small = np.flatnonzero(sizes <= _BULK_HULL)
    if not len(small):
        return angles
    # sizes rounded up to a power of two: few groups, little padding
    width = np.maximum(4, 1 << np.ceil(np.log2(np.maximum(sizes[small], 1))).astype(np.int64))
    for w in np.unique(width):
        group = small[width == w]
        step = max(1, _BULK_BLOCK // (w * (w + 1)))
        for b in range(0, len(group), step):
            block = group[b:b + step]
            angles[block] = _min_box_angles_padded(points, offsets[block], sizes[block], int(w))
    return angles


def _min_box_angles_padded(points, starts, sizes, width):
    """:func:`min_box_angle` of hulls ``points[starts[k]:starts[k] + sizes[k]]``, each of at
    most ``width`` points, measured together (a hull is padded with its last point, which
    changes no extent)."""
    j = np.arange(width)
    n = sizes[:, None]
    index = starts[:, None] + np.minimum(j, n - 1)
    nxt = starts[:, None] + np.where(j + 1 < n, j + 1, 0)
    hull = points[index]                                  # (B, W, 2)
    edges = points[nxt] - hull
    valid = (j < n) & (np.hypot(edges[..., 0], edges[..., 1]) > 0)
    # candidates: every edge turned to the u axis, then no turn at all (last)
    cand = np.concatenate([-np.arctan2(edges[..., 1], edges[..., 0]),
                           np.zeros((len(sizes), 1))], axis=1)
    ok = np.concatenate([valid, np.ones((len(sizes), 1), dtype=bool)], axis=1)
    real = (j < n)[..., None]
    centre = np.where(real, hull, 0.0).sum(axis=1) / sizes[:, None]
    centred = hull - centre[:, None, :]                   # padding repeats a real point
    c, s = np.cos(cand)[..., None], np.sin(cand)[..., None]
    px, py = centred[:, None, :, 0], centred[:, None, :, 1]
    x = c * px - s * py                                   # (B, W + 1, W)
    y = s * px + c * py
    area = np.ptp(x, axis=2) * np.ptp(y, axis=2)
    area = np.where(ok, area, np.inf)
    pick = np.argmin(area, axis=1)
    rows = np.arange(len(sizes))
    best_area, best = area[rows, pick], cand[rows, pick]
    best = (best + np.pi / 4) % (np.pi / 2) - np.pi / 4
    c0 = np.ptp(centred[..., 0], axis=1) * np.ptp(centred[..., 1], axis=1)
    turned = np.any(valid, axis=1) & ~(c0 <= best_area * (1.0 + 1e-6))
    return np.where(turned, best, 0.0)
