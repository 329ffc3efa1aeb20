"""Tests of the Python API of uvflat: shapes, dtypes, typed errors and analytic cases.

Every expected number here follows from geometry (a planar mesh maps isometrically, a
stretch by 2 has sigma1/sigma2 = 2, ...), never from a stored snapshot.
"""

from __future__ import annotations

import math
import sys
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import uvflat
from meshio_util import read_mesh

# ---------------------------------------------------------------------------------------------
# Mesh builders


def grid(nx: int, ny: int, *, triangles: bool = False, size: float = 1.0):
    """Planar grid in z = 0 of nx * ny unit-ish cells (quads, or triangles split along the
    anti-diagonal so that the cell's corner (i, j) lies in exactly one triangle)."""
    xs, ys = np.meshgrid(np.arange(nx + 1) * size, np.arange(ny + 1) * size, indexing="xy")
    positions = np.stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)], axis=1)

    def vid(i, j):
        return j * (nx + 1) + i

    faces = []
    for j in range(ny):
        for i in range(nx):
            a, b, c, d = vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)
            if triangles:
                faces += [[a, b, d], [b, c, d]]
            else:
                faces.append([a, b, c, d])
    corner_verts = np.array([v for f in faces for v in f], dtype=np.int64)
    face_sizes = np.array([len(f) for f in faces], dtype=np.int64)
    return positions, corner_verts, face_sizes


def cube():
    """Closed unit cube of 6 outward-oriented quads."""
    positions = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        dtype=np.float64,
    )
    faces = [
        [0, 3, 2, 1],  # bottom z=0
        [4, 5, 6, 7],  # top z=1
        [0, 1, 5, 4],  # y=0
        [1, 2, 6, 5],  # x=1
        [2, 3, 7, 6],  # y=1
        [3, 0, 4, 7],  # x=0
    ]
    corner_verts = np.array([v for f in faces for v in f], dtype=np.int64)
    face_sizes = np.full(6, 4, dtype=np.int64)
    return positions, corner_verts, face_sizes


# Cutting the cube along a spanning tree of its vertices (three top edges and the four
# vertical edges) unfolds it into the classic cross: the bottom in the middle, four sides
# around it and the top hanging off the x=0 side.
CROSS_SEAMS = np.array([[4, 5], [5, 6], [6, 7], [0, 4], [1, 5], [2, 6], [3, 7]])


def corner_faces(face_sizes):
    return np.repeat(np.arange(len(face_sizes)), face_sizes)


def identity_uv(positions, corner_verts):
    return positions[corner_verts, :2].copy()


# ---------------------------------------------------------------------------------------------
# Module surface


def test_methods_and_exports():
    assert isinstance(uvflat.METHODS, tuple)
    assert {"tutte", "harmonic", "mean_value", "lscm", "spectral"} <= set(uvflat.METHODS)
    assert all(isinstance(m, str) for m in uvflat.METHODS)
    assert isinstance(uvflat.__version__, str)
    for name in uvflat.__all__:
        assert hasattr(uvflat, name), name


@pytest.mark.parametrize(
    "cls, parents",
    [
        ("InputError", ("UvflatError", "ValueError")),
        ("MeshError", ("UvflatError", "ValueError")),
        ("VertexIndexError", ("MeshError", "UvflatError", "ValueError")),
        ("NonFiniteError", ("MeshError",)),
        ("FaceSizeError", ("MeshError",)),
        ("RepeatedVertexError", ("MeshError",)),
        ("SeamError", ("MeshError",)),
        ("PinError", ("UvflatError", "ValueError")),
        ("OptionError", ("UvflatError", "ValueError")),
        ("AngleSumError", ("OptionError", "UvflatError", "ValueError")),
        ("Cancelled", ("UvflatError",)),
        ("UvflatError", ("Exception",)),
    ],
)
def test_exception_hierarchy(cls, parents):
    builtin = {"ValueError": ValueError, "Exception": Exception}
    c = getattr(uvflat, cls)
    for p in parents:
        assert issubclass(c, builtin[p] if p in builtin else getattr(uvflat, p)), (cls, p)
    assert c.__module__ == "uvflat"
    assert c.__doc__


def test_panic_in_core_becomes_uvflat_error():
    from uvflat import _uvflat

    with pytest.raises(uvflat.UvflatError) as ei:
        _uvflat._internal_panic_check()
    assert type(ei.value) is uvflat.UvflatError
    assert "internal error" in str(ei.value) and "deliberate panic" in str(ei.value)


def test_pin_and_option_errors_are_not_mesh_errors():
    assert not issubclass(uvflat.PinError, uvflat.MeshError)
    assert not issubclass(uvflat.OptionError, uvflat.MeshError)
    assert not issubclass(uvflat.InputError, uvflat.MeshError)


# ---------------------------------------------------------------------------------------------
# Output shapes, dtypes and reports


def test_output_shapes_and_dtypes():
    pos, cv, fs = grid(4, 3)
    r = uvflat.unwrap(pos, cv, fs)
    C, F = len(cv), len(fs)
    assert isinstance(r, uvflat.UnwrapResult)
    assert r.uv.shape == (C, 2) and r.uv.dtype == np.float64 and r.uv.flags.c_contiguous
    assert r.chart.shape == (F,) and r.chart.dtype == np.int32
    assert r.face_solved.shape == (F,) and r.face_solved.dtype == np.bool_
    assert isinstance(r.seconds, float) and r.seconds >= 0.0
    assert r.method == "abf"
    assert isinstance(r.charts, list) and len(r.charts) == 1
    assert np.all(r.chart == 0) and np.all(r.face_solved)
    assert np.all(np.isfinite(r.uv))

    rep = r.charts[0]
    assert isinstance(rep, uvflat.ChartReport)
    int_fields = ["id", "faces", "triangles", "vertices", "boundary_loops", "genus", "iterations", "flips", "cones"]
    float_fields = ["residual", "conformal", "area", "symmetric_dirichlet", "seconds", "cut_length",
                    "density_p5", "density_p95", "density_outside"]
    for f in int_fields:
        assert isinstance(getattr(rep, f), int), f
    for f in float_fields:
        assert isinstance(getattr(rep, f), float), f
    assert isinstance(rep.overlap, bool)
    assert rep.reason is None or isinstance(rep.reason, str)
    assert (rep.id, rep.method, rep.kind, rep.status) == (0, "abf", "disk", "solved")
    assert 0.0 <= rep.density_outside <= 0.05 and rep.density_p5 <= 1.0 <= rep.density_p95
    assert (rep.faces, rep.triangles, rep.vertices) == (12, 24, 20)
    assert (rep.boundary_loops, rep.genus) == (1, 0)

    d = rep.as_dict()
    assert set(d) == set(int_fields + float_fields + ["method", "kind", "status", "reason", "overlap",
                                                     "reason_code"])
    assert d["faces"] == 12 and d["status"] == "solved"
    assert "ChartReport(" in repr(rep) and "solved" in repr(rep)

    rd = r.as_dict()
    assert {"uv", "chart", "face_solved", "charts", "seconds"} <= set(rd)
    assert isinstance(rd["charts"][0], dict)
    assert "UnwrapResult(" in repr(r)


def test_results_are_immutable():
    pos, cv, fs = grid(2, 2)
    r = uvflat.unwrap(pos, cv, fs)
    with pytest.raises(AttributeError):
        r.seconds = 1.0
    with pytest.raises(AttributeError):
        r.charts[0].flips = 3


@pytest.mark.parametrize("idx_dtype", [np.int32, np.int64, np.uint32, np.uint16, np.int16, np.uint64])
@pytest.mark.parametrize("pos_dtype", [np.float32, np.float64, np.int64])
def test_input_dtypes_accepted(idx_dtype, pos_dtype):
    pos, cv, fs = grid(3, 2)
    ref = uvflat.unwrap(pos, cv, fs)
    r = uvflat.unwrap(pos.astype(pos_dtype), cv.astype(idx_dtype), fs.astype(idx_dtype))
    # Grid coordinates are small integers, exact in every dtype: same input, same output.
    np.testing.assert_array_equal(r.uv, ref.uv)
    np.testing.assert_array_equal(r.chart, ref.chart)


def test_python_lists_and_non_contiguous_arrays_accepted():
    pos, cv, fs = grid(3, 2)
    ref = uvflat.unwrap(pos, cv, fs)
    r = uvflat.unwrap(pos.tolist(), cv.tolist(), fs.tolist())
    np.testing.assert_array_equal(r.uv, ref.uv)
    # Fortran-ordered positions and a strided index view.
    wide = np.zeros((len(cv), 2), dtype=np.int64)
    wide[:, 0] = cv
    r2 = uvflat.unwrap(np.asfortranarray(pos), wide[:, 0], fs)
    np.testing.assert_array_equal(r2.uv, ref.uv)


def test_empty_optional_arrays():
    pos, cv, fs = grid(2, 2)
    ref = uvflat.unwrap(pos, cv, fs)
    r = uvflat.unwrap(pos, cv, fs, seams=[], pins=[], pin_uvs=[], selected=None, fit_to=None)
    np.testing.assert_array_equal(r.uv, ref.uv)
    r = uvflat.unwrap(pos, cv, fs, seams=np.zeros((0, 2), np.int32))
    np.testing.assert_array_equal(r.uv, ref.uv)


def test_empty_and_degenerate_meshes_do_not_crash():
    r = uvflat.unwrap(np.zeros((0, 3)), [], [])
    assert r.uv.shape == (0, 2) and r.chart.shape == (0,) and r.face_solved.shape == (0,)
    assert r.charts == []
    m = uvflat.metrics(np.zeros((0, 3)), [], [], np.zeros((0, 2)))
    assert m.charts == 0 and m.flips == 0 and m.per_chart == []
    # A zero-area triangle: any outcome but a crash or an internal error.
    try:
        r = uvflat.unwrap(np.zeros((3, 3)), [0, 1, 2], [3])
    except uvflat.UvflatError as e:
        assert not str(e).startswith("internal error")
    else:
        assert r.uv.shape == (3, 2)


# ---------------------------------------------------------------------------------------------
# Typed errors naming the element


def test_vertex_index_out_of_range():
    pos, cv, fs = grid(2, 1)  # faces 0 and 1, 4 corners each, 6 vertices
    cv = cv.copy()
    cv[5] = 99  # face 1, corner 5
    with pytest.raises(uvflat.VertexIndexError) as ei:
        uvflat.unwrap(pos, cv, fs)
    e = ei.value
    assert (e.face, e.corner, e.vertex) == (1, 5, 99)
    assert e.n_vertices == 6
    assert "face 1" in str(e) and "99" in str(e)
    assert isinstance(e, uvflat.MeshError) and isinstance(e, ValueError)


def test_vertex_index_negative():
    pos, cv, fs = grid(2, 1)
    cv = cv.copy()
    cv[6] = -3
    with pytest.raises(uvflat.VertexIndexError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert (ei.value.face, ei.value.corner, ei.value.vertex) == (1, 6, -3)
    assert "face 1" in str(ei.value)


def test_vertex_index_too_large_for_uint32():
    pos, cv, fs = grid(1, 1)
    cv = cv.copy()
    cv[2] = 2**40
    with pytest.raises(uvflat.VertexIndexError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert (ei.value.face, ei.value.vertex) == (0, 2**40)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_position(bad):
    pos, cv, fs = grid(2, 2)
    pos = pos.copy()
    pos[4, 1] = bad
    with pytest.raises(uvflat.NonFiniteError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert ei.value.vertex == 4
    assert "vertex 4" in str(ei.value)


def test_face_too_small():
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    cv = np.array([0, 1, 2, 1, 3])
    fs = np.array([3, 2])
    with pytest.raises(uvflat.FaceSizeError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert (ei.value.face, ei.value.size) == (1, 2)
    assert "face 1" in str(ei.value)


def test_face_size_negative():
    pos, cv, fs = grid(2, 1)
    fs = fs.copy()
    fs[1] = -4
    with pytest.raises(uvflat.FaceSizeError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert (ei.value.face, ei.value.size) == (1, -4)


def test_repeated_vertex():
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    cv = np.array([0, 1, 2, 1, 3, 3])
    fs = np.array([3, 3])
    with pytest.raises(uvflat.RepeatedVertexError) as ei:
        uvflat.unwrap(pos, cv, fs)
    assert (ei.value.face, ei.value.vertex) == (1, 3)
    assert "face 1" in str(ei.value)


@pytest.mark.parametrize("bad", [50, -1])
def test_bad_seam(bad):
    pos, cv, fs = grid(2, 2)
    seams = np.array([[0, 1], [1, 2], [4, bad]])
    with pytest.raises(uvflat.SeamError) as ei:
        uvflat.unwrap(pos, cv, fs, seams=seams)
    assert (ei.value.seam, ei.value.vertex) == (2, bad)
    assert ei.value.n_vertices == 9
    assert "seam 2" in str(ei.value)


@pytest.mark.parametrize("bad", [1000, -2])
def test_bad_pin_corner(bad):
    pos, cv, fs = grid(2, 2)
    with pytest.raises(uvflat.PinError) as ei:
        uvflat.unwrap(pos, cv, fs, pins=[0, bad], pin_uvs=[[0, 0], [1, 1]])
    assert (ei.value.pin, ei.value.corner) == (1, bad)
    assert ei.value.n_corners == len(cv)
    assert "pin 1" in str(ei.value)


def test_nan_pin_uv():
    pos, cv, fs = grid(2, 2)
    with pytest.raises(uvflat.PinError) as ei:
        uvflat.unwrap(pos, cv, fs, pins=[0, 5], pin_uvs=[[0, 0], [np.nan, 1]])
    assert (ei.value.pin, ei.value.corner) == (1, 5)


def test_nan_fit_to():
    pos, cv, fs = grid(2, 2)
    prev = identity_uv(pos, cv)
    prev[7, 0] = np.nan
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.unwrap(pos, cv, fs, fit_to=prev)
    assert ei.value.corner == 7 and ei.value.argument == "fit_to"


@pytest.mark.parametrize(
    "argument, mutate",
    [
        ("positions", lambda a: a.update(positions=a["positions"][:, :2])),
        ("positions", lambda a: a.update(positions=a["positions"].ravel())),
        ("positions", lambda a: a.update(positions=a["positions"].astype(complex))),
        ("positions", lambda a: a.update(positions=[[0, 0, 0], [1, 0]])),
        ("corner_verts", lambda a: a.update(corner_verts=a["corner_verts"].reshape(-1, 4))),
        ("corner_verts", lambda a: a.update(corner_verts=a["corner_verts"].astype(float))),
        ("corner_verts", lambda a: a.update(corner_verts=["a", "b"])),
        ("face_sizes", lambda a: a.update(face_sizes=a["face_sizes"].astype(np.float32))),
        ("face_sizes", lambda a: a.update(face_sizes=a["face_sizes"][:, None])),
        ("seams", lambda a: a.update(seams=np.array([[0, 1, 2]]))),
        ("seams", lambda a: a.update(seams=np.array([0.0, 1.0]))),
        ("selected", lambda a: a.update(selected=np.ones((2, 2), bool))),
        ("selected", lambda a: a.update(selected=np.array([0.5, 1.0, 1.0, 1.0]))),
        ("pin_uvs", lambda a: a.update(pins=[0, 1], pin_uvs=[[0, 0, 0], [1, 1, 1]])),
        ("pin_uvs", lambda a: a.update(pins=[0, 1], pin_uvs=[[0, 0]])),
        ("pin_uvs", lambda a: a.update(pins=[0, 1])),
        ("pins", lambda a: a.update(pin_uvs=[[0, 0]])),
        ("fit_to", lambda a: a.update(fit_to=np.zeros((3, 2)))),
        ("fit_to", lambda a: a.update(fit_to=np.zeros((16, 3)))),
    ],
)
def test_wrong_shapes_raise_input_error(argument, mutate):
    pos, cv, fs = grid(2, 2)
    args = dict(positions=pos, corner_verts=cv, face_sizes=fs)
    mutate(args)
    positional = [args.pop(k) for k in ("positions", "corner_verts", "face_sizes")]
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.unwrap(*positional, **args)
    assert ei.value.argument == argument
    assert argument in str(ei.value)


def test_shape_error_reports_shape_received():
    pos, cv, fs = grid(2, 2)
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.unwrap(pos[:, :2], cv, fs)
    assert ei.value.shape == (9, 2)
    assert "(9, 2)" in str(ei.value) and "(V, 3)" in str(ei.value)


def test_length_mismatches_raise_input_error():
    pos, cv, fs = grid(2, 2)
    # face_sizes do not add up to the number of corners.
    with pytest.raises(uvflat.InputError):
        uvflat.unwrap(pos, cv[:-1], fs)
    # selected has the wrong number of faces.
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.unwrap(pos, cv, fs, selected=[True, False])
    assert "selected" in str(ei.value)


def test_unknown_method_and_options():
    pos, cv, fs = grid(2, 2)
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="no_such_method")
    assert "no_such_method" in str(ei.value)
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="lscm", boundary="circle")
    assert "boundary" in str(ei.value)
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="tutte", boundary="hexagon")
    assert ei.value.option == "boundary"
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="spectral", max_iterations=[1, 2])
    assert ei.value.option == "max_iterations"
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="spectral", max_iterations=2**70)
    assert ei.value.option == "max_iterations"
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="spectral", tolerance=-1.0)
    assert ei.value.option == "tolerance"
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="tutte", boundary=None)
    assert ei.value.option == "boundary"
    with pytest.raises(uvflat.OptionError):
        uvflat.unwrap(pos, cv, fs, method="tutte", frobnicate=True)


def test_valid_options_accepted():
    pos, cv, fs = grid(3, 3)
    for shape in ("circle", "square"):
        r = uvflat.unwrap(pos, cv, fs, method="tutte", boundary=shape)
        assert r.charts[0].status == "solved" and r.charts[0].flips == 0
    r = uvflat.unwrap(pos, cv, fs, method="spectral", max_iterations=np.int64(300), tolerance=1e-9)
    assert r.charts[0].status in ("solved", "fallback")


# ---------------------------------------------------------------------------------------------
# Analytic unwraps


@pytest.mark.parametrize("triangles", [False, True])
def test_planar_grid_lscm_is_conformal(triangles):
    pos, cv, fs = grid(6, 4, triangles=triangles, size=0.5)
    r = uvflat.unwrap(pos, cv, fs, method="lscm")
    (rep,) = r.charts
    assert rep.status == "solved" and rep.kind == "disk"
    assert rep.flips == 0 and not rep.overlap
    assert abs(rep.conformal - 1.0) < 1e-9
    assert abs(rep.area - 1.0) < 1e-9
    assert abs(rep.symmetric_dirichlet - 1.0) < 1e-9
    # The independent metric agrees.
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.charts == 1 and m.flips == 0 and m.overlapping_charts == 0
    assert abs(m.conformal - 1.0) < 1e-9
    # Default fit: UV area equals 3D area (an isometry up to rotation/translation).
    d3 = np.linalg.norm(pos[cv[0]] - pos[cv[2]])
    duv = np.linalg.norm(r.uv[0] - r.uv[2])
    assert abs(d3 - duv) < 1e-9


def test_lscm_without_pins_is_the_spectral_map_and_with_pins_holds_them():
    """Without pins, LSCM's free map is fixed on the whole outline (methods/lscm.rs), which is
    spectral's map up to a similarity; two pins are held exactly, and then the map differs."""
    pos, cv, fs = grid(12, 9, triangles=True, size=0.25)
    x, y = pos[:, 0] - 1.5, pos[:, 1] - 1.1
    pos = pos.copy()
    pos[:, 2] = 0.6 * np.sin(2.1 * x) * np.cos(1.7 * y) + 0.3 * x * x
    lscm = uvflat.unwrap(pos, cv, fs, method="lscm", auto_seams=False)
    spectral = uvflat.unwrap(pos, cv, fs, method="spectral", auto_seams=False)

    def similarity_gap(a, b):
        # Least-squares complex similarity a -> b, then the largest gap relative to b's size.
        za, zb = a[:, 0] + 1j * a[:, 1], b[:, 0] + 1j * b[:, 1]
        za0, zb0 = za - za.mean(), zb - zb.mean()
        s = np.vdot(za0, zb0) / np.vdot(za0, za0)
        return np.abs(s * za0 - zb0).max() / np.abs(zb0).max()

    assert similarity_gap(lscm.uv, spectral.uv) < 1e-6
    corners = [0, len(cv) - 1]
    pins = np.array([[0.0, 0.0], [3.0, 1.0]])
    pinned = uvflat.unwrap(pos, cv, fs, method="lscm", auto_seams=False, pins=np.array(corners), pin_uvs=pins)
    assert np.abs(pinned.uv[corners] - pins).max() < 1e-9
    assert similarity_gap(pinned.uv, spectral.uv) > 1e-4


@pytest.mark.parametrize("method", ["tutte", "harmonic", "mean_value", "lscm", "spectral", "bff"])
def test_every_method_maps_a_disk_without_flips(method):
    pos, cv, fs = grid(5, 5, triangles=True)
    r = uvflat.unwrap(pos, cv, fs, method=method)
    (rep,) = r.charts
    assert rep.status in ("solved", "fallback"), rep.reason
    assert rep.flips == 0
    assert np.all(np.isfinite(r.uv))
    assert np.all(r.face_solved)


def test_selected_mask():
    pos, cv, fs = grid(4, 2)
    F = len(fs)
    selected = np.zeros(F, dtype=bool)
    selected[:4] = True  # bottom row of cells
    r = uvflat.unwrap(pos, cv, fs, selected=selected)
    assert np.all(r.chart[~selected] == -1)
    assert np.all(r.chart[selected] >= 0)
    assert not r.face_solved[~selected].any()
    assert r.face_solved[selected].all()
    unselected_corners = ~selected[corner_faces(fs)]
    np.testing.assert_array_equal(r.uv[unselected_corners], 0.0)
    assert len(r.charts) == 1 and r.charts[0].faces == 4
    # Integer masks behave like bool masks.
    r2 = uvflat.unwrap(pos, cv, fs, selected=selected.astype(np.int8))
    np.testing.assert_array_equal(r2.chart, r.chart)


def test_selection_splits_into_charts():
    pos, cv, fs = grid(5, 1)
    selected = np.array([True, True, False, True, True])
    r = uvflat.unwrap(pos, cv, fs, selected=selected)
    assert len(r.charts) == 2
    assert r.chart.tolist()[2] == -1
    assert r.chart[0] == r.chart[1] != r.chart[3] == r.chart[4]
    assert sorted(c.faces for c in r.charts) == [2, 2]


def test_closed_cube_fails_and_says_why():
    pos, cv, fs = cube()
    r = uvflat.unwrap(pos, cv, fs, auto_seams=False)
    (rep,) = r.charts
    assert rep.kind == "closed" and rep.status == "failed"
    assert rep.genus == 0 and rep.boundary_loops == 0
    assert rep.reason is not None and "seam" in rep.reason.lower()
    assert not r.face_solved.any()
    assert np.all(r.chart == 0)
    np.testing.assert_array_equal(r.uv, 0.0)


def test_cube_cut_into_a_cross_solves():
    pos, cv, fs = cube()
    r = uvflat.unwrap(pos, cv, fs, seams=CROSS_SEAMS)
    (rep,) = r.charts
    assert rep.kind == "disk" and rep.status == "solved", rep.reason
    assert rep.boundary_loops == 1 and rep.faces == 6
    assert r.face_solved.all()
    assert rep.flips == 0
    # Every cone vertex lies on the cut, so the cut cube is developable: LSCM unfolds it
    # isometrically (up to similarity).
    assert abs(rep.conformal - 1.0) < 1e-9
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.charts == 1 and m.flips == 0
    assert abs(m.conformal - 1.0) < 1e-9
    # Unfolded cross: total UV area equals the 3D area (6) and every face is a unit square.
    for f in range(6):
        quad = r.uv[4 * f: 4 * f + 4]
        edges = np.roll(quad, -1, axis=0) - quad
        np.testing.assert_allclose(np.linalg.norm(edges, axis=1), 1.0, atol=1e-9)


def test_seams_in_either_order_are_the_same():
    pos, cv, fs = cube()
    a = uvflat.unwrap(pos, cv, fs, seams=CROSS_SEAMS)
    b = uvflat.unwrap(pos, cv, fs, seams=CROSS_SEAMS[:, ::-1].astype(np.uint32))
    np.testing.assert_allclose(a.uv, b.uv, atol=1e-12)


def test_lscm_pins_are_exact():
    pos, cv, fs = grid(4, 3, triangles=True)
    # Pin one corner of vertex 0 = (0, 0) and one corner of vertex 4 = (4, 0).
    c0 = int(np.flatnonzero(cv == 0)[0])
    c4 = int(np.flatnonzero(cv == 4)[0])
    pin_uvs = np.array([[0.25, -1.0], [8.25, -1.0]])
    r = uvflat.unwrap(pos, cv, fs, method="lscm", pins=[c0, c4], pin_uvs=pin_uvs)
    assert r.charts[0].status == "solved"
    np.testing.assert_array_equal(r.uv[cv == 0], np.broadcast_to(pin_uvs[0], (np.sum(cv == 0), 2)))
    np.testing.assert_array_equal(r.uv[cv == 4], np.broadcast_to(pin_uvs[1], (np.sum(cv == 4), 2)))
    # A planar mesh pinned at two points is mapped by the similarity through them:
    # here uv = 2 * (x, y) + (0.25, -1).
    expected = 2.0 * pos[cv, :2] + np.array([0.25, -1.0])
    np.testing.assert_allclose(r.uv, expected, atol=1e-9)


def test_pins_accept_int32_and_float32():
    pos, cv, fs = grid(2, 2)
    c0 = int(np.flatnonzero(cv == 0)[0])
    c8 = int(np.flatnonzero(cv == 8)[0])
    r = uvflat.unwrap(pos, cv, fs, pins=np.array([c0, c8], np.int32),
                      pin_uvs=np.array([[0, 0], [1, 1]], np.float32))
    np.testing.assert_array_equal(r.uv[c0], [0.0, 0.0])
    np.testing.assert_array_equal(r.uv[c8], [1.0, 1.0])


def test_fit_to_previous_uvs():
    pos, cv, fs = grid(3, 2)
    # Previous UVs: the mesh rotated by 90 degrees, scaled by 3 and moved.
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    prev = 3.0 * pos[cv, :2] @ rot.T + np.array([10.0, 5.0])
    r = uvflat.unwrap(pos, cv, fs, fit_to=prev)
    np.testing.assert_allclose(r.uv, prev, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# metrics on known maps


def tilted(positions):
    """Rigidly rotate positions out of the z = 0 plane (rotations keep every metric)."""
    a, b = 0.3, -0.7
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    rz = np.array([[math.cos(b), -math.sin(b), 0], [math.sin(b), math.cos(b), 0], [0, 0, 1]])
    return positions @ (rz @ rx).T + np.array([1.0, 2.0, 3.0])


def test_metrics_identity_map():
    pos, cv, fs = grid(4, 4, triangles=True)
    uv = identity_uv(pos, cv)
    m = uvflat.metrics(tilted(pos), cv, fs, uv)
    assert isinstance(m, uvflat.Metrics)
    assert (m.charts, m.flips, m.overlapping_charts) == (1, 0, 0)
    for value in (m.conformal, m.area, m.symmetric_dirichlet):
        assert abs(value - 1.0) < 1e-9
    (pc,) = m.per_chart
    assert pc["faces"] == len(fs) and pc["flips"] == 0 and pc["overlap"] is False
    assert abs(pc["area_3d"] - 16.0) < 1e-9
    assert abs(pc["conformal"] - 1.0) < 1e-9
    d = m.as_dict()
    assert {"charts", "flips", "overlapping_charts", "conformal", "area", "symmetric_dirichlet", "per_chart"} <= set(d)
    assert "Metrics(" in repr(m)


def test_metrics_counts_one_flipped_triangle():
    pos, cv, fs = grid(3, 3, triangles=True)
    uv = identity_uv(pos, cv)
    # Vertex 0 (the grid corner) lies in exactly one triangle (0, 1, 4). Moving its UV across
    # the edge (1, 4) flips that triangle and no other; the island stays one piece.
    assert np.sum(cv == 0) == 1
    uv[cv == 0] = [0.6, 0.6]
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.charts == 1
    assert m.flips == 1


def test_metrics_face_flips_name_the_flipped_faces():
    # The triangle grid with vertex 0 moved across the edge (1, 4): the one face holding it.
    pos, cv, fs = grid(3, 3, triangles=True)
    uv = identity_uv(pos, cv)
    uv[cv == 0] = [0.6, 0.6]
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.face_flips.dtype == np.uint32 and m.face_flips.shape == (len(fs),)
    face_of_vertex_0 = np.repeat(np.arange(len(fs)), fs)[np.flatnonzero(cv == 0)[0]]
    assert np.flatnonzero(m.face_flips).tolist() == [face_of_vertex_0]
    assert m.face_flips.sum() == m.flips == 1
    # A 2 x 2 quad grid whose middle vertex moves deep into quad 0 (vertices 0, 1, 4, 3): that
    # quad becomes a dart, reflex at the vertex, folded on one diagonal split (one flip); the
    # other three stay convex.
    pos, cv, fs = grid(2, 2)
    uv = identity_uv(pos, cv)
    uv[cv == 4] = [0.2, 0.2]
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.face_flips.tolist() == [1, 0, 0, 0]
    assert m.flips == 1
    # Only measured faces hold flips.
    m = uvflat.metrics(pos, cv, fs, uv, selected=[False, True, True, True])
    assert m.face_flips.tolist() == [0, 0, 0, 0] and m.flips == 0
    assert "face_flips" in m.as_dict()


def test_unwrap_face_flips_sum_to_the_reports():
    # Every corner pinned at its position except vertex 0, pinned across the edge (1, 4): the
    # pins force the fold of the one triangle holding vertex 0 (automatic seams off, so the
    # chart is reported invalid with its UVs).
    pos, cv, fs = grid(3, 3, triangles=True)
    uv = identity_uv(pos, cv)
    uv[cv == 0] = [0.6, 0.6]
    r = uvflat.unwrap(pos, cv, fs, method="lscm", pins=np.arange(len(cv)), pin_uvs=uv,
                      auto_seams=False)
    assert r.face_flips.dtype == np.uint32 and r.face_flips.shape == (len(fs),)
    face_of_vertex_0 = np.repeat(np.arange(len(fs)), fs)[np.flatnonzero(cv == 0)[0]]
    assert np.flatnonzero(r.face_flips).tolist() == [face_of_vertex_0]
    assert r.face_flips.sum() == sum(c.flips for c in r.charts) == 1
    assert "face_flips" in r.as_dict()
    # A curved quad mesh LSCM folds: the per-face counts sum to every chart's report and agree
    # with measuring the returned UVs.
    pos, cv, fs = grid(8, 8)
    rng = np.random.default_rng(3)
    pos[:, :2] += rng.uniform(-0.35, 0.35, (len(pos), 2))
    pos[:, 2] = 0.8 * np.sin(pos[:, 0]) * np.cos(pos[:, 1])
    for method in ("lscm", "abf"):
        r = uvflat.unwrap(pos, cv, fs, method=method)
        chart = np.asarray(r.chart)
        for report in r.charts:
            assert r.face_flips[chart == report.id].sum() == report.flips
        assert r.face_flips.sum() == sum(c.flips for c in r.charts)
        m = uvflat.metrics(pos, cv, fs, r.uv)
        assert m.face_flips.sum() == m.flips == r.face_flips.sum()


def test_metrics_stretch_by_two():
    pos, cv, fs = grid(3, 2, triangles=True)
    uv = identity_uv(pos, cv)
    uv[:, 0] *= 2.0
    m = uvflat.metrics(tilted(pos), cv, fs, uv)
    # J = diag(2, 1): sigma1 / sigma2 = 2. After area normalisation sigma = (sqrt2, 1/sqrt2),
    # so the area distortion is 1 and the symmetric Dirichlet energy (2 + 1/2 + 1/2 + 2) / 4.
    assert abs(m.conformal - 2.0) < 1e-9
    assert abs(m.area - 1.0) < 1e-9
    assert abs(m.symmetric_dirichlet - 1.25) < 1e-9
    assert m.flips == 0


def test_metrics_islands_follow_uv_equality():
    pos, cv, fs = grid(2, 1)  # two quads sharing the edge (1, 4)
    uv = identity_uv(pos, cv).astype(np.float32)
    assert uvflat.metrics(pos, cv, fs, uv).charts == 1
    uv[4:] += 5.0  # move the second face away: two islands
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.charts == 2 and len(m.per_chart) == 2
    assert abs(m.conformal - 1.0) < 1e-6


def test_metrics_selected_and_errors():
    pos, cv, fs = grid(2, 1)
    uv = identity_uv(pos, cv)
    uv[4:] += 5.0
    m = uvflat.metrics(pos, cv, fs, uv, selected=[True, False])
    assert m.charts == 1
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.metrics(pos, cv, fs, uv[:, :1])
    assert ei.value.argument == "uv"
    bad = uv.copy()
    bad[3, 1] = np.inf
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.metrics(pos, cv, fs, bad)
    assert ei.value.corner == 3
    with pytest.raises(uvflat.VertexIndexError):
        uvflat.metrics(pos, np.where(cv == 4, 17, cv), fs, uv)


# ---------------------------------------------------------------------------------------------
# Threads: the core runs without the GIL


def test_unwraps_in_threads():
    pos, cv, fs = grid(60, 50, triangles=True)  # 6,000 triangles
    barrier = threading.Barrier(2)

    def job(scale):
        barrier.wait()
        return uvflat.unwrap(pos * scale, cv, fs, method="lscm")

    with ThreadPoolExecutor(max_workers=2) as ex:
        results = list(ex.map(job, [1.0, 2.0]))
    for r in results:
        (rep,) = r.charts
        assert rep.status == "solved" and rep.flips == 0
        assert abs(rep.conformal - 1.0) < 1e-9
        assert r.uv.shape == (len(cv), 2)
    # Same mesh at twice the size: UV edge lengths scale by 2 (area-scaled fit).
    e1 = np.linalg.norm(results[0].uv[1] - results[0].uv[0])
    e2 = np.linalg.norm(results[1].uv[1] - results[1].uv[0])
    assert abs(e2 - 2.0 * e1) < 1e-9


def test_gil_released_while_core_runs():
    """Another Python thread runs while this thread is inside the core.

    With a huge switch interval the interpreter never forces a thread switch, so the waiting
    thread can only run if the caller gives the GIL up voluntarily: inside ``unwrap`` that is
    the core call. Inputs are already float64/int64 and contiguous, so numpy makes no copies
    (which could also release the GIL).
    """
    pos, cv, fs = grid(200, 150, triangles=True)  # 60,000 triangles
    pos = np.ascontiguousarray(pos, dtype=np.float64)
    cv = np.ascontiguousarray(cv, dtype=np.int64)
    fs = np.ascontiguousarray(fs, dtype=np.int64)
    go = threading.Event()
    ran = []

    def other():
        go.wait()
        ran.append(True)

    old = sys.getswitchinterval()
    t = threading.Thread(target=other)
    t.start()
    try:
        sys.setswitchinterval(100.0)
        go.set()
        r = uvflat.unwrap(pos, cv, fs, method="harmonic")
        ran_during_unwrap = bool(ran)
    finally:
        sys.setswitchinterval(old)
        t.join()
    assert ran_during_unwrap, "no other Python thread ran during unwrap: the GIL was held"
    # A harmonic map of a disk onto a convex polygon never flips (Tutte, Floater).
    assert r.charts[0].status == "solved" and r.charts[0].flips == 0


# ---------------------------------------------------------------------------------------------
# Real meshes (../shared/meshes), skipped when the folder is absent


def test_real_alligator_near_developable():
    pos, cv, fs = read_mesh("alligator.obj")
    r = uvflat.unwrap(pos, cv, fs, method="lscm")
    assert len(r.charts) == 1
    (rep,) = r.charts
    assert rep.kind == "disk" and rep.status == "solved"
    assert np.all(np.isfinite(r.uv))
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.charts == 1
    assert abs(m.conformal - rep.conformal) < 1e-9


def _robustness():
    """``blender_scripts/robustness.py``, whose variants stand for the meshes users bring."""
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "blender_scripts"))
    import robustness
    return robustness


@pytest.mark.parametrize("method", ["abf", "slim"])
def test_small_islands_are_laid_on_the_islands_around_them(method):
    """3holes with three large holes: the cuts joining the holes leave a few faces between
    them and the outline as islands of their own (28 of the 34 islands had under 10 faces).
    Their faces are laid on the islands around them where they fit: few islands, every one
    keeps the rule, and the seams reported are exactly the islands' borders."""
    robustness = _robustness()
    pos, cv, fs = robustness.holes(read_mesh("3holes.off"), 3, 600, 2)
    r = uvflat.unwrap(pos, cv, fs, method=method)
    assert r.phases["glued"] >= 10, r.phases
    assert len(r.charts) <= 10, [c.faces for c in r.charts]
    assert all(c.status in ("solved", "fallback") and c.density_outside <= 0.05 for c in r.charts)
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.flips == 0 and m.overlapping_charts == 0 and m.charts == len(r.charts)
    # The seams reported cut the mesh into exactly these islands, each a disk.
    split = uvflat.unwrap(pos, cv, fs, method="tutte", seams=r.new_seams, auto_seams=False)
    assert len(split.charts) == len(r.charts)
    assert all(c.kind == "disk" for c in split.charts)
    assert sorted(c.faces for c in split.charts) == sorted(c.faces for c in r.charts)


def test_arap_on_collapsed_triangles_keeps_the_rule_by_peeling_the_faces_that_fold():
    """The camel's head with a vertex collapsed onto a neighbour in 1% of its triangles
    (``blender_scripts/robustness.py``): under ``arap`` a piece folds at a zero-area UV
    triangle after every split, and its last resort (``scaffold``) left 35.5% of it outside the
    density bound. The faces that fold are peeled into an island of their own instead: every
    island keeps the rule, and the piece keeps its ``arap`` map with a note that says why."""
    robustness = _robustness()
    pos, cv, fs = robustness.collapsed(read_mesh("camelhead.off"), 0.01, 5)
    r = uvflat.unwrap(pos, cv, fs, method="arap")
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.flips == 0 and m.overlapping_charts == 0
    assert all(c.status in ("solved", "fallback") and c.density_outside <= 0.05 for c in r.charts), [
        (c.faces, c.status, c.density_outside, c.reason) for c in r.charts]
    peeled = [c for c in r.charts if "triangles folded" in (c.reason or "")]
    assert peeled and all(c.method == "arap" and c.status == "solved" for c in peeled), [
        (c.faces, c.method, c.reason) for c in r.charts]
    assert sum(c.faces for c in r.charts) == len(fs)


def test_real_halftunnel_quads_with_holes():
    pos, cv, fs = read_mesh("halftunnel.off")
    r = uvflat.unwrap(pos, cv, fs, method="lscm")
    assert r.face_solved.all()
    assert all(c.status != "failed" for c in r.charts)
    assert sum(c.faces for c in r.charts) == len(fs)


def test_real_closed_bunny_reports_failure_not_error():
    pos, cv, fs = read_mesh("bunny.off")
    r = uvflat.unwrap(pos, cv, fs)
    assert sum(c.faces for c in r.charts) == len(fs)
    for c in r.charts:
        if c.status == "failed":
            assert c.reason


@pytest.mark.parametrize("name", ["beetle-nonmanifold.obj", "cube_40k.obj"])
def test_real_bad_input_never_crashes(name):
    pos, cv, fs = read_mesh(name)
    try:
        r = uvflat.unwrap(pos, cv, fs)
    except uvflat.UvflatError as e:
        assert not str(e).startswith("internal error"), str(e)
    else:
        assert r.uv.shape == (len(cv), 2)
        assert np.all(np.isfinite(r.uv))


def test_factorization_seconds_is_defined_for_the_linear_methods_only():
    positions, corner_verts, face_sizes = grid(12, 9)
    for method in ("tutte", "harmonic", "mean_value", "lscm", "bff"):
        t = uvflat.factorization_seconds(positions, corner_verts, face_sizes, method=method)
        assert isinstance(t, float) and t > 0.0, method
    assert uvflat.factorization_seconds(positions, corner_verts, face_sizes, method="spectral") is None
    # Unselected or unmappable charts are skipped: nothing selected, nothing factored.
    none = np.zeros(len(face_sizes), dtype=bool)
    assert uvflat.factorization_seconds(positions, corner_verts, face_sizes, selected=none) == 0.0
    with pytest.raises(uvflat.SeamError):
        uvflat.factorization_seconds(positions, corner_verts, face_sizes, seams=[[0, 10**6]])


# ---------------------------------------------------------------------------------------------
# ABF prescribed angle sums


def polar_disk(rings: int, n: int):
    """Planar disk of radius 1: a centre vertex and `rings` rings of `n` vertices each (ring r
    turned by half a step against ring r-1), triangulated counter-clockwise. The outer ring is
    vertices (rings-1)*n+1 ... rings*n."""
    pos = [[0.0, 0.0, 0.0]]
    for r in range(1, rings + 1):
        for k in range(n):
            t = 2 * math.pi * (k + 0.5 * (r % 2)) / n
            pos.append([r / rings * math.cos(t), r / rings * math.sin(t), 0.0])

    def vid(r, k):
        return 0 if r == 0 else 1 + (r - 1) * n + k % n

    faces = [[0, vid(1, k), vid(1, k + 1)] for k in range(n)]
    for r in range(1, rings):
        for k in range(n):
            if r % 2:  # ring r is turned by +half a step: ring r+1 vertex k sits below it
                faces += [[vid(r, k), vid(r + 1, k + 1), vid(r, k + 1)], [vid(r, k), vid(r + 1, k), vid(r + 1, k + 1)]]
            else:
                faces += [[vid(r, k), vid(r + 1, k), vid(r, k + 1)], [vid(r, k + 1), vid(r + 1, k), vid(r + 1, k + 1)]]
    cv = np.array([v for f in faces for v in f], dtype=np.int64)
    return np.array(pos), cv, np.full(len(faces), 3, dtype=np.int64)


def vertex_uv(cv, uv):
    """UV of every vertex (meshes without seams: all corners of a vertex agree)."""
    out = np.zeros((cv.max() + 1, 2))
    out[cv] = uv
    return out


def uv_angle_sums(cv, fs, uv):
    """Angle sum of the UV map at every vertex, over the corners of triangle faces."""
    sums = np.zeros(cv.max() + 1)
    tri = cv.reshape(-1, 3)
    q = uv.reshape(-1, 3, 2)
    for k in range(3):
        a, b = q[:, (k + 1) % 3] - q[:, k], q[:, (k + 2) % 3] - q[:, k]
        ang = np.abs(np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(axis=1)))
        np.add.at(sums, tri[:, k], ang)
    return sums


def test_abf_angle_sums_make_a_rectangle():
    rings, n = 5, 24
    pos, cv, fs = polar_disk(rings, n)
    outer = np.arange((rings - 1) * n + 1, rings * n + 1)
    corners = outer[:: n // 4]
    sums = np.where(np.isin(outer, corners), math.pi / 2, math.pi)
    # The prescribed corners, uncut: automatic seams would hold the square to the density rule.
    r = uvflat.unwrap(pos, cv, fs, method="abf", angle_sums=(outer, sums), auto_seams=False)
    (rep,) = r.charts
    assert rep.status == "solved", rep.reason
    assert rep.flips == 0 and not rep.overlap
    # Without the option the outline is round: the option is what makes it a rectangle.
    free = uvflat.unwrap(pos, cv, fs, method="abf")
    assert abs(uv_angle_sums(cv, fs, free.uv)[outer[1]] - math.pi) > 0.05
    got = uv_angle_sums(cv, fs, r.uv)
    assert np.allclose(got[outer], sums, atol=1e-6)
    # Rotated so that the first side is horizontal, every boundary edge is axis-aligned.
    p = vertex_uv(cv, r.uv)[outer]
    d = p[1] - p[0]
    c, s = d / np.hypot(*d)
    q = p @ np.array([[c, -s], [s, c]])
    e = np.roll(q, -1, axis=0) - q
    assert np.all(np.minimum(np.abs(e[:, 0]), np.abs(e[:, 1])) < 1e-6 * np.hypot(e[:, 0], e[:, 1]))


def test_abf_angle_sum_at_an_interior_vertex_makes_a_cone():
    pos, cv, fs = grid(8, 8, triangles=True)
    v = 4 * 9 + 4  # the centre vertex (4, 4)
    seams = np.array([[4 * 9 + i, 4 * 9 + i + 1] for i in range(4, 8)])  # a slit to the border
    r = uvflat.unwrap(pos, cv, fs, method="abf", seams=seams, angle_sums=([v], [math.pi]))
    (rep,) = r.charts
    assert rep.status == "solved", rep.reason
    assert rep.flips == 0
    assert abs(uv_angle_sums(cv, fs, r.uv)[v] - math.pi) < 1e-6
    # The same slit without the option: the flat angle 2*pi.
    flat = uvflat.unwrap(pos, cv, fs, method="abf", seams=seams)
    assert abs(uv_angle_sums(cv, fs, flat.uv)[v] - 2 * math.pi) < 1e-6


def test_abf_angle_sum_errors():
    pos, cv, fs = grid(3, 3)  # quads: an interior vertex has 4 corners
    cases = [
        (([1000], [1.0]), 0, 1000),
        (([2, -1], [1.0, 1.0]), 1, -1),
        (([5, 6], [1.0, float("nan")]), 1, 6),
        (([5], [0.0]), 0, 5),
        (([5], [-2.0]), 0, 5),
        (([5], [8 * math.pi + 0.1]), 0, 5),
        (([5, 5], [1.0, 2.0]), 1, 5),
    ]
    for sums, entry, vertex in cases:
        with pytest.raises(uvflat.AngleSumError) as ei:
            uvflat.unwrap(pos, cv, fs, method="abf", angle_sums=sums)
        assert isinstance(ei.value, uvflat.OptionError)
        assert ei.value.option == "angle_sums"
        assert (ei.value.entry, ei.value.vertex) == (entry, vertex), (sums, str(ei.value))
        assert str(vertex) in str(ei.value)
    # A sum just below the bound is accepted (it may not be reachable: then ABF falls back).
    uvflat.unwrap(pos, cv, fs, method="abf", angle_sums=([5], [8 * math.pi - 0.1]))
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="lscm", angle_sums=([5], [1.0]))
    assert not isinstance(ei.value, uvflat.AngleSumError)
    with pytest.raises(uvflat.OptionError):
        uvflat.unwrap(pos, cv, fs, method="abf", angle_sums=([5], [1.0], [2.0]))
    with pytest.raises(uvflat.InputError):
        uvflat.unwrap(pos, cv, fs, method="abf", angle_sums=([1, 2], [1.0]))


def _outer_loop_is_convex(cv, fs, uv, faces):
    """Whether the outer boundary loop of the UV chart made of `faces` is convex: every chart
    UV lies left of (or on) every edge of the loop of largest signed area."""
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    key = lambda c: (int(cv[c]), round(float(uv[c, 0]), 9), round(float(uv[c, 1]), 9))
    edges = {}
    for f in faces:
        cs = list(range(starts[f], starts[f] + fs[f]))
        for i, c in enumerate(cs):
            edges[key(c)] = edges.get(key(c), []) + [key(cs[(i + 1) % len(cs)])]
    directed = {(a, b) for a, bs in edges.items() for b in bs}
    nxt = {a: b for (a, b) in directed if (b, a) not in directed}
    loops, seen = [], set()
    for a in nxt:
        if a in seen:
            continue
        loop = [a]
        seen.add(a)
        while nxt[loop[-1]] != a:
            loop.append(nxt[loop[-1]])
            seen.add(loop[-1])
        loops.append(np.array([[p[1], p[2]] for p in loop]))
    area = lambda q: 0.5 * np.sum(q[:, 0] * np.roll(q[:, 1], -1) - np.roll(q[:, 0], -1) * q[:, 1])
    outer = max(loops, key=area)
    pts = np.array([[p[1], p[2]] for p in edges])
    scale = np.ptp(pts, axis=0).max()
    for a, b in zip(outer, np.roll(outer, -1, axis=0)):
        d = b - a
        side = d[0] * (pts[:, 1] - a[1]) - d[1] * (pts[:, 0] - a[0])
        if side.min() < -1e-9 * scale * scale:
            return False
    return True


def test_abf_convex_boundary_on_suzanne_with_her_seams():
    """Suzanne (Blender's primitive) cut along the seams of her own UV islands: with
    boundary="convex" every chart is solved by ABF, has no flipped triangle and no boundary
    self-overlap, and its outer UV outline is convex (with a free boundary it is not)."""
    pytest.importorskip("bpy")
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("bs_common", Path(__file__).parent.parent / "blender_scripts" / "common.py")
    common = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(common)
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    me = common.suzanne().data
    pos = np.array([v.co[:] for v in me.vertices])
    cv = np.array([l.vertex_index for l in me.loops])
    fs = np.array([p.loop_total for p in me.polygons])
    seams = np.array([e.vertices[:] for e in me.edges if e.use_seam])
    assert len(seams) > 0
    convex_somewhere = False
    for boundary in ("free", "convex"):
        r = uvflat.unwrap(pos, cv, fs, method="abf", seams=seams, boundary=boundary, auto_seams=False)
        assert len(r.charts) >= 2
        for rep in r.charts:
            faces = np.flatnonzero(r.chart == rep.id)
            convex = _outer_loop_is_convex(cv, fs, r.uv, faces)
            if boundary == "convex":
                assert rep.status == "solved", rep.reason
                assert rep.flips == 0 and not rep.overlap, rep.as_dict()
                assert convex, rep.id
            else:
                convex_somewhere |= not convex
    assert convex_somewhere, "the free boundary should leave some outline non-convex"


# ---------------------------------------------------------------------------------------------
# Option errors, documentation, degenerate charts, non-manifold edges, per-face distortion


def test_unknown_option_names_the_keyword():
    pos, cv, fs = grid(2, 2)
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="tutte", frobnicate=True)
    assert ei.value.option == "frobnicate"
    assert "frobnicate" in str(ei.value) and "options" not in str(ei.value)
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="lscm", max_iterations=3)
    assert ei.value.option == "max_iterations"


def test_help_shows_signature_and_documentation():
    import inspect
    import pydoc

    sig = inspect.signature(uvflat.unwrap)
    assert list(sig.parameters)[:3] == ["positions", "corner_verts", "face_sizes"]
    assert sig.parameters["method"].default == "abf"
    assert sig.parameters["method"].kind is inspect.Parameter.KEYWORD_ONLY
    text = pydoc.render_doc(uvflat.unwrap, renderer=pydoc.plaintext)
    assert "See the package documentation" not in text
    for word in ("positions", "fit_to", "OptionError", *uvflat.METHODS):
        assert word in text, f"help(uvflat.unwrap) does not mention {word}"


def _stub_unwrap_options():
    """Methods and option names listed by the .pyi stub (parsed, not imported)."""
    import ast
    from pathlib import Path

    stub = Path(uvflat.__file__).with_name("__init__.pyi")
    tree = ast.parse(stub.read_text())
    methods, options = None, None
    for node in tree.body:
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "Method":
            methods = [e.value for e in node.value.slice.elts]
        if isinstance(node, ast.ClassDef) and node.name == "UnwrapOptions":
            options = [n.target.id for n in node.body if isinstance(n, ast.AnnAssign)]
    return methods, options


# One valid value of every option keyword, for the methods that take it.
_OPTION_SAMPLES = {
    "boundary": {"tutte": "square", "harmonic": "circle", "mean_value": "virtual",
                 "abf": "convex"},
    "max_iterations": dict.fromkeys(("spectral", "abf", "arap", "slim", "mips", "scaffold"), 3),
    "tolerance": dict.fromkeys(("spectral", "abf", "arap", "slim", "mips", "scaffold"), 1e-3),
    "solver": {"abf": "abf"},
    "angle_sums": {"abf": ([0], [math.pi / 2])},
    "start": {"slim": "mean_value"},
    "step": {"slim": "proxy"},
}


def test_stub_lists_every_method_and_option():
    methods, options = _stub_unwrap_options()
    assert methods is not None and options is not None, "the stub lost Method / UnwrapOptions"
    assert set(methods) == set(uvflat.METHODS)
    assert set(options) == set(_OPTION_SAMPLES)
    pos, cv, fs = grid(2, 2, triangles=True)
    for name, per_method in _OPTION_SAMPLES.items():
        for method in uvflat.METHODS:
            kwargs = {name: per_method[method]} if method in per_method else {name: 1}
            if method in per_method:
                uvflat.unwrap(pos, cv, fs, method=method, **kwargs)  # accepted
            else:
                with pytest.raises(uvflat.OptionError) as ei:
                    uvflat.unwrap(pos, cv, fs, method=method, **kwargs)
                assert ei.value.option == name


@pytest.mark.parametrize("method", ["tutte", "lscm", "abf", "slim"])
def test_zero_area_triangle_is_a_flip_never_nan(method):
    # Three collinear vertices: the triangle has no 3D area; its area-normalised UV
    # triangle has none either, so the report, metrics and docs count it as a flip.
    pos = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    r = uvflat.unwrap(pos, [0, 1, 2], [3], method=method)
    c = r.charts[0]
    if c.status == "failed":
        assert c.reason
        return
    assert c.flips == 1
    assert not math.isnan(c.conformal) and not math.isnan(c.area)
    m = uvflat.metrics(pos, [0, 1, 2], [3], r.uv)
    assert m.flips == 1 and not math.isnan(m.conformal)


def test_zero_area_triangle_has_no_weight_in_a_chart():
    # A flat grid plus one collinear sliver sharing an edge: the grid's distortion is 1, and
    # the sliver (weight 0) neither adds NaN nor changes it.
    pos, cv, fs = grid(3, 3, triangles=True)
    pos = np.vstack([pos, [[1.5, 0.0, 0.0]]])
    cv = np.concatenate([cv, [1, len(pos) - 1, 2]])
    fs = np.concatenate([fs, [3]])
    uv = pos[cv, :2].copy()
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.flips == 1  # the sliver's UV triangle has zero area
    assert m.conformal == pytest.approx(1.0) and m.area == pytest.approx(1.0)


def test_non_manifold_edges_are_counted():
    # Three triangles on edge 0-1 (a fin) and one more on edge 2-3 of a separate pair.
    pos = np.array([[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0], [0.5, 0, 1]], float)
    cv = [0, 1, 2, 1, 0, 3, 0, 1, 4]
    r = uvflat.unwrap(pos, cv, [3, 3, 3], method="lscm")
    assert r.non_manifold_edges == 1
    assert len(r.charts) == 3
    assert r.as_dict()["non_manifold_edges"] == 1
    pos, cv, fs = grid(3, 3)
    assert uvflat.unwrap(pos, cv, fs).non_manifold_edges == 0


def test_edges_between_opposite_normals_are_counted():
    # A Möbius strip (one-sided): the closing quad runs edge 0-1 the way the first one does.
    n = 40
    t = 2 * np.pi * np.arange(n) / n
    s = np.array([-0.3, 0.3])
    r = 1 + s[None, :] * np.cos(t / 2)[:, None]
    pos = np.stack([r * np.cos(t)[:, None], r * np.sin(t)[:, None],
                    s[None, :] * np.sin(t / 2)[:, None]], axis=-1).reshape(-1, 3)
    i = np.arange(n - 1)
    cv = np.concatenate([np.stack([2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2], 1).ravel(),
                         [2 * n - 2, 2 * n - 1, 0, 1]])
    res = uvflat.unwrap(pos, cv, np.full(n, 4), method="abf")
    assert res.inconsistent_edges == 1 and res.as_dict()["inconsistent_edges"] == 1
    assert [c.kind for c in res.charts] == ["disk"] and res.charts[0].flips == 0
    # Wound consistently (the closing quad turned), it is an open cylinder: nothing counted.
    cv[-4:] = [2 * n - 2, 2 * n - 1, 1, 0]
    assert uvflat.unwrap(pos, cv, np.full(n, 4), method="abf").inconsistent_edges == 0


def test_metrics_per_face_distortion():
    # Stretch a planar grid by 2 along x in UV: every face has sigma1/sigma2 = 2 and, after
    # area normalisation, sigma1*sigma2 = 1.
    pos, cv, fs = grid(3, 2)
    uv = pos[cv, :2] * [2.0, 1.0]
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.face_conformal.shape == (len(fs),) and m.face_area.shape == (len(fs),)
    np.testing.assert_allclose(m.face_conformal, 2.0)
    np.testing.assert_allclose(m.face_area, 1.0)
    # Unselected faces are not measured: NaN.
    sel = np.ones(len(fs), dtype=bool)
    sel[-1] = False
    m = uvflat.metrics(pos, cv, fs, pos[cv, :2], selected=sel)
    assert np.isnan(m.face_conformal[-1]) and np.isnan(m.face_area[-1])
    np.testing.assert_allclose(m.face_conformal[:-1], 1.0)
    # The area-weighted mean of the per-face values is the whole-map value.
    rng = np.random.default_rng(1)
    uv = (pos[:, :2] + rng.normal(scale=0.05, size=(len(pos), 2)))[cv]
    m = uvflat.metrics(pos, cv, fs, uv)
    assert m.charts == 1 and np.ptp(m.face_conformal) > 1e-3
    # (equal face areas: the mean of the faces is the area-weighted mean)
    np.testing.assert_allclose(np.mean(m.face_conformal), m.conformal, rtol=1e-9)
    np.testing.assert_allclose(np.mean(m.face_area), m.area, rtol=1e-9)


# ---------------------------------------------------------------------------------------------
# Progress and cancel


def _disks(n):
    """``n`` separate flat grids: ``n`` charts."""
    pos, cv, fs = grid(4, 4)
    return (np.vstack([pos + [10.0 * k, 0, 0] for k in range(n)]),
            np.concatenate([cv + k * len(pos) for k in range(n)]), np.tile(fs, n))


def test_progress_reports_to_the_last_chart_and_changes_nothing():
    pos, cv, fs = _disks(6)
    calls = []
    r = uvflat.unwrap(pos, cv, fs, progress=lambda done, total: calls.append((done, total)))
    plain = uvflat.unwrap(pos, cv, fs)
    np.testing.assert_array_equal(r.uv, plain.uv)
    assert calls and calls[-1] == (6, 6) or (6, 6) in calls, calls
    assert all(total == 6 and 1 <= done <= 6 for done, total in calls)


def test_progress_returning_false_cancels():
    pos, cv, fs = _disks(5)
    with pytest.raises(uvflat.Cancelled) as ei:
        uvflat.unwrap(pos, cv, fs, progress=lambda done, total: False)
    assert isinstance(ei.value, uvflat.UvflatError)
    assert ei.value.charts_total == 5 and 1 <= ei.value.charts_done <= 5


def test_progress_exception_is_re_raised():
    pos, cv, fs = _disks(3)

    def boom(done, total):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        uvflat.unwrap(pos, cv, fs, progress=boom)
    with pytest.raises(uvflat.InputError) as ei:
        uvflat.unwrap(pos, cv, fs, progress=42)
    assert ei.value.argument == "progress"


def test_cancel_from_another_thread_stops_an_iterative_method():
    # A curved disk under ARAP with no tolerance and a huge budget: only the cancel stops it.
    pos, cv, fs = grid(40, 40, triangles=True, size=0.05)
    pos[:, 2] = np.sin(3 * pos[:, 0]) * np.cos(3 * pos[:, 1])
    stop = threading.Event()
    threading.Timer(0.5, stop.set).start()
    import time

    t0 = time.perf_counter()
    with pytest.raises(uvflat.Cancelled):
        uvflat.unwrap(pos, cv, fs, method="arap", max_iterations=10**9, tolerance=0.0,
                      progress=lambda done, total: not stop.is_set())
    assert time.perf_counter() - t0 < 30


# ---------------------------------------------------------------------------------------------
# One contract for options: METHOD_OPTIONS


def test_method_options_are_declared_for_every_method_and_accepted():
    assert set(uvflat.METHOD_OPTIONS) == set(uvflat.METHODS)
    pos, cv, fs = grid(2, 2, triangles=True)
    for method, specs in uvflat.METHOD_OPTIONS.items():
        for spec in specs:
            assert set(spec) == {"name", "type", "default", "min", "max", "min_exclusive",
                                 "max_exclusive", "choices", "doc"} and spec["doc"]
            if spec["type"] == "vertex_values":
                continue
            # the declared default is accepted, and a value outside the domain is refused
            uvflat.unwrap(pos, cv, fs, method=method, **{spec["name"]: spec["default"]})
            bad = {"int": (spec["min"] or 0) - 1, "float": -1.0, "choice": "no such choice"}
            with pytest.raises(uvflat.OptionError) as ei:
                uvflat.unwrap(pos, cv, fs, method=method, **{spec["name"]: bad[spec["type"]]})
            assert ei.value.option == spec["name"]


def test_stub_and_docstring_follow_method_options():
    methods, options = _stub_unwrap_options()
    declared = {s["name"] for specs in uvflat.METHOD_OPTIONS.values() for s in specs}
    assert set(options) == declared
    doc = uvflat.unwrap.__doc__
    for method, specs in uvflat.METHOD_OPTIONS.items():
        assert method in doc
        for s in specs:
            assert s["name"] in doc, f"help(uvflat.unwrap) does not document {method}'s {s['name']}"
            if s["type"] in ("int", "float"):
                d = s["default"]
                spelled = {str(d), f"{d:g}", f"{d:.0e}".replace("e-0", "e-")}
                assert any(f"default {x}" in doc for x in spelled), \
                    f"{method}.{s['name']} default {d} not documented"
            if s["type"] == "choice":
                assert f'"{s["default"]}" (default)' in doc, f"{method}.{s['name']}"


def test_reason_codes_are_stable():
    pos, cv, fs = grid(3, 3)
    r = uvflat.unwrap(pos, cv, fs)
    assert [c.reason_code for c in r.charts] == ["solved"]
    assert r.charts[0].as_dict()["reason_code"] == "solved"
    pos, cv, fs = cube()
    c = uvflat.unwrap(pos, cv, fs, auto_seams=False).charts[0]
    assert c.status == "failed" and c.reason_code == "failed_closed" and c.reason


def test_every_wrong_argument_type_is_a_typed_error():
    """A value of the wrong type for any argument raises a uvflat error (never a bare
    TypeError): OptionError for the method and its options, InputError for arrays."""
    pos, cv, fs = grid(2, 2)
    for bad in (3, 2.5, b"lscm", ["lscm"], object()):
        for call in (uvflat.unwrap, uvflat.factorization_seconds):
            with pytest.raises(uvflat.OptionError) as ei:
                call(pos, cv, fs, method=bad)
            assert ei.value.option == "method"
            assert type(bad).__name__ in str(ei.value)
    # None is the default method.
    assert all(c.method == "lscm" for c in uvflat.unwrap(pos, cv, fs, method=None).charts)
    for bad in (object(), {"a": 1}, "abc", None, 3.5):
        with pytest.raises(uvflat.InputError):
            uvflat.unwrap(bad, cv, fs)
        with pytest.raises(uvflat.InputError):
            uvflat.unwrap(pos, bad, fs)
        with pytest.raises(uvflat.InputError):
            uvflat.metrics(pos, cv, fs, bad)
    for kw in ("seams", "selected", "fit_to"):
        with pytest.raises(uvflat.InputError) as ei:
            uvflat.unwrap(pos, cv, fs, **{kw: object()})
        assert ei.value.argument == kw
    with pytest.raises(uvflat.InputError):
        uvflat.unwrap(pos, cv, fs, pins=object(), pin_uvs=[[0.0, 0.0]])
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="slim", max_iterations="many")
    assert ei.value.option == "max_iterations"
    with pytest.raises(uvflat.OptionError) as ei:
        uvflat.unwrap(pos, cv, fs, method="slim", tolerance=object())
    assert ei.value.option == "tolerance"


def test_fit_to_ignores_unselected_corners_and_never_collapses_a_mirrored_chart():
    pos, cv, fs = grid(3, 3)
    flat = pos[cv][:, :2].astype(float)
    selected = np.ones(len(fs), dtype=bool)
    selected[-1] = False
    prev = flat.copy()
    prev[-4:] = np.nan  # the corners of the unselected last face
    r = uvflat.unwrap(pos, cv, fs, selected=selected, fit_to=prev)
    assert all(c.status == "solved" for c in r.charts)
    assert np.isfinite(r.uv).all()
    # Mirrored previous UVs: the island keeps its size (area-scaled) and says so.
    mirrored = flat * [-1.0, 1.0]
    r = uvflat.unwrap(pos, cv, fs, fit_to=mirrored)
    (c,) = r.charts
    assert c.status == "solved" and c.flips == 0
    assert "area-scaled" in c.reason
    width = np.ptp(r.uv[:, 0])
    assert abs(width - 3.0) < 1e-9, width


@pytest.mark.parametrize("method", ["lscm", "abf", "slim", "tutte"])
def test_result_carries_the_per_face_distortion_of_its_uvs(method):
    # A bumpy quad grid (non-planar, so distortion varies per face), a seam splitting it in
    # two charts, and a few faces left unselected.
    pos, cv, fs = grid(8, 6)
    pos = np.asarray(pos, dtype=float).copy()
    pos[:, 2] = 0.3 * np.sin(3.0 * pos[:, 0]) * np.cos(2.0 * pos[:, 1])
    seams = np.array([[4 + 9 * j, 4 + 9 * (j + 1)] for j in range(6)])
    selected = np.ones(len(fs), dtype=bool)
    selected[[0, 1, 10]] = False
    r = uvflat.unwrap(pos, cv, fs, method=method, seams=seams, selected=selected, auto_seams=False)
    solved = np.asarray(r.face_solved)
    assert solved.sum() == selected.sum() and len(r.charts) == 2
    m = uvflat.metrics(pos, cv, fs, r.uv, selected=solved)
    for got, want in [(r.face_conformal, m.face_conformal), (r.face_area, m.face_area)]:
        got, want = np.asarray(got), np.asarray(want)
        assert got.shape == (len(fs),)
        assert np.all(np.isnan(got[~solved]))
        assert np.all(np.isfinite(got[solved])) and np.all(got[solved] >= 1.0)
        np.testing.assert_allclose(got[solved], want[solved], rtol=1e-9)
    assert np.ptp(np.asarray(r.face_area)[solved]) > 1e-3  # the measure is not constant
    d = r.as_dict()
    np.testing.assert_array_equal(d["face_conformal"], r.face_conformal)


# Island hulls (the packer's view of each island)


def _check_hull(points, hull):
    """``hull``: strictly convex, counter-clockwise, made of input points, holding them all."""
    n = len(hull)
    assert n >= 3
    for i in range(n):
        a, b, c = hull[i], hull[(i + 1) % n], hull[(i + 2) % n]
        assert (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) > 0.0
        edge = (b[0] - a[0]) * (points[:, 1] - a[1]) - (b[1] - a[1]) * (points[:, 0] - a[0])
        assert np.all(edge >= -1e-12)
    assert all(np.any(np.all(points == v, axis=1)) for v in hull)


@pytest.mark.parametrize("seed", range(5))
def test_island_hulls_hold_every_corner_of_their_island(seed):
    rng = np.random.default_rng(seed)
    face_sizes = rng.integers(3, 7, size=300)
    n_islands = 7
    face_island = rng.integers(0, n_islands, size=len(face_sizes))
    selected = rng.random(len(face_sizes)) > 0.2
    uv = rng.normal(size=(int(face_sizes.sum()), 2)).astype(np.float32)  # as Blender stores them
    offsets, points = uvflat.island_hulls(uv, face_sizes, face_island, selected=selected)
    assert offsets.shape == (n_islands + 1,) and points.shape == (offsets[-1], 2)
    corner_island = np.repeat(np.where(selected, face_island, -1), face_sizes)
    for k in range(n_islands):
        mine = uv[corner_island == k].astype(np.float64)
        _check_hull(mine, points[offsets[k]:offsets[k + 1]])


def test_island_hulls_report_islands_without_area_and_bad_input():
    face_sizes = np.array([3, 3, 4])
    uv = np.array([[0, 0], [1, 0], [0, 1],          # island 0: a triangle
                   [0, 0], [1, 1], [2, 2],          # island 1: collinear
                   [0, 0], [1, 0], [np.nan, 1], [0, 1]])  # island 2: a non-finite UV
    offsets, points = uvflat.island_hulls(uv, face_sizes, np.array([0, 1, 2]))
    assert list(np.diff(offsets)) == [3, 0, 0]
    with pytest.raises(uvflat.InputError, match="face 2"):
        uvflat.island_hulls(uv, face_sizes, np.array([0, 1, 3]))
    with pytest.raises(uvflat.InputError) as err:
        uvflat.island_hulls(uv[:9], face_sizes, np.array([0, 1, 2]))
    assert err.value.argument == "uv"
    # a negative island number puts a face in no island, as unwrap's chart of a face it left
    offsets, _ = uvflat.island_hulls(uv, face_sizes, np.array([-1, 0, -1]))
    assert list(np.diff(offsets)) == [0]
    with pytest.raises(uvflat.InputError):
        uvflat.island_hulls(uv, face_sizes, np.array([0.0, 1.0, 2.0]))


def test_island_box_angles_number_islands_like_hulls_and_name_bad_input():
    # island 0: a 2 by 1 rectangle turned by 0.3, and a face far out (deselected below);
    # island 1: collinear; island 2: a non-finite UV
    c, s = np.cos(0.3), np.sin(0.3)
    rect = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float) @ np.array([[c, s], [-s, c]])
    uv = np.vstack([rect, [[5, 0], [6, 0], [5, 3]],
                    [[0, 0], [1, 1], [2, 2]], [[0, 0], [1, 0], [np.nan, 1]]])
    face_sizes = np.array([4, 3, 3, 3])
    face_island = np.array([0, 0, 1, 2])
    selected = np.array([True, False, True, True])
    angles = uvflat.island_box_angles(uv, face_sizes, face_island, selected=selected)
    offsets, _ = uvflat.island_hulls(uv, face_sizes, face_island, selected=selected)
    assert angles.dtype == np.float64 and angles.shape == (len(offsets) - 1,) == (3,)
    assert angles[0] == pytest.approx(-0.3, abs=1e-12)
    assert angles[1:].tolist() == [0.0, 0.0]
    # the face far out belongs to island 0 unless deselected: another hull, another angle
    assert abs(uvflat.island_box_angles(uv, face_sizes, face_island)[0] + 0.3) > 1e-3
    assert uvflat.island_box_angles(uv.astype(np.float32), face_sizes, face_island,
                                    selected=selected)[0] == pytest.approx(-0.3, abs=1e-6)

    bad = [
        ((uv[:12], face_sizes, face_island), {}, "uv"),
        ((uv, face_sizes, face_island[:3]), {}, "face_island"),
        ((uv, face_sizes, face_island.astype(float)), {}, "face_island"),
        ((uv, np.array([4, 3, -3, 3]), face_island), {}, "face_sizes"),
        ((uv, face_sizes, face_island), {"selected": selected[:3]}, "selected"),
        ((uv[:, :1], face_sizes, face_island), {}, "uv"),
    ]
    for args, kwargs, argument in bad:
        with pytest.raises(uvflat.InputError) as err:
            uvflat.island_box_angles(*args, **kwargs)
        assert err.value.argument == argument, (argument, str(err.value))
        # the same arguments are checked the same way for island_hulls
        with pytest.raises(uvflat.InputError) as hull_err:
            uvflat.island_hulls(*args, **kwargs)
        assert str(hull_err.value) == str(err.value)
    with pytest.raises(uvflat.InputError, match="face 3"):
        uvflat.island_box_angles(uv, face_sizes, np.array([0, 0, 1, 4]))


@pytest.mark.parametrize("falsy", [np.False_, 0, "", 0.0])
def test_any_false_progress_value_cancels(falsy):
    pos, cv, fs = _disks(5)
    with pytest.raises(uvflat.Cancelled):
        uvflat.unwrap(pos, cv, fs, progress=lambda done, total: falsy)


@pytest.mark.parametrize("truthy", [None, True, np.True_, 1])
def test_none_or_true_progress_values_go_on(truthy):
    pos, cv, fs = _disks(5)
    r = uvflat.unwrap(pos, cv, fs, progress=lambda done, total: truthy)
    assert len(r.charts) == 5


def test_plan_seams_are_the_seams_unwrap_adds():
    pos, cv, fs = cube()
    for method in ("abf", "slim"):
        planned = uvflat.plan_seams(pos, cv, fs, method=method)
        r = uvflat.unwrap(pos, cv, fs, method=method)
        assert planned.dtype == np.uint32 and planned.shape[1] == 2 and len(planned) > 0
        np.testing.assert_array_equal(planned, r.new_seams)
    assert len(uvflat.plan_seams(pos, cv, fs, auto_seams=False)) == 0


def _density_outside(pos, cv, fs, uv, chart, bound=2.0):
    """Share of 3D area outside [1/bound, bound] of its island's density (fan triangles)."""
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    num = den = 0.0
    tris = [(f, starts[f], starts[f] + k, starts[f] + k + 1) for f in range(len(fs)) for k in range(1, fs[f] - 1)]
    a3 = {}
    a2 = {}
    for f, a, b, c in tris:
        p = pos[cv[[a, b, c]]]
        q = uv[[a, b, c]]
        a3[(f, b)] = 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))
        e1, e2 = q[1] - q[0], q[2] - q[0]
        a2[(f, b)] = 0.5 * (e1[0] * e2[1] - e1[1] * e2[0])
    for island in np.unique(chart):
        keys = [k for k in a3 if chart[k[0]] == island]
        s3 = sum(a3[k] for k in keys)
        s2 = sum(a2[k] for k in keys)
        sign = 1.0 if s2 >= 0 else -1.0
        s2 = sum(max(sign * a2[k], 0.0) for k in keys)
        for k in keys:
            r = max(sign * a2[k], 0.0) / a3[k] / (s2 / s3)
            if not (1 / bound <= r <= bound):
                num += a3[k]
        den += s3
    return num / den


def test_density_spread_matches_its_definition():
    # A bumpy grid whose LSCM map stretches: the reported share equals the definition's.
    pos, cv, fs = grid(8, 6, triangles=True)
    pos = np.asarray(pos, dtype=float).copy()
    pos[:, 2] = 1.2 * np.sin(3.0 * pos[:, 0]) * np.cos(2.0 * pos[:, 1])
    r = uvflat.unwrap(pos, cv, fs, method="lscm", auto_seams=False)
    want = _density_outside(pos, cv, fs, r.uv, np.asarray(r.chart), bound=2.0)
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert abs(m.density_outside - want) < 1e-9, (m.density_outside, want)
    assert m.density_p5 <= 1.0 <= m.density_p95
    assert abs(r.charts[0].density_outside - want) < 1e-9  # the report, against max_stretch = 2
    assert abs(m.per_chart[0]["density_outside"] - want) < 1e-9
    # A tighter bound counts at least as much.
    r3 = uvflat.unwrap(pos, cv, fs, method="lscm", auto_seams=False, max_stretch=1.2)
    assert r3.charts[0].density_outside >= want


def test_phases_account_for_the_pipeline():
    pos, cv, fs = cube()
    r = uvflat.unwrap(pos, cv, fs, method="abf")
    p = r.phases
    parts = {"cut_state", "cone_placement", "split_plans", "cut_graphs"}
    assert set(p) == {"build_charts", "plan_cuts", "solve", "repair_solve", "measure",
                      "predicted_rounds", "repair_rounds", "repair_pieces", "splits", "predicted_splits",
                      "far_splits", "crease_cuts", "parts", "peels", "last_resort", "glue",
                      "glued", "holes_filled", "fill_undone"} | parts
    assert all(v >= 0 for v in p.values())
    # The parts of plan_cuts add up to it; a cube planned on the prediction has cutting state,
    # placed cones and cut graphs.
    assert sum(p[k] for k in parts) == pytest.approx(p["plan_cuts"], rel=1e-9, abs=1e-12)
    assert p["cut_state"] > 0 and p["cone_placement"] > 0 and p["cut_graphs"] > 0
    # Every piece of the cube keeps the rule with ABF: nothing handed to scaffold.
    assert p["last_resort"] == 0 and all(c.method == "abf" for c in r.charts)
    # A closed cube is cut: planned and solved in at least one repair round.
    assert p["repair_rounds"] >= 1 and p["repair_pieces"] >= 1 and p["plan_cuts"] > 0
    r = uvflat.unwrap(pos, cv, fs, method="abf", auto_seams=False)
    assert r.phases["repair_rounds"] == 0 and r.phases["plan_cuts"] == 0
    assert r.phases["predicted_rounds"] == 0
    # ABF (conformal) plans the cube's cones on the prediction first; SLIM does not.
    assert uvflat.unwrap(pos, cv, fs, method="abf").phases["predicted_rounds"] >= 1
    assert uvflat.unwrap(pos, cv, fs, method="slim").phases["predicted_rounds"] == 0


def test_pieces_still_broken_after_repair_are_mapped_by_scaffold():
    # The cow with holes cut into it, as a scan loses patches: LSCM lays cuts that join a hole
    # to the outline flat on themselves and crushes regions its cones were not planned for, so
    # some pieces break the rule at every split level; each is mapped by scaffold, reported as
    # a fallback naming LSCM, and the whole atlas keeps the rule as measured on the UVs.
    from meshio_util import mesh_path, read_off
    pos, cv, fs = read_off(mesh_path("cow.off"))
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    faces = [tuple(cv[a:a + n]) for a, n in zip(starts, fs)]
    by_edge = {}
    for f, face in enumerate(faces):
        for a, b in zip(face, face[1:] + face[:1]):
            by_edge.setdefault((min(a, b), max(a, b)), []).append(f)
    dead = set()
    for seed in (11, 1800, 2900, 4100, 5000):
        queue, taken = [seed], {seed}
        while queue and len(taken) < 60:
            face = faces[queue.pop(0)]
            for a, b in zip(face, face[1:] + face[:1]):
                for g in by_edge[(min(a, b), max(a, b))]:
                    if g not in taken and len(taken) < 60:
                        taken.add(g)
                        queue.append(g)
        dead |= taken
    keep = [f for f in range(len(faces)) if f not in dead]
    cv2 = np.concatenate([cv[starts[f]:starts[f] + fs[f]] for f in keep])
    fs2 = fs[keep]
    r = uvflat.unwrap(pos, cv2, fs2, method="lscm")
    fell_back = [c for c in r.charts if c.method == "scaffold"]
    assert fell_back, "the test mesh should make LSCM break the rule somewhere"
    assert r.phases["last_resort"] >= len(fell_back)
    for c in fell_back:
        assert c.status == "fallback" and c.reason_code == "fallback"
        assert c.reason.startswith("lscm broke the atlas rule") and "scaffold" in c.reason
    assert all(c.status in ("solved", "fallback") for c in r.charts), [c.reason for c in r.charts]
    m = uvflat.metrics(pos, cv2, fs2, r.uv)
    assert m.flips == 0 and m.overlapping_charts == 0
    assert max(c.density_outside for c in r.charts) <= 0.05
    # Without automatic seams nothing is replaced: a broken island says so.
    r = uvflat.unwrap(pos, cv2, fs2, method="lscm", auto_seams=False)
    assert r.phases["last_resort"] == 0 and all(c.method == "lscm" for c in r.charts)
