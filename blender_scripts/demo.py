# SPDX-License-Identifier: GPL-3.0-or-later
"""Demo: Suzanne (seams from her own UV islands) and camelhead, unwrapped by every uvflat method.

    .venv/bin/python blender_scripts/demo.py [--out out] [--size 768]

Writes ``out/<mesh>_<method>.png`` (one UV layout per method; flipped faces in red),
``out/<mesh>_methods.png`` (all of them side by side) and ``out/suzanne.blend`` (one UV map
per method, named ``uvflat_<method>``).  camelhead comes from ../shared/meshes and is skipped
where that folder is absent.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402

import common  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out", help="output folder (default: out)")
    parser.add_argument("--size", type=int, default=768, help="PNG size in pixels")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import uvflat

    common.reset_scene()
    addon = common.load_addon()
    methods = [m.id for m in addon.methods.METHODS if m.id in uvflat.METHODS]
    ok = run(addon, uvflat, common.suzanne(), "suzanne", methods, out, args.size)
    bpy.ops.wm.save_as_mainfile(filepath=str((out / "suzanne.blend").resolve()))
    print(f"-> {out / 'suzanne.blend'}")
    camelhead = common.SHARED_MESHES / "camelhead.off"
    if camelhead.is_file():
        common.reset_scene()
        ok &= run(addon, uvflat, common.load_mesh_object(camelhead), "camelhead", methods, out,
                  args.size)
    else:
        print(f"note: {camelhead} not found, camelhead layouts skipped")
    return 0 if ok else 1


def run(addon, uvflat, obj, name, methods, out, size):
    """Unwrap ``obj`` with every method into its own UV map; draw each layout."""
    mesh_io = addon.mesh_io
    mesh = obj.data
    positions, corner_verts, face_sizes = mesh_io.read_topology(mesh)
    print(f"{name}: {len(mesh.polygons)} faces, {int(mesh_io.read_seams(mesh).shape[0])} seam edges")
    images = []
    for method in methods:
        layer = mesh.uv_layers.new(name=f"uvflat_{method}")
        mesh.uv_layers.active = layer
        common.edit_mode([obj])
        t0 = time.perf_counter()
        result = bpy.ops.uv.uvflat_unwrap(method=method, pack="ALL", margin=0.01)
        seconds = time.perf_counter() - t0
        common.object_mode()
        summary = addon.engine.LAST_SUMMARY
        if "FINISHED" not in result or summary is None:
            print(f"  {method:<11} FAILED ({result})")
            continue
        uv = mesh_io.read_uv(mesh).astype("float64")
        m = uvflat.metrics(positions, corner_verts, face_sizes, uv)
        title = (f"{name} {method}: {m.charts} charts, {m.flips} flips, conformal {m.conformal:.3f},"
                 f" area {m.area:.3f}, {seconds * 1000:.0f} ms")
        print(f"  {summary.line()}")
        print(f"  {'':<11} read back: {title}")
        image = common.draw_layout(uv, face_sizes, size=size, title=title)
        image.save(out / f"{name}_{method}.png")
        images.append(image)
        print(f"  {'':<11} -> {out / f'{name}_{method}.png'}")
    if images:
        common.grid(images, columns=min(3, len(images))).save(out / f"{name}_methods.png")
        print(f"-> {out / f'{name}_methods.png'}")
    return len(images) == len(methods)


if __name__ == "__main__":
    sys.exit(main())
