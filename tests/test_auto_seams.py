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


# ---------------------------------------------------------------------------------------------
# One contract for the automatic-seams options: AUTO_SEAM_OPTIONS

# unwrap's keywords that are not automatic-seams options
_NOT_AUTO_SEAMS = {"method", "seams", "selected", "pins", "pin_uvs", "fit_to", "triangles",
                   "progress"}


def _stub_keywords(function):
    """Keyword-only arguments of ``function`` in the .pyi stub, with their defaults (parsed,
    not imported)."""
    import ast
    from pathlib import Path

    tree = ast.parse(Path(uvflat.__file__).with_name("__init__.pyi").read_text())
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name == function:
            return {a.arg: ast.literal_eval(d) for a, d in zip(node.args.kwonlyargs,
                                                               node.args.kw_defaults)}
    raise AssertionError(f"the stub lost {function}")


def test_auto_seam_options_are_declared_like_method_options():
    names = [s["name"] for s in uvflat.AUTO_SEAM_OPTIONS]
    assert names == ["auto_seams", "max_stretch", "max_cones", "avoid_vertices", "sharp_angle",
                     "visibility_weight", "symmetry", "same_seams"]
    method_keys = {k for specs in uvflat.METHOD_OPTIONS.values() for s in specs for k in s}
    for s in uvflat.AUTO_SEAM_OPTIONS:
        assert set(s) == method_keys and s["doc"], s
    by_name = {s["name"]: s for s in uvflat.AUTO_SEAM_OPTIONS}
    assert by_name["symmetry"]["choices"] == ("none", "x", "y", "z", "auto")
    assert by_name["symmetry"]["default"] == "none"
    assert by_name["visibility_weight"]["default"] == 1.0
    assert (by_name["visibility_weight"]["min"], by_name["visibility_weight"]["max"]) == (0.0, 100.0)


@pytest.mark.parametrize("function", ["unwrap", "plan_seams"])
def test_auto_seam_options_are_the_keywords_of_unwrap(function):
    """The declared options are exactly the automatic-seams keywords of the Python function, of
    the stub and of the native function, with the declared defaults, and its help names
    each of them."""
    import inspect

    declared = {s["name"]: s["default"] for s in uvflat.AUTO_SEAM_OPTIONS}
    signature = inspect.signature(getattr(uvflat, function)).parameters
    python = {n: p.default for n, p in signature.items()
              if p.kind is inspect.Parameter.KEYWORD_ONLY and n not in _NOT_AUTO_SEAMS}
    assert python == declared
    stub = {n: d for n, d in _stub_keywords(function).items() if n not in _NOT_AUTO_SEAMS}
    assert stub == declared
    native = inspect.signature(uvflat._uvflat.unwrap).parameters
    assert set(declared) <= set(native)
    assert set(native) - set(declared) - _NOT_AUTO_SEAMS == {"positions", "corner_verts",
                                                              "face_sizes", "options"}
    if function == "unwrap":
        for name in declared:
            assert f"{name}:" in uvflat.unwrap.__doc__, f"help(uvflat.unwrap) lacks {name}"


def test_auto_seam_declared_values_are_accepted_and_bounds_refused():
    pos, cv, fs = cube()
    for s in uvflat.AUTO_SEAM_OPTIONS:
        if s["type"] == "vertices" or s["default"] is None:
            continue
        uvflat.unwrap(pos, cv, fs, method="lscm", **{s["name"]: s["default"]})
        bad = {"bool": 1, "int": s["max"] + 1 if s["max"] is not None else -1,
               "float": s["max"] * 2 if s["max"] is not None else s["min"],
               "choice": "no such choice"}[s["type"]]
        with pytest.raises(uvflat.OptionError) as ei:
            uvflat.unwrap(pos, cv, fs, method="lscm", **{s["name"]: bad})
        assert ei.value.option == s["name"], (s, str(ei.value))


@pytest.mark.parametrize(
    "kwargs, option",
    [
        ({"symmetry": "w"}, "symmetry"),
        ({"symmetry": "X"}, "symmetry"),
        ({"symmetry": 3}, "symmetry"),
        ({"visibility_weight": -1}, "visibility_weight"),
        ({"visibility_weight": 101.0}, "visibility_weight"),
        ({"visibility_weight": float("nan")}, "visibility_weight"),
        ({"visibility_weight": "a"}, "visibility_weight"),
        ({"visibility_weight": True}, "visibility_weight"),
        ({"same_seams": 1}, "same_seams"),
        ({"same_seams": "yes"}, "same_seams"),
    ],
)
@pytest.mark.parametrize("function", [uvflat.unwrap, uvflat.plan_seams])
def test_bad_seam_symmetry_and_visibility_are_option_errors(kwargs, option, function):
    pos, cv, fs = cube()
    with pytest.raises(uvflat.OptionError) as e:
        function(pos, cv, fs, **kwargs)
    assert e.value.option == option, str(e.value)
    assert option in str(e.value)


def mirror_of(positions, axis=0):
    """The vertex each vertex is the mirror image of, across the plane through the vertices'
    centroid facing ``axis`` (matched by nearest reflected position; asserts a match)."""
    pos = np.asarray(positions, dtype=float)
    reflected = pos.copy()
    reflected[:, axis] = 2 * pos[:, axis].mean() - reflected[:, axis]
    tol = 1e-5 * np.linalg.norm(np.ptp(pos, axis=0))
    image = np.empty(len(pos), dtype=np.int64)
    for start in range(0, len(pos), 256):
        d = np.linalg.norm(reflected[start:start + 256, None, :] - pos[None, :, :], axis=2)
        image[start:start + 256] = d.argmin(axis=1)
        assert d.min(axis=1).max() < tol, "the mesh is not mirror-symmetric"
    return image


def mirrored(seams, image):
    return {tuple(sorted((int(image[a]), int(image[b])))) for a, b in seams}


def assert_atlas_rule(pos, cv, fs, r):
    """Every face solved; every island a disk without flips or a crossing outline, with at
    most 5% of its area outside [1/2, 2] of its texel density."""
    assert r.face_solved.all(), [c.reason for c in r.charts]
    for c in r.charts:
        assert c.kind == "disk" and c.status == "solved", c
        assert c.flips == 0 and not c.overlap and c.density_outside <= 0.05 + 1e-9, c
    m = uvflat.metrics(pos, cv, fs, r.uv)
    assert m.flips == 0 and m.overlapping_charts == 0


def lopsided_sphere():
    """A closed UV sphere bent so that its only mirror plane is x = 0."""
    pos, cv, fs = uv_sphere(24, 12)
    x, y, z = pos[:, 0], pos[:, 1], pos[:, 2]
    bent = np.column_stack([1.3 * x, y + 0.4 * z * z, 0.9 * z + 0.25 * y * y + 0.2 * y])
    return bent, cv, fs


def test_symmetry_x_mirrors_the_seams_of_a_symmetric_closed_mesh():
    pos, cv, fs = lopsided_sphere()
    image = mirror_of(pos, axis=0)
    assert not np.array_equal(image, np.arange(len(pos)))
    r = uvflat.unwrap(pos, cv, fs, method="abf", symmetry="x")
    assert_atlas_rule(pos, cv, fs, r)
    seams = {tuple(map(int, s)) for s in r.new_seams}
    assert len(seams) > 0
    assert mirrored(seams, image) == seams, "the seams do not map onto themselves"
    # plan_seams passes the option on: the same seams
    planned = uvflat.plan_seams(pos, cv, fs, method="abf", symmetry="x")
    assert {tuple(map(int, s)) for s in planned} == seams
    # a plane the mesh is not symmetric about changes nothing
    plain = uvflat.plan_seams(pos, cv, fs, method="abf")
    assert np.array_equal(uvflat.plan_seams(pos, cv, fs, method="abf", symmetry="z"), plain)


def dented_sphere(n_lon=48, n_lat=24, level=0.2, depth=1.6):
    """A closed UV sphere whose cap above ``level`` is pushed inside: a cup-shaped pocket,
    mostly hidden from view. Returns the mesh and the mask of the pocket's vertices."""
    pos, cv, fs = uv_sphere(n_lon, n_lat)
    pocket = pos[:, 2] > level
    pos[pocket, 2] = level - (pos[pocket, 2] - level) * depth
    return pos, cv, fs, pocket


def test_visibility_weight_moves_seams_into_hidden_places_and_keeps_the_rule():
    pos, cv, fs, pocket = dented_sphere()
    share = {}
    for w in (0.0, 1.0, 100.0):
        r = uvflat.unwrap(pos, cv, fs, method="abf", visibility_weight=w)
        assert_atlas_rule(pos, cv, fs, r)
        s = np.asarray(r.new_seams, dtype=np.int64)
        length = np.linalg.norm(pos[s[:, 0]] - pos[s[:, 1]], axis=1)
        share[w] = length[pocket[s].all(axis=1)].sum() / length.sum()
        if w == 1.0:  # the declared default
            default = {tuple(map(int, x)) for x in uvflat.plan_seams(pos, cv, fs, method="abf")}
            assert {tuple(map(int, x)) for x in s} == default
    # weighing exposure puts more of the seams inside the pocket than ignoring it
    assert share[1.0] > share[0.0] + 0.05, share
    assert share[100.0] > share[0.0] + 0.05, share


def five_armed_sphere(n_lon=64, n_lat=32):
    """A UV sphere pulled out into five arms around its equator: its conformal flattening
    crushes the arms, so the plan of the cuts needs more cones than the methods that even out
    area would add by themselves."""
    pos, cv, fs = uv_sphere(n_lon, n_lat)
    pos = np.array(pos, dtype=float)
    lon = np.arctan2(pos[:, 1], pos[:, 0])
    scale = 1 + 2.0 * np.maximum(0, np.cos(5 * lon)) ** 4 * np.linalg.norm(pos[:, :2], axis=1)
    pos[:, :2] *= scale[:, None]
    return pos, cv, fs


def test_same_seams_gives_the_area_balancing_methods_one_plan_and_off_their_own():
    pos, cv, fs = five_armed_sphere()
    planned = {m: uvflat.plan_seams(pos, cv, fs, method=m, same_seams=True)
               for m in ("slim", "arap", "scaffold")}
    assert len(planned["slim"]) > 0
    assert np.array_equal(planned["slim"], planned["arap"])
    assert np.array_equal(planned["slim"], planned["scaffold"])
    own = uvflat.plan_seams(pos, cv, fs, method="slim")  # off by default
    assert len(own) < len(planned["slim"]), (len(own), len(planned["slim"]))
    # unwrap adds exactly the seams plan_seams gives, and keeps the rule on every island
    r = uvflat.unwrap(pos, cv, fs, method="slim", same_seams=True)
    assert np.array_equal(r.new_seams, planned["slim"])
    assert_atlas_rule(pos, cv, fs, r)
    r = uvflat.unwrap(pos, cv, fs, method="slim", same_seams=False)
    assert np.array_equal(r.new_seams, own)
    assert_atlas_rule(pos, cv, fs, r)


def test_bff_keeps_the_rule_on_the_plan_where_lscm_needs_more_islands():
    """``bff`` is the map the cuts are planned on (u = 0 on the outline), so the planned seams
    hold for it where ``lscm``'s free outline breaks the rule and is cut again."""
    pos, cv, fs = five_armed_sphere()
    r = uvflat.unwrap(pos, cv, fs, method="bff")
    assert_atlas_rule(pos, cv, fs, r)
    assert np.array_equal(r.new_seams, uvflat.plan_seams(pos, cv, fs, method="bff"))
    lscm = uvflat.unwrap(pos, cv, fs, method="lscm")
    abf = uvflat.unwrap(pos, cv, fs, method="abf")
    assert len(r.charts) <= len(abf.charts) < len(lscm.charts), (len(r.charts), len(abf.charts), len(lscm.charts))
