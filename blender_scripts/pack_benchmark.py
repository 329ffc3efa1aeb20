# SPDX-License-Identifier: GPL-3.0-or-later
"""Time the add-on's packing of many small islands in Blender.

    .venv/bin/python blender_scripts/pack_benchmark.py [--islands 2000] [--repeat 3] \
        [--modes ALL,AROUND] [--shape CONCAVE] [--no-orient] [--out pack.md]

One mesh of ``--islands`` separate patches of 2 x 2 quads (9 vertices each, so every patch is
its own island), of random sizes (0.5 to 2), proportions (1:1 to 1:3) and turns, on a gently
curved sheet. ``ALL`` unwraps every patch with the add-on's operator (``lscm``, *Whole Tile*);
``AROUND`` also has one big existing island (a 20 x 20 grid whose UVs fill the lower half of
the 0-1 tile, not selected) and packs the patches around it (*Around Others*, the default). The
shape asked for is ``--shape`` (the operator's default, exact shapes); the add-on chooses the
shape Blender's packer is given from the island count (``engine.pack_shape``). *Orient* is on,
as by default (``--no-orient``: off).

Columns (medians of ``--repeat`` runs, each on a freshly built mesh): *packing s*, the whole
packing step of the operator (``engine._pack``: texel density, Orient, the UDIM tile, selection
and mode changes, Blender's packer, writing the UVs, coverage); *packer s*, Blender's
``uv.pack_islands`` alone (the summary's ``pack`` phase); *unwrap s*, the whole operator call;
*shape*, the shape the packer was given; *coverage*, the summary's tile coverage; *in tile*,
whether every new island landed inside the 0-1 tile in every run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import common  # noqa: E402


def patches(n, seed=0):
    """Positions, corner vertices and face sizes of ``n`` separate 2 x 2 quad patches."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n)))
    g = np.linspace(-0.5, 0.5, 3)
    local = np.stack(np.meshgrid(g, g, indexing="xy"), -1).reshape(-1, 2)  # 9 points
    quads = np.array([[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]])
    size = rng.uniform(0.5, 2.0, n)
    stretch = rng.uniform(1.0, 3.0, n)
    turn = rng.uniform(0.0, np.pi, n)
    c, s = np.cos(turn), np.sin(turn)
    x = local[None, :, 0] * (size * stretch)[:, None]
    y = local[None, :, 1] * size[:, None]
    cell = np.arange(n)
    cx, cy = 4.0 * (cell % side), 4.0 * (cell // side)
    px = cx[:, None] + c[:, None] * x - s[:, None] * y
    py = cy[:, None] + s[:, None] * x + c[:, None] * y
    pz = 0.2 * np.sin(0.05 * px) * np.cos(0.05 * py)
    positions = np.stack([px, py, pz], -1).reshape(-1, 3)
    corner_verts = (quads[None] + 9 * np.arange(n)[:, None, None]).reshape(-1)
    return positions, corner_verts, np.full(4 * n, 4, dtype=np.int64)


def existing_island(first_vertex, side, m=20):
    """An ``m`` x ``m`` quad grid of ``side`` metres beside the patches, its UVs over the lower
    half of the tile."""
    g = np.arange(m + 1, dtype=np.float64)
    xx, yy = np.meshgrid(g, g, indexing="xy")
    cell = side / m
    positions = np.stack([cell * xx.ravel() - 1.5 * side, cell * yy.ravel(), np.zeros(xx.size)],
                         -1)
    i, j = np.meshgrid(np.arange(m), np.arange(m), indexing="xy")
    a = (j * (m + 1) + i).ravel()
    quads = np.stack([a, a + 1, a + m + 2, a + m + 1], -1)
    uv_of_vertex = np.stack([xx.ravel() / m, 0.5 * yy.ravel() / m], -1)
    return positions, (quads + first_vertex).reshape(-1), np.full(m * m, 4), uv_of_vertex, quads


def patch_area(positions, corner_verts):
    """Surface area of the quads ``corner_verts`` (split on their first diagonal)."""
    q = positions[corner_verts.reshape(-1, 4)]
    a = np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0])
    b = np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 0])
    return 0.5 * float(np.linalg.norm(a, axis=1).sum() + np.linalg.norm(b, axis=1).sum())


def build(n_islands, mode):
    """The benchmark object in Object Mode: the patches selected, the existing island (AROUND)
    unselected with its UVs."""
    io = common.mesh_io()
    positions, corner_verts, face_sizes = patches(n_islands)
    n_new = len(face_sizes)
    uv_grid = None
    if mode == "AROUND":
        # the existing island's density leaves the new islands about 0.2 of the tile
        area = patch_area(positions, corner_verts)
        p2, c2, f2, uv_of_vertex, quads = existing_island(len(positions),
                                                          np.sqrt(0.5 * area / 0.2))
        uv_grid = uv_of_vertex[quads.reshape(-1)]
        positions = np.vstack([positions, p2])
        corner_verts = np.concatenate([corner_verts, c2])
        face_sizes = np.concatenate([face_sizes, f2])
    mesh = io.new_mesh("Islands", positions, corner_verts, face_sizes)
    obj = common.link_mesh_object("Islands", mesh)
    name, _ = io.ensure_uv_map(mesh)
    uv = np.zeros((len(corner_verts), 2), dtype=np.float32)
    if uv_grid is not None:
        uv[4 * n_new:] = uv_grid
    io.write_uv(mesh, name, uv)
    selected = np.zeros(len(face_sizes), dtype=bool)
    selected[:n_new] = True
    io.select_faces(mesh, selected)
    return obj


def run_once(addon, n_islands, mode, shape, orient=True):
    engine = addon.engine
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    obj = build(n_islands, mode)
    packing = []
    real_pack = engine._pack

    def timed_pack(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return real_pack(*args, **kwargs)
        finally:
            packing.append(time.perf_counter() - t0)

    common.edit_mode([obj], select_all=False)
    engine._pack = timed_pack
    try:
        t0 = time.perf_counter()
        result = bpy.ops.uv.uvflat_unwrap(method="lscm", pack=mode, shape_method=shape,
                                          orient=orient)
        seconds = time.perf_counter() - t0
    finally:
        engine._pack = real_pack
        common.object_mode()
    if "FINISHED" not in result:
        raise SystemExit(f"the unwrap returned {result}")
    summary = engine.LAST_SUMMARY
    if summary.charts != n_islands:
        raise SystemExit(f"expected {n_islands} islands, the unwrap made {summary.charts}")
    uv = common.mesh_io().read_uv(obj.data)[:16 * n_islands]
    inside = bool(np.all((uv >= -1e-6) & (uv <= 1 + 1e-6)))
    return dict(packing=sum(packing), packer=summary.phases.get("pack", 0.0), unwrap=seconds,
                shape="+".join(summary.pack_shapes), coverage=summary.coverage, inside=inside)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--islands", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--modes", default="ALL,AROUND")
    parser.add_argument("--shape", default="CONCAVE", choices=("CONCAVE", "CONVEX", "AABB"))
    parser.add_argument("--no-orient", dest="orient", action="store_false")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args(argv)
    common.reset_scene()
    addon = common.load_addon()
    lines = ["| islands | pack | orient | shape asked | shape used | packing s | packer s "
             "| unwrap s | coverage | in tile |", "|---|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines), flush=True)
    for mode in args.modes.split(","):
        runs = [run_once(addon, args.islands, mode, args.shape, args.orient)
                for _ in range(args.repeat)]
        med = {k: statistics.median(r[k] for r in runs) for k in ("packing", "packer", "unwrap")}
        coverage = runs[-1]["coverage"]
        line = (f"| {args.islands:,} | {mode} | {'on' if args.orient else 'off'} | "
                f"{args.shape} | {runs[-1]['shape']} | "
                f"{med['packing']:.3f} | {med['packer']:.3f} | {med['unwrap']:.3f} | "
                f"{'-' if coverage is None else f'{100 * coverage:.0f}%'} | "
                f"{'yes' if all(r['inside'] for r in runs) else 'no'} |")
        lines.append(line)
        print(line, flush=True)
    if args.out is not None:
        args.out.write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
