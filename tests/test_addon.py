# SPDX-License-Identifier: GPL-3.0-or-later
"""Headless-bpy tests of the uvflat extension *as installed* from dist/uvflat-<version>.zip.

The zip is built by ``bash .ci/build`` (``bash .ci/bootstrap test`` runs it first); the tests
install it into a throw-away Blender user folder with Blender's own extension installer and
drive the registered operator ``bpy.ops.uv.uvflat_unwrap``.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

# A private Blender user folder, set before bpy is first imported in this process.
_USER_DIR = tempfile.mkdtemp(prefix="uvflat-blender-user-")
if "bpy" not in sys.modules:
    os.environ["BLENDER_USER_RESOURCES"] = _USER_DIR

import numpy as np  # noqa: E402
import pytest  # noqa: E402

bpy = pytest.importorskip("bpy", reason="the bpy module (Blender as a Python module) is not installed")
import addon_utils  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "blender_scripts"))
import common  # noqa: E402
from test_triangulation import convex_in_3d  # noqa: E402

SHARED = REPO.parent / "shared" / "meshes"
SHARED_MESHES = ("camelhead.off", "lion.off", "beetle.off", "halftunnel.off")
# Methods that promise no flipped triangle (positive weights, convex boundary).
FLIP_FREE = [("tutte", {}), ("mean_value", {"boundary": "circle"}), ("slim", {}), ("mips", {}),
             ("mean_value", {"boundary": "virtual"})]
# LSCM promises no injectivity; it must still solve, respect seams and report flips honestly,
# and it has none on these disks (where Blender's CONFORMAL flips thousands on camelhead); on
# halftunnel the holes are filled after the open-hole map folded.
LSCM_NO_FLIP_MESHES = {"camelhead.off", "lion.off", "beetle.off", "halftunnel.off"}


# ---------------------------------------------------------------------------------------------
# Installation


def _extension_zip():
    if os.environ.get("UVFLAT_EXTENSION_ZIP"):
        return Path(os.environ["UVFLAT_EXTENSION_ZIP"])
    manifest = (REPO / "addon" / "blender_manifest.toml").read_text()
    version = next(line.split('"')[1] for line in manifest.splitlines()
                   if line.startswith("version = "))
    path = REPO / "dist" / f"uvflat-{version}.zip"
    assert path.is_file(), f"{path} is missing: build it with `bash .ci/build`"
    return path


def _user_repo():
    """The extension repository to install into, inside a temporary folder."""
    repos = bpy.context.preferences.extensions.repos
    repo = repos.get("user_default") if hasattr(repos, "get") else None
    if repo is None:
        repo = next((r for r in repos if r.module == "user_default"), None)
    if repo is not None and repo.directory.startswith(_USER_DIR):
        return repo
    # bpy was imported before this module: add a repository of our own in the temp folder
    return repos.new(name="uvflat tests", module="uvflat_tests", custom_directory=os.path.join(
        _USER_DIR, "extensions", "uvflat_tests"), source="USER")


@pytest.fixture(scope="module")
def ext():
    zip_path = _extension_zip()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    repo = _user_repo()
    result = bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo=repo.module, enable_on_install=True, overwrite=True)
    module_name = f"bl_ext.{repo.module}.uvflat"
    assert "FINISHED" in result, f"package_install_files returned {result}"
    loaded_default, loaded_state = addon_utils.check(module_name)
    assert loaded_default and loaded_state, (
        f"{module_name} is not enabled after installing {zip_path.name} "
        f"(loaded_default={loaded_default}, loaded_state={loaded_state})")
    assert hasattr(bpy.types, "UV_OT_uvflat_unwrap"), "the operator was not registered"
    module = sys.modules[module_name]
    assert Path(module.__file__).resolve().is_relative_to(Path(repo.directory).resolve())
    common.use_mesh_io(module.mesh_io)
    yield module
    common.use_mesh_io(None)
    addon_utils.disable(module_name)


@pytest.fixture
def scene(ext):
    """An empty scene in object mode (without resetting preferences: the add-on stays on)."""
    common.object_mode()
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    tool_settings = bpy.context.scene.tool_settings
    tool_settings.mesh_select_mode = (False, False, True)
    yield bpy.context.scene
    common.object_mode()


# ---------------------------------------------------------------------------------------------
# Helpers (all mesh access through the installed add-on's mesh_io)


def unwrap(ext, objects, *, select_all=True, **props):
    """Run the operator with ``objects`` in edit mode; back in object mode afterwards."""
    common.edit_mode(objects, select_all=select_all)
    try:
        result = bpy.ops.uv.uvflat_unwrap(**props)
        assert all(o.mode == "EDIT" for o in objects), "objects must be back in edit mode"
    finally:
        common.object_mode()
    return result, ext.engine.LAST_SUMMARY


def read(ext, obj):
    io = ext.mesh_io
    positions, corner_verts, face_sizes = io.read_topology(obj.data)
    return SimpleNamespace(positions=positions, corner_verts=corner_verts, face_sizes=face_sizes,
                           uv=(io.read_uv(obj.data).astype(np.float64)
                               if io.active_uv_name(obj.data) is not None
                               else np.zeros((len(corner_verts), 2))),
                           seams=io.read_seams(obj.data),
                           triangles=io.read_loop_triangles(obj.data, face_sizes))


def fan_triangles(face_sizes):
    """Corner triples of a fan triangulation of every face, and the face of each triangle."""
    face_sizes = np.asarray(face_sizes, dtype=np.int64)
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    n_tris = face_sizes - 2
    face = np.repeat(np.arange(len(face_sizes)), n_tris)
    offset = np.arange(n_tris.sum()) - np.repeat(np.cumsum(n_tris) - n_tris, n_tris)
    first = starts[face]
    return np.column_stack([first, first + 1 + offset, first + 2 + offset]), face


def _signed(uv, a, b, c):
    pa, pb, pc = uv[a], uv[b], uv[c]
    return (pb[:, 0] - pa[:, 0]) * (pc[:, 1] - pa[:, 1]) - (pc[:, 0] - pa[:, 0]) * (pb[:, 1] - pa[:, 1])


def flipped_triangles(data, faces_chart):
    """Faces that are flipped in UV: computed here, independently of the core.

    Triangles and n-gons (n >= 5) by the triangles Blender renders (``data.triangles``, its
    loop triangles, when ``data`` has them; else a fan from each face's first corner); a quad
    counts as flipped only if neither of its two diagonals splits it into two triangles of
    the chart's orientation (a non-convex quad image is not a flip).  The orientation of a
    chart is the sign of the majority of its faces' areas.  Returns the number of flipped
    faces.
    """
    fs = np.asarray(data.face_sizes, dtype=np.int64)
    chart = np.asarray(faces_chart)
    starts = np.zeros(len(fs), dtype=np.int64)
    np.cumsum(fs[:-1], out=starts[1:])
    # orientation per chart from the polygon areas (shoelace)
    nxt = np.arange(len(data.uv)) + 1
    nxt[starts + fs - 1] = starts
    cross = data.uv[:, 0] * data.uv[nxt, 1] - data.uv[nxt, 0] * data.uv[:, 1]
    area = np.add.reduceat(cross, starts)
    sign = np.zeros(len(fs))
    for k in np.unique(chart[chart >= 0]):
        a = area[chart == k]
        sign[chart == k] = 1.0 if (a > 0).sum() >= (a < 0).sum() else -1.0
    flipped = np.zeros(len(fs), dtype=bool)
    tris = getattr(data, "triangles", None)
    if tris is None:
        tris, face = fan_triangles(fs)
    else:
        tris = np.asarray(tris, dtype=np.int64).reshape(-1, 3)
        face = np.searchsorted(starts, tris[:, 0], side="right") - 1
    bad = _signed(data.uv, tris[:, 0], tris[:, 1], tris[:, 2]) * sign[face] <= 0
    not_quad = fs[face] != 4
    np.logical_or.at(flipped, face[not_quad], bad[not_quad])
    q = np.flatnonzero(fs == 4)
    if len(q):
        c0, c1, c2, c3 = (starts[q] + i for i in range(4))
        s = sign[q]
        split02 = ((_signed(data.uv, c0, c1, c2) * s > 0) & (_signed(data.uv, c0, c2, c3) * s > 0))
        split13 = ((_signed(data.uv, c1, c2, c3) * s > 0) & (_signed(data.uv, c1, c3, c0) * s > 0))
        flipped[q] = ~(split02 | split13)
    return int((flipped & (chart >= 0)).sum())


def test_the_flip_count_reads_the_triangles_blender_renders():
    """A concave pentagon whose fan from its first corner is unfolded while the triangulation
    given as Blender's has a flipped triangle: the helper counts the face flipped with those
    triangles and not with the fan (so a fold on Blender's triangles cannot hide behind it)."""
    uv = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.2], [2.0, 2.0], [0.0, 2.0]])
    base = dict(positions=np.zeros((5, 3)), corner_verts=np.arange(5), face_sizes=np.array([5]), uv=uv)
    assert flipped_triangles(SimpleNamespace(**base), [0]) == 0
    blender = np.array([[1, 2, 3], [0, 1, 3], [0, 3, 4]])
    assert flipped_triangles(SimpleNamespace(**base, triangles=blender), [0]) == 1
    assert flipped_triangles(SimpleNamespace(**base, triangles=blender), [-1]) == 0


def edge_pairs(data):
    """Interior edges as pairs of opposite corners: (edge key, c1, c1_next, c2, c2_next)."""
    fs = np.asarray(data.face_sizes, dtype=np.int64)
    starts = np.zeros(len(fs), dtype=np.int64)
    np.cumsum(fs[:-1], out=starts[1:])
    n_c = len(data.corner_verts)
    nxt = np.arange(n_c) + 1
    nxt[starts + fs - 1] = starts
    v0, v1 = data.corner_verts.astype(np.int64), data.corner_verts[nxt].astype(np.int64)
    n_v = len(data.positions)
    key = np.minimum(v0, v1) * n_v + np.maximum(v0, v1)
    order = np.argsort(key, kind="stable")
    k = key[order]
    counts = np.bincount(np.unique(k, return_inverse=True)[1])
    uniq = np.unique(k)
    manifold = np.repeat(counts == 2, counts)
    first = order[manifold][0::2]
    second = order[manifold][1::2]
    return uniq[counts == 2], first, nxt[first], second, nxt[second]


def seam_check(data, face, chart_kinds=None, closed=None):
    """(non-seam edges with a UV jump, seam edges without one) between solved faces.

    ``face[c]`` is the face of corner c; ``chart_kinds`` maps face -> chart kind: charts that
    the core had to cut (not "disk") may jump away from seams, so they are left out there.
    ``closed``: seams the core reports as closed (``closed_seams``: both sides keep the same
    UVs by design), left out of the seams that must jump.
    """
    keys, c1, c1n, c2, c2n = edge_pairs(data)
    n_v = len(data.positions)

    def key_set(pairs):
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        return set((np.minimum(pairs[:, 0], pairs[:, 1]) * n_v + np.maximum(pairs[:, 0], pairs[:, 1])).tolist())

    seam_keys = key_set(data.seams) - (key_set(closed) if closed is not None else set())
    is_seam = np.array([int(k) in seam_keys for k in keys], dtype=bool)
    # opposite corners: c1 (u -> v) and c2 (v -> u), so c1 and c2n sit on the same vertex
    same = (np.all(data.uv[c1] == data.uv[c2n], axis=1) & np.all(data.uv[c1n] == data.uv[c2], axis=1))
    both = np.ones(len(keys), dtype=bool) if face is None else (face[c1] & face[c2])
    jump_ok = np.ones(len(keys), dtype=bool)
    if chart_kinds is not None:
        jump_ok = ~(chart_kinds[c1] | chart_kinds[c2])
    bad_cont = int((both & ~is_seam & ~same & jump_ok).sum())
    bad_seam = int((both & is_seam & same).sum())
    return bad_cont, bad_seam, int((both & is_seam).sum())


def corner_mask(face_mask, face_sizes):
    return np.repeat(np.asarray(face_mask, dtype=bool), face_sizes)


def check_result(ext, obj, summary, expect_all_solved=True, expect_no_flips=True):
    data = read(ext, obj)
    result = summary.results[obj.name]
    solved = np.asarray(result.face_solved, dtype=bool)
    if expect_all_solved:
        assert solved.all(), summary.line()
    chart = np.where(solved, np.asarray(result.chart), -1)
    import uvflat

    # Measured on the triangles Blender renders (DESIGN: n-gons by loop_triangles).
    metrics = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv,
                             selected=solved, triangles=ext.mesh_io.read_loop_triangles(obj.data))
    if expect_no_flips:
        assert flipped_triangles(data, chart) == 0, f"{obj.name}: flipped faces; {summary.line()}"
        assert metrics.flips == 0, f"{obj.name}: uvflat.metrics counts {metrics.flips} flips"
    else:
        # The report must tell the truth about the UVs that reached Blender.
        reported = sum(c.flips for c in result.charts if c.status != "failed")
        assert metrics.flips == reported, f"{obj.name}: reported {reported}, measured {metrics.flips}"
    cut = {c.id for c in result.charts if c.kind != "disk"}
    cut_faces = np.isin(np.asarray(result.chart), list(cut)) if cut else np.zeros(len(solved), bool)
    closed = np.asarray(result.closed_seams)
    bad_cont, bad_seam, n_seam = seam_check(
        data, corner_mask(solved, data.face_sizes), corner_mask(cut_faces, data.face_sizes), closed)
    assert bad_cont == 0, f"{obj.name}: {bad_cont} non-seam edges with a UV discontinuity"
    assert bad_seam == 0, f"{obj.name}: {bad_seam} of {n_seam} seam edges without a UV discontinuity"
    return data


def suzanne(name="Suzanne"):
    return common.suzanne(name)


def shared_mesh(name):
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent (the shared test meshes live beside the repository)")
    return common.load_mesh_object(SHARED / name)


# ---------------------------------------------------------------------------------------------
# Tests


def test_installed_extension_is_enabled_with_menus(ext):
    assert ext.__name__.startswith("bl_ext.")
    assert bpy.ops.uv.uvflat_unwrap.idname() == "UV_OT_uvflat_unwrap"
    # appended to the UV editor's Unwrap menu only: the 3D Viewport's UV menu inlines it
    assert ext.ui.menu_entry in bpy.types.IMAGE_MT_uvs_unwrap._dyn_ui_initialize()
    assert ext.ui.menu_entry not in bpy.types.VIEW3D_MT_uv_map._dyn_ui_initialize()
    assert hasattr(bpy.types.Scene, "uvflat")
    assert "UVFLAT_PT_defaults" in dir(bpy.types)


def test_method_table_matches_core(ext):
    import uvflat

    ids = [m.id for m in ext.methods.METHODS]
    assert set(ids) <= set(uvflat.METHODS), f"add-on lists methods the core lacks: {ids}"
    assert {"tutte", "harmonic", "mean_value", "lscm", "spectral"} <= set(ids)


@pytest.mark.parametrize("method,options", FLIP_FREE + [("lscm", {})],
                         ids=[m for m, _ in FLIP_FREE] + ["lscm"])
def test_suzanne_seams_and_no_flips(ext, scene, method, options):
    obj = suzanne()
    assert len(ext.mesh_io.read_seams(obj.data)) > 0
    result, summary = unwrap(ext, [obj], method=method, **options)
    assert result == {"FINISHED"}
    assert summary.charts >= 2, summary.line()
    # every chart solved; no flips (the quads around Suzanne's valence-2 vertices are split
    # through them, so flattening opens no sliver); lscm promises nothing and folds a couple of
    # quads on one diagonal: its report must count them. UV jumps exactly at seams.
    check_result(ext, obj, summary, expect_no_flips=(method != "lscm"))


@pytest.mark.parametrize("method,options", FLIP_FREE + [("lscm", {})],
                         ids=[m for m, _ in FLIP_FREE] + ["lscm"])
def test_suzanne_every_chart_solved(ext, scene, method, options):
    """Every island of Suzanne (seams from her own UVs) is a disk, the head included: two
    quads around a valence-2 vertex must not be split along the same diagonal."""
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method=method, **options)
    assert result == {"FINISHED"}
    assert not summary.failed, summary.line()


@pytest.mark.parametrize("mesh", SHARED_MESHES)
@pytest.mark.parametrize("method,options", FLIP_FREE + [("lscm", {})],
                         ids=[m for m, _ in FLIP_FREE] + ["lscm"])
def test_shared_meshes_no_flips(ext, scene, mesh, method, options):
    obj = shared_mesh(mesh)
    result, summary = unwrap(ext, [obj], method=method, **options)
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    check_result(ext, obj, summary,
                 expect_no_flips=(method != "lscm" or mesh in LSCM_NO_FLIP_MESHES))


@pytest.mark.parametrize("pack", ["AROUND", "ALL", "OFF"])
def test_unselected_faces_unchanged(ext, scene, pack):
    obj = suzanne()
    io = ext.mesh_io
    sel = np.zeros(len(obj.data.polygons), dtype=bool)
    sel[::3] = True
    io.select_faces(obj.data, sel)
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], select_all=False, method="lscm", pack=pack)
    assert result == {"FINISHED"}
    after = read(ext, obj)
    selected = io.read_face_selection(obj.data)
    np.testing.assert_array_equal(selected, sel, err_msg="the face selection changed")
    corners = corner_mask(sel, before.face_sizes)
    assert np.array_equal(after.uv[~corners], before.uv[~corners]), "unselected UVs changed"
    assert not np.array_equal(after.uv[corners], before.uv[corners])


@pytest.mark.parametrize("pack", ["AROUND", "ALL", "OFF"])
def test_pinned_uvs_unchanged(ext, scene, pack):
    obj = suzanne()
    io = ext.mesh_io
    data = read(ext, obj)
    # pin every corner of two vertices of the same face (so of the same chart)
    pinned_verts = data.corner_verts[[0, 2]]
    pins = np.isin(data.corner_verts, pinned_verts)
    io.write_pins(obj.data, io.active_uv_name(obj.data), pins)
    result, summary = unwrap(ext, [obj], method="lscm", pack=pack)
    assert result == {"FINISHED"}, summary
    after = read(ext, obj)
    assert np.array_equal(after.uv[pins], data.uv[pins]), "pinned UVs moved"
    assert np.array_equal(io.read_pins(obj.data), pins), "pin flags changed"


def _cube(name="Cube"):
    bpy.ops.mesh.primitive_cube_add()
    obj = bpy.context.active_object
    obj.name = name
    io = common.mesh_io()
    io.write_seams(obj.data, np.zeros(len(obj.data.edges), dtype=bool))
    return obj


def test_closed_cube_without_seams(ext, scene):
    """Either the core cuts the closed chart itself, or the chart fails and keeps its UVs."""
    obj = _cube()
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], method="lscm")
    assert result == {"FINISHED"}
    after = read(ext, obj)
    res = summary.results[obj.name]
    failed = ~np.asarray(res.face_solved, dtype=bool)
    corners = corner_mask(failed, before.face_sizes)
    assert np.array_equal(after.uv[corners], before.uv[corners]), "a failed chart's UVs changed"
    if failed.any():
        assert summary.failed and "not solved" in summary.line()
    else:
        chart = np.asarray(res.chart)
        assert flipped_triangles(after, chart) == 0


def test_failed_chart_keeps_uvs_exactly(ext, scene, monkeypatch):
    """A chart reported as failed keeps its old UVs bit for bit, the others are written."""
    import uvflat

    real = uvflat.unwrap

    def unwrap_with_failure(*args, **kwargs):
        r = real(*args, **kwargs)
        chart = np.asarray(r.chart)
        solved = np.asarray(r.face_solved, dtype=bool) & (chart != 0)
        charts = [SimpleNamespace(**{**c.as_dict(), "status": "failed", "reason": "test failure"})
                  if c.id == 0 else c for c in r.charts]
        failed = ~solved
        return SimpleNamespace(uv=np.asarray(r.uv), chart=chart, face_solved=solved,
                               charts=charts, seconds=r.seconds,
                               face_conformal=np.where(failed, np.nan, r.face_conformal),
                               face_area=np.where(failed, np.nan, r.face_area),
                               face_flips=np.where(failed, 0, r.face_flips))

    monkeypatch.setattr(uvflat, "unwrap", unwrap_with_failure)
    obj = suzanne()
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], method="lscm", pack="ALL")
    assert result == {"FINISHED"}
    assert any(p.reason == "test failure" for p in summary.failed), summary.line()
    after = read(ext, obj)
    res = summary.results[obj.name]
    chart = np.asarray(res.chart)
    failed_corners = corner_mask(chart == 0, before.face_sizes)
    assert np.array_equal(after.uv[failed_corners], before.uv[failed_corners])
    solved = corner_mask(np.asarray(res.face_solved, dtype=bool), before.face_sizes)
    assert solved.any() and not (solved & failed_corners).any()
    assert not np.array_equal(after.uv[solved], before.uv[solved])


@pytest.mark.parametrize("stage", ["solve", "pack"])
def test_error_leaves_every_uv_map_unchanged(ext, scene, monkeypatch, stage):
    import uvflat

    with_uv = suzanne("WithUV")
    io = ext.mesh_io
    io.write_seams(with_uv.data, np.zeros(len(with_uv.data.edges), dtype=bool))
    second = with_uv.data.uv_layers.new(name="Second")
    with_uv.data.uv_layers.active = second
    without_uv = common.link_mesh_object("NoUV", io.new_mesh("NoUV", *read_shape_ngon()))
    before = {o.name: {n: io.read_uv(o.data, n).copy() for n in io.uv_map_names(o.data)}
              for o in (with_uv, without_uv)}
    if stage == "solve":
        calls = []

        def failing_unwrap(*args, **kwargs):
            calls.append(1)
            if len(calls) == 2:
                raise uvflat.UvflatError("injected failure")
            return uvflat_real(*args, **kwargs)

        uvflat_real = uvflat.unwrap
        monkeypatch.setattr(uvflat, "unwrap", failing_unwrap)
    else:
        def failing_pack(*args, **kwargs):
            raise RuntimeError("injected packing failure")

        monkeypatch.setattr(ext.engine, "_pack", failing_pack)
    with pytest.raises(RuntimeError, match="injected"):
        unwrap(ext, [with_uv, without_uv], method="lscm", pack="ALL")
    for o in (with_uv, without_uv):
        assert io.uv_map_names(o.data) == list(before[o.name]), f"{o.name}: UV maps added/removed"
        for name, uv in before[o.name].items():
            assert np.array_equal(io.read_uv(o.data, name), uv), f"{o.name}/{name} changed"
    assert with_uv.data.uv_layers.active.name == "Second"


def read_shape_ngon():
    """A flat disk of n-gons: a hexagon fan of pentagons around a central hexagon."""
    ring_in = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.arange(6) * np.pi / 3])
    ring_out = 2.2 * np.array([[np.cos(a), np.sin(a), 0.0] for a in (np.arange(6) + 0.5) * np.pi / 3])
    positions = np.vstack([ring_in, ring_out, 2.0 * ring_in])
    faces = [list(range(6))]  # counter-clockwise seen from +z
    for i in range(6):
        j = (i + 1) % 6
        faces.append([i, 12 + i, 6 + i, 12 + j, j])
    return positions, np.concatenate(faces), np.array([len(f) for f in faces])


@pytest.mark.parametrize("method", ["tutte", "lscm", "harmonic", "spectral", "bff"])
def test_ngons(ext, scene, method):
    io = ext.mesh_io
    obj = common.link_mesh_object("Ngons", io.new_mesh("Ngons", *read_shape_ngon()))
    bpy.ops.mesh.primitive_cylinder_add(vertices=12, end_fill_type="NGON")
    cyl = bpy.context.active_object
    data = read(ext, cyl)
    edge_verts, _ = io.read_edges(cyl.data)
    z = data.positions[:, 2]
    ring = (np.abs(z[edge_verts[:, 0]] - z[edge_verts[:, 1]]) < 1e-6)  # cap boundary edges
    vertical = np.flatnonzero(~ring)[:1]  # one side edge opens the tube
    seam = ring.copy()
    seam[vertical] = True
    io.write_seams(cyl.data, seam)
    assert data.face_sizes.max() == 12 and read(ext, obj).face_sizes.max() == 6
    result, summary = unwrap(ext, [obj, cyl], method=method)
    assert result == {"FINISHED"}, summary
    assert summary.objects == 2 and not summary.failed, summary.line()
    for o in (obj, cyl):
        check_result(ext, o, summary)


def test_multi_object_edit_mode(ext, scene):
    a = suzanne("A")
    b = suzanne("B")
    b.location.x = 3.0
    if SHARED.is_dir():
        c = common.load_mesh_object(SHARED / "halftunnel.off")
        objects = [a, b, c]
    else:
        objects = [a, b]
    before = {o.name: read(ext, o).uv for o in objects}
    result, summary = unwrap(ext, objects, method="tutte")
    assert result == {"FINISHED"}
    assert summary.objects == len(objects), summary.line()
    for o in objects:
        data = check_result(ext, o, summary, expect_all_solved=False)
        assert not np.array_equal(data.uv, before[o.name]), f"{o.name} was not unwrapped"


def test_pack_off_keeps_islands_near(ext, scene):
    obj = suzanne()
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], method="lscm", pack="OFF")
    assert result == {"FINISHED"}
    after = read(ext, obj)
    chart = np.asarray(summary.results[obj.name].chart)
    for k in np.unique(chart[chart >= 0]):
        corners = corner_mask(chart == k, before.face_sizes)
        old, new = before.uv[corners], after.uv[corners]
        old_c, new_c = (old.min(0) + old.max(0)) / 2, (new.min(0) + new.max(0)) / 2
        old_d, new_d = np.linalg.norm(np.ptp(old, 0)), np.linalg.norm(np.ptp(new, 0))
        assert np.linalg.norm(new_c - old_c) <= 0.5 * old_d, f"chart {k} moved away"
        assert 0.25 * old_d <= new_d <= 4.0 * old_d, f"chart {k} rescaled {new_d / old_d:.2f}x"


def test_creates_uv_map_when_missing(ext, scene):
    io = ext.mesh_io
    obj = common.link_mesh_object("Ngons", io.new_mesh("Ngons", *read_shape_ngon()))
    assert io.active_uv_name(obj.data) is None
    result, summary = unwrap(ext, [obj], method="tutte", boundary="square")
    assert result == {"FINISHED"}
    assert io.active_uv_name(obj.data) == "UVMap"
    # A square boundary promises no flips: pentagons with three corners on one side of the
    # square get a zero-area triangle in Blender's triangulation. The report must count them.
    check_result(ext, obj, summary, expect_no_flips=False)


def test_scene_defaults_panel_properties(ext, scene):
    defaults = bpy.context.scene.uvflat
    defaults.method = "spectral"
    defaults.max_iterations = 321
    names = ext.methods.SETTING_NAMES
    assert {"method", "pack", "margin", "boundary", "max_iterations"} <= set(names)
    assert ext.methods.core_options(defaults) == {"max_iterations": 321, "tolerance": 1e-10}


def test_texel_density_settings_go_from_the_sidebar_to_the_unwrap(ext, scene):
    """The sidebar's Texel Density (declared once with the other shared settings) is drawn in
    the redo panel and the sidebar, copied into the operator when it is invoked, and reaches
    the packing: Fixed 256 px/m at 2048 px is 1/8 UV unit per metre."""
    defaults = bpy.context.scene.uvflat
    names = ("density_mode", "texel_density", "texture_size")
    assert set(names) <= set(ext.methods.SETTING_NAMES)
    drawn = []
    layout = SimpleNamespace(prop=lambda _props, name, **_kw: drawn.append(name),
                             column=lambda: layout, use_property_split=True,
                             use_property_decorate=False,
                             prop_search=lambda _p, name, *_a: drawn.append(name))
    ext.methods.draw_settings(layout, defaults)
    assert set(names) <= set(drawn)
    defaults.density_mode, defaults.texel_density, defaults.texture_size = "FIXED", 256.0, 2048
    defaults.shape_method = "AABB"  # packs in a millisecond: the unwrap runs in one go
    try:
        settings = ext.engine.PackSettings(**ext.methods.pack_settings(defaults))
        assert (settings.density, settings.texel_density, settings.texture_size) == \
            ("FIXED", 256.0, 2048)
        assert settings.uv_per_metre == 1 / 8
        # invoke copies the sidebar's values into the operator (headless Blender runs no
        # invoke from bpy.ops, so it is called on a stand-in of the operator's properties,
        # as test_invoke_keeps_the_properties_the_caller_set does), which then runs with them
        props = _Props(dict.fromkeys(ext.methods.SETTING_NAMES), set())
        ran = []
        stand_in = SimpleNamespace(properties=props,
                                   execute=lambda ctx: ran.append(ctx) or {"FINISHED"})
        assert ext.operators.UV_OT_uvflat_unwrap.invoke(stand_in, bpy.context, None) == \
            {"FINISHED"} and ran
        assert (props.density_mode, props.texel_density, props.texture_size) == \
            ("FIXED", 256.0, 2048)
        obj = suzanne()
        result, summary = unwrap(ext, [obj], **{n: getattr(props, n) for n in names},
                                 shape_method=props.shape_method)
        assert result == {"FINISHED"}, summary
        assert summary.density == "FIXED" and summary.texture_size == 2048
        rows = ext.engine.chart_rows(summary)
        assert rows and all(r["density"] == pytest.approx(256.0, rel=0.02) for r in rows
                            if r["status"] != "failed")
    finally:
        for name in names + ("shape_method",):
            defaults.property_unset(name)


# ---------------------------------------------------------------------------------------------
# ABF / ABF++

# ABF's solved angles are those of a planar triangulation with every angle in (0, pi), so the
# reconstruction of a *disk* chart never flips.  On a chart with holes the angles do not close
# the holes up (as in the papers): the reconstruction is least squares there and promises
# nothing, so only the report's honesty is checked (as for LSCM).


def _abf_check(ext, obj, summary):
    """Every chart solved by ABF; seams respected; the report tells the truth about flips;
    no flipped face (counted here, independently of the core) on the disk charts, with or
    without holes (holes are closed by the angle constraints of a virtual fill)."""
    result = summary.results[obj.name]
    for c in result.charts:
        assert c.status == "solved", f"{obj.name}: chart {c.id} {c.status}: {c.reason}"
        assert c.method == "abf"
    data = check_result(ext, obj, summary, expect_no_flips=False)
    disks = [c.id for c in result.charts if c.kind in ("disk", "disk_with_holes")]
    chart = np.asarray(result.chart)
    on_disks = np.where(np.isin(chart, disks), chart, -1)
    assert flipped_triangles(data, on_disks) == 0, f"{obj.name}: flips on a disk chart"
    assert all(c.flips == 0 for c in result.charts if c.kind in ("disk", "disk_with_holes"))
    return result


def test_abf_suzanne_seams_and_no_flips(ext, scene):
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"}
    assert summary.charts >= 2, summary.line()
    res = _abf_check(ext, obj, summary)
    assert sum(c.kind == "disk" for c in res.charts) >= 2


@pytest.mark.parametrize("mesh", SHARED_MESHES)
def test_abf_shared_meshes(ext, scene, mesh):
    obj = shared_mesh(mesh)
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    res = _abf_check(ext, obj, summary)
    import uvflat

    # The report agrees with uvflat.metrics measuring the UVs as written into Blender (float32
    # storage and packing scale aside): flips exactly, conformal distortion closely.
    data = read(ext, obj)
    m = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv)
    assert m.flips == sum(c.flips for c in res.charts)
    if len(res.charts) == 1:
        c = res.charts[0]
        assert abs(m.conformal - c.conformal) < 1e-3 * m.conformal, (m.conformal, c.conformal)


@pytest.mark.parametrize("mesh", SHARED_MESHES + ("alligator.obj", "suzanne"))
def test_abf_convex_boundary(ext, scene, mesh):
    """Convex outer outline: every chart solved by ABF (no LSCM fallback), no flipped face,
    no island whose outline crosses itself, on disks and disks with holes."""
    obj = suzanne() if mesh == "suzanne" else shared_mesh(mesh)
    # The method on the charts as given (automatic seams would also cut for density).
    result, summary = unwrap(ext, [obj], method="abf", abf_boundary="convex", auto_seams=False)
    assert result == {"FINISHED"}, summary
    _abf_check(ext, obj, summary)
    import uvflat

    data = read(ext, obj)
    m = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv)
    assert m.overlapping_charts == 0


def test_abf_options_reach_the_core_and_the_panel_shows_only_them(ext, scene):
    defaults = bpy.context.scene.uvflat
    defaults.method = "abf"
    defaults.abf_solver = "abf"
    defaults.abf_boundary = "convex"
    defaults.abf_max_iterations = 17
    defaults.abf_tolerance_exponent = -11
    assert ext.methods.core_options(defaults) == {
        "solver": "abf", "boundary": "convex", "max_iterations": 17, "tolerance": 1e-11}
    keys = set(ext.methods.OPTIONS)
    assert len(keys) == len(set(ext.methods.SETTING_NAMES) & keys)

    class Layout:
        def __init__(self):
            self.props = []

        def prop(self, _props, name):
            self.props.append(name)

        def column(self):
            return self

    layout = Layout()
    ext.methods.draw_settings(layout, defaults)
    shown = set(layout.props) & keys
    assert shown == {"abf_solver", "abf_boundary", "abf_max_iterations", "abf_tolerance_exponent"}
    defaults.method = "spectral"
    layout = Layout()
    ext.methods.draw_settings(layout, defaults)
    assert set(layout.props) & keys == {"max_iterations", "tolerance_exponent"}


def test_abf_plain_solver_through_the_operator(ext, scene):
    """The plain ABF solver (sparse LU of the full system) reaches the same kind of result."""
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method="abf", abf_solver="abf")
    assert result == {"FINISHED"}
    _abf_check(ext, obj, summary)


# ---------------------------------------------------------------------------------------------
# Scaffold (bijective) and ARAP (no injectivity promise)


@pytest.mark.parametrize("mesh", ("suzanne", "camelhead.off", "lion.off"))
def test_scaffold_no_flips_and_no_overlap(ext, scene, mesh):
    obj = suzanne() if mesh == "suzanne" else shared_mesh(mesh)
    result, summary = unwrap(ext, [obj], method="scaffold")
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    data = check_result(ext, obj, summary)
    import uvflat

    solved = np.asarray(summary.results[obj.name].face_solved, dtype=bool)
    m = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv, selected=solved)
    assert m.overlapping_charts == 0, f"{obj.name}: {m}"


@pytest.mark.parametrize("mesh", ("suzanne", "camelhead.off"))
def test_arap_reports_its_flips_honestly(ext, scene, mesh):
    obj = suzanne() if mesh == "suzanne" else shared_mesh(mesh)
    result, summary = unwrap(ext, [obj], method="arap")
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    check_result(ext, obj, summary, expect_no_flips=False)


# ---------------------------------------------------------------------------------------------
# Quality against Blender's own unwrap (same mesh, same seams, same process; not timed)

# uvflat method, the Blender method of its family, the metric the method minimises.
ANCHORS = [("slim", "MINIMUM_STRETCH", "symmetric_dirichlet"),
           ("scaffold", "MINIMUM_STRETCH", "symmetric_dirichlet"),
           ("abf", "ANGLE_BASED", "conformal"),
           ("lscm", "CONFORMAL", "conformal")]


def _compare_with_blender(ext, obj, method, blender_method, metric):
    """Blender's unwrap, then uvflat's with default options, on the same object: uvflat has no
    more flipped triangles and at most Blender's distortion (+1e-4) in ``metric``."""
    import uvflat

    common.edit_mode([obj])
    try:
        assert bpy.ops.uv.unwrap(method=blender_method, margin=0.001) == {"FINISHED"}
    finally:
        common.object_mode()
    data = read(ext, obj)
    # Both measured on the triangles Blender renders (DESIGN: n-gons by loop_triangles).
    tris = ext.mesh_io.read_loop_triangles(obj.data)
    theirs = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv, triangles=tris)
    # Same seams as Blender's: automatic seams off (they would also cut for density).
    result, summary = unwrap(ext, [obj], method=method, margin=0.001, auto_seams=False)
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    data = read(ext, obj)
    ours = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv, triangles=tris)
    assert ours.charts == theirs.charts
    assert ours.flips <= theirs.flips, (ours.flips, theirs.flips)
    assert getattr(ours, metric) <= getattr(theirs, metric) + 1e-4, (
        f"{method} {metric} {getattr(ours, metric):.5f} vs Blender {blender_method} "
        f"{getattr(theirs, metric):.5f}")


@pytest.mark.parametrize("mesh", ("suzanne", "camelhead.off"))
@pytest.mark.parametrize("method,blender_method,metric", ANCHORS, ids=[a[0] for a in ANCHORS])
def test_default_quality_matches_or_beats_blender(ext, scene, mesh, method, blender_method, metric):
    """With its default options each method reaches at most the distortion (the one it
    minimises) of Blender's unwrap of the same family, with no more flipped triangles."""
    obj = suzanne() if mesh == "suzanne" else shared_mesh(mesh)
    _compare_with_blender(ext, obj, method, blender_method, metric)


@pytest.mark.parametrize("mesh", ("halftunnel.off", "beetle.off"))
def test_abf_quality_on_charts_with_holes(ext, scene, mesh):
    """Charts with holes (Blender fills holes before unwrapping): ABF no worse than
    ANGLE_BASED and flip-free."""
    _compare_with_blender(ext, shared_mesh(mesh), "abf", "ANGLE_BASED", "conformal")


# ---------------------------------------------------------------------------------------------
# Menus, invoke and keymap (stand-ins for what background mode lacks: windows, events, menus)


class _RecordingLayout:
    """Stand-in for a menu's UILayout: records operator ids, expands ``menu_contents``."""

    def __init__(self, expand):
        self.operators = []
        self._expand = expand
        self.operator_context = "EXEC_REGION_WIN"

    def operator(self, idname, **_kwargs):
        self.operators.append(idname)
        return SimpleNamespace()

    def menu_contents(self, name):
        self._expand(name, self)

    def __getattr__(self, _name):  # separator, menu, template_* ...: nothing to record
        return lambda *args, **kwargs: SimpleNamespace()


def _draw_menu(menu_name, layout=None):
    """Run every draw function of a menu (its own and the appended ones) on a recording
    layout, following ``menu_contents`` into inlined menus as Blender does."""
    layout = layout or _RecordingLayout(_draw_menu)
    menu = getattr(bpy.types, menu_name)
    stand_in = SimpleNamespace(layout=layout, bl_idname=menu_name)
    for draw in menu._dyn_ui_initialize():
        draw(stand_in, bpy.context)
    return layout


@pytest.mark.parametrize("menu_name", ["VIEW3D_MT_uv_map", "IMAGE_MT_uvs_unwrap"])
def test_menu_shows_the_operator_once(ext, menu_name):
    layout = _draw_menu(menu_name)
    assert layout.operators.count("uv.uvflat_unwrap") == 1, layout.operators


class _Props:
    """Stand-in for an operator's properties: values plus the names the caller set."""

    def __init__(self, values, set_names):
        self.__dict__.update(values)
        self._set = set(set_names)

    def is_property_set(self, name):
        return name in self._set


def _defaults_values(ext):
    return {name: getattr(bpy.context.scene.uvflat, name) for name in ext.methods.SETTING_NAMES}


def test_invoke_keeps_the_properties_the_caller_set(ext, scene):
    defaults = bpy.context.scene.uvflat
    defaults.method, defaults.margin, defaults.pack = "lscm", 0.05, "ALL"
    # bounding boxes pack in a millisecond: the unwrap runs in one go, not modal
    defaults.shape_method = "AABB"
    values = _defaults_values(ext)
    values.update(method="abf", margin=0.2, pack="AROUND")
    props = _Props(values, {"method", "margin"})  # e.g. layout.operator(...).method = "abf"
    executed = []
    stand_in = SimpleNamespace(properties=props, execute=lambda ctx: executed.append(ctx) or {"FINISHED"})
    assert ext.operators.UV_OT_uvflat_unwrap.invoke(stand_in, bpy.context, None) == {"FINISHED"}
    assert executed, "invoke did not run execute"
    assert props.method == "abf" and props.margin == 0.2, "invoke overwrote what the caller set"
    assert props.pack == "ALL", "a property the caller did not set must come from the sidebar"
    assert props.preset == "ADVANCED", "a method named by the caller runs as named"
    defaults.shape_method = "CONCAVE"


def test_default_keymap_entry_runs_the_method_it_names(ext, scene):
    keyconfig = bpy.context.window_manager.keyconfigs.addon
    items = [(km.name, kmi) for km in keyconfig.keymaps for kmi in km.keymap_items
             if kmi.idname == "uv.uvflat_unwrap"]
    assert {"Mesh", "UV Editor"} <= {name for name, _ in items}, items
    kmi = items[0][1]
    assert not kmi.properties.is_property_set("method"), "by default the sidebar's method runs"
    # A user edits the shortcut to name a method: invoking it runs that method, whatever the
    # sidebar says.
    bpy.context.scene.uvflat.method = "lscm"
    # bounding boxes pack in a millisecond: the unwrap runs in one go, not modal
    bpy.context.scene.uvflat.shape_method = "AABB"
    kmi.properties.method = "tutte"
    try:
        assert kmi.properties.is_property_set("method")
        values = _defaults_values(ext)
        values.update({name: getattr(kmi.properties, name) for name in ext.methods.SETTING_NAMES
                       if kmi.properties.is_property_set(name)})
        props = _Props(values, [n for n in ext.methods.SETTING_NAMES
                                if kmi.properties.is_property_set(n)])
        ran = {}
        stand_in = SimpleNamespace(properties=props,
                                   execute=lambda ctx: ran.update(method=props.method) or {"FINISHED"})
        ext.operators.UV_OT_uvflat_unwrap.invoke(stand_in, bpy.context, None)
        assert ran["method"] == "tutte"
        obj = suzanne()
        result, summary = unwrap(ext, [obj], method=ran["method"])
        assert result == {"FINISHED"} and summary.method == "tutte"
        assert "tutte" in summary.line()
    finally:
        kmi.properties.property_unset("method")
        bpy.context.scene.uvflat.shape_method = "CONCAVE"


def test_keymap_unregistered_with_the_addon(ext):
    keyconfig = bpy.context.window_manager.keyconfigs.addon
    count = lambda: sum(kmi.idname == "uv.uvflat_unwrap"  # noqa: E731
                        for km in keyconfig.keymaps for kmi in km.keymap_items)
    assert count() == len(ext.ui.KEYMAP_ITEMS)
    ext.ui.unregister_keymaps()
    try:
        assert count() == 0
    finally:
        ext.ui.register_keymaps()
    assert count() == len(ext.ui.KEYMAP_ITEMS)


# ---------------------------------------------------------------------------------------------
# Packing


def raster(uv, face_sizes, faces, lo, hi, n=256):
    """Grid cells (n x n over [lo, hi]^2) whose centre lies strictly inside a triangle of the
    given faces (fan triangulation)."""
    tris, face = fan_triangles(face_sizes)
    tris = tris[np.asarray(faces, dtype=bool)[face]]
    covered = np.zeros((n, n), dtype=bool)
    step = (hi - lo) / n
    centres = lo + (np.arange(n) + 0.5) * step
    for a, b, c in tris:
        p = uv[[a, b, c]]
        i0, j0 = np.clip(((p.min(0) - lo) / step).astype(int), 0, n - 1)
        i1, j1 = np.clip(((p.max(0) - lo) / step).astype(int) + 1, 0, n)
        if i1 <= i0 or j1 <= j0:
            continue
        x, y = np.meshgrid(centres[i0:i1], centres[j0:j1], indexing="ij")
        d = [(p[(k + 1) % 3, 0] - p[k, 0]) * (y - p[k, 1]) - (p[(k + 1) % 3, 1] - p[k, 1]) * (x - p[k, 0])
             for k in range(3)]
        inside = ((d[0] > 0) & (d[1] > 0) & (d[2] > 0)) | ((d[0] < 0) & (d[1] < 0) & (d[2] < 0))
        covered[i0:i1, j0:j1] |= inside
    return covered


def test_pack_around_keeps_other_islands_and_does_not_overlap_them(ext, scene):
    obj = suzanne()
    io = ext.mesh_io
    # Suzanne's own islands are the locked ones; move them into the lower half of the tile so
    # that there is free space to pack into.
    data = read(ext, obj)
    io.write_uv(obj.data, io.active_uv_name(obj.data), data.uv * [1.0, 0.5])
    sel = np.zeros(len(obj.data.polygons), dtype=bool)
    sel[::4] = True
    io.select_faces(obj.data, sel)
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], select_all=False, method="lscm", pack="AROUND")
    assert result == {"FINISHED"}, summary
    after = read(ext, obj)
    kept = corner_mask(~sel, before.face_sizes)
    assert np.array_equal(after.uv[kept], before.uv[kept]), "locked islands moved"
    assert np.array_equal(io.read_face_selection(obj.data), sel), "selection changed"
    assert not io.read_pins(obj.data).any(), "pins left behind"
    lo, hi = min(after.uv.min(), 0.0), max(after.uv.max(), 1.0)
    old = raster(after.uv, after.face_sizes, ~sel, lo, hi)
    new = raster(after.uv, after.face_sizes, sel, lo, hi)
    assert new.sum() > 50, "the new islands were not rasterised"
    assert not (old & new).any(), f"{(old & new).sum()} cells covered by old and new islands"
    assert after.uv[corner_mask(sel, after.face_sizes)].min() >= -1e-6
    assert after.uv[corner_mask(sel, after.face_sizes)].max() <= 1 + 1e-6


def test_pack_off_without_previous_uvs_lands_in_the_tile(ext, scene):
    io = ext.mesh_io
    # two separate n-gon disks, no UV map: nothing to fit to
    pos, cv, fs = read_shape_ngon()
    pos2 = pos + [10.0, 0.0, 0.0]
    obj = common.link_mesh_object("Two", io.new_mesh("Two", np.vstack([pos, pos2]),
                                                     np.concatenate([cv, cv + len(pos)]),
                                                     np.concatenate([fs, fs])))
    result, summary = unwrap(ext, [obj], method="lscm", pack="OFF")
    assert result == {"FINISHED"}
    data = read(ext, obj)
    assert data.uv.min() >= -1e-6 and data.uv.max() <= 1 + 1e-6, "islands left outside 0-1"
    half = np.arange(len(data.face_sizes)) < len(fs)
    a = raster(data.uv, data.face_sizes, half, 0.0, 1.0)
    b = raster(data.uv, data.face_sizes, ~half, 0.0, 1.0)
    assert a.any() and b.any() and not (a & b).any(), "the two islands overlap"


def test_non_manifold_edges_are_a_warning(ext, scene):
    io = ext.mesh_io
    # three quads on one edge (a fin) plus a fourth
    pos = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, -1, 0], [0, -1, 0],
                    [1, 0, 1], [0, 0, 1]], float)
    cv = np.array([0, 1, 2, 3, 1, 0, 5, 4, 0, 1, 6, 7])
    obj = common.link_mesh_object("Fin", io.new_mesh("Fin", pos, cv, [4, 4, 4]))
    common.edit_mode([obj])
    reports = []
    stand_in = SimpleNamespace(report=lambda kind, text: reports.append((kind, text)),
                               **_defaults_values(ext))
    stand_in.preset, stand_in.method = "ADVANCED", "lscm"
    try:
        assert ext.operators.UV_OT_uvflat_unwrap.execute(stand_in, bpy.context) == {"FINISHED"}
    finally:
        common.object_mode()
    assert ext.engine.LAST_SUMMARY.non_manifold_edges == 1
    (kind, text), = reports
    assert kind == {"WARNING"} and "1 non-manifold edge" in text, reports
    assert ext.engine.LAST_SUMMARY.method == "lscm"


def _pydata_grid_with_a_flipped_face(n=4):
    """An ``n`` by ``n`` quad grid made by ``Mesh.from_pydata``, as scripts and importers make
    meshes, with one inner face wound the other way (its normal points down)."""
    verts = [(x, y, 0.0) for y in range(n + 1) for x in range(n + 1)]
    faces = []
    for y in range(n):
        for x in range(n):
            a = y * (n + 1) + x
            faces.append((a, a + 1, a + n + 2, a + n + 1))
    inner = (n // 2) * n + n // 2
    faces[inner] = faces[inner][::-1]
    mesh = bpy.data.meshes.new("PyData")
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    return common.link_mesh_object("PyData", mesh), inner


def test_selection_of_a_mesh_made_by_from_pydata(ext, scene):
    """Blender 5.0.1 lists ``.select_edge`` of a ``from_pydata`` mesh as an INT32_2D attribute
    over a boolean array; selecting faces must still work (and leave a boolean attribute)."""
    obj, _ = _pydata_grid_with_a_flipped_face()
    mesh = obj.data
    assert mesh.attributes[".select_edge"].data_type != "BOOLEAN", "Blender fixed the quirk"
    mask = np.zeros(len(mesh.polygons), bool)
    mask[:3] = True
    ext.mesh_io.select_faces(mesh, mask)
    assert mesh.attributes[".select_edge"].data_type == "BOOLEAN"
    assert np.array_equal(ext.mesh_io.read_face_selection(mesh), mask)
    edges = np.zeros(len(mesh.edges), bool)
    mesh.edges.foreach_get("select", edges)
    assert edges.sum() == 10  # the three quads of the first row: 4 + 3 + 3 edges


def test_edges_between_opposite_normals_are_a_warning(ext, scene):
    """A face whose normal points the other way is cut off along its four inner edges (the
    faces run those edges the same way); the status line says so and how to join it."""
    obj, inner = _pydata_grid_with_a_flipped_face()
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"}
    assert summary.inconsistent_edges == 4 and summary.non_manifold_edges == 0
    assert summary.needs_attention
    assert "4 edges between faces with opposite normals treated as seams" in summary.line()
    assert "Recalculate Outside" in summary.line()
    res = summary.results[obj.name]
    chart = np.asarray(res.chart)
    assert len(set(chart.tolist())) == 2 and np.sum(chart == chart[inner]) == 1
    data = read(ext, obj)
    assert np.asarray(res.face_solved).all()
    assert flipped_triangles(data, chart) == 0


# ---------------------------------------------------------------------------------------------
# Modal unwrap on a worker thread (stand-ins for the window manager, window and events)


class _WindowManagerStandIn:
    def __init__(self):
        self.handlers, self.timers, self.progress = [], [], []

    def event_timer_add(self, step, window=None):
        timer = SimpleNamespace(step=step, window=window)
        self.timers.append(timer)
        return timer

    def event_timer_remove(self, timer):
        self.timers.remove(timer)

    def modal_handler_add(self, op):
        self.handlers.append(op)
        return True

    def progress_begin(self, lo, hi):
        self.progress.append(("begin", lo, hi))

    def progress_update(self, value):
        self.progress.append(("update", value))

    def progress_end(self):
        self.progress.append(("end",))


class _ContextStandIn:
    """bpy.context with a window, a window manager and a workspace that record what the
    operator does with them."""

    def __init__(self):
        self.window = SimpleNamespace(name="window")
        self.window_manager = _WindowManagerStandIn()
        self.status = []
        self.workspace = SimpleNamespace(status_text_set=self.status.append)

    def __getattr__(self, name):
        return getattr(bpy.context, name)


def _operator_stand_in(ext, **props):
    """An object with the operator's own methods and properties (defaults from the sidebar)."""
    op_cls = ext.operators.UV_OT_uvflat_unwrap

    class Op:
        invoke, execute, start_modal, modal = (op_cls.invoke, op_cls.execute,
                                               op_cls.start_modal, op_cls.modal)
        _status, _end_ui = op_cls._status, op_cls._end_ui

        def __init__(self):
            self.__dict__.update(_defaults_values(ext))
            self.__dict__.update(props)
            self._set = set(props)
            self.properties = self
            self.reports = []

        def is_property_set(self, name):
            return name in self._set

        def report(self, kind, text):
            self.reports.append((kind, text))

    return Op()


def _snapshot(mesh):
    """Bytes of every UV map, pin layer, seam and selection attribute of ``mesh``."""
    state = {}
    for attr in mesh.attributes:
        if (attr.domain == "CORNER" and attr.data_type == "FLOAT2") or attr.name.startswith(
                (".pn.", ".select_", ".uv_select_", "uv_seam", ".uv_seam")):
            width = 2 if attr.data_type == "FLOAT2" else 1
            field = "vector" if attr.data_type == "FLOAT2" else "value"
            dtype = np.float32 if attr.data_type == "FLOAT2" else bool
            values = np.empty(len(attr.data) * width, dtype=dtype)
            attr.data.foreach_get(field, values)
            state[attr.name] = values.tobytes()
    state["uv maps"] = tuple(layer.name for layer in mesh.uv_layers)
    return state


def _drive_modal(op, ctx, first_event="TIMER", timeout=120.0):
    import time

    events = [first_event]
    t0 = time.perf_counter()
    while True:
        kind = events.pop(0) if events else "TIMER"
        result = op.modal(ctx, SimpleNamespace(type=kind, value="PRESS"))
        if result != {"RUNNING_MODAL"}:
            return result
        assert time.perf_counter() - t0 < timeout, "the modal unwrap never ended"
        time.sleep(0.02)


def test_modal_unwrap_matches_the_direct_one(ext, scene, monkeypatch):
    monkeypatch.setattr(ext.engine, "MODAL_AFTER_SECONDS", 0.0)
    obj = suzanne()
    io = ext.mesh_io
    before = read(ext, obj)
    seams_before = io.read_edges(obj.data)[1].copy()
    common.edit_mode([obj])
    ctx = _ContextStandIn()
    op = _operator_stand_in(ext, method="lscm", pack="OFF")
    try:
        assert op.invoke(ctx, SimpleNamespace(type="LEFTMOUSE", value="PRESS")) == {"RUNNING_MODAL"}
        assert ctx.window_manager.handlers == [op] and ctx.window_manager.timers
        # other events are swallowed while the solve runs (nothing can edit the mesh)
        assert op.modal(ctx, SimpleNamespace(type="G", value="PRESS")) == {"RUNNING_MODAL"}
        assert _drive_modal(op, ctx) == {"FINISHED"}
        assert obj.mode == "EDIT"
    finally:
        common.object_mode()
    modal_uv = read(ext, obj).uv
    assert not ctx.window_manager.timers, "timer left running"
    assert ctx.window_manager.progress[0][0] == "begin" and ctx.window_manager.progress[-1] == ("end",)
    assert ctx.status and "Esc" in ctx.status[0] and ctx.status[-1] is None
    assert op.reports and "lscm" in op.reports[-1][1]
    # the same unwrap in one go gives the same UVs (from the same UVs and seams: automatic
    # seams marked the seams they cut)
    io.write_uv(obj.data, io.active_uv_name(obj.data), before.uv)
    io.write_seams(obj.data, seams_before)
    result, _ = unwrap(ext, [obj], method="lscm", pack="OFF")
    assert result == {"FINISHED"}
    np.testing.assert_array_equal(read(ext, obj).uv, modal_uv)


@pytest.mark.parametrize("method,options", [("lscm", {}),
                                            ("slim", {"slim_iterations": 500})])
def test_modal_escape_leaves_everything_byte_identical(ext, scene, monkeypatch, method, options):
    monkeypatch.setattr(ext.engine, "MODAL_AFTER_SECONDS", 0.0)
    obj = common.suzanne_subdivided(levels=1)
    io = ext.mesh_io
    obj.data.uv_layers.new(name="Second")
    sel = np.zeros(len(obj.data.polygons), dtype=bool)
    sel[: len(sel) // 2] = True
    io.select_faces(obj.data, sel)
    before = _snapshot(obj.data)
    common.edit_mode([obj], select_all=False)
    ctx = _ContextStandIn()
    op = _operator_stand_in(ext, method=method, **options)
    try:
        assert op.invoke(ctx, SimpleNamespace(type="LEFTMOUSE", value="PRESS")) == {"RUNNING_MODAL"}
        assert _drive_modal(op, ctx, first_event="ESC") == {"CANCELLED"}
        assert obj.mode == "EDIT", "back in edit mode after cancelling"
    finally:
        common.object_mode()
    assert not ctx.window_manager.timers and ctx.status[-1] is None
    assert any("cancelled" in text for _, text in op.reports), op.reports
    assert _snapshot(obj.data) == before, "cancel changed a UV map, seam or selection"
    assert ext.engine.LAST_SUMMARY is None


def test_small_unwrap_or_no_window_runs_directly(ext, scene):
    obj = suzanne()
    common.edit_mode([obj])
    # not packed: Blender's packer may take longer than the solve (see test_addon_artist)
    op = _operator_stand_in(ext, method="tutte", pack="OFF")
    ran = []
    op.execute = lambda ctx: ran.append("execute") or {"FINISHED"}
    try:
        # background mode: no window
        assert op.invoke(bpy.context, None) == {"FINISHED"}
        # a window, but a small selection (Suzanne: 500 faces of Tutte, well under 0.5 s) and
        # no packing
        assert op.invoke(_ContextStandIn(), None) == {"FINISHED"}
    finally:
        common.object_mode()
    assert ran == ["execute", "execute"]


# ---------------------------------------------------------------------------------------------
# Seeing the result: per-face distortion attributes, heat map, flipped faces, chart list


def test_face_attributes_equal_uvflat_metrics(ext, scene):
    import uvflat

    obj = suzanne()
    io = ext.mesh_io
    sel = np.ones(len(obj.data.polygons), dtype=bool)
    sel[::5] = False
    io.select_faces(obj.data, sel)
    result, summary = unwrap(ext, [obj], select_all=False, method="lscm", pack="ALL")
    assert result == {"FINISHED"}
    data = read(ext, obj)
    solved = np.asarray(summary.results[obj.name].face_solved, dtype=bool) & sel
    # measured on the triangles Blender renders, as the unwrap measures its quads and n-gons
    m = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv,
                       selected=solved, triangles=io.read_loop_triangles(obj.data))
    conformal = io.read_attribute(obj.data, "uvflat_conformal")
    area = io.read_attribute(obj.data, "uvflat_area")
    assert obj.data.attributes["uvflat_conformal"].domain == "FACE"
    np.testing.assert_allclose(conformal[solved], m.face_conformal[solved], rtol=1e-4)
    np.testing.assert_allclose(area[solved], m.face_area[solved], rtol=1e-4)
    assert np.isnan(conformal[~sel]).all(), "faces never unwrapped have no measure"
    flipped = io.read_attribute(obj.data, "uvflat_flipped")
    assert flipped.shape == (len(sel),) and not flipped[~sel].any()
    # the heat map is hidden (the default): no heat colours slow the mesh's edit mode down
    colors = obj.data.color_attributes
    assert colors.get("uvflat_conformal_color") is None and colors.get("uvflat_area_color") is None


def test_heat_colors_scale(ext):
    dist = ext.distortion
    rgba = dist.heat_colors([1.0, dist.RED_AT, 10.0, np.inf, np.nan])
    np.testing.assert_allclose(rgba[0, :3], dist._RGB[0])
    np.testing.assert_allclose(rgba[1, :3], dist._RGB[-1])
    np.testing.assert_allclose(rgba[2, :3], dist._RGB[-1])
    np.testing.assert_allclose(rgba[3, :3], dist._RGB[-1])
    np.testing.assert_allclose(rgba[4, :3], 0.5)


def test_select_flipped_measures_the_existing_map(ext, scene):
    """Select Flipped asks the core about the active UV map as it is, one uvflat never made:
    a 3 x 3 quad grid mapped flat, with two inner vertices moved deep into a corner quad each,
    folds exactly those two quads (darts, reflex at the moved vertex; the quads around them
    stay convex). Hidden faces are never selected."""
    io = ext.mesh_io
    n = 3
    xs, ys = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0), indexing="xy")
    positions = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(xs.size)])
    vid = lambda i, j: j * (n + 1) + i  # noqa: E731
    corner_verts = np.array([[vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1)]
                             for j in range(n) for i in range(n)]).ravel()
    obj = common.link_mesh_object("Folded", io.new_mesh("Folded", positions, corner_verts,
                                                         np.full(n * n, 4)))
    name, _ = io.ensure_uv_map(obj.data)
    uv = positions[corner_verts, :2].copy()
    uv[corner_verts == vid(1, 1)] = [0.2, 0.2]  # into quad 0
    uv[corner_verts == vid(2, 2)] = [2.8, 2.8]  # into quad 8
    io.write_uv(obj.data, name, uv)
    assert io.read_attribute(obj.data, "uvflat_flipped") is None, "never unwrapped by uvflat"
    # independently of the core: the quads that are not strictly convex in UV (all four
    # triangles of both diagonal splits counter-clockwise)
    c = np.arange(4 * n * n).reshape(-1, 4)
    uv_read = read(ext, obj).uv
    convex = np.ones(n * n, dtype=bool)
    for a, b, d in ((0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)):
        convex &= _signed(uv_read, c[:, a], c[:, b], c[:, d]) > 0
    assert np.flatnonzero(~convex).tolist() == [0, 8]
    common.edit_mode([obj], select_all=False)
    try:
        assert bpy.ops.uv.uvflat_select_flipped() == {"FINISHED"}
        assert obj.mode == "EDIT"
    finally:
        common.object_mode()
    assert np.flatnonzero(io.read_face_selection(obj.data)).tolist() == [0, 8]
    hidden = np.zeros(n * n, dtype=bool)
    hidden[8] = True
    obj.data.polygons.foreach_set("hide", hidden)
    common.edit_mode([obj], select_all=False)
    try:
        assert bpy.ops.uv.uvflat_select_flipped() == {"FINISHED"}
    finally:
        common.object_mode()
    assert np.flatnonzero(io.read_face_selection(obj.data, include_hidden=True)).tolist() == [0]


def test_heat_map_toggle_sets_and_restores_the_viewport(ext, scene):
    """The sidebar toggle on a real screen: every 3D view of headless Blender's window shades
    solid with attribute colours, the mesh's active colour attribute is the uvflat heat map,
    and turning it off puts the view's own shading back."""
    obj = suzanne()
    result, _ = unwrap(ext, [obj], method="lscm")
    assert result == {"FINISHED"}
    # The screen of headless Blender's window: real areas and real 3D view spaces.
    screen = bpy.context.screen
    assert screen is not None and bpy.data.screens.get(screen.name) == screen
    spaces = [area.spaces.active for area in screen.areas if area.type == "VIEW_3D"]
    assert spaces, "the layout screen has a 3D viewport"
    # Blender's own name for the colour type that shows the active colour attribute
    attribute = [item.identifier for item in
                 bpy.types.View3DShading.bl_rna.properties["color_type"].enum_items
                 if item.name == "Attribute"]
    assert len(attribute) == 1
    for space in spaces:
        space.shading.type, space.shading.color_type = "MATERIAL", "OBJECT"
    view_layer = bpy.context.view_layer
    for o in view_layer.objects:
        o.select_set(o == obj)
    view_layer.objects.active = obj
    settings = bpy.context.scene.uvflat
    settings.distortion_kind = "area"
    try:
        # the sidebar's toggle: its update runs with Blender's own context
        settings.show_distortion = True
        for space in spaces:
            assert space.shading.type == "SOLID"
            assert space.shading.color_type == attribute[0]
        colors = obj.data.color_attributes
        assert colors.active_color_name == "uvflat_area_color"
        assert colors.active_color.domain == "CORNER"
        # written from the stored per-face measure, one colour per corner
        dist, io = ext.distortion, ext.mesh_io
        expected = dist._linear_heat_colors(io.read_attribute(obj.data, dist.AREA))
        np.testing.assert_array_equal(io.read_attribute(obj.data, dist.COLOR["area"]),
                                      np.repeat(expected, io.read_face_sizes(obj.data), axis=0))
        settings.distortion_kind = "conformal"
        assert colors.active_color_name == "uvflat_conformal_color"
        assert colors.get("uvflat_area_color") is None, "only the shown kind"
        assert all(space.shading.color_type == attribute[0] for space in spaces)
    finally:
        settings.show_distortion = False
        settings.distortion_kind = "conformal"
    for space in spaces:
        assert (space.shading.type, space.shading.color_type) == ("MATERIAL", "OBJECT"), \
            "the viewport's own shading is put back"


def test_heat_map_on_a_mesh_in_edit_mode_keeps_it_in_edit_mode(ext, scene):
    """Showing the heat map writes its colours from object mode: a mesh in edit mode leaves
    it for the write and is back in edit mode, its selection unchanged, with the colours."""
    obj = suzanne()
    result, _ = unwrap(ext, [obj], method="lscm")
    assert result == {"FINISHED"}
    io, dist = ext.mesh_io, ext.distortion
    selection = np.zeros(len(obj.data.polygons), dtype=bool)
    selection[::3] = True
    io.select_faces(obj.data, selection)
    common.edit_mode([obj], select_all=False)
    try:
        ctx = SimpleNamespace(objects_in_mode=[obj], screen=None, view_layer=bpy.context.view_layer)
        ext.ui.show_heat_map(ctx, True, "conformal")
        assert obj.mode == "EDIT"
    finally:
        common.object_mode()
    assert obj.data.color_attributes.active_color_name == dist.COLOR["conformal"]
    colors = io.read_attribute(obj.data, dist.COLOR["conformal"])
    assert colors.shape == (len(obj.data.loops), 4) and np.isfinite(colors).all()
    np.testing.assert_array_equal(io.read_face_selection(obj.data), selection)


def test_unwrap_writes_heat_colours_only_while_the_heat_map_shows(ext, scene):
    obj = suzanne()
    settings = bpy.context.scene.uvflat
    dist, io = ext.distortion, ext.mesh_io
    try:
        for kind in ("area", "conformal"):
            settings.show_distortion, settings.distortion_kind = True, kind
            result, _ = unwrap(ext, [obj], method="lscm")
            assert result == {"FINISHED"}
            colors = obj.data.color_attributes
            assert colors.active_color_name == dist.COLOR[kind]
            other = "conformal" if kind == "area" else "area"
            assert colors.get(dist.COLOR[other]) is None
            expected = dist._linear_heat_colors(io.read_attribute(obj.data, {"area": dist.AREA, "conformal": dist.CONFORMAL}[kind]))
            np.testing.assert_array_equal(io.read_attribute(obj.data, dist.COLOR[kind]),
                                          np.repeat(expected, io.read_face_sizes(obj.data), axis=0))
        settings.show_distortion = False
        result, _ = unwrap(ext, [obj], method="lscm")
        assert result == {"FINISHED"}
        assert all(obj.data.color_attributes.get(n) is None for n in dist.COLOR.values()), \
            "stale colours are removed when the heat map is hidden"
    finally:
        settings.show_distortion = False


def _chart(id, status="solved", flips=0, overlap=False, conformal=1.0, reason=None):
    return SimpleNamespace(id=id, method="lscm", status=status, faces=10, flips=flips,
                           overlap=overlap, conformal=conformal, area=1.0, seconds=0.001,
                           reason=reason, kind="disk")


def test_status_line_is_short_and_groups_reasons(ext):
    engine = ext.engine
    charts = ([_chart(k, "failed", reason="closed surface: add a seam") for k in range(5)]
              + [_chart(5, "fallback", reason="did not converge")]
              + [_chart(6, flips=3), _chart(7, conformal=1.8), _chart(8, overlap=True)])
    summary = engine.Summary(method="lscm", charts=4, faces=40, seconds=0.5,
                             results={"Obj": SimpleNamespace(charts=charts)})
    for c in charts:
        problem = engine.ChartProblem("Obj", c.id, c.kind, c.status, c.reason or "")
        (summary.failed if c.status == "failed" else summary.fallback if c.status == "fallback"
         else []).append(problem)
    line = summary.line()
    assert line.count("closed surface") == 1 and "(x5)" in line, line
    assert "3 flipped" in line and line.endswith("see the uvflat sidebar"), line
    assert len(line) < 250, line
    rows = engine.chart_rows(summary)
    assert [r["chart"] for r in rows[:9]] == [0, 1, 2, 3, 4, 5, 6, 8, 7]
    clean = engine.Summary(method="lscm", charts=1, faces=10, seconds=0.1,
                           results={"Obj": SimpleNamespace(charts=[_chart(0)])})
    assert "sidebar" not in clean.line()


class _PanelLayout:
    """Stand-in for a panel's UILayout: every call returns the layout itself; labels and
    operators are recorded."""

    def __init__(self):
        self.labels, self.operators, self.props = [], [], []

    def label(self, text="", **_kwargs):
        self.labels.append(text)
        return self

    def operator(self, idname, **_kwargs):
        self.operators.append(idname)
        return SimpleNamespace()

    def prop(self, data, name, **_kwargs):
        self.props.append(name)
        return self

    def __getattr__(self, _name):
        return lambda *args, **kwargs: self


def test_result_panel_lists_the_last_unwraps_charts(ext, scene):
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method="lscm")
    assert result == {"FINISHED"}
    layout = _PanelLayout()
    stand_in = SimpleNamespace(layout=layout)
    ext.ui.UVFLAT_PT_result.draw(stand_in, bpy.context)
    assert "show_distortion" in layout.props and "distortion_kind" in layout.props
    assert "uv.uvflat_select_flipped" in layout.operators
    assert {"Chart", "Method", "Faces", "Flips", "Overlap", "Conformal", "Area", "Time"} <= set(layout.labels)
    first = ext.engine.chart_rows(summary)[0]
    assert f"{obj.name}:{first['chart']}" in layout.labels
    # the same panel in the 3D Viewport, where the heat map shows
    assert "UVFLAT_PT_result_3d" in dir(bpy.types)
    assert ext.ui.UVFLAT_PT_result_3d.bl_space_type == "VIEW_3D"


def test_addon_options_follow_the_core_contract(ext):
    """Every option the add-on offers is declared by the core for that method, with the same
    default, choices within the declared ones, and bounds within the declared domain."""
    import uvflat

    for info in ext.methods.METHODS:
        declared = {s["name"]: s for s in uvflat.METHOD_OPTIONS[info.id]}
        for key in info.options:
            option = ext.methods.OPTIONS[key]
            spec = declared.get(option.keyword)
            assert spec is not None, f"{info.id}: the add-on offers {option.keyword}, the core does not"
            keywords = option.make_property().keywords
            default = option.to_core(keywords["default"])
            if spec["type"] == "float":
                assert default == pytest.approx(spec["default"]), (info.id, key)
                low = option.to_core(keywords["min"])
                assert low > spec["min"] or (low == spec["min"] and not spec["min_exclusive"])
            elif spec["type"] == "int":
                assert default == spec["default"] and keywords["min"] >= spec["min"], (info.id, key)
            elif spec["type"] == "choice":
                assert default == spec["default"], (info.id, key)
                assert {i[0] for i in keywords["items"]} <= set(spec["choices"]), (info.id, key)


# ---------------------------------------------------------------------------------------------
# Correct aspect


def _material_with_image(obj, width, height):
    image = bpy.data.images.new("Texture", width, height)
    material = bpy.data.materials.new("Textured")
    if material.node_tree is None:  # older Blenders: nodes are off by default
        material.use_nodes = True
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    obj.data.materials.append(material)
    return image


def test_image_aspect_sources(ext, scene):
    obj = suzanne()
    aspect = ext.aspect
    assert aspect.image_aspect(SimpleNamespace(space_data=None), obj) == 1.0
    _material_with_image(obj, 200, 100)
    assert aspect.image_aspect(SimpleNamespace(space_data=None), obj) == 2.0
    # the UV editor's image wins over the material's
    editor = SimpleNamespace(type="IMAGE_EDITOR", image=SimpleNamespace(size=(100, 300)))
    assert aspect.image_aspect(SimpleNamespace(space_data=editor), obj) == pytest.approx(1 / 3)
    empty_editor = SimpleNamespace(type="IMAGE_EDITOR", image=None)
    assert aspect.image_aspect(SimpleNamespace(space_data=empty_editor), obj) == 2.0


def test_correct_aspect_halves_u_for_a_wide_texture(ext, scene):
    obj = suzanne()
    io = ext.mesh_io
    before = read(ext, obj)
    seams_before = io.read_edges(obj.data)[1].copy()
    result, summary = unwrap(ext, [obj], method="lscm", pack="OFF", correct_aspect=False)
    assert result == {"FINISHED"}
    plain = read(ext, obj).uv
    _material_with_image(obj, 256, 128)
    io.write_uv(obj.data, io.active_uv_name(obj.data), before.uv)
    io.write_seams(obj.data, seams_before)  # the seams the first run marked are undone
    result, summary = unwrap(ext, [obj], method="lscm", pack="OFF", correct_aspect=True)
    assert result == {"FINISHED"}
    wide = read(ext, obj).uv
    chart = np.repeat(np.asarray(summary.results[obj.name].chart), before.face_sizes)
    for k in np.unique(chart[chart >= 0]):
        a, b = plain[chart == k], wide[chart == k]
        np.testing.assert_allclose(np.ptp(b[:, 0]), np.ptp(a[:, 0]) / 2, rtol=1e-4)
        np.testing.assert_allclose(np.ptp(b[:, 1]), np.ptp(a[:, 1]), rtol=1e-4)
        # scaled about the island's centre
        np.testing.assert_allclose(b.min(0) + b.max(0), a.min(0) + a.max(0), atol=1e-5)
    # the distortion attributes measure texture pixels: the same with and without correction
    assert ext.mesh_io.read_attribute(obj.data, "uvflat_conformal") is not None


@pytest.mark.parametrize("pack", ["ALL", "OFF"], ids=["pack", "no_pack"])
def test_phase_timings_cover_the_run(ext, scene, pack):
    """The summary's phase timings name every phase once, are non-negative and add up to at
    most the whole run (they are disjoint parts of it); the solve phase is the core's time."""
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method="lscm", pack=pack)
    assert result == {"FINISHED"}
    phases = summary.phases
    expected = ({"read", "solve", "quality", "write", "mode", "other"}
                | ({"pack"} if pack != "OFF" else set()))
    assert set(phases) == expected, phases
    assert all(t >= 0.0 for t in phases.values()), phases
    assert sum(phases.values()) == pytest.approx(summary.seconds, abs=1e-6), (phases, summary.seconds)
    assert phases["solve"] == pytest.approx(summary.solve_seconds, rel=1e-9, abs=1e-12)
# Any triangulation: Blender's loop_triangles and the other diagonal of every quad

# Methods that promise no flips, on any triangulation an exporter may pick.
PROMISING = ["tutte", "mean_value", "slim", "mips", "scaffold", "abf"]


def blender_folds(ext, obj, result):
    """(flipped loop triangles, non-convex quads) of ``obj``'s UVs, measured here from
    Blender's own ``loop_triangles`` and both diagonals of every quad, each chart with the
    orientation of the majority of its triangles. Quads not convex in 3D count as their own
    triangles only (their faithful map keeps them concave). Quads with a corner at a vertex inside a
    chart shared by only two faces are left out: the two corner angles there sum to a full
    turn, so one of the two quads cannot be convex (the core splits them through that
    vertex; Blender may not)."""
    data = read(ext, obj)
    mesh = obj.data
    mesh.calc_loop_triangles()
    n_tri = len(mesh.loop_triangles)
    loops = np.empty(3 * n_tri, dtype=np.int32)
    mesh.loop_triangles.foreach_get("loops", loops)
    loops = loops.reshape(-1, 3).astype(np.int64)
    poly = np.empty(n_tri, dtype=np.int32)
    mesh.loop_triangles.foreach_get("polygon_index", poly)
    chart = np.asarray(result.chart)
    solved = np.asarray(result.face_solved, dtype=bool)
    uv = data.uv
    fs = np.asarray(data.face_sizes, dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    # Vertices on a mesh border or a seam are free to open up; count faces per vertex.
    cv = data.corner_verts.astype(np.int64)
    nxt = np.arange(len(cv)) + 1
    nxt[starts + fs - 1] = starts
    n_v = len(data.positions)
    all_keys = np.minimum(cv, cv[nxt]) * n_v + np.maximum(cv, cv[nxt])
    uniq, counts = np.unique(all_keys, return_counts=True)
    border = uniq[counts != 2]
    seam_keys = (np.minimum(data.seams[:, 0], data.seams[:, 1]).astype(np.int64) * n_v
                 + np.maximum(data.seams[:, 0], data.seams[:, 1])) if len(data.seams) else np.zeros(0, np.int64)
    open_keys = np.union1d(border, seam_keys)
    on_open = np.zeros(n_v, dtype=bool)
    on_open[(open_keys // n_v)] = True
    on_open[(open_keys % n_v)] = True
    faces_at = np.bincount(cv, minlength=n_v)
    face_of = np.repeat(np.arange(len(fs)), fs)
    exempt = np.zeros(len(fs), dtype=bool)
    np.logical_or.at(exempt, face_of, (faces_at[cv] == 2) & ~on_open[cv])
    exempt &= fs == 4
    # Blender's triangles, each chart with its majority orientation.
    area = _signed(uv, loops[:, 0], loops[:, 1], loops[:, 2])
    tri_chart = np.where(solved[poly] & ~exempt[poly], chart[poly], -1)
    sign = np.zeros(n_tri)
    for k in np.unique(tri_chart[tri_chart >= 0]):
        m = tri_chart == k
        sign[m] = 1.0 if (area[m] > 0).sum() >= (area[m] < 0).sum() else -1.0
    flipped = int(((sign * area <= 0) & (tri_chart >= 0)).sum())
    face_sign = np.zeros(len(fs))
    face_sign[poly] = sign
    # Quads: both splits, for quads convex in 3D (a concave or folded quad's faithful map keeps
    # its shape: one split is turned over on the surface itself).
    q = np.flatnonzero((fs == 4) & solved & ~exempt & convex_in_3d(data.positions, cv, fs, margin=0.02))
    c = [starts[q] + k for k in range(4)]
    s = face_sign[q]
    splits = [(0, 1, 2), (0, 2, 3), (0, 1, 3), (1, 2, 3)]
    convex = np.all([s * _signed(uv, c[a], c[b], c[d]) > 0 for a, b, d in splits], axis=0)
    return flipped, int((~convex).sum())


def noisy_quad_grid_smart_uv(name="NoisyGrid", n=40, seed=5):
    """A curved, noisy quad grid (some quads dart-shaped, i.e. concave in 3D) cut into charts
    by Smart UV Project's islands (seams from islands)."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=n + 1, y_subdivisions=n + 1, size=2.0)
    obj = bpy.context.active_object
    obj.name = name
    mesh = obj.data
    co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3).astype(np.float64)
    rng = np.random.default_rng(seed)
    h = 2.0 / n
    x = co[:, 0] + 0.3 * h * (rng.random(len(co)) - 0.5)
    y = co[:, 1] + 0.3 * h * (rng.random(len(co)) - 0.5)
    dart = rng.random(len(co)) < 0.03
    x[dart] = co[dart, 0] + 0.6 * h
    y[dart] = co[dart, 1] + 0.6 * h
    z = 0.6 * (x * x - y * y) + 0.25 * np.sin(4 * x) * np.cos(3 * y) + 0.05 * h * rng.random(len(co))
    mesh.vertices.foreach_set("co", np.column_stack([x, y, z]).astype(np.float32).ravel())
    mesh.update()
    common.edit_mode([obj])
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.smart_project()
    bpy.ops.uv.seams_from_islands(mark_seams=True)
    common.object_mode()
    return obj


@pytest.mark.parametrize("method", PROMISING)
def test_smart_uv_noisy_quad_grid_no_folds_under_any_triangulation(ext, scene, method):
    obj = noisy_quad_grid_smart_uv()
    assert len(ext.mesh_io.read_seams(obj.data)) > 0
    result, summary = unwrap(ext, [obj], method=method)
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    flipped, nonconvex = blender_folds(ext, obj, summary.results[obj.name])
    assert flipped == 0, f"{method}: {flipped} of Blender's loop triangles flipped; {summary.line()}"
    assert nonconvex == 0, f"{method}: {nonconvex} quads fold on one diagonal; {summary.line()}"


def test_smart_uv_noisy_quad_grid_folds_are_reported(ext, scene):
    """Tutte onto a square promises nothing: it lays border triangles whose corners reach one
    side of the square flat (zero area, a fold), and the report counts them (so the check above
    can fail). Automatic seams off."""
    obj = noisy_quad_grid_smart_uv()
    result, summary = unwrap(ext, [obj], method="tutte", boundary="square", auto_seams=False)
    assert result == {"FINISHED"}, summary
    flipped, nonconvex = blender_folds(ext, obj, summary.results[obj.name])
    assert nonconvex + flipped > 0
    reported = sum(c.flips for c in summary.results[obj.name].charts if c.status != "failed")
    assert reported >= nonconvex


@pytest.mark.parametrize("method", PROMISING)
def test_suzanne_no_folds_under_any_triangulation(ext, scene, method):
    obj = suzanne()
    result, summary = unwrap(ext, [obj], method=method)
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    flipped, nonconvex = blender_folds(ext, obj, summary.results[obj.name])
    assert flipped == 0, f"{method}: {flipped} of Blender's loop triangles flipped"
    assert nonconvex == 0, f"{method}: {nonconvex} quads fold on one diagonal"


@pytest.mark.parametrize("mesh", SHARED_MESHES)
@pytest.mark.parametrize("method", PROMISING)
def test_shared_meshes_no_folds_under_any_triangulation(ext, scene, mesh, method):
    obj = shared_mesh(mesh)
    result, summary = unwrap(ext, [obj], method=method)
    assert result == {"FINISHED"}, summary
    assert not summary.failed, summary.line()
    flipped, nonconvex = blender_folds(ext, obj, summary.results[obj.name])
    assert flipped == 0, f"{mesh} {method}: {flipped} of Blender's loop triangles flipped"
    assert nonconvex == 0, f"{mesh} {method}: {nonconvex} quads fold on one diagonal"
