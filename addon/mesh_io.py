# SPDX-License-Identifier: GPL-3.0-or-later
"""The only module of uvflat that touches Blender mesh data.

Everything is read and written in bulk with ``foreach_get`` / ``foreach_set`` on numpy arrays
whose dtype matches Blender's storage (float32 positions and UVs, int32 indices, bool flags),
never element by element.  All functions expect the mesh to be out of edit mode (the edit-mode
BMesh is the live copy there); ``engine.py`` takes care of the mode switches.

Flags Blender stores as optional attributes (seams, selection, hidden faces: attributes in every
supported Blender, 4.2 and later) are read from the attribute when it exists and are all False
when it does not: the element-wise RNA properties (``edges.use_seam`` …) are never read, they
cost a tenth of a second per million elements and only report the same False.

Note: Blender re-creates the ``uv_layers`` collection when the mesh leaves or enters edit mode,
so UV layers are always looked up by name here, never kept across mode switches.
"""

from __future__ import annotations

import numpy as np

DEFAULT_UV_NAME = "UVMap"

# Boolean attributes that hold selection state (mesh and UV selection, Blender 4.x and 5.x).
_SELECTION_PREFIXES = (".select_", ".uv_select_")


# ---------------------------------------------------------------------------------------------
# Reading


def _get(collection, attr, count, dtype, width=1):
    out = np.empty(count * width, dtype=dtype)
    if count:
        collection.foreach_get(attr, out)
    return out if width == 1 else out.reshape(count, width)


def _attribute(mesh, names, count, dtype, width=1, field="value", data_type=None):
    """Bulk copy of the first built-in attribute of ``names`` the mesh stores, else ``None``.

    Attribute arrays are copied with one memcpy; the equivalent RNA properties
    (``loops.vertex_index``, ``polygons.select`` …) go element by element inside Blender and
    are one to two orders of magnitude slower on large meshes. With ``data_type``, an attribute
    of another type is passed over (see :func:`_set_bool_attribute`).
    """
    for name in names:
        attr = mesh.attributes.get(name)
        if attr is not None and (data_type is None or attr.data_type == data_type):
            return _get(attr.data, field, count, dtype, width)
    return None


def _flags(mesh, names, count):
    """A boolean attribute of ``names`` as a ``(count,)`` mask; all False when Blender stores
    none (it creates the attribute the first time a flag is set)."""
    flags = _attribute(mesh, names, count, bool, data_type="BOOLEAN")
    return np.zeros(count, dtype=bool) if flags is None else flags


def read_topology(mesh):
    """Positions, corners and faces of ``mesh`` as flat arrays.

    Returns ``(positions (V,3) float64, corner_verts (C,) int32, face_sizes (F,) int32)``.
    """
    n_v, n_c = len(mesh.vertices), len(mesh.loops)
    positions = _attribute(mesh, ("position",), n_v, np.float32, 3, "vector")
    if positions is None:
        positions = _get(mesh.vertices, "co", n_v, np.float32, 3)
    positions = positions.astype(np.float64)
    corner_verts = _attribute(mesh, (".corner_vert",), n_c, np.int32)
    if corner_verts is None:
        corner_verts = _get(mesh.loops, "vertex_index", n_c, np.int32)
    return positions, corner_verts, read_face_sizes(mesh)


def read_face_sizes(mesh):
    """Corners of every face, ``(F,)`` int32."""
    n_c, n_f = len(mesh.loops), len(mesh.polygons)
    loop_start = _get(mesh.polygons, "loop_start", n_f, np.int32)
    face_sizes = np.diff(np.append(loop_start, np.int32(n_c))).astype(np.int32)
    if n_f and (loop_start[0] != 0 or np.any(face_sizes <= 0)):
        # Blender stores face corners contiguously in face order; anything else would make
        # per-corner arrays ambiguous, so refuse rather than guess.
        raise RuntimeError(f"mesh '{mesh.name}': face corners are not stored in face order")
    return face_sizes


def read_loop_triangles(mesh, face_sizes=None):
    """The triangles Blender renders, bakes and exports: ``(T, 3) int64`` corner indices.

    When ``face_sizes`` says every face is a triangle they are the faces' own corners in
    order (Blender's loop triangle of a triangle), so nothing is read. Otherwise calls ``mesh.calc_loop_triangles()`` (cheap when they are up to date) and copies
    ``loop_triangles``' ``loops`` in one ``foreach_get``. The core splits n-gons the same way
    and keeps quads convex on both diagonals, so what it promises is what Blender shows.
    """
    if face_sizes is not None and len(face_sizes) and bool(np.all(face_sizes == 3)):
        return np.arange(3 * len(face_sizes), dtype=np.int64).reshape(-1, 3)
    mesh.calc_loop_triangles()
    tris = mesh.loop_triangles
    return _get(tris, "loops", len(tris), np.int32, 3).astype(np.int64)


def read_edges(mesh):
    """``(edge_verts (E,2) int32, use_seam (E,) bool)``."""
    n_e = len(mesh.edges)
    edge_verts = _attribute(mesh, (".edge_verts",), n_e, np.int32, 2)
    if edge_verts is None:
        edge_verts = _get(mesh.edges, "vertices", n_e, np.int32, 2)
    use_seam = _flags(mesh, ("uv_seam", ".uv_seam"), n_e)
    return edge_verts, use_seam


def read_seams(mesh):
    """Seam edges as ``(S,2)`` int32 vertex pairs."""
    edge_verts, use_seam = read_edges(mesh)
    return edge_verts[use_seam]


def read_vertex_selection(mesh):
    """Selected vertices as a ``(V,)`` bool mask."""
    return _flags(mesh, (".select_vert",), len(mesh.vertices))


def read_corner_edges(mesh):
    """Edge of every corner (the edge from the corner's vertex to the next corner's), ``(C,)``
    int32."""
    n_c = len(mesh.loops)
    corner_edges = _attribute(mesh, (".corner_edge",), n_c, np.int32)
    if corner_edges is None:
        corner_edges = _get(mesh.loops, "edge_index", n_c, np.int32)
    return corner_edges


def seam_mask_of_pairs(mesh, pairs):
    """``(E,)`` bool mask of the edges whose vertex pairs are in ``pairs`` ((K,2), any order)."""
    edge_verts, _ = read_edges(mesh)
    mask = np.zeros(len(edge_verts), dtype=bool)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if not len(pairs) or not len(edge_verts):
        return mask
    n = np.int64(max(int(edge_verts.max()), int(pairs.max())) + 1)
    ev = np.sort(edge_verts.astype(np.int64), axis=1)
    keys = ev[:, 0] * n + ev[:, 1]
    pp = np.sort(pairs, axis=1)
    mask[np.isin(keys, pp[:, 0] * n + pp[:, 1])] = True
    return mask


def read_face_selection(mesh, *, include_hidden=False):
    """Selected faces as an ``(F,)`` bool mask; hidden faces are left out unless asked."""
    selected = _flags(mesh, (".select_poly",), len(mesh.polygons))
    if not include_hidden:
        selected &= ~read_hidden_faces(mesh)
    return selected


def read_hidden_faces(mesh):
    """Hidden faces as an ``(F,)`` bool mask."""
    return _flags(mesh, (".hide_poly",), len(mesh.polygons))


def uv_map_names(mesh):
    return [layer.name for layer in mesh.uv_layers]


def active_uv_name(mesh):
    """Name of the active UV map, or ``None`` if the mesh has none."""
    layer = mesh.uv_layers.active
    return None if layer is None else layer.name


def read_uv(mesh, name=None):
    """Per-corner UVs of UV map ``name`` (default: the active one) as ``(C,2)`` float32."""
    layer = mesh.uv_layers[name] if name is not None else mesh.uv_layers.active
    if layer is None:
        raise KeyError(f"mesh '{mesh.name}' has no UV map")
    return _get(layer.uv, "vector", len(mesh.loops), np.float32, 2)


def read_pins(mesh, name=None):
    """Per-corner pin flags of UV map ``name`` (default: active) as ``(C,)`` bool.

    Blender only stores the pin layer once something was pinned; an absent layer means no pins.
    """
    layer = mesh.uv_layers[name] if name is not None else mesh.uv_layers.active
    n_c = len(mesh.loops)
    if layer is None or len(layer.pin) != n_c:
        return np.zeros(n_c, dtype=bool)
    return _get(layer.pin, "value", n_c, bool)


# ---------------------------------------------------------------------------------------------
# Writing


def ensure_uv_map(mesh):
    """Return ``(name, created)`` of the active UV map, creating one if the mesh has none."""
    name = active_uv_name(mesh)
    if name is not None:
        return name, False
    layer = mesh.uv_layers.new(name=DEFAULT_UV_NAME, do_init=False)
    if layer is None:
        raise RuntimeError(f"mesh '{mesh.name}': could not create a UV map")
    mesh.uv_layers.active = layer
    return layer.name, True


def make_first_uv_map(mesh, name):
    """Reorder the UV maps so that ``name`` is the first one (exporters such as glTF write
    the maps in order: the first becomes TEXCOORD_0), then make it active and the render map.
    Every map keeps its name, UVs and pin flags."""
    names = uv_map_names(mesh)
    if name not in names:
        raise KeyError(f"mesh '{mesh.name}' has no UV map {name!r}")
    if names[0] != name:
        saved = [(n, read_uv(mesh, n), save_pins(mesh, n)) for n in names]
        saved.sort(key=lambda item: item[0] != name)  # stable: the others keep their order
        for n in names:
            mesh.uv_layers.remove(mesh.uv_layers[n])
        for n, uv, pins in saved:
            layer = mesh.uv_layers.new(name=n, do_init=False)
            if layer is None or layer.name != n:
                raise RuntimeError(f"mesh '{mesh.name}': could not re-create UV map {n!r}")
            write_uv(mesh, n, uv)
            if pins is not None:
                write_pins(mesh, n, pins)
    layer = mesh.uv_layers[name]
    mesh.uv_layers.active = layer
    layer.active_render = True


def remove_uv_map(mesh, name):
    layer = mesh.uv_layers.get(name)
    if layer is not None:
        mesh.uv_layers.remove(layer)


def write_uv(mesh, name, uv):
    """Write ``(C,2)`` UVs into UV map ``name`` (converted to Blender's float32)."""
    layer = mesh.uv_layers[name]
    data = np.ascontiguousarray(uv, dtype=np.float32).reshape(-1)
    if data.size != 2 * len(mesh.loops):
        raise ValueError(f"mesh '{mesh.name}': {data.size // 2} UVs for {len(mesh.loops)} corners")
    layer.uv.foreach_set("vector", data)
    mesh.update()


def write_pins(mesh, name, pins):
    """Set the per-corner pin flags of UV map ``name`` from a ``(C,)`` bool mask."""
    mesh.uv_layers[name].pin  # noqa: B018 - make sure the layer exists
    attr_name = f".pn.{name}"
    attr = mesh.attributes.get(attr_name)
    if attr is None:
        attr = mesh.attributes.new(attr_name, "BOOLEAN", "CORNER")
    attr.data.foreach_set("value", np.ascontiguousarray(pins, dtype=bool))
    mesh.update()


def save_pins(mesh, name):
    """The pin attribute of UV map ``name`` as stored (``None`` when the map has none)."""
    attr = mesh.attributes.get(f".pn.{name}")
    if attr is None:
        return None
    return _get(attr.data, "value", len(attr.data), bool)


def restore_pins(mesh, name, saved):
    """Put the pin attribute of UV map ``name`` back as :func:`save_pins` found it."""
    attr_name = f".pn.{name}"
    if saved is None:
        attr = mesh.attributes.get(attr_name)
        if attr is not None:
            mesh.attributes.remove(attr)
        mesh.update()
    else:
        write_pins(mesh, name, saved)


# Generic attributes (quality attributes written after an unwrap): field and width per type
_FIELDS = {"FLOAT": ("value", 1, np.float32), "BOOLEAN": ("value", 1, bool),
           "BYTE_COLOR": ("color_srgb", 4, np.float32), "FLOAT_COLOR": ("color", 4, np.float32)}


def read_attribute(mesh, name):
    """Values of attribute ``name`` as stored (``(N,)`` or ``(N,4)`` for colours), or ``None``."""
    attr = mesh.attributes.get(name)
    if attr is None or attr.data_type not in _FIELDS:
        return None
    field, width, dtype = _FIELDS[attr.data_type]
    return _get(attr.data, field, len(attr.data), dtype, width)


def write_attribute(mesh, name, domain, data_type, values):
    """Create or replace attribute ``name`` (``domain``, ``data_type``) with ``values``."""
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.domain != domain or attr.data_type != data_type):
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, data_type, domain)
    field, width, dtype = _FIELDS[data_type]
    data = np.ascontiguousarray(values, dtype=dtype).reshape(-1)
    if data.size != width * len(attr.data):
        raise ValueError(f"mesh '{mesh.name}': {data.size // width} values for attribute {name} "
                         f"of {len(attr.data)} elements")
    attr.data.foreach_set(field, data)


def save_attribute(mesh, name):
    """``(domain, data_type, values)`` of attribute ``name``, or ``None`` if absent."""
    attr = mesh.attributes.get(name)
    if attr is None:
        return None
    return attr.domain, attr.data_type, read_attribute(mesh, name)


def restore_attribute(mesh, name, saved):
    """Put attribute ``name`` back as :func:`save_attribute` found it."""
    if saved is None:
        attr = mesh.attributes.get(name)
        if attr is not None:
            mesh.attributes.remove(attr)
    else:
        domain, data_type, values = saved
        write_attribute(mesh, name, domain, data_type, values)


def write_seams(mesh, use_seam):
    """Set every edge's seam flag from an ``(E,)`` bool mask: one copy into the seam
    attribute when the mesh has one (its name depends on Blender's version), else through
    ``edges.use_seam``, which creates it."""
    use_seam = np.ascontiguousarray(use_seam, dtype=bool)
    for name in ("uv_seam", ".uv_seam"):
        attr = mesh.attributes.get(name)
        if attr is not None and attr.data_type == "BOOLEAN" and attr.domain == "EDGE":
            if len(attr.data) != len(use_seam):
                raise ValueError(f"mesh '{mesh.name}': {len(use_seam)} seam flags for "
                                 f"{len(attr.data)} edges")
            attr.data.foreach_set("value", use_seam)
            break
    else:
        mesh.edges.foreach_set("use_seam", use_seam)
    mesh.update()


# ---------------------------------------------------------------------------------------------
# Selection state (saved and restored around packing)


def save_selection(mesh):
    """Snapshot of every selection attribute (mesh and UV selection) of ``mesh``."""
    state = {}
    for attr in mesh.attributes:
        if attr.name.startswith(_SELECTION_PREFIXES) and attr.data_type == "BOOLEAN":
            state[attr.name] = (attr.domain, _get(attr.data, "value", len(attr.data), bool))
    return state


def restore_selection(mesh, state):
    """Put the selection attributes back exactly as :func:`save_selection` found them."""
    for attr in list(mesh.attributes):
        if attr.name.startswith(_SELECTION_PREFIXES) and attr.name not in state:
            mesh.attributes.remove(mesh.attributes[attr.name])
    for name, (domain, values) in state.items():
        _set_bool_attribute(mesh, name, domain, values)
    mesh.update()


def select_faces(mesh, faces):
    """Select exactly the faces in the ``(F,)`` mask (plus their edges and vertices), in both
    the mesh selection and, where the mesh stores one, the UV selection."""
    faces = np.ascontiguousarray(faces, dtype=bool)
    _, corner_verts, face_sizes = read_topology(mesh)
    corner_in = np.repeat(faces, face_sizes)
    verts = np.zeros(len(mesh.vertices), dtype=bool)
    verts[corner_verts[corner_in]] = True
    edge_verts, _ = read_edges(mesh)
    edges = np.zeros(len(mesh.edges), dtype=bool)
    if len(mesh.loops):
        edges[read_corner_edges(mesh)[corner_in]] = True
    # Written through the attributes: on a mesh that never had a selection, Blender 5.0.1
    # crashes in ``edges.foreach_set("select", ...)`` (the attribute does not exist yet).
    _set_bool_attribute(mesh, ".select_vert", "POINT", verts)
    _set_bool_attribute(mesh, ".select_edge", "EDGE", edges)
    _set_bool_attribute(mesh, ".select_poly", "FACE", faces)
    for name, values in ((".uv_select_face", faces), (".uv_select_vert", corner_in),
                         (".uv_select_edge", corner_in)):
        if mesh.attributes.get(name) is not None:
            _set_bool_attribute(mesh, name, None, values)
    mesh.update()


def _set_bool_attribute(mesh, name, domain, values):
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.data_type != "BOOLEAN"
                             or (domain is not None and attr.domain != domain)):
        # A mesh made by ``Mesh.from_pydata`` in Blender 5.0.1 lists ``.select_edge`` as an
        # INT32_2D attribute over a boolean array: writing it, or ``edges.foreach_set("select")``,
        # fails or crashes. Selection carries no data of the user's, so it is made anew.
        if domain is None:
            domain = attr.domain
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, "BOOLEAN", domain)
    if len(attr.data) != len(values):
        raise ValueError(f"mesh '{mesh.name}': attribute {name} has {len(attr.data)} values, "
                         f"expected {len(values)}")
    attr.data.foreach_set("value", np.ascontiguousarray(values, dtype=bool))


def select_all_faces(mesh):
    select_faces(mesh, np.ones(len(mesh.polygons), dtype=bool))


# ---------------------------------------------------------------------------------------------
# Creating meshes (batch scripts and tests)


def new_mesh(name, positions, corner_verts, face_sizes):
    """A new ``bpy.types.Mesh`` built in bulk from a polygon soup (no UV map, no seams)."""
    import bpy

    positions = np.ascontiguousarray(positions, dtype=np.float32).reshape(-1, 3)
    corner_verts = np.ascontiguousarray(corner_verts, dtype=np.int32).reshape(-1)
    face_sizes = np.ascontiguousarray(face_sizes, dtype=np.int32).reshape(-1)
    if int(face_sizes.sum()) != corner_verts.size:
        raise ValueError("face sizes do not add up to the number of corners")
    loop_start = np.zeros(face_sizes.size, dtype=np.int32)
    np.cumsum(face_sizes[:-1], out=loop_start[1:])

    # Edges computed here rather than by ``mesh.update(calc_edges=True)``: in Blender 5.0.1 that
    # call leaves a ``.select_edge`` attribute of the wrong type, and writing the edge
    # selection afterwards crashes Blender.
    n_v = positions.shape[0]
    following = np.arange(corner_verts.size) + 1
    following[loop_start + face_sizes - 1] = loop_start
    a = corner_verts.astype(np.int64)
    b = corner_verts[following].astype(np.int64)
    keys, corner_edges = np.unique(np.minimum(a, b) * n_v + np.maximum(a, b), return_inverse=True)
    edge_verts = np.column_stack([keys // n_v, keys % n_v]).astype(np.int32)

    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(n_v)
    mesh.edges.add(edge_verts.shape[0])
    mesh.loops.add(corner_verts.size)
    mesh.polygons.add(face_sizes.size)
    mesh.vertices.foreach_set("co", positions.reshape(-1))
    mesh.edges.foreach_set("vertices", edge_verts.reshape(-1))
    mesh.loops.foreach_set("vertex_index", corner_verts)
    mesh.loops.foreach_set("edge_index", corner_edges.astype(np.int32).reshape(-1))
    mesh.polygons.foreach_set("loop_start", loop_start)
    mesh.update()
    # Blender repairs what it cannot store (e.g. duplicate faces); callers re-read the topology.
    mesh.validate(verbose=False)
    return mesh


def corner_faces(face_sizes):
    """``(C,)`` index of the face owning each corner."""
    return np.repeat(np.arange(len(face_sizes), dtype=np.int64), face_sizes)
