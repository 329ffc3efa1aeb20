"""The render triangulation (``triangles=``) and the quad flip rule of ``uvflat``.

A quad counts as folded when either of its two diagonal splits has a flipped triangle (not
strictly convex in UV); n-gons are measured on the triangles given (Blender's
``loop_triangles``). Methods that promise no flips keep quads strictly convex, except quads
that are not convex in 3D (concave or folded): their faithful map keeps that shape, and one of
their splits is turned over on the surface itself, so they count as their own two triangles.
"""

from __future__ import annotations

import numpy as np
import pytest

import uvflat

SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
DART = np.array([[0.0, 0.0], [2.0, 0.0], [0.5, 0.5], [0.0, 2.0]])  # corner 2 is reflex


def curved_quad_grid(n, seed):
    """A curved ``n`` x ``n`` quad grid with some dart-shaped quads, and random seams."""
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1))
    i, j = i.ravel(), j.ravel()
    h = 2.0 / n
    x = i * h - 1 + 0.3 * h * (rng.random(i.size) - 0.5)
    y = j * h - 1 + 0.3 * h * (rng.random(i.size) - 0.5)
    dart = (i > 0) & (j > 0) & (i < n - 1) & (j < n - 1) & ((7 * i + 3 * j) % 11 == 0)
    x[dart] = i[dart] * h - 1 + 0.6 * h
    y[dart] = j[dart] * h - 1 + 0.6 * h
    z = 0.6 * (x * x - y * y) + 0.2 * np.sin(3 * x) * np.cos(2 * y)
    positions = np.column_stack([x, y, z])
    vid = lambda a, b: b * (n + 1) + a  # noqa: E731
    faces = [[vid(a, b), vid(a + 1, b), vid(a + 1, b + 1), vid(a, b + 1)] for b in range(n) for a in range(n)]
    seams = []
    for w in range(4):
        a, b = (0, int(rng.integers(n))) if w % 2 == 0 else (int(rng.integers(n)), 0)
        for _ in range(n):
            na, nb = (min(a + 1, n), b) if rng.random() < 0.5 else (a, min(b + 1, n))
            if (na, nb) == (a, b):
                break
            seams.append([vid(a, b), vid(na, nb)])
            a, b = na, nb
    return positions, np.array(faces).ravel(), np.full(n * n, 4), np.array(seams)


def convex_in_3d(positions, corner_verts, face_sizes, margin=0.05):
    """Per face: a quad whose four split triangles, seen along the sum of their normals (its
    Newell normal), each hold at least ``margin`` of its area. Written here apart from the
    core's own test (``charts::convex_quad``), which asks 2%: with the default 5%, every quad
    this accepts is one the methods must keep convex; with 2%, exactly the core's quads."""
    fs = np.asarray(face_sizes)
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    out = np.zeros(len(fs), dtype=bool)
    q = np.flatnonzero(fs == 4)
    p = [np.asarray(positions, float)[np.asarray(corner_verts)[starts[q] + k]] for k in range(4)]
    tris = [np.cross(p[b] - p[a], p[d] - p[a]) for a, b, d in [(0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)]]
    n = sum(tris)
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    signed = [np.einsum("ij,ij->i", t, n) for t in tris]
    area = 0.5 * sum(signed)
    out[q] = np.all([s >= margin * area for s in signed], axis=0) & (area > 0)
    return out


def nonconvex_quads(face_sizes, uv, chart, convex3d=None):
    """Quads whose UV image is not strictly convex, with each chart's majority orientation;
    only the quads marked in ``convex3d`` (per face), if given."""
    fs = np.asarray(face_sizes)
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    q = np.flatnonzero((fs == 4) & (chart >= 0) & (True if convex3d is None else convex3d))
    c = [starts[q] + k for k in range(4)]

    def signed(a, b, d):
        return ((uv[b, 0] - uv[a, 0]) * (uv[d, 1] - uv[a, 1])
                - (uv[d, 0] - uv[a, 0]) * (uv[b, 1] - uv[a, 1]))

    area = signed(c[0], c[1], c[2]) + signed(c[0], c[2], c[3])
    sign = np.zeros(len(q))
    for k in np.unique(chart[q]):
        m = chart[q] == k
        sign[m] = 1.0 if area[m].sum() >= 0 else -1.0
    tris = [(0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)]
    ok = np.all([sign * signed(c[a], c[b], c[d]) > 0 for a, b, d in tris], axis=0)
    return int((~ok).sum())


def test_metrics_counts_a_concave_quad_once_on_either_split():
    for tris in (None, [[0, 1, 2], [0, 2, 3]], [[0, 1, 3], [1, 2, 3]], [[3, 1, 0], [3, 2, 1]]):
        m = uvflat.metrics(SQUARE, [0, 1, 2, 3], [4], DART, triangles=tris)
        assert m.flips == 1, tris
    square_uv = SQUARE[:, :2]
    assert uvflat.metrics(SQUARE, [0, 1, 2, 3], [4], square_uv, triangles=[[0, 1, 3], [1, 2, 3]]).flips == 0


def test_a_quad_concave_in_3d_mapped_as_it_is_is_no_fold():
    """A dart in 3D mapped to the same dart: the split through the reflex corner is positive
    in both, the other one is turned over in both, so nothing folds."""
    dart3 = np.column_stack([DART, np.zeros(4)])
    assert uvflat.metrics(dart3, [0, 1, 2, 3], [4], DART).flips == 0
    assert uvflat.metrics(dart3, [0, 1, 2, 3], [4], DART, triangles=[[0, 1, 2], [0, 2, 3]]).flips == 0
    # Every method keeps a flat dart as it is (an isometry up to scale).
    for method in ("abf", "slim", "lscm", "mips", "scaffold"):
        r = uvflat.unwrap(dart3, [0, 1, 2, 3], [4], method=method)
        uv = r.uv - r.uv[0]
        # Similarity: compare with the 3D dart after matching the first edge.
        e = uv[1] / np.linalg.norm(uv[1])
        rot = np.array([[e[0], e[1]], [-e[1], e[0]]])
        flat = uv @ rot.T * (2.0 / np.linalg.norm(uv[1]))
        assert np.allclose(np.abs(flat), np.abs(DART), atol=1e-6), (method, flat)
        assert r.charts[0].flips == 0 and r.charts[0].status == "solved", (method, r.charts[0].reason)


def test_metrics_measures_a_pentagon_on_the_given_triangles():
    a = 2 * np.pi * np.arange(5) / 5
    positions = np.column_stack([np.cos(a), np.sin(a), np.zeros(5)])
    uv = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.5], [0.0, 2.0]])  # reflex at 3
    fan0 = uvflat.metrics(positions, np.arange(5), [5], uv, triangles=[[0, 1, 2], [0, 2, 3], [0, 3, 4]])
    fan3 = uvflat.metrics(positions, np.arange(5), [5], uv, triangles=[[3, 4, 0], [3, 0, 1], [3, 1, 2]])
    assert fan0.flips >= 1
    assert fan3.flips == 0


@pytest.mark.parametrize("bad,row,needle", [
    ([[0, 1, 2], [0, 2, 9]], 1, "out of range"),
    ([[0, 1, 2], [0, 2, 4]], 1, "face"),
    ([[0, 1, 2]], None, "needs 2 triangles"),
    ([[0, 1, 2], [0, 1, 2]], 0, "do not triangulate"),
    ([[0, 1, 2], [0, -2, 3]], 1, "out of range"),
])
def test_bad_triangles_raise_a_typed_error_naming_the_row(bad, row, needle):
    positions = np.vstack([SQUARE, [[2, 0, 0], [2, 1, 0]]])
    corner_verts = [0, 1, 2, 3, 1, 4, 5, 2]
    faces = [4, 4]
    full = bad + [[4, 5, 6], [4, 6, 7]]
    with pytest.raises(uvflat.TriangleError) as info:
        uvflat.unwrap(positions, corner_verts, faces, method="tutte", triangles=np.array(full))
    assert isinstance(info.value, uvflat.MeshError)
    if row is not None:
        assert info.value.triangle == row
    assert needle in str(info.value)
    with pytest.raises(uvflat.TriangleError):
        uvflat.metrics(positions, corner_verts, faces, np.zeros((8, 2)), triangles=np.array(full))


def test_wrong_shape_of_triangles_is_an_input_error():
    with pytest.raises(uvflat.InputError):
        uvflat.unwrap(SQUARE, [0, 1, 2, 3], [4], triangles=np.zeros((2, 2), dtype=np.int64))


@pytest.mark.parametrize("method", ["tutte", "mean_value", "slim", "mips", "scaffold", "abf"])
@pytest.mark.parametrize("split", ["core", "02", "13"])
def test_promising_methods_keep_quads_strictly_convex(method, split):
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    f = 4 * np.arange(len(face_sizes))
    triangles = {
        "core": None,
        "02": np.column_stack([f, f + 1, f + 2, f, f + 2, f + 3]).reshape(-1, 3),
        "13": np.column_stack([f, f + 1, f + 3, f + 1, f + 2, f + 3]).reshape(-1, 3),
    }[split]
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method=method, seams=seams, triangles=triangles)
    assert all(c.status != "failed" for c in r.charts)
    chart = np.asarray(r.chart)
    convex3d = convex_in_3d(positions, corner_verts, face_sizes)
    assert 0 < (~convex3d).sum() < len(face_sizes) // 10  # the grid's darts
    assert nonconvex_quads(face_sizes, r.uv, chart, convex3d) == 0
    assert sum(c.flips for c in r.charts) == 0
    for tris in (None, triangles):
        assert uvflat.metrics(positions, corner_verts, face_sizes, r.uv, triangles=tris).flips == 0


def test_folds_are_found_and_counted_alike():
    """The checks can fail: Tutte onto a square lays a chart's border triangles whose corners
    reach one side of the square flat (zero area, a fold), and what the reports count is what
    the independent check finds. Automatic seams off."""
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method="tutte", boundary="square", seams=seams,
                      auto_seams=False)
    bad = nonconvex_quads(face_sizes, r.uv, np.asarray(r.chart))
    assert bad > 0
    reported = sum(c.flips for c in r.charts)
    assert reported >= bad  # a quad folded on both splits counts its two folds
    assert uvflat.metrics(positions, corner_verts, face_sizes, r.uv).flips == reported


def test_lscm_leaves_the_darts_as_they_are_and_no_quad_folded():
    """LSCM is conformal, so it keeps the grid's darts darts (nothing folds: their split through
    the reflex corner is the positive one), and where its linear map folds a quad convex in 3D
    the `lscm` method makes it convex in place (`rust/uvflat-core/tests/quads.rs` has a grid
    where it does). Automatic seams off."""
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method="lscm", seams=seams, auto_seams=False)
    convex3d = convex_in_3d(positions, corner_verts, face_sizes)
    chart = np.asarray(r.chart)
    assert nonconvex_quads(face_sizes, r.uv, chart, convex3d) == 0
    # The darts stay concave in UV, and that is no fold.
    assert nonconvex_quads(face_sizes, r.uv, chart, ~convex3d) > 0
    assert sum(c.flips for c in r.charts) == 0 == uvflat.metrics(positions, corner_verts, face_sizes, r.uv).flips


def test_with_automatic_seams_every_lscm_island_keeps_the_rule():
    """The same grid with automatic seams on: every island keeps the rule; an island LSCM could
    not map within it is a fallback that names LSCM and the method used instead."""
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method="lscm", seams=seams)
    convex3d = convex_in_3d(positions, corner_verts, face_sizes)
    assert nonconvex_quads(face_sizes, r.uv, np.asarray(r.chart), convex3d) == 0
    m = uvflat.metrics(positions, corner_verts, face_sizes, r.uv)
    assert sum(c.flips for c in r.charts) == 0 == m.flips and m.overlapping_charts == 0
    for c in r.charts:
        assert c.density_outside <= 0.05 + 1e-12, (c.id, c.density_outside)
        if c.method == "lscm":
            assert c.status == "solved", c.reason
        else:
            assert c.status == "fallback" and c.reason.startswith("lscm broke the atlas rule"), c.reason
            assert f"; {c.method}, which" in c.reason, c.reason
