"""Meshes built in real Blender the way users build them (primitives, boolean CAD parts, text,
modifier stacks): automatic seams keep the atlas rule on every island, with ``abf``, ``slim``
and ``lscm``. The shapes come from ``blender_scripts/shapes.py``; nothing here reads the shared
meshes, so these run on any machine."""

from __future__ import annotations

import sys
import types
from pathlib import Path

import numpy as np
import pytest

import uvflat

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "blender_scripts"))

import shapes  # noqa: E402

bpy = pytest.importorskip("bpy")


@pytest.fixture(scope="module")
def built():
    """Every shape, built once (the objects are removed again after reading them)."""
    return {name: shapes.make(name) for name in shapes.SHAPES}


def euler_and_parts(cv, fs):
    """``(V − E + F, connected parts, boundary edges)`` of a polygon mesh."""
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    edges = {}
    parent = list(range(int(cv.max()) + 1))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for s, n in zip(starts, fs):
        f = cv[s:s + n]
        for k in range(n):
            a, b = int(f[k]), int(f[(k + 1) % n])
            e = (min(a, b), max(a, b))
            edges[e] = edges.get(e, 0) + 1
            parent[find(a)] = find(b)
    used = np.unique(cv)
    parts = len({find(int(v)) for v in used})
    boundary = sum(1 for m in edges.values() if m == 1)
    return len(used) - len(edges) + len(fs), parts, boundary


@pytest.mark.parametrize("name, euler, parts, closed", [
    ("cad_hole", 0, 1, True),        # a bore through a cube: one handle
    ("cad_bracket", -4, 1, True),    # three bores: genus 3
    ("torus", 0, 1, True),
    ("array_cubes", 20, 10, True),   # ten separate cubes
    ("grid_open", 1, 1, False),      # a disk
    ("screw", 0, 1, False),          # a tube open at both ends
    ("gear", 2, 1, True),            # a solid extrusion: a sphere's topology
    ("cad_cross_bores", -2, 1, True),  # two bores that do not meet: genus 2
    ("perforated", -8, 1, False),    # a disk with nine holes
    ("glyphs", 0, 7, False),         # O, B, A, Q and the three parts of %: 7 holes in 7 parts
])
def test_the_shapes_are_what_they_stand_for(built, name, euler, parts, closed):
    pos, cv, fs, tri = built[name]
    chi, n_parts, boundary = euler_and_parts(cv, fs)
    assert (chi, n_parts, boundary == 0) == (euler, parts, closed)
    assert len(tri) == int((fs - 2).sum())


def test_the_folded_shell_folds(built):
    """The solidified head's inner shell turns back on itself in its concave places (adjacent
    faces facing opposite ways), the kind of surface ABF does not converge on."""
    pos, cv, fs, tri = built["thick_shell"]
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    normals = np.zeros((len(fs), 3))
    for f, (s, n) in enumerate(zip(starts, fs)):
        p = pos[cv[s:s + n]]
        normals[f] = np.cross(p[1] - p[0], p[2] - p[0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    edge_faces = {}
    for f, (s, n) in enumerate(zip(starts, fs)):
        ring = cv[s:s + n]
        for k in range(n):
            a, b = int(ring[k]), int(ring[(k + 1) % n])
            edge_faces.setdefault((min(a, b), max(a, b)), []).append(f)
    folds = sum(1 for fl in edge_faces.values() if len(fl) == 2 and normals[fl[0]] @ normals[fl[1]] < -0.5)
    assert folds > 0


@pytest.mark.parametrize("method", ["abf", "slim", "lscm"])
@pytest.mark.parametrize("name", shapes.SHAPES)
def test_every_island_keeps_the_atlas_rule(built, name, method):
    pos, cv, fs, tri = built[name]
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    # A fallback names the method it replaces.
    for c in r.charts:
        if c.status == "fallback":
            assert method in c.reason and c.method != method, c.reason


@pytest.mark.parametrize("name", ["cylinder_ngon", "cylinder_fan", "cad_hole", "cad_bracket", "long_cylinder",
                                  "cone", "gear"])
def test_hard_surfaces_are_cut_along_their_creases(built, name):
    """Flat or rolled everywhere but along their creases (and at a cone's tip, cut to the rim),
    with more curved corners than cones: cut along the creases, every piece laid flat without
    distortion by the method itself, and the same seams whatever the method."""
    pos, cv, fs, tri = built[name]
    seams = {}
    for method in ("abf", "slim", "lscm"):
        r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
        assert r.phases["crease_cuts"] >= 1
        assert shapes.check(pos, cv, fs, tri, r) == []
        for c in r.charts:
            assert (c.status, c.method) == ("solved", method), c.reason
            assert c.conformal < 1.001 and c.area < 1.001, (c.conformal, c.area)
        seams[method] = sorted(map(tuple, np.sort(np.asarray(r.new_seams), axis=1).tolist()))
    assert seams["abf"] == seams["slim"] == seams["lscm"]


@pytest.mark.parametrize("method", ["abf", "slim", "lscm"])
def test_an_extrusion_s_side_is_one_strip_on_blender_s_triangles(built, method):
    """The gear (a 96-gon solidified in Blender, its n-gon caps on Blender's own triangles): its
    side faces meet at the teeth's 90° corners, yet the side is one island beside the two caps,
    not one island per face."""
    pos, cv, fs, tri = built["gear"]
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    assert len(r.charts) == 3, sorted(c.faces for c in r.charts)
    assert sorted(c.faces for c in r.charts) == [1, 1, 96]


@pytest.mark.parametrize("method", ["abf", "slim", "lscm"])
def test_bores_along_two_axes_are_each_one_strip(built, method):
    """A cube with a hexagonal bore along x above one along y: each bore's wall is a ring of
    faces meeting at 60° creases, along its own axis, and unrolls as one strip; the rims,
    where the walls meet the cube's faces at 90°, stay cut. Before the creases along a second
    axis were joined, the second bore's wall was one island per face (11 islands)."""
    pos, cv, fs, tri = built["cad_cross_bores"]
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    assert r.phases["crease_cuts"] >= 1
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    centre = np.array([pos[cv[s:s + n]].mean(axis=0) for s, n in zip(starts, fs)])
    walls = []
    for axis, across, height in ((0, 1, 0.5), (1, 0, -0.5)):
        # A wall face: inside the cube, within the bore's radius of its axis.
        off_axis = np.hypot(centre[:, across], centre[:, 2] - height)
        wall = (np.abs(centre[:, axis]) < 0.99) & (off_axis < 0.41)
        assert wall.sum() == 6
        # The wall is one island, and nothing else is in it.
        islands = set(r.chart[wall].tolist())
        assert len(islands) == 1, (axis, r.chart[wall])
        assert (r.chart == islands.pop()).sum() == 6
        walls.append(wall)
    assert len(r.charts) <= 5, sorted(c.faces for c in r.charts)
    for c in r.charts:
        assert (c.status, c.method) == ("solved", method), c.reason
        assert c.conformal < 1.001 and c.area < 1.001, (c.conformal, c.area)


@pytest.mark.parametrize("method", ["abf", "slim", "lscm"])
def test_a_perforated_plate_is_one_island_laid_as_it_is(built, method):
    """A flat plate cut by nine cylinders in Blender: the boolean leaves corners 1e-7 apart
    where a cylinder touches a grid line. The plate is one island, its bores joined to its
    outline, laid as it is (its projection; the methods' solves bent it around the slivers
    there and split it in five)."""
    pos, cv, fs, tri = built["perforated"]
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    assert len(r.charts) == 1, sorted(c.faces for c in r.charts)
    c = r.charts[0]
    assert (c.status, c.method, c.iterations) == ("solved", method, 0), c.reason
    assert c.conformal < 1 + 1e-9 and c.area < 1 + 1e-9, (c.conformal, c.area)
    assert len(r.new_seams) > 0


@pytest.mark.parametrize("method", ["abf", "slim", "lscm", "scaffold"])
def test_flat_glyphs_are_one_island_each_even_where_contours_touch(built, method):
    """Flat text as Blender fills it: the Q's tail touches its ring at a vertex lying on an
    outline edge of the ring (a crack of zero width). Each glyph part is one island laid as it
    is, its holes joined to its outline; the crack, laid closed, is no outline crossing (it
    was: the Q came out invalid, or in two)."""
    pos, cv, fs, tri = built["glyphs"]
    chi, parts, boundary = euler_and_parts(cv, fs)
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    assert len(r.charts) == parts, sorted(c.faces for c in r.charts)
    for c in r.charts:
        assert (c.status, c.method, c.iterations) == ("solved", method, 0), c.reason
        assert c.conformal < 1 + 1e-9 and c.area < 1 + 1e-9, (c.conformal, c.area)
    assert len(r.new_seams) > 0  # the holes of O, B, A, Q and %


@pytest.mark.parametrize("method", ["abf", "slim", "lscm", "arap"])
def test_flat_letters_with_holes_are_laid_as_they_are(built, method):
    """Extruded text: every letter's faces are flat or rolled, its holes joined to its outline
    by a cut whose sides the map lays on each other (a closed seam). Every island is the
    method's own map, undistorted, with the same seams whatever the method."""
    pos, cv, fs, tri = built["text"]
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    for c in r.charts:
        assert (c.status, c.method) == ("solved", method), c.reason
        assert c.conformal < 1.001, c.conformal
    ref = uvflat.unwrap(pos, cv, fs, method="abf", triangles=tri)
    pairs = lambda x: sorted(map(tuple, np.sort(np.asarray(x.new_seams), axis=1).tolist()))  # noqa: E731
    assert pairs(r) == pairs(ref)


@pytest.mark.parametrize("name", ["bevel_cube", "monkey", "uv_sphere", "torus", "thick_shell", "twisted_torus"])
def test_rounded_and_organic_shapes_keep_the_cones_road(built, name):
    """Curvature inside the regions (bevels, organic surfaces) or spread everywhere: not cut
    along creases."""
    pos, cv, fs, tri = built[name]
    r = uvflat.unwrap(pos, cv, fs, method="abf", triangles=tri)
    assert r.phases["crease_cuts"] == 0


@pytest.mark.parametrize("name", ["cad_bracket", "text", "thick_shell"])
def test_the_same_shape_unwraps_the_same_way_twice(built, name):
    pos, cv, fs, tri = built[name]
    a = uvflat.unwrap(pos, cv, fs, method="abf", triangles=tri)
    b = uvflat.unwrap(pos, cv, fs, method="abf", triangles=tri)
    assert np.array_equal(a.uv, b.uv)
    assert np.array_equal(np.asarray(a.new_seams), np.asarray(b.new_seams))


def flat_ring(n=12):
    """A flat ring of `n` quads between radii 1 and 2, with its render triangles."""
    ang = np.linspace(0, 2 * np.pi, n, endpoint=False)
    pos = np.concatenate([np.c_[np.cos(ang), np.sin(ang), np.zeros(n)],
                          np.c_[2 * np.cos(ang), 2 * np.sin(ang), np.zeros(n)]])
    quads = [[k, (k + 1) % n, n + (k + 1) % n, n + k] for k in range(n)]
    cv = np.array([v for q in quads for v in q], dtype=np.int64)
    fs = np.full(n, 4, dtype=np.int64)
    tri = np.array([[4 * k, 4 * k + 1, 4 * k + 2] for k in range(n)] + [[4 * k, 4 * k + 2, 4 * k + 3] for k in range(n)])
    return pos, cv, fs, tri


@pytest.mark.parametrize("method", ["abf", "slim", "lscm", "arap", "mips"])
def test_a_flat_face_with_a_hole_keeps_its_shape(method):
    """The hole is joined to the outline by one cut; the map lays the ring as it is, the cut's
    two sides on each other. That is a closed seam, not an outline crossing itself: the
    method's own map is kept (no fallback), undistorted."""
    pos, cv, fs, tri = flat_ring()
    r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
    assert shapes.check(pos, cv, fs, tri, r) == []
    assert len(r.new_seams) == 1 and len(r.charts) == 1
    c = r.charts[0]
    assert (c.status, c.method, c.overlap) == ("solved", method, False), c.reason
    assert c.conformal < 1.001 and c.area < 1.001


def test_the_island_check_sees_a_ring_and_a_flip():
    """The check itself fails where it must: a flat ring (not a disk) unwrapped without
    automatic seams, and a map with one triangle turned over."""
    pos, cv, fs, tri = flat_ring()
    ring = uvflat.unwrap(pos, cv, fs, method="lscm", auto_seams=False, triangles=tri)
    assert any("not a disk" in p for p in shapes.check(pos, cv, fs, tri, ring))
    cut = uvflat.unwrap(pos, cv, fs, method="lscm", triangles=tri)
    assert shapes.check(pos, cv, fs, tri, cut) == []
    bent = cut.uv.copy()
    bent[0] = bent[2] + 3.0 * (bent[2] - bent[0])  # corner 0 past corner 2: its triangle turns over
    turned = types.SimpleNamespace(face_solved=cut.face_solved, charts=[], uv=bent, chart=cut.chart,
                                   new_seams=cut.new_seams)
    assert any(p.startswith("metrics:") for p in shapes.check(pos, cv, fs, tri, turned))
