# SPDX-License-Identifier: GPL-3.0-or-later
"""Headless-bpy tests of automatic seams through the installed extension's operator."""

from __future__ import annotations

import numpy as np
import pytest

from test_addon import (  # noqa: F401  (fixtures are used by name)
    bpy,
    common,
    ext,
    flipped_triangles,
    read,
    scene,
    shared_mesh,
    unwrap,
)


def _sphere(name="Sphere"):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=24, ring_count=12)
    obj = bpy.context.active_object
    obj.name = name
    common.mesh_io().write_seams(obj.data, np.zeros(len(obj.data.edges), dtype=bool))
    return obj


def test_closed_sphere_is_cut_seams_marked_and_every_face_unwrapped(ext, scene):
    obj = _sphere()
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"}
    res = summary.results[obj.name]
    assert np.asarray(res.face_solved).all()
    after = read(ext, obj)
    # The marked seams are exactly the cut edges the core reported.
    assert summary.seams_added == len(after.seams) == len(res.new_seams) > 0
    marked = {tuple(sorted(map(int, s))) for s in after.seams}
    assert marked == {tuple(map(int, s)) for s in res.new_seams}
    assert summary.cones >= 2 and "auto seams" in summary.line()
    assert flipped_triangles(after, np.asarray(res.chart)) == 0
    # Unwrapping again with those seams cuts nothing more and keeps every face solved.
    result, summary = unwrap(ext, [obj], method="abf")
    assert summary.seams_added == 0
    assert np.asarray(summary.results[obj.name].face_solved).all()


def test_auto_seams_off_keeps_the_refusal_and_the_mesh(ext, scene):
    obj = _sphere()
    before = read(ext, obj)
    result, summary = unwrap(ext, [obj], method="lscm", auto_seams=False)
    assert result == {"FINISHED"}
    after = read(ext, obj)
    assert summary.failed and "not solved" in summary.line() and "seam" in summary.line()
    assert np.array_equal(after.uv, before.uv)
    assert len(after.seams) == 0


def test_mark_seams_off_unwraps_without_touching_seams(ext, scene):
    obj = _sphere()
    result, summary = unwrap(ext, [obj], method="lscm", mark_seams=False)
    assert result == {"FINISHED"}
    assert np.asarray(summary.results[obj.name].face_solved).all()
    assert len(read(ext, obj).seams) == 0
    assert summary.seams_added > 0 and "marked" not in summary.line()


def test_avoid_group_keeps_seams_away_and_selection_intact(ext, scene):
    obj = _sphere()
    positions = read(ext, obj).positions
    top = np.flatnonzero(positions[:, 2] > 0.2)
    group = obj.vertex_groups.new(name="face")
    group.add(top.tolist(), 1.0, "REPLACE")
    io = common.mesh_io()
    result, summary = unwrap(ext, [obj], method="slim", avoid_group="face")
    assert result == {"FINISHED"}
    after = read(ext, obj)
    assert len(after.seams) > 0
    assert not np.isin(after.seams, top).any(), "a new seam touches the avoided vertex group"
    # Every face was selected for the unwrap and still is; the group's active index is kept.
    assert io.read_face_selection(obj.data).all()
    assert obj.vertex_groups.active_index == group.index


def test_failure_after_marking_restores_seams_and_uvs(ext, scene, monkeypatch):
    obj = _sphere()
    io = common.mesh_io()
    before = read(ext, obj)

    def failing_pack(*args, **kwargs):
        raise RuntimeError("injected packing failure")

    monkeypatch.setattr(ext.engine, "_pack", failing_pack)
    with pytest.raises(RuntimeError, match="injected"):
        unwrap(ext, [obj], method="lscm", pack="ALL")
    after = read(ext, obj)
    assert len(after.seams) == 0, "seams marked by a failed unwrap were not removed"
    assert np.array_equal(after.uv, before.uv)
    assert io.read_face_selection(obj.data).all()


@pytest.mark.parametrize("name", ["bunny.off", "3holes.off"])
def test_shared_closed_meshes_through_the_operator(ext, scene, name):
    obj = shared_mesh(name)
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"}
    res = summary.results[obj.name]
    assert np.asarray(res.face_solved).all()
    assert not summary.failed
    after = read(ext, obj)
    assert flipped_triangles(after, np.asarray(res.chart)) == 0


def _open_dome(name="Dome"):
    """A UV sphere with its bottom cap deleted (below z = -0.6): an open mesh with one
    boundary loop, too curved to flatten within Max Stretch uncut."""
    obj = _sphere(name)
    io = common.mesh_io()
    me = obj.data
    n = len(me.vertices)
    co = np.empty(3 * n)
    me.vertices.foreach_get("co", co)
    z = co.reshape(-1, 3)[:, 2]
    common.edit_mode([obj], select_all=False)
    try:
        import bmesh

        bm = bmesh.from_edit_mesh(me)
        bmesh.ops.delete(bm, geom=[v for v in bm.verts if z[v.index] < -0.6], context="VERTS")
        bmesh.update_edit_mesh(me)
    finally:
        common.object_mode()
    io.write_seams(me, np.zeros(len(me.edges), dtype=bool))
    return obj


def _islands_density_outside(data, bound):
    """Per island (uvflat.metrics), the share of area outside [1/bound, bound] of its density."""
    import uvflat

    m = uvflat.metrics(data.positions, data.corner_verts, data.face_sizes, data.uv)
    assert bound == 2.0  # metrics measure against [1/2, 2]
    return m, [c["density_outside"] for c in m.per_chart]


@pytest.mark.parametrize("shape", ["closed", "open"])
def test_auto_seams_hold_max_stretch_on_closed_and_open_meshes(ext, scene, shape):
    """The atlas rule through the real operator: every island within Max Stretch (at most 5%
    of its area outside [1/2, 2] of its density), no flips, no crossing outline; the open dome
    is cut too (flattened whole, its rim is crushed against its pole)."""
    obj = _sphere() if shape == "closed" else _open_dome()
    before_open = read(ext, obj)
    result, summary = unwrap(ext, [obj], method="abf", max_stretch=2.0)
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    after = read(ext, obj)
    m, outside = _islands_density_outside(after, 2.0)
    assert m.flips == 0 and m.overlapping_charts == 0, m
    assert max(outside) <= 0.05 + 1e-9, outside
    assert summary.seams_added > 0 and len(after.seams) > 0
    # The same mesh uncut breaks the rule: the cuts were needed.
    import uvflat

    raw = uvflat.unwrap(before_open.positions, before_open.corner_verts, before_open.face_sizes,
                        method="abf", auto_seams=False)
    if shape == "open":
        assert raw.charts[0].density_outside > 0.05, raw.charts[0]


def test_mark_seams_only_marks_the_planned_seams_and_writes_no_uv(ext, scene):
    import uvflat

    obj = _sphere()
    before = read(ext, obj)
    n_maps = len(obj.data.uv_layers)
    result, summary = unwrap(ext, [obj], method="abf", seams_only=True)
    assert result == {"FINISHED"}, summary
    after = read(ext, obj)
    assert len(obj.data.uv_layers) == n_maps
    assert np.array_equal(after.uv, before.uv), "Mark Seams Only wrote UVs"
    # The operator passes Blender's render triangles; so does the plan.
    tris = ext.mesh_io.read_loop_triangles(obj.data)
    planned = uvflat.plan_seams(before.positions, before.corner_verts, before.face_sizes, method="abf",
                                triangles=tris)
    marked = {tuple(sorted(map(int, s))) for s in after.seams}
    assert marked == {tuple(map(int, s)) for s in planned} and len(marked) > 0
    assert "seams only" in summary.line()
    # Unwrapping afterwards on those seams adds none and solves every face.
    result, summary = unwrap(ext, [obj], method="abf")
    assert summary.seams_added == 0
    assert np.asarray(summary.results[obj.name].face_solved).all()


# ---------------------------------------------------------------------------------------------
# The options declared by the core (uvflat.AUTO_SEAM_OPTIONS): Symmetry and Seam Visibility


def test_auto_seam_properties_follow_the_core_table(ext, scene):
    """Every automatic-seams property has the declared default, bounds within the declared
    domain and the declared choices; the keywords the operator hands to the core from default
    properties are the declared defaults."""
    from types import SimpleNamespace

    import uvflat

    props = ext.methods.auto_seam_properties()
    declared = {s["name"]: s for s in uvflat.AUTO_SEAM_OPTIONS}
    defaults = SimpleNamespace(**{k: p.keywords["default"] for k, p in props.items()})
    assert ext.methods.auto_seam_options(defaults) == {
        name: s["default"] for name, s in declared.items()
        if name not in ext.methods.BLENDER_SIDE_OPTIONS}
    assert {"symmetry", "visibility_weight"} <= set(props)
    for name, s in declared.items():
        if name in ext.methods.BLENDER_SIDE_OPTIONS:
            continue
        kw = props[name].keywords
        if s["default"] is not None:
            assert kw["default"] == s["default"], name
        if s["type"] == "choice":
            assert tuple(i[0] for i in kw["items"]) == s["choices"], name
        if s["type"] in ("int", "float"):
            if s["min"] is not None:
                assert kw["min"] > s["min"] or (kw["min"] == s["min"] and not s["min_exclusive"])
            if s["max"] is not None:
                assert kw["max"] < s["max"] or (kw["max"] == s["max"] and not s["max_exclusive"])
    # the registered operator and the sidebar defaults carry the two new settings
    rna = bpy.ops.uv.uvflat_unwrap.get_rna_type().properties
    assert rna["symmetry"].default == "none"
    assert {i.identifier for i in rna["symmetry"].enum_items} == set(declared["symmetry"]["choices"])
    assert rna["visibility_weight"].default == declared["visibility_weight"]["default"]
    assert (rna["visibility_weight"].hard_min, rna["visibility_weight"].hard_max) == (0.0, 100.0)
    assert scene.uvflat.symmetry == "none" and scene.uvflat.visibility_weight == 1.0
    # the redo panel and the sidebar show them with the other automatic-seams settings
    from test_addon import _PanelLayout

    layout = _PanelLayout()
    ext.methods.draw_settings(layout, scene.uvflat)
    assert {"auto_seams", "max_stretch", "max_cones", "symmetry", "visibility_weight",
            "same_seams", "avoid_group"} <= set(layout.props)


def _lopsided_sphere(name="Lopsided"):
    """A closed UV sphere bent so that its only mirror plane is x = 0."""
    obj = _sphere(name)
    me = obj.data
    co = np.empty(3 * len(me.vertices))
    me.vertices.foreach_get("co", co)
    x, y, z = co.reshape(-1, 3).T
    bent = np.column_stack([1.3 * x, y + 0.4 * z * z, 0.9 * z + 0.25 * y * y + 0.2 * y])
    me.vertices.foreach_set("co", bent.ravel())
    me.update()
    return obj


def test_symmetry_marks_mirrored_seams(ext, scene):
    """Symmetry X through the operator: the marked seams map onto themselves under the mirror
    across x = 0, every island keeps the atlas rule; Mark Seams Only passes Symmetry and Seam
    Visibility on too (the plan of uvflat.plan_seams with them)."""
    import uvflat
    from test_auto_seams import mirror_of, mirrored

    obj = _lopsided_sphere()
    before = read(ext, obj)
    image = mirror_of(before.positions, axis=0)
    result, summary = unwrap(ext, [obj], method="abf", symmetry="x")
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    after = read(ext, obj)
    marked = {tuple(sorted(map(int, s))) for s in after.seams}
    assert marked == {tuple(map(int, s)) for s in summary.results[obj.name].new_seams}
    assert len(marked) > 0 and mirrored(marked, image) == marked
    m, outside = _islands_density_outside(after, 2.0)
    assert m.flips == 0 and m.overlapping_charts == 0 and max(outside) <= 0.05 + 1e-9

    obj = _lopsided_sphere("Planned")
    tris = ext.mesh_io.read_loop_triangles(obj.data)
    result, summary = unwrap(ext, [obj], method="abf", seams_only=True, symmetry="x",
                             visibility_weight=0.0)
    assert result == {"FINISHED"}
    marked = {tuple(sorted(map(int, s))) for s in read(ext, obj).seams}
    planned = uvflat.plan_seams(before.positions, before.corner_verts, before.face_sizes,
                                method="abf", triangles=tris, symmetry="x", visibility_weight=0.0)
    assert marked == {tuple(map(int, s)) for s in planned} and mirrored(marked, image) == marked


def test_benchmark_starts_every_run_from_the_mesh_s_own_seams(ext, scene, monkeypatch):
    """``blender_scripts/benchmark.py`` times the operator on the same mesh with the same seams:
    an unwrap with automatic seams marks its cuts (Mark Seams), and a later run or method that
    took them as given would cut nothing and time another job. Each run starts from the
    mesh's own seams again (the operator really marks new ones), and a row leaves them so."""
    import sys

    import uvflat

    sys.path.insert(0, str(common.REPO / "blender_scripts"))
    import benchmark

    obj = _sphere("BenchSphere")
    mesh_io = ext.mesh_io
    seen, marked = [], []
    run_once = benchmark.run_once

    def marking(o, kind, method):
        seen.append(len(mesh_io.read_seams(o.data)))
        out = run_once(o, kind, method)
        marked.append(len(mesh_io.read_seams(o.data)))
        return out

    monkeypatch.setattr(benchmark, "run_once", marking)
    for method in ("abf", "lscm"):
        row = benchmark.measure(uvflat, mesh_io, obj, "uvflat", method, 2)
        assert row["error"] is None, row
        assert row["flips"] == 0 and row["unsolved"] == 0
        assert len(mesh_io.read_seams(obj.data)) == 0, f"{method}: the row left its seams"
    assert seen == [0, 0, 0, 0]
    assert all(m > 0 for m in marked), f"an unwrap marked no seams: {marked}"


def test_same_seams_marks_the_seams_of_abf_under_slim(ext, scene):
    """An artist unwraps the bunny with ABF, clears the seams and switches to SLIM: with Same
    Seams the operator marks exactly ABF's seams again (both keep the rule on them there);
    without it, SLIM's own, fewer ones."""
    obj = shared_mesh("bunny.off")
    io = ext.mesh_io
    no_seams = np.zeros(len(obj.data.edges), dtype=bool)

    def marked(**props):
        io.write_seams(obj.data, no_seams)
        result, summary = unwrap(ext, [obj], **props)
        assert result == {"FINISHED"} and not summary.failed
        res = summary.results[obj.name]
        assert np.asarray(res.face_solved).all()
        after = read(ext, obj)
        assert flipped_triangles(after, np.asarray(res.chart)) == 0
        return {tuple(sorted(map(int, s))) for s in after.seams}

    abf = marked(method="abf")
    assert abf
    assert marked(method="slim", same_seams=True) == abf
    own = marked(method="slim", same_seams=False)
    assert len(own) < len(abf)


def _collapsed_ico(name="Collapsed", step=29):
    """An ico sphere (5,120 triangles) made bumpy, with the second corner of every `step`-th
    triangle moved onto its first: triangles without area, and the moved vertices' other
    triangles folded over their new neighbours, as careless decimation leaves them."""
    bpy.ops.mesh.primitive_ico_sphere_add(subdivisions=5)
    obj = bpy.context.active_object
    obj.name = name
    me = obj.data
    n = len(me.vertices)
    co = np.empty(3 * n)
    me.vertices.foreach_get("co", co)
    p = co.reshape(-1, 3)
    r = 1.0 + 0.25 * np.sin(5.0 * p[:, 0]) * np.cos(4.0 * p[:, 1]) + 0.3 * p[:, 2] ** 2
    p *= r[:, None] * np.array([1.0, 1.0, 1.6])
    loops = np.empty(len(me.loops), dtype=np.int64)
    me.loops.foreach_get("vertex_index", loops)
    tri = loops.reshape(-1, 3)
    for k in range(0, len(tri), step):
        p[tri[k, 1]] = p[tri[k, 0]]
    me.vertices.foreach_set("co", p.ravel())
    me.update()
    common.mesh_io().write_seams(me, np.zeros(len(me.edges), dtype=bool))
    return obj


@pytest.mark.parametrize("method", ["scaffold", "mips"])
def test_triangles_without_area_keep_the_rule_through_the_operator(ext, scene, method):
    """Vertices collapsed onto neighbours (`_collapsed_ico`): with Auto Seams every island
    still keeps the rule in the real operator (no flips, no crossing outline, at most 5% of
    each island outside [1/2, 2] of its density). `scaffold` and `mips` let such triangles
    fold when they carried no energy."""
    obj = _collapsed_ico()
    data = read(ext, obj)
    q = data.positions[np.asarray(data.corner_verts).reshape(-1, 3)]
    zero = (np.linalg.norm(np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), axis=1) == 0).sum()
    assert zero >= 250, zero
    result, summary = unwrap(ext, [obj], method=method)
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    res = summary.results[obj.name]
    assert np.asarray(res.face_solved).all()
    assert all(c.status in ("solved", "fallback") for c in res.charts), [c.reason for c in res.charts]
    after = read(ext, obj)
    m, outside = _islands_density_outside(after, 2.0)
    assert m.flips == 0 and m.overlapping_charts == 0, m
    assert max(outside) <= 0.05 + 1e-9, outside


def _perforated_plate(name="Plate"):
    """A flat plate of 40 x 40 quads with 3 x 3 bores, cut by a boolean whose result is applied
    (its n-gons, and corners 1e-7 apart where a cylinder touches a grid line)."""
    bpy.ops.mesh.primitive_cylinder_add(vertices=12, radius=0.12, depth=2, location=(-1.6, -1.6, 0))
    cutter = bpy.context.active_object
    for axis, name_ in ((0, "x"), (1, "y")):
        m = cutter.modifiers.new(name_, "ARRAY")
        m.count = 3
        m.relative_offset_displace = (4.5, 0, 0) if axis == 0 else (0, 4.5, 0)
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=40, y_subdivisions=40, size=4)
    obj = bpy.context.active_object
    obj.name = name
    b = obj.modifiers.new("bores", "BOOLEAN")
    b.operation, b.object = "DIFFERENCE", cutter
    bpy.ops.object.modifier_apply(modifier=b.name)
    bpy.data.objects.remove(cutter)
    common.mesh_io().write_seams(obj.data, np.zeros(len(obj.data.edges), dtype=bool))
    return obj


@pytest.mark.parametrize("method", ["abf", "slim"])
def test_a_perforated_plate_is_one_island_laid_as_it_is_through_the_operator(ext, scene, method):
    """The plate (`_perforated_plate`) through the real operator: its nine bores are joined to
    its outline by marked seams, and it is one island solved by the method with no distortion
    and no flip on Blender's triangles (before the flat projection: five islands)."""
    obj = _perforated_plate()
    assert len(obj.data.polygons) > 1500
    result, summary = unwrap(ext, [obj], method=method)
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    res = summary.results[obj.name]
    assert np.asarray(res.face_solved).all()
    assert len(res.charts) == 1, [(c.faces, c.reason) for c in res.charts]
    c = res.charts[0]
    assert (c.status, c.method, c.iterations) == ("solved", method, 0), c.reason
    assert c.conformal < 1 + 1e-6 and c.area < 1 + 1e-6, (c.conformal, c.area)
    after = read(ext, obj)
    assert summary.seams_added == len(after.seams) > 0
    # Blender's own triangles (its n-gons are concave around the bores, so a fan from the first
    # corner is no triangulation of them).
    _assert_no_flip_on_blender_triangles(obj, after)


def _assert_no_flip_on_blender_triangles(obj, after):
    """Every one of Blender's `loop_triangles` of `obj` turns the same way on the UVs as
    Blender stores them (`after`), and `uvflat.metrics` on those triangles finds no flip and no
    island whose outline crosses itself."""
    import uvflat

    me = obj.data
    me.calc_loop_triangles()
    tri = np.empty(3 * len(me.loop_triangles), dtype=np.int64)
    me.loop_triangles.foreach_get("loops", tri)
    a, b, c = (after.uv[tri[k::3]] for k in range(3))
    signed = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    assert (signed > 0).all() or (signed < 0).all(), (signed > 0).sum()
    m = uvflat.metrics(after.positions, after.corner_verts, after.face_sizes, after.uv, triangles=tri.reshape(-1, 3))
    assert m.flips == 0 and m.overlapping_charts == 0, m


def test_flat_glyphs_are_one_island_each_through_the_operator(ext, scene):
    """Flat text converted to a mesh in Blender: the Q's tail touches its ring at a vertex on a
    ring edge (a crack). Through the real operator each of the 7 glyph parts is one island laid
    as it is, the Q too (before: invalid, its outline read as crossing itself), with no flip
    on Blender's triangles."""
    bpy.ops.object.text_add()
    txt = bpy.context.active_object
    txt.data.body = "OBAQ%"
    bpy.ops.object.convert(target="MESH")
    obj = bpy.context.active_object
    obj.name = "Glyphs"
    common.mesh_io().write_seams(obj.data, np.zeros(len(obj.data.edges), dtype=bool))
    result, summary = unwrap(ext, [obj], method="abf")
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    res = summary.results[obj.name]
    assert np.asarray(res.face_solved).all()
    assert len(res.charts) == 7, [(c.faces, c.reason) for c in res.charts]
    for c in res.charts:
        assert (c.status, c.method, c.iterations) == ("solved", "abf", 0), c.reason
        assert c.conformal < 1 + 1e-6 and c.area < 1 + 1e-6, (c.conformal, c.area)
    after = read(ext, obj)
    assert summary.seams_added == len(after.seams) > 0  # the letters' holes joined
    _assert_no_flip_on_blender_triangles(obj, after)


def _sphere_with_holes(name="Holey"):
    """A UV sphere (48 × 24) with five small holes: the faces around five points deleted, as a
    scan loses surface (the vertices stay)."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24)
    obj = bpy.context.active_object
    obj.name = name
    me = obj.data
    centres = np.array([[0.9, 0.3, 0.2], [-0.5, 0.7, -0.4], [0.1, -0.8, 0.5], [-0.6, -0.5, -0.6],
                        [0.3, 0.4, 0.85]])
    centres /= np.linalg.norm(centres, axis=1)[:, None]
    common.edit_mode([obj], select_all=False)
    try:
        import bmesh

        bm = bmesh.from_edit_mesh(me)
        doomed = [f for f in bm.faces
                  if min(np.linalg.norm(np.asarray(f.calc_center_median()) - c) for c in centres) < 0.16]
        bmesh.ops.delete(bm, geom=doomed, context="FACES_ONLY")
        bmesh.update_edit_mesh(me)
    finally:
        common.object_mode()
    common.mesh_io().write_seams(me, np.zeros(len(me.edges), dtype=bool))
    return obj


@pytest.mark.parametrize("method", ["abf", "slim"])
def test_small_holes_are_joined_by_closed_seams_through_the_operator(ext, scene, method):
    """A closed surface with small holes is unwrapped as the surface without them: its holes are
    filled for the unwrap (the operator passes Blender's render triangles) and joined to the
    outline by seams whose two sides share their UVs; every island keeps the rule. Of the five
    holes, the longest is the outline (the sphere with holes is a disk with four holes)."""
    obj = _sphere_with_holes()
    result, summary = unwrap(ext, [obj], method=method, max_stretch=2.0)
    assert result == {"FINISHED"} and not summary.failed, summary.line()
    res = summary.results[obj.name]
    assert res.phases["holes_filled"] == 4 and res.phases["fill_undone"] == 0, res.phases
    after = read(ext, obj)
    m, outside = _islands_density_outside(after, 2.0)
    assert m.flips == 0 and m.overlapping_charts == 0 and max(outside) <= 0.05 + 1e-9, m
    # Every island is a disk: the marked seams split the faces into exactly the islands in UV.
    marked = {tuple(sorted(map(int, s))) for s in after.seams}
    assert marked == {tuple(map(int, s)) for s in res.new_seams}
    # The closed seams (both sides at the same UVs) join the holes: at least one edge each.
    fs, cv, uv = after.face_sizes, after.corner_verts, after.uv
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    chart = np.asarray(res.chart)
    sides = {}
    for f, (s, n) in enumerate(zip(starts, fs)):
        for i in range(n):
            a, b = int(cv[s + i]), int(cv[s + (i + 1) % n])
            sides.setdefault((min(a, b), max(a, b)), []).append((f, {a: s + i, b: s + (i + 1) % n}))
    closed = {tuple(map(int, e)) for e in np.asarray(res.closed_seams)}
    assert len(closed) >= 4 and closed <= marked, (len(closed), closed - marked)
    for e in closed:
        faces = sides[e]
        assert len(faces) == 2 and chart[faces[0][0]] == chart[faces[1][0]], e
        assert all(np.array_equal(uv[faces[0][1][v]], uv[faces[1][1][v]]) for v in e), e
    # Every other seam inside an island has its sides apart in UV.
    for e in marked - closed:
        faces = sides.get(e, [])
        if len(faces) == 2 and chart[faces[0][0]] == chart[faces[1][0]]:
            assert not all(np.array_equal(uv[faces[0][1][v]], uv[faces[1][1][v]]) for v in e), e
