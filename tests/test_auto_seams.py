"""Automatic seams through the Python API: closed and higher-genus meshes unwrap completely.

Every check follows from topology or from the API's own contract (each face gets UVs, new
seams are real mesh edges, avoided vertices stay free of seams, options are type- and
range-checked), never from stored numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import uvflat
from meshio_util import read_mesh

from test_api import cube

PROMISING = ("tutte", "mean_value", "abf", "slim", "mips", "scaffold")


def uv_sphere(n_lon: int = 24, n_lat: int = 12):
    """Closed UV sphere: quads with triangle fans at the poles."""
    pos = [[0.0, 0.0, 1.0]]
    for j in range(1, n_lat):
        t = math.pi * j / n_lat
        for i in range(n_lon):
            p = 2 * math.pi * i / n_lon
            pos.append([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])
    pos.append([0.0, 0.0, -1.0])
    south = len(pos) - 1

    def ring(j, i):
        return 1 + (j - 1) * n_lon + (i % n_lon)

    faces = []
    for i in range(n_lon):
        faces.append([0, ring(1, i), ring(1, i + 1)])
    for j in range(1, n_lat - 1):
        for i in range(n_lon):
            faces.append([ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)])
    for i in range(n_lon):
        faces.append([south, ring(n_lat - 1, i + 1), ring(n_lat - 1, i)])
    cv = np.array([v for f in faces for v in f], dtype=np.int64)
    fs = np.array([len(f) for f in faces], dtype=np.int64)
    return np.array(pos), cv, fs


def mesh_edges(cv, fs):
    edges = set()
    start = 0
    for n in fs:
        f = cv[start:start + n]
        for k in range(n):
            a, b = int(f[k]), int(f[(k + 1) % n])
            edges.add((min(a, b), max(a, b)))
        start += n
    return edges


@pytest.mark.parametrize("method", uvflat.METHODS)
def test_closed_cube_unwraps_every_face_with_every_method(method):
    pos, cv, fs = cube()
    r = uvflat.unwrap(pos, cv, fs, method=method)
    assert r.face_solved.all(), [c.reason for c in r.charts]
    assert np.all(np.isfinite(r.uv))
    seams = r.new_seams
    assert seams.dtype == np.uint32 and seams.ndim == 2 and seams.shape[1] == 2 and len(seams) > 0
    assert np.all(seams[:, 0] < seams[:, 1])
    assert {tuple(map(int, s)) for s in seams} <= mesh_edges(cv, fs), "a new seam is not a mesh edge"
    # Cut through at least two cones, or split into pieces when cones were not enough
    # (a fixed-boundary method stretches a cube's single disk beyond the area bound).
    assert sum(c.cones for c in r.charts) >= 2 or len(r.charts) > 1
    assert sum(c.cut_length for c in r.charts) > 0
    for c in r.charts:
        assert c.kind == "disk"
        if method in PROMISING and c.status == "solved":
            assert c.flips == 0, (method, c)


def test_new_seams_as_input_reproduce_the_cut_without_new_seams():
    pos, cv, fs = uv_sphere()
    first = uvflat.unwrap(pos, cv, fs, method="abf")
    again = uvflat.unwrap(pos, cv, fs, method="abf", seams=first.new_seams)
    assert len(again.new_seams) == 0
    assert again.face_solved.all()
    np.testing.assert_array_equal(again.chart, first.chart)
    assert [c.cones for c in again.charts] == [0] * len(again.charts)


def test_avoided_vertices_stay_free_of_seams():
    pos, cv, fs = uv_sphere()
    avoid = np.flatnonzero(pos[:, 2] > 0.2)
    r = uvflat.unwrap(pos, cv, fs, method="slim", avoid_vertices=avoid)
    assert r.face_solved.all()
    assert len(r.new_seams) > 0
    assert not np.isin(r.new_seams, avoid).any()


def test_auto_seams_off_keeps_the_refusal():
    pos, cv, fs = uv_sphere()
    r = uvflat.unwrap(pos, cv, fs, auto_seams=False)
    (c,) = r.charts
    assert c.status == "failed" and c.kind == "closed" and "seam" in c.reason
    assert len(r.new_seams) == 0 and r.new_seams.shape == (0, 2)


def test_report_dicts_carry_cones_and_cut_length():
    pos, cv, fs = cube()
    r = uvflat.unwrap(pos, cv, fs)
    d = r.as_dict()
    assert d["new_seams"].shape == r.new_seams.shape
    assert {"cones", "cut_length"} <= set(d["charts"][0])


@pytest.mark.parametrize(
    "kwargs, option",
    [
        ({"max_stretch": 1.0}, "max_stretch"),
        ({"max_stretch": float("nan")}, "max_stretch"),
        ({"max_stretch": "2"}, "max_stretch"),
        ({"max_cones": -1}, "max_cones"),
        ({"max_cones": 2.5}, "max_cones"),
        ({"auto_seams": "yes"}, "auto_seams"),
        ({"sharp_angle": 4.0}, "sharp_angle"),
        ({"sharp_angle": 0.0}, "sharp_angle"),
        ({"avoid_vertices": [0, 99]}, "avoid_vertices"),
        ({"avoid_vertices": [-1]}, "avoid_vertices"),
    ],
)
def test_bad_auto_seam_options_are_option_errors(kwargs, option):
    pos, cv, fs = cube()
    with pytest.raises(uvflat.OptionError) as e:
        uvflat.unwrap(pos, cv, fs, **kwargs)
    assert e.value.option == option, str(e.value)


@pytest.mark.parametrize("name, genus", [("bunny.off", 0), ("3holes.off", 3), ("fertility.off", 4)])
def test_shared_closed_meshes_unwrap_completely(name, genus):
    pos, cv, fs = read_mesh(name)
    off = uvflat.unwrap(pos, cv, fs, auto_seams=False)
    assert max(c.genus for c in off.charts) == genus
    r = uvflat.unwrap(pos, cv, fs, method="abf")
    assert r.face_solved.all()
    assert all(c.flips == 0 and not c.overlap for c in r.charts if c.status == "solved")
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.flips == 0
