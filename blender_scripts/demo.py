# SPDX-License-Identifier: GPL-3.0-or-later
"""Demo: uvflat's automatic seams on a closed model and an open one, beside Smart UV Project.

    .venv/bin/python blender_scripts/demo.py [--out out] [--size 512] [--closed auto]

Two meshes without seams are unwrapped inside Blender, each twice, from UVs all at the origin:

* the **closed** model: the bunny of ../shared/meshes (``--closed bunny``, the default where the
  folder is present; ``--closed cow`` takes the cow), else a built-in closed Suzanne (Blender's
  monkey without her eyes, the eye holes filled, one Subdivision Surface level applied;
  ``--closed builtin`` forces it);
* the **open** model: Suzanne, Blender's monkey with one Subdivision Surface level applied, no
  seams (open at the eyes; the eyes are separate parts).

Row 1 of each picture is uvflat's Unwrap operator with its default settings (Auto Seams on: it
cuts the model open by itself and marks the cuts as seams); row 2 is Blender's Smart UV Project
(angle limit 66°). Each row shows the model from the front, side, back and top with the seams
(edges whose two faces' UVs differ) in red, and the UV layout with every face coloured by its
texel density against its island's: ``(UV area / 3D area) / (island UV area / island 3D area)``
on a log scale from ¼ (blue: squeezed) through 1 (white) to 4 (red: stretched), island outlines
dark. Each row's title gives the islands, the seam length over √(3D area), the flipped triangles,
the share of the surface whose density is outside [½, 2] of its island's, and the seconds of
the operator (``uvflat.metrics`` measures every map the same way).

Writes, per mesh (``bunny``, ``suzanne``; ``suzanne_closed`` for the built-in closed model):

* ``out/demo_<mesh>.png``: the picture, ``2 * size`` pixels wide and
  ``2 * size + 4 * (size // 8)`` high (a header, then per row a title and the panels: four
  3D views of ``size / 2`` in a square beside a ``size`` UV layout);
* ``out/demo_<mesh>.json``: each row's title, figures and panel boxes (pixels);
* ``out/demo_<mesh>.npz``: the mesh (``positions``, ``corner_verts``, ``face_sizes``) and
  each row's UVs (``uv_uvflat``, ``uv_smart_uv``);
* ``out/<mesh>.blend``: the mesh with both UV maps (``uvflat`` active, its seams marked).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import common  # noqa: E402

SEAM_RED = (255, 0, 0)  # the seams on the 3D views; nothing else in the pictures is pure red
DENSITY_RANGE = 4.0  # the colour scale runs from 1/4 to 4
DENSITY_BOUND = 2.0  # the title's share: density outside [1/2, 2] of its island's
SMART_ANGLE = 66.0  # Smart UV Project's angle limit, degrees
ROWS = ("uvflat", "smart_uv")  # the picture's rows (also the UV maps' names)
VIEWS = (("front", 0.0, 12.0), ("side", 90.0, 12.0), ("back", 180.0, 12.0),
         ("top", 0.0, 90.0))  # name, azimuth, elevation (degrees; Z up, front looks along +Y)


def picture_size(size):
    """``(width, height)`` of a demo picture for ``--size size``."""
    return 2 * size, 2 * size + 4 * (size // 8)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out", help="output folder (default: out)")
    parser.add_argument("--size", type=int, default=512,
                        help="UV layout panel size in pixels; the picture is twice as wide "
                             "(default: 512)")
    parser.add_argument("--closed", choices=("auto", "bunny", "cow", "builtin"), default="auto",
                        help="the closed model: the shared bunny or cow, or the built-in closed "
                             "Suzanne (default auto: the bunny where ../shared/meshes has it)")
    args = parser.parse_args(argv)
    if args.size < 64:
        parser.error("--size must be at least 64")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import uvflat

    t_start = time.perf_counter()
    for name, build, title in models(args.closed):
        common.reset_scene()
        addon = common.load_addon()
        demo(addon, uvflat, build(), name, title, out, args.size)
    print(f"demo done in {time.perf_counter() - t_start:.1f} s")
    return 0


# ---------------------------------------------------------------------------------------------
# The models


def models(closed="auto"):
    """``(name, build, title)`` of the closed model then the open one."""
    shared = {k: common.SHARED_MESHES / f"{k}.off" for k in FACING}
    if closed == "auto":
        closed = "bunny" if shared["bunny"].is_file() else "builtin"
        if closed == "builtin":
            print(f"note: {shared['bunny']} not found, the closed model is the built-in closed "
                  "Suzanne")
    elif closed in shared and not shared[closed].is_file():
        raise SystemExit(f"{shared[closed]} not found (use --closed builtin)")
    if closed == "builtin":
        first = ("suzanne_closed", closed_suzanne,
                 "Suzanne made closed (eyes removed, eye holes filled), no seams")
    else:
        first = (closed, lambda: shared_model(shared[closed], FACING[closed]),
                 f"The {closed}: a closed surface, no seams")
    return [first, ("suzanne", open_suzanne,
                    "Suzanne: open at the eyes (the eyes are separate parts), no seams")]


# Turn about Z (degrees) that makes a shared model, once stood up (its file's Y up becomes
# Blender's Z up), face the front view (-Y).
FACING = {"bunny": 90.0, "cow": -90.0}


def shared_model(path, turn):
    """A shared .off model stood up from its file's Y-up to Blender's Z-up and turned by
    ``turn`` degrees about Z (to face the front view)."""
    from mathutils import Matrix

    obj = common.load_mesh_object(path)
    obj.data.transform(Matrix.Rotation(math.radians(turn), 4, "Z")
                       @ Matrix.Rotation(math.pi / 2, 4, "X"))
    obj.data.update()
    return obj


def _subdivide(obj, levels=1):
    modifier = obj.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = modifier.render_levels = levels
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.modifier_apply(modifier=modifier.name)


def open_suzanne():
    """Blender's monkey, one Subdivision Surface level applied, no seams."""
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.name = "suzanne"
    _subdivide(obj)
    return obj


def closed_suzanne():
    """Blender's monkey without her eyes, the eye holes filled, one Subdivision Surface level
    applied: a closed surface."""
    import bmesh

    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.active_object
    obj.name = "suzanne_closed"
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    # keep the largest part (the head), delete the eyes
    parts, seen = [], set()
    for face in bm.faces:
        if face in seen:
            continue
        part, todo = [], [face]
        seen.add(face)
        while todo:
            f = todo.pop()
            part.append(f)
            for e in f.edges:
                for g in e.link_faces:
                    if g not in seen:
                        seen.add(g)
                        todo.append(g)
        parts.append(part)
    parts.sort(key=len)
    bmesh.ops.delete(bm, geom=[f for p in parts[:-1] for f in p], context="FACES")
    bmesh.ops.holes_fill(bm, edges=[e for e in bm.edges if e.is_boundary], sides=0)
    bm.to_mesh(obj.data)
    bm.free()
    obj.data.update()
    _subdivide(obj)
    return obj


# ---------------------------------------------------------------------------------------------
# Unwraps


def _clear(mesh, mesh_io):
    """No seams, and a UV map named ``uvflat`` active with every UV at the origin."""
    mesh_io.write_seams(mesh, np.zeros(len(mesh.edges), dtype=bool))
    for layer in list(mesh.uv_layers):
        mesh.uv_layers.remove(layer)
    layer = mesh.uv_layers.new(name="uvflat", do_init=False)
    mesh.uv_layers.active = layer
    mesh_io.write_uv(mesh, "uvflat", np.zeros((len(mesh.loops), 2), dtype=np.float32))


def run_uvflat(obj):
    """uvflat's Unwrap operator with its default settings; returns the seconds it took."""
    common.edit_mode([obj])
    t0 = time.perf_counter()
    result = bpy.ops.uv.uvflat_unwrap()
    seconds = time.perf_counter() - t0
    common.object_mode()
    if "FINISHED" not in result:
        raise RuntimeError(f"uvflat Unwrap did not finish: {result}")
    return seconds


def run_smart_uv(obj):
    """Blender's Smart UV Project (angle limit 66°) into a new UV map ``smart_uv``."""
    mesh = obj.data
    layer = mesh.uv_layers.new(name="smart_uv", do_init=False)
    mesh.uv_layers.active = layer
    common.edit_mode([obj])
    t0 = time.perf_counter()
    result = bpy.ops.uv.smart_project(angle_limit=math.radians(SMART_ANGLE))
    seconds = time.perf_counter() - t0
    common.object_mode()
    if "FINISHED" not in result:
        raise RuntimeError(f"Smart UV Project did not finish: {result}")
    return seconds


def uvflat_label(addon):
    """``uvflat Unwrap`` and its default settings, as the operator declares them."""
    props = bpy.ops.uv.uvflat_unwrap.get_rna_type().properties
    parts = []
    try:
        preset = addon.methods.PRESET_BY_ID[props["preset"].default]
        method = addon.methods.METHOD_BY_ID[preset.method or props["method"].default]
        parts.append(f"{preset.label} preset ({method.label})")
    except (KeyError, AttributeError):
        pass
    if "auto_seams" in props and props["auto_seams"].default:
        parts.append("Auto Seams")
    return "uvflat Unwrap, default settings" + (f": {', '.join(parts)}" if parts else "")


def demo(addon, uvflat, obj, name, title, out, size):
    """Unwrap ``obj`` both ways, measure, draw; write the picture, figures, maps and .blend."""
    mesh_io = addon.mesh_io
    mesh = obj.data
    common.object_mode()
    positions, corner_verts, face_sizes = mesh_io.read_topology(mesh)
    positions = positions.astype(np.float64)
    corner_verts = corner_verts.astype(np.int64)
    face_sizes = face_sizes.astype(np.int64)
    kind = "triangles" if np.all(face_sizes == 3) else "faces"
    print(f"{name}: {len(face_sizes):,} {kind}, {len(mesh.edges):,} edges")

    _clear(mesh, mesh_io)
    seconds = {"uvflat": run_uvflat(obj)}  # (the operator prints its own summary)
    uvs = {"uvflat": mesh_io.read_uv(mesh, "uvflat").astype(np.float64)}
    _, marked = mesh_io.read_edges(mesh)
    mesh_io.write_seams(mesh, np.zeros(len(mesh.edges), dtype=bool))  # Smart UV from no seams
    seconds["smart_uv"] = run_smart_uv(obj)
    uvs["smart_uv"] = mesh_io.read_uv(mesh, "smart_uv").astype(np.float64)
    mesh_io.write_seams(mesh, marked)  # the .blend shows uvflat's seams and map
    mesh.uv_layers.active = mesh.uv_layers["uvflat"]

    labels = {"uvflat": uvflat_label(addon),
              "smart_uv": f"Blender Smart UV Project, angle limit {SMART_ANGLE:g}°"}
    mesh_info = Mesh(positions, corner_verts, face_sizes)
    rows = []
    for key in ROWS:
        maps = UvMap(mesh_info, uvs[key])
        figures = measure(uvflat, mesh_info, maps, seconds[key])
        line = figures_line(figures)
        print(f"  {labels[key]}\n    {line}")
        rows.append(dict(key=key, title=labels[key], figures_line=line, figures=figures,
                         map=maps))

    t0 = time.perf_counter()
    image, boxes = draw_picture(mesh_info, rows, title, kind, size)
    png = out / f"demo_{name}.png"
    image.save(png, optimize=True)
    print(f"  drawn in {time.perf_counter() - t0:.1f} s -> {png}")
    record = dict(mesh=name, title=title, faces=int(len(face_sizes)), size=size,
                  picture=list(image.size),
                  rows=[dict(key=r["key"], title=r["title"], figures_line=r["figures_line"],
                             figures=r["figures"], **boxes[r["key"]]) for r in rows])
    (out / f"demo_{name}.json").write_text(json.dumps(record, indent=1) + "\n")
    np.savez_compressed(out / f"demo_{name}.npz", positions=positions, corner_verts=corner_verts,
                        face_sizes=face_sizes, **{f"uv_{k}": v for k, v in uvs.items()})
    blend = (out / f"{name}.blend").resolve()
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 beside it on a re-run
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    print(f"  -> {out / f'{name}.blend'} (UV maps uvflat and smart_uv)")


# ---------------------------------------------------------------------------------------------
# Measures (numpy)


class Mesh:
    """A polygon mesh as flat arrays, with what the measures and pictures need of it."""

    def __init__(self, positions, corner_verts, face_sizes):
        self.positions = positions
        self.corner_verts = corner_verts
        self.face_sizes = face_sizes
        self.starts = np.zeros(len(face_sizes), dtype=np.int64)
        np.cumsum(face_sizes[:-1], out=self.starts[1:])
        self.face_of = np.repeat(np.arange(len(face_sizes)), face_sizes)
        self.next = np.arange(len(corner_verts)) + 1
        self.next[self.starts + face_sizes - 1] = self.starts
        a, b = corner_verts, corner_verts[self.next]
        key = np.minimum(a, b) * (len(positions) + 1) + np.maximum(a, b)
        order = np.argsort(key, kind="stable")
        _, first, count = np.unique(key[order], return_index=True, return_counts=True)
        two = first[count == 2]
        # the two sides (corners) of every edge of exactly two faces
        self.side1, self.side2 = order[two], order[two + 1]
        p = positions[corner_verts]
        # vector area of every face (Newell): normal times area
        cross = np.cross(p, p[self.next])
        self.vector_area = 0.5 * np.add.reduceat(cross, self.starts, axis=0)
        self.area = np.linalg.norm(self.vector_area, axis=1)
        self.total_area = float(self.area.sum())


class UvMap:
    """A per-corner UV map of a :class:`Mesh`: its islands, seams and texel density."""

    def __init__(self, mesh, uv, tol=1e-6):
        self.mesh, self.uv = mesh, uv
        m = mesh
        c1, c2 = m.side1, m.side2
        cv, nxt = m.corner_verts, m.next
        # match the two ends of the two sides by vertex
        same_dir = cv[c1] == cv[c2]
        e1 = np.where(same_dir, c2, nxt[c2])
        e2 = np.where(same_dir, nxt[c2], c2)
        agree = ((np.abs(uv[c1] - uv[e1]).max(axis=1) <= tol)
                 & (np.abs(uv[nxt[c1]] - uv[e2]).max(axis=1) <= tol))
        self.island = common.components(len(m.face_sizes), m.face_of[c1[agree]], m.face_of[c2[agree]])
        _, self.island = np.unique(self.island, return_inverse=True)
        self.islands = int(self.island.max()) + 1 if len(self.island) else 0
        # seams: edges of two faces whose UVs differ (vertex pairs)
        cut = c1[~agree]
        self.seams = np.column_stack([cv[cut], cv[nxt[cut]]])
        # island outline in UV: every side that is not glued to its neighbour
        glued = np.zeros(len(cv), dtype=bool)
        glued[c1[agree]] = glued[c2[agree]] = True
        self.outline = np.flatnonzero(~glued)  # corners: the side from corner to next corner
        lengths = np.linalg.norm(m.positions[self.seams[:, 0]] - m.positions[self.seams[:, 1]],
                                 axis=1)
        self.seam_length = float(lengths.sum())
        # texel density of every face against its island's
        cross = uv[:, 0] * uv[nxt, 1] - uv[nxt, 0] * uv[:, 1]
        uv_area = 0.5 * np.add.reduceat(cross, m.starts) if len(m.starts) else np.zeros(0)
        n = self.islands
        sign = np.where(np.bincount(self.island, weights=uv_area, minlength=n) < 0, -1.0, 1.0)
        oriented = np.maximum(uv_area * sign[self.island], 0.0)
        island_uv = np.bincount(self.island, weights=oriented, minlength=n)
        island_3d = np.bincount(self.island, weights=m.area, minlength=n)
        with np.errstate(divide="ignore", invalid="ignore"):
            mean = island_uv / island_3d
            ratio = (oriented / m.area) / mean[self.island]
        self.density = np.where(np.isfinite(ratio), ratio, 0.0)


def density_outside(mesh, maps, bound=DENSITY_BOUND):
    """Share of the 3D area whose texel density is outside ``[1/bound, bound]`` of its
    island's, per face (used where ``uvflat.metrics`` has no ``density_outside``)."""
    r = maps.density
    out = ~((r >= 1.0 / bound) & (r <= bound))
    return float(mesh.area[out].sum() / mesh.total_area) if mesh.total_area > 0 else 0.0


def measure(uvflat, mesh, maps, seconds):
    """The title figures of one map (``uvflat.metrics`` and the seams measured here)."""
    m = uvflat.metrics(mesh.positions, mesh.corner_verts, mesh.face_sizes, maps.uv)
    outside = getattr(m, "density_outside", None)
    if outside is None:
        outside = density_outside(mesh, maps)
    return dict(islands=int(m.charts), seam=maps.seam_length / math.sqrt(mesh.total_area),
                flips=int(m.flips), outside=float(outside) + 0.0, seconds=float(seconds),
                overlapping=int(m.overlapping_charts), area=float(m.area),
                conformal=float(m.conformal))


def figures_line(f):
    """A row's figures, as its title shows them."""
    seconds = f["seconds"]
    time_text = f"{seconds:.2f} s" if seconds >= 0.1 else f"{1000 * seconds:.1f} ms"
    return (f"{f['islands']} island{'s' * (f['islands'] != 1)} · "
            f"seam length {f['seam']:.2f} × √area · "
            f"{f['flips']} flip{'s' * (f['flips'] != 1)} · "
            f"{100.0 * f['outside']:.1f}% of the surface squeezed or stretched past 2× · "
            f"{time_text}")


# ---------------------------------------------------------------------------------------------
# Pictures (Pillow)

SS = 2  # supersampling of the panels (drawn at SS times the size, then averaged down)
BACKGROUND = (255, 255, 255)
UV_BACKGROUND = (62, 62, 66)
CLAY = np.array([196.0, 198.0, 204.0])
_STOPS = np.array([[33, 102, 172], [103, 169, 207], [247, 247, 247], [239, 138, 98],
                   [178, 24, 43]], dtype=np.float64)  # blue, white at 1, red


def density_colours(ratio):
    """RGB (N,3) uint8 of texel density ratios: log scale, ¼ blue, 1 white, 4 red."""
    with np.errstate(divide="ignore"):
        t = np.log(np.maximum(ratio, 1e-12)) / math.log(DENSITY_RANGE)
    t = (np.clip(t, -1.0, 1.0) + 1.0) * 0.5 * (len(_STOPS) - 1)
    i = np.minimum(t.astype(int), len(_STOPS) - 2)
    w = (t - i)[:, None]
    return np.rint(_STOPS[i] * (1 - w) + _STOPS[i + 1] * w).astype(np.uint8)


def _font(px, bold=False):
    """DejaVu Sans where it is installed (it has ½ √ ×), else Pillow's own font."""
    from PIL import ImageFont

    for name in (("DejaVuSans-Bold.ttf",) if bold else ()) + ("DejaVuSans.ttf",):
        try:
            return ImageFont.truetype(name, px), True
        except OSError:
            pass
    return ImageFont.load_default(size=px), False


def _ascii(text):
    for a, b in (("√area", "sqrt(area)"), ("×", "x"), ("·", "|"),
                 ("–", "-"), ("°", " deg"), ("¼", "1/4"), ("½", "1/2")):
        text = text.replace(a, b)
    return text


class Text:
    """Text of ``px`` pixels (DejaVu Sans where installed, else Pillow's font in ASCII),
    shrunk to fit a width where one is given."""

    def __init__(self, px):
        self.px = px
        self._fonts = {}

    def font(self, px, bold=False):
        if (px, bold) not in self._fonts:
            self._fonts[px, bold] = _font(px, bold)
        return self._fonts[px, bold]

    def __call__(self, draw, xy, text, bold=False, fill=(0, 0, 0), anchor="la", width=None):
        """Draw ``text``; returns its width in pixels."""
        px = self.px
        while True:
            font, unicode = self.font(px, bold)
            shown = text if unicode else _ascii(text)
            length = font.getlength(shown)
            if width is None or length <= width or px <= 6:
                break
            px -= 1
        draw.text(xy, shown, font=font, fill=fill, anchor=anchor)
        return length

    def length(self, text, bold=False):
        font, unicode = self.font(self.px, bold)
        return font.getlength(text if unicode else _ascii(text))


def view_basis(azimuth, elevation):
    """``(right, up, towards the viewer)`` of an orthographic view (Z up)."""
    az, el = math.radians(azimuth), math.radians(elevation)
    if abs(elevation) >= 89.999:
        return np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0])
    v = np.array([math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)])
    right = np.cross(-v, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -v)
    return right, up, v


class View:
    """One orthographic view of a mesh: the shaded picture (at SS times its size) and the
    buffer of the face seen at every pixel, for the seams' depth test."""

    def __init__(self, mesh, name, basis, px, centre, scale, tol):
        from PIL import Image, ImageDraw

        self.mesh, self.name, self.px, self.tol = mesh, name, px, tol
        self.pixels_per_unit = scale * SS
        right, up, toward = basis
        p = mesh.positions - centre
        n = px * SS
        self.xy = np.column_stack([n / 2 + scale * SS * (p @ right),
                                   n / 2 - scale * SS * (p @ up)])
        self.depth = -(p @ toward)  # larger is farther
        normal = mesh.vector_area / np.maximum(mesh.area, 1e-300)[:, None]
        facing = normal @ toward
        normal = np.where((facing < 0)[:, None], -normal, normal)  # two-sided
        light = -0.35 * right + 0.55 * up + 0.76 * toward
        light /= np.linalg.norm(light)
        shade = 0.30 + 0.70 * np.clip(normal @ light, 0.0, 1.0)
        colour = np.rint(CLAY[None, :] * shade[:, None]).astype(int)
        cv, starts, sizes = mesh.corner_verts, mesh.starts, mesh.face_sizes
        face_depth = np.add.reduceat(self.depth[cv], starts) / sizes
        self.face_depth = face_depth
        self.normal_view = np.column_stack([normal @ right, normal @ up, normal @ toward])
        centroid = np.add.reduceat(self.xy[cv], starts, axis=0) / sizes[:, None]
        self.centroid = centroid
        self.image = Image.new("RGB", (n, n), BACKGROUND)
        ids = Image.new("RGB", (n, n), (0, 0, 0))
        draw, draw_ids = ImageDraw.Draw(self.image), ImageDraw.Draw(ids)
        pts = self.xy[cv].tolist()
        for f in np.argsort(-face_depth, kind="stable").tolist():  # far to near
            poly = [tuple(q) for q in pts[starts[f]:starts[f] + sizes[f]]]
            c = tuple(colour[f].tolist())
            draw.polygon(poly, fill=c, outline=c)
            k = f + 1
            c = (k & 255, (k >> 8) & 255, (k >> 16) & 255)
            draw_ids.polygon(poly, fill=c, outline=c)
        rgb = np.asarray(ids, dtype=np.int64)
        self.ids = rgb[..., 0] + (rgb[..., 1] << 8) + (rgb[..., 2] << 16) - 1  # -1: background
        # faces around every vertex, for "is this face next to the seam"
        v_count = len(mesh.positions) + 1
        self._incident = np.unique(mesh.face_of * v_count + cv)
        self._v_count = v_count

    def _touches(self, faces, verts):
        key = faces * self._v_count + verts
        i = np.minimum(np.searchsorted(self._incident, key), len(self._incident) - 1)
        return self._incident[i] == key

    def visible(self, x, y, depth, va, vb, tol):
        """Whether points at pixel ``(x, y)`` and ``depth`` on the edge ``va``–``vb`` are not
        behind the face seen there (or a face next to it, within 1 pixel)."""
        n = self.ids.shape[0]
        seen = np.zeros(len(x), dtype=bool)
        for dx, dy in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)):
            xi = np.clip(np.rint(x).astype(int) + dx, 0, n - 1)
            yi = np.clip(np.rint(y).astype(int) + dy, 0, n - 1)
            f = self.ids[yi, xi]
            bg = f < 0
            g = np.maximum(f, 0)
            near = self._touches(g, va) | self._touches(g, vb)
            # depth of face g's plane at the pixel (its centroid's where it is edge-on)
            nv = self.normal_view[g]
            plane = self.face_depth[g]
            ok = np.abs(nv[:, 2]) > 0.2
            dxp, dyp = xi - self.centroid[g, 0], yi - self.centroid[g, 1]
            # the view's depth grows away from the viewer: d = d0 + (nx dx - ny dy) / nz / s
            plane = np.where(ok, plane + (nv[:, 0] * dxp - nv[:, 1] * dyp)
                             / np.where(ok, nv[:, 2], 1.0) / self.pixels_per_unit, plane)
            seen |= bg | near | (depth <= plane + tol)
        return seen

    def draw_seams(self, seams, colour, width):
        """Draw the visible parts of the seam edges ``seams`` (vertex pairs) on a copy of the
        shaded picture; returns it at the view's size."""
        from PIL import ImageDraw

        image = self.image.copy()
        if len(seams):
            a, b = seams[:, 0], seams[:, 1]
            pa, pb = self.xy[a], self.xy[b]
            length = np.linalg.norm(pb - pa, axis=1)
            pieces = np.maximum(1, np.ceil(length / (1.5 * SS)).astype(int))
            edge = np.repeat(np.arange(len(seams)), pieces)
            k = np.arange(len(edge)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
            t0 = (k / pieces[edge])[:, None]
            t1 = ((k + 1) / pieces[edge])[:, None]
            tm = (t0 + t1) / 2
            mid = pa[edge] * (1 - tm) + pb[edge] * tm
            dm = self.depth[a[edge]] * (1 - tm[:, 0]) + self.depth[b[edge]] * tm[:, 0]
            vis = self.visible(mid[:, 0], mid[:, 1], dm, a[edge], b[edge], self.tol)
            q0 = pa[edge] * (1 - t0) + pb[edge] * t0
            q1 = pa[edge] * (1 - t1) + pb[edge] * t1
            draw = ImageDraw.Draw(image)
            w = max(1, int(round(width * SS)))
            r = w / 2
            for (x0, y0), (x1, y1) in zip(q0[vis].tolist(), q1[vis].tolist()):
                draw.line([(x0, y0), (x1, y1)], fill=colour, width=w)
                draw.ellipse([x0 - r, y0 - r, x0 + r, y0 + r], fill=colour)
                draw.ellipse([x1 - r, y1 - r, x1 + r, y1 + r], fill=colour)
        return image.reduce(SS)


def make_views(mesh, px):
    """The four views of ``mesh`` (front, side, back, top), one scale for all."""
    lo, hi = mesh.positions.min(axis=0), mesh.positions.max(axis=0)
    centre = (lo + hi) / 2
    radius = float(np.linalg.norm(mesh.positions - centre, axis=1).max()) or 1.0
    scale = 0.48 * px / radius
    return [View(mesh, name, view_basis(az, el), px, centre, scale, 0.02 * radius)
            for name, az, el in VIEWS]


def draw_layout(maps, px):
    """The UV layout of ``maps`` in a ``px`` square: faces coloured by texel density, island
    outlines, the UV tile."""
    from PIL import Image, ImageDraw

    n = px * SS
    image = Image.new("RGB", (n, n), UV_BACKGROUND)
    draw = ImageDraw.Draw(image)
    margin = 0.04 * n
    span = n - 2 * margin

    def to_px(uv):
        return np.column_stack([margin + span * uv[:, 0], n - margin - span * uv[:, 1]])

    for t in np.linspace(0.0, 1.0, 9)[1:-1]:
        a = margin + span * t
        draw.line([(a, margin), (a, n - margin)], fill=(74, 74, 78), width=SS)
        draw.line([(margin, a), (n - margin, a)], fill=(74, 74, 78), width=SS)
    draw.rectangle([margin, margin, n - margin, n - margin], outline=(120, 120, 126), width=SS)
    m = maps.mesh
    pts = to_px(maps.uv).tolist()
    colours = density_colours(maps.density).tolist()
    for f, (s, k) in enumerate(zip(m.starts.tolist(), m.face_sizes.tolist())):
        c = tuple(colours[f])
        draw.polygon([tuple(q) for q in pts[s:s + k]], fill=c, outline=c)
    a = to_px(maps.uv[maps.outline])
    b = to_px(maps.uv[m.next[maps.outline]])
    w = max(1, int(round(SS * px / 400)))
    for (x0, y0), (x1, y1) in zip(a.tolist(), b.tolist()):
        draw.line([(x0, y0), (x1, y1)], fill=(25, 25, 28), width=w)
    return image.reduce(SS)


def draw_colour_bar(draw, text, left, y_mid, w, h):
    """The density colour scale ``squeezed ¼× [blue … white … red] 4× stretched`` from
    ``left``."""
    x = int(left + text.length(" squeezed ¼× "))
    y = int(y_mid - h / 2)
    text(draw, (left, y_mid), " squeezed ¼× ", anchor="lm")
    t = np.exp(np.linspace(-1.0, 1.0, w) * math.log(DENSITY_RANGE))
    for i, c in enumerate(density_colours(t).tolist()):
        draw.line([(x + i, y), (x + i, y + h)], fill=tuple(c))
    draw.rectangle([x - 1, y - 1, x + w, y + h], outline=(140, 140, 140))
    draw.line([(x + w // 2, y - 2), (x + w // 2, y + h + 2)], fill=(90, 90, 90))
    text(draw, (x + w, y_mid), " 4× stretched", anchor="lm")


def draw_picture(mesh, rows, title, kind, size):
    """The whole picture and, per row key, the pixel boxes of its panels."""
    from PIL import Image, ImageDraw

    width, height = picture_size(size)
    bar = size // 8
    image = Image.new("RGB", (width, height), BACKGROUND)
    draw = ImageDraw.Draw(image)
    text = Text(max(7, int(bar * 0.29)))
    small = Text(max(6, int(bar * 0.24)))
    half = size // 2
    views = make_views(mesh, half)
    line_h = bar // 2

    # header: what the picture is and how to read it
    third = 2 * bar / 3
    heading = Text(max(8, int(bar * 0.34)))
    heading(draw, (8, third * 0.55), f"{title}, {len(mesh.face_sizes):,} {kind}", bold=True,
            anchor="lm", width=width - 16)
    text(draw, (8, third * 1.5), "Left: the model from four sides, seams in red.",
         anchor="lm", width=width - 16)
    legend = max(30, size // 4)
    end = 8 + text(draw, (8, third * 2.4), "Right: the UV layout, colour = texel density "
                   "against the island's:", anchor="lm",
                   width=width - 16 - legend - text.length(" squeezed ¼× ")
                   - text.length(" 4× stretched"))
    draw_colour_bar(draw, text, end, third * 2.4, legend, max(4, bar // 5))

    boxes = {}
    seam_width = max(2.0, half / 90)  # pixels: at least one pure red pixel across
    for r, row in enumerate(rows):
        top = 2 * bar + r * (bar + size)
        draw.rectangle([0, top, width, top + bar - 1], fill=(236, 238, 242))
        text(draw, (8, top + line_h // 2 + 1), row["title"], bold=True, anchor="lm",
             width=width - 16)
        text(draw, (8, top + line_h + line_h // 2 - 1), row["figures_line"], anchor="lm",
             width=width - 16)
        y0 = top + bar
        view_boxes = []
        for i, v in enumerate(views):
            x, y = (i % 2) * half, y0 + (i // 2) * half
            image.paste(v.draw_seams(row["map"].seams, SEAM_RED, seam_width), (x, y))
            small(draw, (x + 4, y + 3), v.name, fill=(90, 90, 90))
            view_boxes.append([x, y, x + half, y + half])
        draw.line([(half, y0), (half, y0 + size)], fill=(225, 225, 225))
        draw.line([(0, y0 + half), (size, y0 + half)], fill=(225, 225, 225))
        image.paste(draw_layout(row["map"], size), (size, y0))
        boxes[row["key"]] = dict(views=view_boxes, view_names=[v.name for v in views],
                                 layout=[size, y0, 2 * size, y0 + size])
    return image, boxes


if __name__ == "__main__":
    sys.exit(main())
