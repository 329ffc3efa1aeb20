# SPDX-License-Identifier: GPL-3.0-or-later
"""Headless-bpy tests of the operator's Blender round trip: the phase timings, the packing on
a stand-in mesh (``proxy_pack``) against Blender's packer on the mesh itself, and the bulk
reads that replace element-wise ones. Small meshes: the stand-in is forced on by setting
``proxy_pack.MIN_FACES`` to 0."""

from __future__ import annotations

import time

import numpy as np
import pytest

from types import SimpleNamespace

from test_addon import (  # noqa: F401  (fixtures are used by name)
    _ContextStandIn,
    _drive_modal,
    _operator_stand_in,
    bpy,
    common,
    ext,
    read,
    scene,
    unwrap,
)

# Coverage (packed UV area / tile area) of the stand-in packing may differ from Blender's
# packer on the mesh itself by float32 rounding only; the bound stated for the round trip.
COVERAGE_REL = 0.02


def _disk(name="Disk", segments=16, cuts=3):
    """A flat disk (one island), ``segments * (cuts + 1)**2`` triangles."""
    return common.subdivided_disk(name, segments, cuts)


def _coverage(data):
    """Summed absolute UV area of the faces (shoelace)."""
    fs = np.asarray(data.face_sizes, dtype=np.int64)
    starts = np.zeros(len(fs), dtype=np.int64)
    np.cumsum(fs[:-1], out=starts[1:])
    nxt = np.arange(len(data.uv)) + 1
    nxt[starts + fs - 1] = starts
    uv = data.uv
    cross = uv[:, 0] * uv[nxt, 1] - uv[nxt, 0] * uv[:, 1]
    return float(np.abs(np.add.reduceat(cross, starts)).sum() * 0.5)


def _reset_uvs(ext, obj):
    io = ext.mesh_io
    name, _ = io.ensure_uv_map(obj.data)
    io.write_uv(obj.data, name, np.zeros((len(obj.data.loops), 2), dtype=np.float32))


def _both_ways(ext, monkeypatch, obj, **props):
    """UVs after the operator with the stand-in packing, then with Blender's packer on the
    mesh itself (same starting UVs); also how often the stand-in packed."""
    calls = []
    real_pack = ext.proxy_pack.pack

    def counting(*args, **kwargs):
        calls.append(1)
        return real_pack(*args, **kwargs)

    monkeypatch.setattr(ext.proxy_pack, "MIN_FACES", 0)
    monkeypatch.setattr(ext.proxy_pack, "pack", counting)
    out = []
    # Automatic seams mark the seams they cut: both runs start from the same seams.
    seams = ext.mesh_io.read_edges(obj.data)[1].copy()
    for use_proxy in (True, False):
        if not use_proxy:
            monkeypatch.setattr(ext.proxy_pack, "applicable", lambda *a, **k: False)
        _reset_uvs(ext, obj)
        ext.mesh_io.write_seams(obj.data, seams)
        result, summary = unwrap(ext, [obj], method="lscm", **props)
        assert result == {"FINISHED"}, summary
        out.append(read(ext, obj))
    return out[0], out[1], len(calls)


def _islands_aabbs(data, chart):
    corner_chart = np.repeat(np.asarray(chart), data.face_sizes)
    ids = np.unique(corner_chart)
    lo = np.array([data.uv[corner_chart == i].min(axis=0) for i in ids])
    hi = np.array([data.uv[corner_chart == i].max(axis=0) for i in ids])
    return lo, hi


@pytest.mark.parametrize("shape_method,rotate", [("AABB", False), ("AABB", True),
                                                 ("CONVEX", True)])
def test_stand_in_packs_like_blender_on_the_mesh(ext, scene, monkeypatch, shape_method, rotate):
    """Several islands (Suzanne's), bounding-box and convex-hull shapes: the stand-in packing
    moves every island exactly as Blender's packer on the mesh does (float32 rounding), all
    inside the tile, coverage within the stated bound; with bounding boxes the islands' boxes
    do not overlap."""
    obj = common.suzanne("SuzannePack")
    # Stretch one half: Suzanne's mirror-image islands (eyes, ears) are congruent, and which
    # of two equal islands a packer places first is a tie it may break either way.
    co = np.empty(3 * len(obj.data.vertices))
    obj.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    co[co[:, 0] > 0.0, 0] *= 1.05
    obj.data.vertices.foreach_set("co", co.ravel())
    obj.data.update()
    with_proxy, on_mesh, calls = _both_ways(ext, monkeypatch, obj, pack="ALL",
                                            shape_method=shape_method, rotate=rotate)
    assert calls == 1
    assert np.abs(with_proxy.uv - on_mesh.uv).max() < 1e-5
    assert with_proxy.uv.min() >= 0.0 and with_proxy.uv.max() <= 1.0
    assert _coverage(with_proxy) >= (1.0 - COVERAGE_REL) * _coverage(on_mesh)
    if shape_method == "AABB" and not rotate:
        lo, hi = _islands_aabbs(with_proxy, ext.engine.LAST_SUMMARY.results[obj.name].chart)
        n = len(lo)
        assert n > 1
        for i in range(n):
            overlap = np.all((lo[i] < hi - 1e-6) & (lo + 1e-6 < hi[i]), axis=1)
            overlap[i] = False
            assert not overlap.any(), f"island {i} overlaps {np.flatnonzero(overlap)}"


def test_single_island_default_pack_uses_the_stand_in(ext, scene, monkeypatch):
    """One island, the default settings (around others, exact shape, rotation): packed on
    the stand-in, same result as Blender's packer on the mesh."""
    obj = _disk()
    with_proxy, on_mesh, calls = _both_ways(ext, monkeypatch, obj)
    assert calls == 1
    assert np.abs(with_proxy.uv - on_mesh.uv).max() < 1e-5
    assert with_proxy.uv.min() >= 0.0 and with_proxy.uv.max() <= 1.0
    assert _coverage(with_proxy) >= (1.0 - COVERAGE_REL) * _coverage(on_mesh)
    assert not any(o.name.startswith(ext.proxy_pack.PROXY_NAME) for o in bpy.data.objects)
    assert not any(m.name.startswith(ext.proxy_pack.PROXY_NAME) for m in bpy.data.meshes)


def test_exact_shape_with_several_islands_packs_on_the_mesh(ext, scene, monkeypatch):
    """Several islands with the exact shape: the stand-in would not pack the same, so
    Blender's packer runs on the mesh itself."""
    obj = common.suzanne("SuzanneConcave")
    # Suzanne's islands are more than the packer is given exact shapes for by default
    # (engine.pack_shape): keep them exact here
    monkeypatch.setattr(ext.engine, "CONCAVE_MAX_ISLANDS", 1000)
    _, _, calls = _both_ways(ext, monkeypatch, obj, pack="ALL", shape_method="CONCAVE")
    assert calls == 0
    assert ext.engine.LAST_SUMMARY.pack_shapes == ("CONCAVE",)


def test_stand_in_failure_restores_everything(ext, scene, monkeypatch):
    """A failure while packing on the stand-in: UVs, seams and selection exactly as before,
    no stand-in object or mesh left, the object back in edit mode."""
    obj = _disk("DiskFail")
    io = ext.mesh_io
    uv0 = np.random.default_rng(3).random((len(obj.data.loops), 2)).astype(np.float32)
    io.write_uv(obj.data, io.ensure_uv_map(obj.data)[0], uv0)
    selection = io.save_selection(obj.data)  # every face selected by _disk
    monkeypatch.setattr(ext.proxy_pack, "MIN_FACES", 0)

    def failing(*args, **kwargs):
        raise RuntimeError("injected packing failure")

    monkeypatch.setattr(ext.proxy_pack, "pack", failing)
    common.edit_mode([obj], select_all=False)
    try:
        with pytest.raises(RuntimeError):
            bpy.ops.uv.uvflat_unwrap(method="lscm", pack="ALL")
        assert obj.mode == "EDIT"
    finally:
        common.object_mode()
    assert np.array_equal(io.read_uv(obj.data), uv0)
    after = io.save_selection(obj.data)
    assert set(after) == set(selection)
    for name, (domain, values) in selection.items():
        assert np.array_equal(after[name][1], values), name
    assert not any(o.name.startswith(ext.proxy_pack.PROXY_NAME) for o in bpy.data.objects)
    assert not any(m.name.startswith(ext.proxy_pack.PROXY_NAME) for m in bpy.data.meshes)


@pytest.mark.parametrize("pack", ["AROUND", "ALL", "OFF"])
def test_phases_add_up_to_the_operator_time(ext, scene, monkeypatch, pack):
    """The summary's phases add up to its run time exactly, and to the operator's wall time
    measured around ``bpy.ops`` within a small tolerance (the operator call's own overhead)."""
    monkeypatch.setattr(ext.proxy_pack, "MIN_FACES", 0)
    obj = _disk("DiskTime", segments=32, cuts=7)
    _reset_uvs(ext, obj)
    common.edit_mode([obj])
    try:
        t0 = time.perf_counter()
        result = bpy.ops.uv.uvflat_unwrap(method="lscm", pack=pack)
        seconds = time.perf_counter() - t0
    finally:
        common.object_mode()
    assert result == {"FINISHED"}
    summary = ext.engine.LAST_SUMMARY
    phases = summary.phases
    assert {"read", "solve", "quality", "write", "mode", "other"} <= set(phases)
    assert all(t >= 0.0 for t in phases.values()), phases
    total = sum(phases.values())
    assert total == pytest.approx(summary.seconds, abs=1e-6)
    assert total <= seconds + 1e-6
    assert seconds - total <= 0.02 + 0.1 * seconds, (seconds, phases)


def test_loop_triangles_of_a_triangle_mesh_need_no_read(ext, scene):
    """For a mesh of triangles the render triangles are the faces' own corners: the shortcut
    equals what Blender computes."""
    obj = _disk("DiskTris")
    io = ext.mesh_io
    _, _, face_sizes = io.read_topology(obj.data)
    assert np.all(face_sizes == 3)
    assert np.array_equal(io.read_loop_triangles(obj.data, face_sizes),
                          io.read_loop_triangles(obj.data))


def test_absent_flag_attributes_read_as_false(ext, scene):
    """A mesh that never had seams, hidden faces or a selection reads all False (the
    attributes do not exist until a flag is set), and a set flag is read back."""
    io = ext.mesh_io
    mesh = io.new_mesh("Flags", np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
                       np.array([0, 1, 2, 1, 3, 2]), np.array([3, 3]))
    for name in ("uv_seam", ".uv_seam", ".hide_poly"):
        assert mesh.attributes.get(name) is None
    assert len(io.read_seams(mesh)) == 0
    assert not io.read_hidden_faces(mesh).any()
    mesh.edges[0].use_seam = True
    mesh.polygons[1].hide = True
    assert len(io.read_seams(mesh)) == 1
    assert io.read_hidden_faces(mesh).tolist() == [False, True]
    bpy.data.meshes.remove(mesh)


def test_heat_map_colours_display_the_heat_colours(ext, scene):
    """The colour attributes are float colours (one bulk copy to write) holding the heat
    colours of the per-face distortion: read back as sRGB they are the heat colours."""
    obj = _disk("DiskHeat")
    io, dist = ext.mesh_io, ext.distortion
    settings = bpy.context.scene.uvflat
    for kind, name in ((dist.CONFORMAL, "conformal"), (dist.AREA, "area")):
        settings.distortion_kind = name
        settings.show_distortion = True
        try:
            result, summary = unwrap(ext, [obj], method="lscm", pack="ALL")
        finally:
            settings.show_distortion = False
        assert result == {"FINISHED"}
        _, _, face_sizes = io.read_topology(obj.data)
        starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
        attr = obj.data.attributes[dist.COLOR[name]]
        assert attr.data_type == "FLOAT_COLOR" and attr.domain == "CORNER"
        expected = dist.heat_colors(io.read_attribute(obj.data, kind))
        for face in (0, len(face_sizes) // 2, len(face_sizes) - 1):
            shown = np.array(attr.data[int(starts[face])].color_srgb)
            np.testing.assert_allclose(shown, expected[face], atol=2e-3)


def test_write_seams_with_and_without_a_seam_attribute(ext, scene):
    """Seams written into a mesh without any (Blender creates the attribute) and into one
    with them (one copy into the attribute) read back exactly."""
    io = ext.mesh_io
    obj = _disk("DiskSeams")
    mesh = obj.data
    n_e = len(mesh.edges)
    rng = np.random.default_rng(7)
    for _ in range(2):
        flags = rng.random(n_e) < 0.3
        io.write_seams(mesh, flags)
        np.testing.assert_array_equal(io.read_edges(mesh)[1], flags)
        np.testing.assert_array_equal(
            np.array([e.use_seam for e in mesh.edges]), flags)
    with pytest.raises(ValueError):
        io.write_seams(mesh, np.zeros(n_e + 1, dtype=bool))


def test_modal_unwrap_packs_on_the_stand_in_like_the_direct_one(ext, scene, monkeypatch):
    """The modal unwrap (meshes out of edit mode while the core solves) packs on the
    stand-in and gives the direct unwrap's UVs, back in edit mode."""
    monkeypatch.setattr(ext.engine, "MODAL_AFTER_SECONDS", 0.0)
    monkeypatch.setattr(ext.proxy_pack, "MIN_FACES", 0)
    calls = []
    real_pack = ext.proxy_pack.pack
    monkeypatch.setattr(ext.proxy_pack, "pack",
                        lambda *a, **k: calls.append(1) or real_pack(*a, **k))
    obj = _disk("DiskModal")
    _reset_uvs(ext, obj)
    common.edit_mode([obj])
    ctx = _ContextStandIn()
    op = _operator_stand_in(ext, method="lscm", pack="ALL")
    try:
        assert op.invoke(ctx, SimpleNamespace(type="LEFTMOUSE", value="PRESS")) == {"RUNNING_MODAL"}
        assert _drive_modal(op, ctx) == {"FINISHED"}
        assert obj.mode == "EDIT"
    finally:
        common.object_mode()
    modal_uv = read(ext, obj).uv
    assert calls == [1]
    _reset_uvs(ext, obj)
    result, _ = unwrap(ext, [obj], method="lscm", pack="ALL")
    assert result == {"FINISHED"} and calls == [1, 1]
    np.testing.assert_array_equal(read(ext, obj).uv, modal_uv)
