# SPDX-License-Identifier: GPL-3.0-or-later
"""Meshes made in Blender the way users make them: primitives, CAD parts cut by booleans,
text, modifier stacks (bevel, array, screw, solidify, displace). Automatic seams and every
island checked against the atlas rule.

    .venv/bin/python blender_scripts/shapes.py [--shapes cad_hole,text] [--methods abf,slim,lscm] \
        [--repeat 3] [--out shapes.md]

Each shape is built in the running Blender (``bpy``), its modifiers applied, and unwrapped with
``uvflat.unwrap`` (automatic seams, the defaults, Blender's own triangles passed as
``triangles=``). Columns per shape and method: faces, islands, islands solved by a fallback
(another method than the one asked for), whether every island keeps the rule (a disk with one
outline, no flipped triangle, an outline that does not cross itself, at most 5% of its area
outside [1/2, 2] of its density), the conformal distortion of the whole map (area-weighted
mean of sigma1/sigma2, ``uvflat.metrics``; 1 is a map that keeps every angle), median seconds. ``tests/test_generated_shapes.py`` checks the
same on every shape.
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

SHAPES = (
    "cylinder_ngon",   # 32-gon caps
    "cylinder_fan",    # triangle-fan caps
    "cone",
    "torus",
    "uv_sphere",       # triangle fans at the poles
    "monkey",
    "bevel_cube",      # bevel modifier, 4 segments
    "cad_hole",        # a cube with a cylinder bored through it (boolean): genus 1, n-gons
    "cad_bracket",     # a plate with three bores and a notch (booleans): genus 3, long n-gons
    "text",            # extruded text: many parts, letters with holes
    "grid_open",       # an open grid displaced by noise (a terrain or cloth patch)
    "screw",           # screw modifier on a circle: a helical tube, open at both ends
    "array_cubes",     # array + bevel: ten separate parts
    "thick_shell",     # Suzanne subdivided once and solidified: an inner shell that folds
    "twisted_torus",   # a torus twisted by a simple deform
    "long_cylinder",   # 8 sides, 100 times longer than wide
    "gear",            # a 96-gon of 24 teeth solidified: its side faces meet at 90° creases
    "cad_cross_bores", # a cube with two hexagonal bores, along x and along y (booleans): genus 2
    "perforated",      # a flat plate of 40 x 40 quads with 3 x 3 bores (a boolean): nine holes
    "glyphs",          # flat text: letters with holes, the Q's tail touching its ring (a crack)
)


def _object_mode():
    import bpy

    obj = bpy.context.view_layer.objects.active
    if obj is not None and obj.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")


def _remove(objects):
    import bpy

    for obj in objects:
        data = obj.data
        bpy.data.objects.remove(obj)
        if data is not None and data.users == 0:
            if isinstance(data, bpy.types.Mesh):
                bpy.data.meshes.remove(data)
            elif isinstance(data, bpy.types.Curve):
                bpy.data.curves.remove(data)


def _build(name):
    """The objects making `name` (the first is the shape; the others are boolean cutters)."""
    import bpy

    ops = bpy.ops
    _object_mode()

    def added():
        return bpy.context.active_object

    def booleans(base, cutters):
        for c in cutters:
            m = base.modifiers.new("bool", "BOOLEAN")
            m.operation = "DIFFERENCE"
            m.object = c
        return [base] + cutters

    if name == "cylinder_ngon":
        ops.mesh.primitive_cylinder_add(vertices=32, depth=2)
    elif name == "cylinder_fan":
        ops.mesh.primitive_cylinder_add(vertices=48, depth=4, end_fill_type="TRIFAN")
    elif name == "cone":
        ops.mesh.primitive_cone_add(vertices=32)
    elif name == "torus":
        ops.mesh.primitive_torus_add()
    elif name == "uv_sphere":
        ops.mesh.primitive_uv_sphere_add()
    elif name == "monkey":
        ops.mesh.primitive_monkey_add()
    elif name == "bevel_cube":
        ops.mesh.primitive_cube_add()
        m = added().modifiers.new("bevel", "BEVEL")
        m.segments, m.width = 4, 0.2
    elif name == "cad_hole":
        ops.mesh.primitive_cube_add(size=2)
        base = added()
        ops.mesh.primitive_cylinder_add(vertices=24, radius=0.5, depth=4)
        return booleans(base, [added()])
    elif name == "cad_bracket":
        ops.mesh.primitive_cube_add(size=2)
        base = added()
        base.scale = (3, 1, 0.3)
        cutters = []
        for x in (-2, 0, 2):
            ops.mesh.primitive_cylinder_add(vertices=16, radius=0.3, depth=4, location=(x, 0, 0))
            cutters.append(added())
        ops.mesh.primitive_cube_add(size=1, location=(0, 1, 0.3))
        cutters.append(added())
        return booleans(base, cutters)
    elif name == "cad_cross_bores":
        ops.mesh.primitive_cube_add(size=2)
        base = added()
        ops.mesh.primitive_cylinder_add(vertices=6, radius=0.4, depth=4, location=(0, 0, 0.5),
                                        rotation=(0, np.pi / 2, 0))
        along_x = added()
        ops.mesh.primitive_cylinder_add(vertices=6, radius=0.4, depth=4, location=(0, 0, -0.5),
                                        rotation=(np.pi / 2, 0, 0))
        return booleans(base, [along_x, added()])
    elif name == "perforated":
        ops.mesh.primitive_grid_add(x_subdivisions=40, y_subdivisions=40, size=4)
        base = added()
        ops.mesh.primitive_cylinder_add(vertices=12, radius=0.12, depth=2, location=(-1.6, -1.6, 0))
        m = added().modifiers.new("array", "ARRAY")
        m.count, m.relative_offset_displace = 3, (4.5, 0, 0)
        m = added().modifiers.new("array_y", "ARRAY")
        m.count, m.relative_offset_displace = 3, (0, 4.5, 0)
        return booleans(base, [added()])
    elif name == "text":
        ops.object.text_add()
        txt = added()
        txt.data.body = "Blender UV"
        txt.data.extrude = 0.1
        ops.object.convert(target="MESH")
    elif name == "glyphs":
        ops.object.text_add()
        added().data.body = "OBAQ%"
        ops.object.convert(target="MESH")
    elif name == "grid_open":
        ops.mesh.primitive_grid_add(x_subdivisions=60, y_subdivisions=60)
        m = added().modifiers.new("displace", "DISPLACE")
        m.texture = bpy.data.textures.new("uvflat_shapes_clouds", "CLOUDS")
        m.strength = 0.5
    elif name == "screw":
        ops.mesh.primitive_circle_add(vertices=12, radius=0.3, location=(1, 0, 0))
        m = added().modifiers.new("screw", "SCREW")
        m.screw_offset, m.iterations, m.steps = 1.0, 3, 48
    elif name == "array_cubes":
        ops.mesh.primitive_cube_add()
        m = added().modifiers.new("array", "ARRAY")
        m.count = 10
        b = added().modifiers.new("bevel", "BEVEL")
        b.segments, b.width = 2, 0.1
    elif name == "thick_shell":
        ops.mesh.primitive_monkey_add()
        s = added().modifiers.new("subsurf", "SUBSURF")
        s.levels = 1
        m = added().modifiers.new("solidify", "SOLIDIFY")
        m.thickness = 0.05
    elif name == "twisted_torus":
        ops.mesh.primitive_torus_add(major_segments=96, minor_segments=24)
        m = added().modifiers.new("twist", "SIMPLE_DEFORM")
        m.deform_method, m.angle = "TWIST", 3.0
    elif name == "long_cylinder":
        ops.mesh.primitive_cylinder_add(vertices=8, depth=20, radius=0.2)
    elif name == "gear":
        ops.mesh.primitive_circle_add(vertices=96, fill_type="NGON")
        me = added().data
        a = 2 * np.pi * np.arange(96) / 96
        r = np.where((np.arange(96) // 2) % 2 == 0, 1.0, 0.85)
        me.vertices.foreach_set("co", np.stack([r * np.cos(a), r * np.sin(a), 0 * a], 1).ravel())
        m = added().modifiers.new("solidify", "SOLIDIFY")
        m.thickness = 0.3
    else:
        raise ValueError(f"unknown shape {name!r}; known: {', '.join(SHAPES)}")
    return [added()]


def make(name):
    """``(positions, corner_verts, face_sizes, triangles)`` of shape `name` with its modifiers
    applied; the objects made for it are removed again. ``triangles`` are Blender's own
    (``loop_triangles``, corner indices)."""
    import bpy

    objects = _build(name)
    try:
        bpy.context.view_layer.update()
        evaluated = objects[0].evaluated_get(bpy.context.evaluated_depsgraph_get())
        me = evaluated.to_mesh()
        try:
            n = len(me.vertices)
            pos = np.empty(3 * n)
            me.vertices.foreach_get("co", pos)
            cv = np.empty(len(me.loops), np.int64)
            me.loops.foreach_get("vertex_index", cv)
            fs = np.empty(len(me.polygons), np.int64)
            me.polygons.foreach_get("loop_total", fs)
            me.calc_loop_triangles()
            tri = np.empty(3 * len(me.loop_triangles), np.int64)
            me.loop_triangles.foreach_get("loops", tri)
        finally:
            evaluated.to_mesh_clear()
    finally:
        _remove(objects)
        tex = bpy.data.textures.get("uvflat_shapes_clouds")
        if tex is not None:
            bpy.data.textures.remove(tex)
    return pos.reshape(-1, 3), cv, fs, tri.reshape(-1, 3)


def island_topology(cv, fs, chart, seams):
    """Per chart id: ``(Euler characteristic, outline loops)`` of the island as cut: faces of
    the chart glued across every edge they share that is not in `seams` (vertex pairs: the
    user's and the new ones). Measured on the cut, not on the UVs, so a seam whose two sides
    a map lays on each other (a cut from a hole to the outline across flat surface) still
    counts as cut."""
    starts = np.concatenate([[0], np.cumsum(fs)[:-1]])
    cut = {(min(int(a), int(b)), max(int(a), int(b))) for a, b in np.asarray(seams).reshape(-1, 2)}
    parent = list(range(len(cv)))

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    # Corners glued across shared, uncut edges of one chart: the corner at vertex v of one
    # face joins the corner at v of the face across.
    sides = {}
    for f in np.nonzero(chart >= 0)[0]:
        s, n = int(starts[f]), int(fs[f])
        for k in range(n):
            a, b = int(cv[s + k]), int(cv[s + (k + 1) % n])
            sides.setdefault((min(a, b), max(a, b)), []).append((int(chart[f]), {a: s + k, b: s + (k + 1) % n}))
    for e, users in sides.items():
        if len(users) == 2 and users[0][0] == users[1][0] and e not in cut:
            for v in e:
                parent[find(users[0][1][v])] = find(users[1][1][v])
    out = {}
    for c in np.unique(chart[chart >= 0]):
        faces = np.nonzero(chart == c)[0]
        edges = {}
        for f in faces:
            s, n = int(starts[f]), int(fs[f])
            for k in range(n):
                a, b = find(s + k), find(s + (k + 1) % n)
                e = (min(a, b), max(a, b))
                edges[e] = edges.get(e, 0) + 1
        verts = {find(int(x)) for f in faces for x in range(starts[f], starts[f] + fs[f])}
        boundary = [e for e, m in edges.items() if m == 1]
        loop_of = {}

        def root(x):
            while loop_of.get(x, x) != x:
                x = loop_of[x]
            return x

        for a, b in boundary:
            ra, rb = root(a), root(b)
            if ra != rb:
                loop_of[ra] = rb
        loops = len({root(a) for e in boundary for a in e})
        out[int(c)] = (len(verts) - len(edges) + len(faces), loops)
    return out


def check(pos, cv, fs, tri, r, seams=()):
    """Why `r` breaks the atlas rule, one line per problem (empty when it keeps it); `seams`:
    the user's seams the unwrap was given (the new ones are in `r`)."""
    seams = np.concatenate([np.asarray(seams, dtype=np.int64).reshape(-1, 2),
                            np.asarray(r.new_seams, dtype=np.int64).reshape(-1, 2)])
    import uvflat

    problems = []
    if not r.face_solved.all():
        problems.append(f"{int((~r.face_solved).sum())} faces without UVs")
    for c in r.charts:
        if c.status not in ("solved", "fallback"):
            problems.append(f"chart {c.id}: {c.status}: {c.reason}")
        if c.flips or c.overlap or not c.density_outside <= 0.05 + 1e-9:
            problems.append(f"chart {c.id}: flips {c.flips}, overlap {c.overlap}, outside {c.density_outside:.3f}")
    for c, (chi, loops) in island_topology(cv, fs, r.chart, seams).items():
        if (chi, loops) != (1, 1):
            problems.append(f"island {c}: Euler characteristic {chi}, {loops} outline loops (not a disk)")
    m = uvflat.metrics(pos, cv, fs, r.uv, triangles=tri)
    if m.flips or m.overlapping_charts:
        problems.append(f"metrics: {m.flips} flips, {m.overlapping_charts} overlapping islands")
    return problems


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--shapes", default=",".join(SHAPES))
    p.add_argument("--methods", default="abf,slim,lscm")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--out")
    a = p.parse_args(argv)
    import bpy
    import uvflat

    bpy.ops.wm.read_factory_settings(use_empty=True)
    rows = ["| shape | faces | method | islands | fallbacks | rule | conformal | seconds |",
            "|---|---:|---|---:|---:|---|---:|---:|"]
    broken = []
    for name in a.shapes.split(","):
        pos, cv, fs, tri = make(name)
        for method in a.methods.split(","):
            times = []
            for _ in range(a.repeat):
                t = time.perf_counter()
                r = uvflat.unwrap(pos, cv, fs, method=method, triangles=tri)
                times.append(time.perf_counter() - t)
            problems = check(pos, cv, fs, tri, r)
            fallbacks = sum(c.status == "fallback" for c in r.charts)
            conformal = uvflat.metrics(pos, cv, fs, r.uv, triangles=tri).conformal
            rows.append(f"| {name} | {len(fs)} | {method} | {len(r.charts)} | {fallbacks} | "
                        f"{'yes' if not problems else 'NO'} | {conformal:.3f} | {statistics.median(times):.3f} |")
            print(rows[-1], flush=True)
            broken += [f"{name} {method}: {x}" for x in problems]
    text = "\n".join(rows) + "\n" + "".join(f"\n- {b}" for b in broken) + "\n"
    if a.out:
        Path(a.out).write_text(text)
    print(text)
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
