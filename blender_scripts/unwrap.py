# SPDX-License-Identifier: GPL-3.0-or-later
"""Unwrap a mesh file headlessly with uvflat and write the result and a UV layout PNG.

    .venv/bin/python blender_scripts/unwrap.py INPUT OUTPUT [--method lscm] [options]

INPUT: .obj, .ply, .off or .blend (first mesh object).  OUTPUT: .obj, .glb or .blend, with the
new UV map; the UV layout is drawn to OUTPUT's name with ``_uv.png`` (or ``--png``).
Goes through the add-on's own operator (``bpy.ops.uv.uvflat_unwrap``), registered from
``addon/``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402

import common  # noqa: E402


def log(message, t0=[time.perf_counter()]):  # noqa: B006 - start time of the run
    print(f"[{time.perf_counter() - t0[0]:7.2f} s] {message}", flush=True)


class _Parser(argparse.ArgumentParser):
    """argparse whose errors are one line and exit status 1 (2 means unsolved charts)."""

    def error(self, message):
        raise SystemExit(f"{self.prog}: {message}")


def parse_args(argv):
    parser = _Parser(
        description="Unwrap a mesh file headlessly with uvflat.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    parser.add_argument("input", type=Path, help=".obj, .ply, .off or .blend")
    parser.add_argument("output", type=Path, help=".obj, .glb or .blend")
    parser.add_argument("--method", default="lscm",
                        help="uvflat method (tutte, harmonic, mean_value, lscm, spectral, ...)")
    parser.add_argument("--boundary", choices=("circle", "square", "virtual", "free", "convex"),
                        default=None,
                        help="tutte/harmonic/mean_value: circle, square or virtual (default "
                             "circle); abf: free or convex (default free)")
    parser.add_argument("--solver", choices=("abf++", "abf"), default=None,
                        help="abf: ABF++ block elimination or the plain ABF system (default abf++)")
    parser.add_argument("--max-iterations", type=int, default=None,
                        help="iterative methods: most iterations (default: the method's)")
    parser.add_argument("--tolerance-exponent", type=int, default=None,
                        help="iterative methods: tolerance as a power of ten (default: the "
                             "method's)")
    parser.add_argument("--seams-from-islands", action="store_true",
                        help="mark seams from the islands of the input's active UV map first")
    parser.add_argument("--no-pack", action="store_true",
                        help="do not pack (islands are fitted to the previous UVs)")
    parser.add_argument("--margin", type=float, default=0.001, help="packing margin")
    parser.add_argument("--uv-name", default=None,
                        help="write into a new UV map of this name (default: the active one)")
    parser.add_argument("--png", type=Path, default=None, help="UV layout image path")
    parser.add_argument("--size", type=int, default=1024, help="UV layout image size")
    args = parser.parse_args(argv)
    if not (math.isfinite(args.margin) and 0.0 <= args.margin <= 1.0):
        parser.error(f"--margin must be a number from 0 to 1, got {args.margin}")
    if not 16 <= args.size <= 16384:
        parser.error(f"--size must be from 16 to 16384 pixels, got {args.size}")
    try:
        common.check_mesh_file(args.input)
    except common.MeshFileError as ex:
        raise SystemExit(str(ex)) from None
    return args


def export(obj, path: Path):
    suffix = path.suffix.lower()
    path.parent.mkdir(parents=True, exist_ok=True)
    for o in bpy.context.view_layer.objects:
        o.select_set(o == obj)
    bpy.context.view_layer.objects.active = obj
    if suffix == ".obj":
        bpy.ops.wm.obj_export(filepath=str(path), export_selected_objects=True, export_uv=True,
                              export_materials=False)
    elif suffix == ".glb":
        import addon_utils

        addon_utils.enable("io_scene_gltf2", default_set=False)
        bpy.ops.export_scene.gltf(filepath=str(path), export_format="GLB", use_selection=True)
    elif suffix == ".blend":
        bpy.ops.wm.save_as_mainfile(filepath=str(path.resolve()), copy=True)
    else:
        raise SystemExit(f"unsupported output format {suffix} (use .obj, .glb or .blend)")


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    if args.output.suffix.lower() not in (".obj", ".glb", ".blend"):
        raise SystemExit(f"unsupported output format {args.output.suffix} (use .obj, .glb or .blend)")
    common.reset_scene()
    addon = common.load_addon()
    mesh_io = addon.mesh_io
    import uvflat

    known = [m.id for m in addon.methods.METHODS if m.id in uvflat.METHODS]
    if args.method not in known:
        raise SystemExit(f"unknown method {args.method!r}; available: {', '.join(known)}")
    # command-line options onto the operator properties of the chosen method, matched by the
    # keyword each property hands to uvflat.unwrap (tolerances are given as powers of ten)
    by_keyword = {"boundary": args.boundary, "solver": args.solver,
                  "max_iterations": args.max_iterations, "tolerance": args.tolerance_exponent}
    method_props = {}
    for key in addon.methods.METHOD_BY_ID[args.method].options:
        value = by_keyword.get(addon.methods.OPTIONS[key].keyword)
        if value is not None:
            method_props[key] = value
    try:
        for key, value in method_props.items():
            # validate enum values against the property definition before touching the mesh
            prop = addon.methods.OPTIONS[key].make_property()
            items = getattr(prop, "keywords", {}).get("items")
            flag = addon.methods.OPTIONS[key].keyword.replace("_", "-")
            if items and value not in [i[0] for i in items]:
                raise ValueError(f"--{flag} {value!r} "
                                 f"is not an option of {args.method}: {[i[0] for i in items]}")
            # numbers within the property's range (Blender would clamp them silently)
            low, high = (getattr(prop, "keywords", {}).get(k) for k in ("min", "max"))
            if (low is not None and value < low) or (high is not None and value > high):
                flag = "tolerance-exponent" if flag == "tolerance" else flag
                raise ValueError(f"--{flag} {value} is out of range for {args.method}: "
                                 f"from {low if low is not None else '-inf'} "
                                 f"to {high if high is not None else 'inf'}")
    except ValueError as ex:
        raise SystemExit(str(ex)) from None

    log(f"loading {args.input}")
    obj = common.load_mesh_object(args.input)
    try:
        common.check_mesh_object(args.input, obj)
    except common.MeshFileError as ex:
        raise SystemExit(str(ex)) from None
    mesh = obj.data
    log(f"loaded '{obj.name}': {len(mesh.vertices)} vertices, {len(mesh.polygons)} faces")

    if args.seams_from_islands:
        if mesh_io.active_uv_name(mesh) is None:
            raise SystemExit(f"{args.input}: --seams-from-islands needs a UV map, the mesh has none")
        common.seams_from_islands(obj)
        log(f"seams from UV islands: {mesh_io.read_seams(mesh).shape[0]} seam edges")
    if args.uv_name:
        layer = mesh.uv_layers.get(args.uv_name) or mesh.uv_layers.new(name=args.uv_name)
        mesh.uv_layers.active = layer

    common.edit_mode([obj])
    log(f"unwrapping with {args.method}")
    result = bpy.ops.uv.uvflat_unwrap(
        method=args.method, pack=not args.no_pack, margin=args.margin, **method_props)
    common.object_mode()
    summary = addon.engine.LAST_SUMMARY
    if "FINISHED" not in result or summary is None:
        log(f"unwrap failed ({result}); nothing written")
        return 1
    log(summary.line())

    export(obj, args.output)
    log(f"wrote {args.output}")
    png = args.png or args.output.with_name(args.output.stem + "_uv.png")
    _, _, face_sizes = mesh_io.read_topology(mesh)
    common.save_layout(png, mesh_io.read_uv(mesh), face_sizes, size=args.size,
                       title=f"{obj.name} - {args.method}")
    log(f"wrote {png}")
    return 2 if summary.failed else 0


if __name__ == "__main__":
    sys.exit(main())
