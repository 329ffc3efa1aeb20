# SPDX-License-Identifier: GPL-3.0-or-later
"""Helpers shared by the headless scripts (unwrap, benchmark, demo) and the add-on tests.

The add-on is registered straight from ``addon/`` in this repository (same code as the
installed extension), and every read or write of mesh data goes through its ``mesh_io``.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
SHARED_MESHES = REPO.parent / "shared" / "meshes"
ADDON_MODULE = "uvflat_addon"


_MESH_IO = None


def use_mesh_io(module):
    """Use this ``mesh_io`` module (e.g. the installed extension's) instead of ``addon/``'s."""
    global _MESH_IO
    _MESH_IO = module


def mesh_io():
    return _MESH_IO if _MESH_IO is not None else load_addon().mesh_io


def load_addon(register=True):
    """Import ``addon/`` as the module ``uvflat_addon`` and register it (once)."""
    if ADDON_MODULE in sys.modules:
        return sys.modules[ADDON_MODULE]
    spec = importlib.util.spec_from_file_location(
        ADDON_MODULE, REPO / "addon" / "__init__.py",
        submodule_search_locations=[str(REPO / "addon")])
    module = importlib.util.module_from_spec(spec)
    sys.modules[ADDON_MODULE] = module
    spec.loader.exec_module(module)
    if register:
        module.register()
    return module


def reset_scene():
    """Empty the scene (factory settings, no objects)."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)


# ---------------------------------------------------------------------------------------------
# Loading meshes


def read_off(path):
    """Read an OFF file: ``(positions (V,3), corner_verts (C,), face_sizes (F,))``, as written.
    Raises ``MeshFileError`` naming the file and what is wrong (empty, no counts, fewer
    vertices or faces than announced, a value that is not a number, a bad index)."""
    text = Path(path).read_text(errors="replace")
    lines = [ln.split("#", 1)[0].strip() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    if not lines:
        raise MeshFileError(f"{path}: empty file (an OFF file starts with OFF and the vertex and "
                            "face counts)")
    first = lines[0].split()
    if not first[0].endswith("OFF"):
        raise MeshFileError(f"{path}: not an OFF file (it starts with {first[0][:40]!r})")
    counts, at = (first[1:], 1) if len(first) > 1 else (
        lines[1].split() if len(lines) > 1 else [], 2)
    if len(counts) < 2:
        raise MeshFileError(f"{path}: the OFF header has no vertex and face counts")
    try:
        n_v, n_f = int(counts[0]), int(counts[1])
    except ValueError:
        raise MeshFileError(f"{path}: the OFF counts {' '.join(counts[:3])!r} are not "
                            "integers") from None
    if n_v < 0 or n_f < 0:
        raise MeshFileError(f"{path}: negative OFF counts {n_v} {n_f}")
    vertex_rows = lines[at:at + n_v]
    if len(vertex_rows) < n_v:
        raise MeshFileError(f"{path}: the header announces {n_v} vertices, the file holds "
                            f"{len(vertex_rows)}")
    try:
        positions = np.array(" ".join(vertex_rows).split(), dtype=np.float64)
        positions = positions.reshape(n_v, -1)[:, :3]
        if positions.shape[1] != 3:
            raise ValueError
    except ValueError:
        for v, row in enumerate(vertex_rows):  # name the first vertex row that is wrong
            try:
                if len([float(x) for x in row.split()]) < 3:
                    raise ValueError
            except ValueError:
                raise MeshFileError(f"{path}: vertex {v} is not three numbers: "
                                    f"{row[:60]!r}") from None
        positions = np.array([[float(x) for x in row.split()[:3]] for row in vertex_rows],
                             dtype=np.float64).reshape(n_v, 3)
    face_rows = lines[at + n_v:at + n_v + n_f]
    if len(face_rows) < n_f:
        raise MeshFileError(f"{path}: the header announces {n_f} faces, the file holds "
                            f"{len(face_rows)}")
    sizes, corners = [], []
    for f, row in enumerate(face_rows):
        t = row.split()
        try:
            n = int(t[0])
            face = [int(v) for v in t[1:1 + n]]
        except ValueError:
            raise MeshFileError(f"{path}: face {f} is not a corner count and vertex indices: "
                                f"{row[:60]!r}") from None
        if len(face) != n:
            raise MeshFileError(f"{path}: face {f} announces {n} corners, names {len(face)}")
        sizes.append(n)
        corners += face
    face_sizes = np.array(sizes, dtype=np.int64)
    corner_verts = np.array(corners, dtype=np.int64)
    _check_soup(path, positions, corner_verts, face_sizes)
    return positions, corner_verts, face_sizes


def repair_repeated_corners(corner_verts, face_sizes):
    """The repair of faces that name a vertex more than once: the repeated corners of a face
    are merged (cyclically: ``1 2 2 3 4`` and ``1 2 3 4 1`` become ``1 2 3 4``); a face left
    with fewer than three corners, or still naming a vertex twice (``1 2 1 3``), is removed.
    The OBJ importer repairs faces the same way. Returns ``(corner_verts, face_sizes,
    repairs)``, ``repairs`` a list of ``(face, corners as written, corners kept or None)``."""
    corner_verts = np.asarray(corner_verts, dtype=np.int64).reshape(-1)
    face_sizes = np.asarray(face_sizes, dtype=np.int64).reshape(-1)
    if not len(face_sizes):
        return corner_verts, face_sizes, []
    face_of = np.repeat(np.arange(len(face_sizes)), face_sizes)
    n_v = int(corner_verts.max()) + 1 if len(corner_verts) else 1
    distinct = np.unique(face_of * n_v + corner_verts)
    n_distinct = np.bincount(distinct // n_v, minlength=len(face_sizes))
    bad = np.flatnonzero(n_distinct < face_sizes)
    if not len(bad):
        return corner_verts, face_sizes, []
    starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
    repairs = []
    new_sizes = face_sizes.copy()
    for f in bad.tolist():
        corners = corner_verts[starts[f]:starts[f] + face_sizes[f]].tolist()
        kept = corners[:1] + [v for i, v in enumerate(corners[1:], 1) if v != corners[i - 1]]
        while len(kept) > 1 and kept[-1] == kept[0]:
            kept.pop()
        if len(kept) < 3 or len(set(kept)) != len(kept):
            kept = None
        repairs.append((f, corners, kept))
        new_sizes[f] = 0 if kept is None else len(kept)
    # faces not repaired keep their corners; the repaired ones get theirs written after
    new_starts = np.concatenate([[0], np.cumsum(new_sizes)[:-1]])
    out = np.empty(int(new_sizes.sum()), dtype=np.int64)
    good = n_distinct[face_of] == face_sizes[face_of]
    at = new_starts[face_of] + np.arange(len(corner_verts)) - starts[face_of]
    out[at[good]] = corner_verts[good]
    for f, _, kept in repairs:
        if kept is not None:
            out[new_starts[f]:new_starts[f] + len(kept)] = kept
    return out, new_sizes[new_sizes > 0], repairs


class MeshFileError(ValueError):
    """A mesh file holds something no mesh can have (a non-finite coordinate, a face index
    out of range); the message names the file and the element."""


def _check_soup(path, positions, corner_verts, face_sizes):
    """Raise ``MeshFileError`` for the first non-finite coordinate or out-of-range index."""
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    bad = np.flatnonzero(~np.isfinite(positions).all(axis=1))
    if len(bad):
        v = int(bad[0])
        raise MeshFileError(f"{path}: vertex {v} has a non-finite coordinate {positions[v].tolist()}")
    corner_verts = np.asarray(corner_verts, dtype=np.int64)
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    small = np.flatnonzero(face_sizes < 3)
    if len(small):
        f = int(small[0])
        raise MeshFileError(f"{path}: face {f} has {int(face_sizes[f])} corners, at least 3 are needed")
    out = np.flatnonzero((corner_verts < 0) | (corner_verts >= len(positions)))
    if len(out):
        c = int(out[0])
        f = int(np.searchsorted(np.cumsum(face_sizes), c, side="right"))
        raise MeshFileError(f"{path}: face {f} refers to vertex {int(corner_verts[c])}, "
                            f"the file has {len(positions)} vertices")


def _obj_soup(path):
    """Positions and faces of an OBJ file as written (1-based and negative indices resolved),
    without any of an importer's repairs."""
    positions, corner_verts, face_sizes = [], [], []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line_no, line in enumerate(fh, 1):
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                try:
                    positions.append([float(x) for x in parts[1:4]])
                except ValueError:
                    raise MeshFileError(f"{path}, line {line_no}: vertex {len(positions)} has a "
                                        f"coordinate that is not a number: {line.strip()!r}") from None
                if len(positions[-1]) != 3:
                    raise MeshFileError(f"{path}, line {line_no}: vertex {len(positions) - 1} has "
                                        f"{len(positions[-1])} coordinates, 3 are needed")
            elif parts[0] == "f":
                face = []
                for tok in parts[1:]:
                    try:
                        i = int(tok.split("/")[0])
                    except ValueError:
                        raise MeshFileError(f"{path}, line {line_no}: face {len(face_sizes)} has "
                                            f"an index that is not an integer: {tok!r}") from None
                    # 1-based; negative indices count back from the vertices read so far.
                    face.append(i - 1 if i > 0 else (len(positions) + i if i < 0 else -1))
                corner_verts += face
                face_sizes.append(len(face))
    return np.array(positions, dtype=np.float64).reshape(-1, 3), corner_verts, face_sizes


_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}


def _ply_soup(path):
    """Positions and faces of a PLY file (ascii or binary), as written."""
    data = Path(path).read_bytes()
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise MeshFileError(f"{path}: not a PLY file")
    header = data[:end].decode("ascii", errors="replace").splitlines()
    body = data[data.index(b"\n", end) + 1:]
    fmt, elements = "ascii", []
    for line in header:
        t = line.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            elements.append((t[1], int(t[2]), []))
        elif t[0] == "property" and elements:
            elements[-1][2].append(t[1:])
    positions, corner_verts, face_sizes = np.zeros((0, 3)), [], []
    if fmt == "ascii":
        tokens = body.split()
        at = 0
        for name, count, props in elements:
            rows = []
            for _ in range(count):
                row = []
                for prop in props:
                    if prop[0] == "list":
                        n = int(tokens[at])
                        row.append([float(x) for x in tokens[at + 1:at + 1 + n]])
                        at += 1 + n
                    else:
                        row.append(float(tokens[at]))
                        at += 1
                rows.append(row)
            names = [p[-1] for p in props]
            if name == "vertex":
                positions = np.array([[r[names.index(k)] for k in "xyz"] for r in rows]).reshape(-1, 3)
            elif name == "face":
                k = next(i for i, p in enumerate(props) if p[0] == "list")
                for r in rows:
                    corner_verts += [int(x) for x in r[k]]
                    face_sizes.append(len(r[k]))
        return positions, corner_verts, face_sizes
    order = "<" if fmt == "binary_little_endian" else ">"
    at = 0
    for name, count, props in elements:
        if all(p[0] != "list" for p in props):
            dt = np.dtype([(p[-1], order + _PLY_TYPES[p[0]]) for p in props])
            arr = np.frombuffer(body, dtype=dt, count=count, offset=at)
            at += dt.itemsize * count
            if name == "vertex":
                positions = np.stack([arr[k].astype(np.float64) for k in "xyz"], axis=1)
            continue
        for _ in range(count):
            for p in props:
                if p[0] == "list":
                    ct, it = np.dtype(order + _PLY_TYPES[p[1]]), np.dtype(order + _PLY_TYPES[p[2]])
                    n = int(np.frombuffer(body, dtype=ct, count=1, offset=at)[0])
                    at += ct.itemsize
                    vals = np.frombuffer(body, dtype=it, count=n, offset=at).astype(np.int64)
                    at += it.itemsize * n
                    if name == "face":
                        corner_verts += vals.tolist()
                        face_sizes.append(n)
                else:
                    at += np.dtype(_PLY_TYPES[p[0]]).itemsize
    return positions, corner_verts, face_sizes


def check_mesh_file(path):
    """Refuse a mesh file whose vertices are not finite or whose faces name missing vertices:
    importers repair such files silently (a NaN vertex moved to the origin, a bad face
    dropped), which would unwrap something other than the file. ``.off``, ``.obj`` and
    ``.ply`` are read as written; ``.blend`` files are checked after loading
    (``check_mesh_object``). Raises ``MeshFileError`` naming the file and the element, also
    for a file with no faces. Returns the file's ``(positions, corner_verts, face_sizes)`` as
    written (``None`` for ``.blend``)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if not path.is_file():
        raise MeshFileError(f"{path}: no such file")
    if suffix == ".off":
        soup = read_off(path)
    elif suffix == ".obj":
        soup = _obj_soup(path)
        _check_soup(path, *soup)
    elif suffix == ".ply":
        try:
            soup = _ply_soup(path)
        except (ValueError, IndexError, KeyError, StopIteration) as ex:
            if isinstance(ex, MeshFileError):
                raise
            raise MeshFileError(f"{path}: cannot be read as PLY ({ex})") from None
        _check_soup(path, *soup)
    else:
        return None
    positions, corner_verts, face_sizes = soup
    if not len(face_sizes):
        raise MeshFileError(f"{path}: no faces ({len(positions)} vertices): nothing to unwrap")
    return (np.asarray(positions, dtype=np.float64).reshape(-1, 3),
            np.asarray(corner_verts, dtype=np.int64), np.asarray(face_sizes, dtype=np.int64))


def check_mesh_object(path, obj):
    """Refuse a loaded mesh object with a non-finite vertex position (``MeshFileError``)."""
    mesh = obj.data
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float64)
    mesh.vertices.foreach_get("co", co)
    bad = np.flatnonzero(~np.isfinite(co.reshape(-1, 3)).all(axis=1))
    if len(bad):
        v = int(bad[0])
        raise MeshFileError(f"{path}: object {obj.name!r}, vertex {v} has a non-finite coordinate "
                            f"{co.reshape(-1, 3)[v].tolist()}")


def link_mesh_object(name, mesh):
    import bpy

    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def load_mesh_object(path):
    """Load .off/.obj/.ply/.blend as one mesh object in the current scene and return it."""
    import bpy

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".off":
        positions, corner_verts, face_sizes = read_off(path)
        corner_verts, face_sizes, _ = repair_repeated_corners(corner_verts, face_sizes)
        return link_mesh_object(path.stem, mesh_io().new_mesh(path.stem, positions,
                                                              corner_verts, face_sizes))
    before = set(bpy.data.objects)
    if suffix == ".obj":
        bpy.ops.wm.obj_import(filepath=str(path))
    elif suffix == ".ply":
        bpy.ops.wm.ply_import(filepath=str(path))
    elif suffix == ".blend":
        with bpy.data.libraries.load(str(path), link=False) as (src, dst):
            dst.objects = list(src.objects)
        for obj in dst.objects:
            if obj is not None and obj.type == "MESH":
                bpy.context.scene.collection.objects.link(obj)
    else:
        raise ValueError(f"{path}: unsupported format (use .off, .obj, .ply or .blend)")
    new = [o for o in bpy.data.objects if o not in before and o.type == "MESH"
           and o.name in bpy.context.scene.objects]
    if not new:
        raise ValueError(f"{path}: no mesh object found")
    if suffix == ".ply":
        _restore_repaired_ply_faces(path, new[0])
    return new[0]


def _restore_repaired_ply_faces(path, obj):
    """The PLY importer drops every face naming a vertex twice; put back the faces
    ``repair_repeated_corners`` keeps (so that every format gets the same repair)."""
    import bmesh

    try:
        positions, corner_verts, face_sizes = _ply_soup(path)
    except (ValueError, IndexError, KeyError, StopIteration):
        return
    _, _, repairs = repair_repeated_corners(corner_verts, face_sizes)
    kept = [k for _, _, k in repairs if k is not None]
    mesh = obj.data
    if not kept or len(mesh.vertices) != len(positions):
        return
    if len(mesh.polygons) != len(face_sizes) - len(repairs):
        return  # not the importer this was written for: leave the mesh as imported
    bm = bmesh.new()
    bm.from_mesh(mesh)
    bm.verts.ensure_lookup_table()
    for face in kept:
        try:
            bm.faces.new([bm.verts[v] for v in face])
        except ValueError:  # the same face exists already
            pass
    bm.to_mesh(mesh)
    bm.free()
    mesh.update()


def suzanne(name="Suzanne"):
    """Blender's monkey primitive with seams marked from its own UV islands."""
    import bpy

    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.seams_from_islands(mark_seams=True)
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


def suzanne_subdivided(levels=2, name="SuzanneSubdiv"):
    """Suzanne with a subdivision surface modifier of ``levels`` applied (her UV map is
    subdivided with her), then seams marked from her UV islands."""
    import bpy

    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.name = name
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = levels
    modifier.render_levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    seams_from_islands(obj)
    return obj


def seams_from_islands(obj):
    """Mark seams from the islands of ``obj``'s active UV map (Blender's own operator)."""
    import bpy

    edit_mode([obj])
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.seams_from_islands(mark_seams=True)
    bpy.ops.object.mode_set(mode="OBJECT")


def subdivided_disk(name, segments, cuts):
    """A flat disk: a triangle fan of ``segments`` triangles, every triangle split by ``cuts``
    cuts per edge, ``segments * (cuts + 1)**2`` triangles in one island; object mode after."""
    import bpy

    bpy.ops.mesh.primitive_circle_add(vertices=segments, fill_type="TRIFAN")
    obj = bpy.context.active_object
    obj.name = name
    edit_mode([obj])
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.mesh.subdivide(number_cuts=cuts)
    object_mode()
    return obj


def edit_mode(objects, select_all=True):
    """Make ``objects`` (mesh objects) the ones in edit mode, all faces selected."""
    import bpy

    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in bpy.context.view_layer.objects:
        o.select_set(o in objects)
    if select_all:
        for o in objects:
            mesh_io().select_all_faces(o.data)
    bpy.context.view_layer.objects.active = objects[0]
    bpy.ops.object.mode_set(mode="EDIT")


def object_mode():
    import bpy

    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")


# ---------------------------------------------------------------------------------------------
# Drawing UV layouts


def draw_layout(uv, face_sizes, size=1024, title=None):
    """A Pillow image of a UV layout: faces grey, flipped faces red, edges dark."""
    from PIL import Image, ImageDraw

    uv = np.asarray(uv, dtype=np.float64)
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    # signed area per face (shoelace), vectorised over corners
    nxt = np.arange(len(uv)) + 1
    nxt[starts + face_sizes - 1] = starts
    cross = uv[:, 0] * uv[nxt, 1] - uv[nxt, 0] * uv[:, 1]
    area = np.add.reduceat(cross, starts) * 0.5 if len(starts) else np.zeros(0)
    majority = 1.0 if (area > 0).sum() >= (area < 0).sum() else -1.0
    flipped = area * majority <= 0

    img = Image.new("RGB", (size, size), (255, 255, 255))
    draw = ImageDraw.Draw(img)
    pix = np.column_stack([uv[:, 0] * (size - 1), (1.0 - uv[:, 1]) * (size - 1)])
    for k in (0, 1):
        for t in np.linspace(0, size - 1, 9):
            xy = [(t, 0), (t, size - 1)] if k == 0 else [(0, t), (size - 1, t)]
            draw.line(xy, fill=(228, 228, 228))
    pts = pix.tolist()
    for f, (s, n) in enumerate(zip(starts.tolist(), face_sizes.tolist())):
        poly = [tuple(p) for p in pts[s:s + n]]
        draw.polygon(poly, fill=(235, 90, 80) if flipped[f] else (205, 215, 230),
                     outline=(40, 60, 90))
    if title:
        draw.rectangle([0, 0, size, 22], fill=(255, 255, 255))
        draw.text((6, 5), title, fill=(0, 0, 0))
    return img


def save_layout(path, uv, face_sizes, size=1024, title=None):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    draw_layout(uv, face_sizes, size=size, title=title).save(path)
    return path


def grid(images, columns):
    """Tile same-size Pillow images into one."""
    from PIL import Image

    w, h = images[0].size
    rows = (len(images) + columns - 1) // columns
    out = Image.new("RGB", (w * columns, h * rows), (255, 255, 255))
    for i, im in enumerate(images):
        out.paste(im, ((i % columns) * w, (i // columns) * h))
    return out


def components(n, a, b):
    """Connected-component label of each of ``n`` nodes joined by the edges ``a``–``b``."""
    label = np.arange(n)
    while True:
        new = label.copy()
        np.minimum.at(new, a, label[b])
        np.minimum.at(new, b, label[a])
        new = new[new]
        if np.array_equal(new, label):
            return label
        label = new
