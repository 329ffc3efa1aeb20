"""The render triangulation (``triangles=``) and the quad flip rule of ``uvflat``.

A quad counts as folded when either of its two diagonal splits has a flipped triangle (not
strictly convex in UV); n-gons are measured on the triangles given (Blender's
``loop_triangles``). Methods that promise no flips keep quads strictly convex.
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


def nonconvex_quads(face_sizes, uv, chart):
    """Quads whose UV image is not strictly convex, with each chart's majority orientation."""
    fs = np.asarray(face_sizes)
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    q = np.flatnonzero((fs == 4) & (chart >= 0))
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
    assert nonconvex_quads(face_sizes, r.uv, chart) == 0
    assert sum(c.flips for c in r.charts) == 0
    for tris in (None, triangles):
        assert uvflat.metrics(positions, corner_verts, face_sizes, r.uv, triangles=tris).flips == 0


def test_lscm_folds_quads_and_says_so():
    """The grid above is hard enough that LSCM (no promise) folds quads: the checks can fail,
    and what the reports count is what an independent check finds. Automatic seams off: with
    them on, a piece LSCM folds is mapped by scaffold instead (next test)."""
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method="lscm", seams=seams, auto_seams=False)
    bad = nonconvex_quads(face_sizes, r.uv, np.asarray(r.chart))
    assert bad > 0
    reported = sum(c.flips for c in r.charts)
    assert reported >= bad  # a quad folded on both splits counts its two folds
    assert uvflat.metrics(positions, corner_verts, face_sizes, r.uv).flips == reported


def test_with_automatic_seams_folded_lscm_pieces_are_mapped_by_scaffold():
    """The same grid with automatic seams on: the pieces LSCM folds are handed to scaffold,
    which keeps every quad convex, and say so; the rest keep LSCM's map."""
    positions, corner_verts, face_sizes, seams = curved_quad_grid(20, 3)
    r = uvflat.unwrap(positions, corner_verts, face_sizes, method="lscm", seams=seams)
    assert nonconvex_quads(face_sizes, r.uv, np.asarray(r.chart)) == 0
    assert sum(c.flips for c in r.charts) == 0 == uvflat.metrics(positions, corner_verts, face_sizes, r.uv).flips
    by = {c.method for c in r.charts}
    assert "scaffold" in by, by
    for c in r.charts:
        assert c.status == ("fallback" if c.method == "scaffold" else "solved"), (c.method, c.reason)
