# SPDX-License-Identifier: GPL-3.0-or-later
"""Time and quality of uvflat against Blender's own unwrap, same mesh, same seams, same process.

    .venv/bin/python blender_scripts/benchmark.py [--meshes camelhead,suzanne] \
        [--methods lscm,tutte] [--repeat 3] [--out bench.md] [--phases] [--large] [--threads N]

For every mesh (the files of ../shared/meshes, Blender's Suzanne with seams from her own UV
islands, and ``suzanne_subdiv2``: Suzanne with a subdivision surface modifier of two levels
applied, seams from her subdivided UV islands) and every method, the whole operator call is timed, from ``bpy.ops...`` in edit mode
to the UVs written (both sides pack their islands with Blender's packer).  Medians of
``--repeat`` runs.  Quality is measured by ``uvflat.metrics`` on the UVs read back from
Blender, so both sides are measured by the same code.

Columns: seconds (median), ratio to Blender CONFORMAL and to the Blender method of the same
family, faces left without a UV solution (all corners on one point: Blender refuses closed
charts, uvflat reports failed charts), charts, flipped triangles, overlapping charts, and the
area-weighted conformal / area / symmetric Dirichlet distortions (1 is perfect).

Cases besides the files: ``camelhead_smart`` (camelhead cut by Blender's Smart UV Project,
seams marked from its islands: 128 charts, the many-charts case; any other shared mesh
``NAME`` can be named as ``NAME_smart``, e.g. ``cube_40k_smart``, 47,240 charts of one or
two quads) and, with
``--large`` or when named (slow), ``disk_840k``: a flat disk of 128 triangles subdivided with
80 cuts, 839,808 triangles in one chart, and ``disk_300k``: the same with 47 cuts, 294,912
triangles. ``--blender-methods none`` leaves Blender's own unwraps out (they take long on
the large disks).

``--phases`` adds, for uvflat rows, the median seconds of each phase of the add-on's operator
(read, solve, quality = the core's per-face distortion measure, write, pack = the packing,
mode = edit/object mode switches, other = the rest of the operator call), taken from the
engine's ``Summary.phases``; "other" also holds the operator call's own overhead, so the
phases add up to the ``seconds`` column (of the same run; medians may not add up exactly).
``floor × family`` is the "× family" ratio a solve of zero seconds would leave: uvflat's
seconds outside the solve (reading, quality, writing, Blender's packer, mode switches) over
the Blender method's seconds; no speed-up of the core can take "× family" below it.  ``peak MB`` is the process's peak resident memory so far
(``resource.getrusage``; it only grows, so read it in run order), ``threads`` the size of the
core's thread pool (``--threads N`` sets ``RAYON_NUM_THREADS`` before the core is loaded).

The ``factor s`` column is the time of one sparse Cholesky factorization of the chart system
for the linear methods, if the uvflat module provides ``uvflat.factorization_seconds(positions,
corner_verts, face_sizes, *, method, seams, selected)`` (the hook below); "n/a" otherwise.

How time and peak memory grow with the mesh (one disk chart from 50k to about 1M triangles,
through the Python API alone, each run in its own process) is measured by ``scaling.py``
beside this script.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

import common  # noqa: E402

BLENDER_METHODS = ("ANGLE_BASED", "CONFORMAL", "MINIMUM_STRETCH")
# The Blender unwrap of the same family as each uvflat method (the linear ones compare with
# Blender's linear LSCM; ABF with ABF++; the isometric/nonlinear ones with SLIM).
FAMILY = {
    "tutte": "CONFORMAL", "harmonic": "CONFORMAL", "mean_value": "CONFORMAL",
    "lscm": "CONFORMAL", "spectral": "CONFORMAL", "bff": "CONFORMAL", "mips": "CONFORMAL",
    "abf": "ANGLE_BASED",
    "arap": "MINIMUM_STRETCH", "slim": "MINIMUM_STRETCH", "scaffold": "MINIMUM_STRETCH",
}
LINEAR = {"tutte", "harmonic", "mean_value", "lscm", "bff"}
MARGIN = 0.001


def factorization_seconds(uvflat, positions, corner_verts, face_sizes, method, seams):
    """Hook: one sparse Cholesky factorization of the chart system, if the module exposes it."""
    hook = getattr(uvflat, "factorization_seconds", None)
    if hook is None or method not in LINEAR:
        return None
    return float(hook(positions, corner_verts, face_sizes, method=method, seams=seams,
                      selected=None))


SMART_MESH = "camelhead"  # the shared mesh cut by Smart UV Project for the many-charts case
LARGE_DISK = "disk_840k"
# the large disks: name -> subdivision cuts of the 128-triangle fan
LARGE_DISKS = {LARGE_DISK: 80, "disk_300k": 47}


def mesh_list(names, large=False):
    available = {"suzanne": None, "suzanne_subdiv2": None}
    if common.SHARED_MESHES.is_dir():
        for path in sorted(common.SHARED_MESHES.iterdir()):
            if path.suffix.lower() in (".off", ".obj", ".ply"):
                available[path.stem] = path
        smart = common.SHARED_MESHES / f"{SMART_MESH}.off"
        if smart.is_file():
            available[f"{SMART_MESH}_smart"] = smart
        # Any other shared mesh cut by Smart UV Project, when named (e.g. cube_40k_smart:
        # tens of thousands of one-quad charts).
        for name in names or ():
            stem = name[: -len("_smart")] if name.endswith("_smart") else None
            if stem and name not in available and stem in available and available[stem] is not None:
                available[name] = available[stem]
    else:
        print(f"note: {common.SHARED_MESHES} not found; only Blender's primitives are measured")
    for disk in LARGE_DISKS:
        if large or disk in names:
            available[disk] = None
    if names:
        missing = [n for n in names if n not in available]
        if missing:
            raise SystemExit(f"unknown mesh(es) {missing}; available: {', '.join(available)}")
        return {n: available[n] for n in names}
    return available


def smart_cut(obj):
    """Cut ``obj`` with Blender's Smart UV Project and mark seams from its islands."""
    common.edit_mode([obj])
    bpy.ops.mesh.select_all(action="SELECT")
    bpy.ops.uv.smart_project()
    bpy.ops.object.mode_set(mode="OBJECT")
    common.seams_from_islands(obj)
    return obj


def large_disk(segments=128, cuts=80, name=LARGE_DISK):
    """A flat disk: a triangle fan of ``segments`` triangles, every triangle split by ``cuts``
    cuts per edge into (cuts + 1)² triangles (839,808 with the defaults)."""
    return common.subdivided_disk(name, segments, cuts)


def load(name, path):
    common.reset_scene()
    common.load_addon()
    if name in LARGE_DISKS:
        return large_disk(cuts=LARGE_DISKS[name], name=name)
    if path is None:
        return common.suzanne_subdivided(2) if name == "suzanne_subdiv2" else common.suzanne()
    obj = common.load_mesh_object(path)
    return smart_cut(obj) if name.endswith("_smart") else obj


def peak_mb():
    """Peak resident memory of this process so far, in MB (ru_maxrss is in KB on Linux)."""
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return rss / 1024.0 if sys.platform != "darwin" else rss / (1024.0 * 1024.0)


def unsolved_faces(uv, face_sizes):
    """Faces whose corners all sit on one UV point (no solution was written)."""
    starts = np.zeros(len(face_sizes), dtype=np.int64)
    np.cumsum(face_sizes[:-1], out=starts[1:])
    lo = np.minimum.reduceat(uv, starts, axis=0)
    hi = np.maximum.reduceat(uv, starts, axis=0)
    return int(np.all(hi - lo == 0.0, axis=1).sum())


def run_once(obj, kind, method):
    """One end-to-end unwrap of all faces; returns (seconds, error message or None)."""
    common.edit_mode([obj])
    t0 = time.perf_counter()
    try:
        if kind == "uvflat":
            result = bpy.ops.uv.uvflat_unwrap(method=method, pack="ALL", shape_method="AABB", margin=MARGIN)
        else:
            result = bpy.ops.uv.unwrap(method=method, margin=MARGIN)
        error = None if "FINISHED" in result else f"returned {set(result)}"
    except RuntimeError as ex:  # a report of type ERROR raises from bpy.ops
        error = str(ex).strip().splitlines()[-1]
    seconds = time.perf_counter() - t0
    common.object_mode()
    return seconds, error


def measure(uvflat, mesh_io, obj, kind, method, repeat):
    """One table row: ``repeat`` timed runs of one method on ``obj``, each from the mesh's own
    seams and UVs at the origin, and the quality of the last. The mesh's seams are as they
    were when it returns (an unwrap with automatic seams marks its cuts, which the next
    method would take as given)."""
    _, own_seams = mesh_io.read_edges(obj.data)
    try:
        return _measure(uvflat, mesh_io, obj, kind, method, repeat, own_seams)
    finally:
        mesh_io.write_seams(obj.data, own_seams)


def _measure(uvflat, mesh_io, obj, kind, method, repeat, own_seams):
    mesh = obj.data
    positions, corner_verts, face_sizes = mesh_io.read_topology(mesh)
    times, error, phases = [], None, []
    # the add-on whose mesh_io this is (its engine keeps the last unwrap's summary)
    addon = sys.modules[mesh_io.__name__.rpartition(".")[0]]
    for _ in range(repeat):
        # start from the same state every time: the mesh's own seams (an unwrap with automatic
        # seams marks its cuts, which a later run or method would take as given and cut
        # nothing) and all UVs at the origin
        mesh_io.write_seams(mesh, own_seams)
        mesh_io.write_uv(mesh, mesh_io.ensure_uv_map(mesh)[0],
                         np.zeros((len(corner_verts), 2), dtype=np.float32))
        seconds, error = run_once(obj, kind, method)
        if error:
            break
        times.append(seconds)
        if kind == "uvflat":
            summary = addon.engine.LAST_SUMMARY
            ph = dict(getattr(summary, "phases", None) or {})
            # the operator call's own overhead (outside the engine's run) is "other" too
            ph["other"] = ph.get("other", 0.0) + max(0.0, seconds - sum(ph.values()))
            phases.append(ph)
    row = {"kind": kind, "method": method, "error": error,
           "seconds": statistics.median(times) if times else None, "peak_mb": peak_mb()}
    if phases:
        row["phases"] = {name: statistics.median(p.get(name, 0.0) for p in phases)
                         for name in PHASES}
    if error:
        return row
    uv = mesh_io.read_uv(mesh).astype(np.float64)
    row["unsolved"] = unsolved_faces(uv, face_sizes)
    try:
        m = uvflat.metrics(positions, corner_verts, face_sizes, uv)
        row.update(charts=m.charts, flips=m.flips, overlapping=m.overlapping_charts,
                   conformal=m.conformal, area=m.area, dirichlet=m.symmetric_dirichlet)
    except uvflat.UvflatError as ex:
        row["metrics_error"] = str(ex)
    if kind == "uvflat":
        summary = addon.engine.LAST_SUMMARY
        if summary is not None and summary.failed:
            row["note"] = f"{len(summary.failed)} chart(s) failed: {summary.failed[0].reason}"
        try:
            row["factor"] = factorization_seconds(uvflat, positions, corner_verts, face_sizes,
                                                  method, mesh_io.read_seams(mesh))
        except Exception as ex:  # the hook is optional; never let it break the table
            row["factor_error"] = str(ex)
    return row


PHASES = ("read", "solve", "quality", "write", "pack", "mode", "other")


def fmt(value, spec):
    return "–" if value is None else format(value, spec)


def table(results, threads, show_phases=False):
    phase_head = ("".join(f" {p} s |" for p in PHASES) + " floor × family |") if show_phases else ""
    head = ("| mesh | faces | method | seconds | × CONFORMAL | × family | unsolved faces | charts "
            "| flips | overlapping | conformal | area | sym. Dirichlet | factor s |" + phase_head
            + " peak MB | threads | note |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    dashes = " – |" * (len(PHASES) + 1 if show_phases else 0)
    for mesh_name, n_faces, rows in results:
        by_method = {r["method"]: r for r in rows if r["kind"] == "blender"}
        for r in rows:
            label = r["method"] if r["kind"] == "uvflat" else f"Blender {r['method']}"
            if r["error"]:
                lines.append(f"| {mesh_name} | {n_faces} | {label} | – | – | – | – | – | – | – | – | – "
                             f"| – | – |{dashes} – | {threads} | refused: {r['error']} |")
                continue
            ref = by_method.get("CONFORMAL", {}).get("seconds")
            fam_name = FAMILY.get(r["method"]) if r["kind"] == "uvflat" else r["method"]
            fam = by_method.get(fam_name, {}).get("seconds") if fam_name else None
            ratio = fmt(r["seconds"] / ref, ".2f") if ref else "–"
            fam_ratio = (f"{r['seconds'] / fam:.2f} ({fam_name})" if fam else "–")
            factor = r.get("factor")
            note = r.get("note") or r.get("metrics_error") or r.get("factor_error") or ""
            ph = r.get("phases")
            # The smallest "× family" a solve of zero seconds would leave: everything the
            # operator does besides the solve, over the Blender method's whole time.
            floor = ((r["seconds"] - ph.get("solve", 0.0)) / fam
                     if ph and fam and r["kind"] == "uvflat" else None)
            phase_cells = ("".join(f" {fmt(ph.get(p) if ph else None, '.4f')} |" for p in PHASES)
                           + f" {fmt(floor, '.3f')} |" if show_phases else "")
            lines.append(
                f"| {mesh_name} | {n_faces} | {label} | {r['seconds']:.4f} | {ratio} | {fam_ratio} "
                f"| {r.get('unsolved', '–')} | {r.get('charts', '–')} | {r.get('flips', '–')} "
                f"| {r.get('overlapping', '–')} | {fmt(r.get('conformal'), '.4f')} "
                f"| {fmt(r.get('area'), '.4f')} | {fmt(r.get('dirichlet'), '.4f')} "
                f"| {fmt(factor, '.4f') if factor is not None else 'n/a'} |{phase_cells} "
                f"{fmt(r.get('peak_mb'), '.0f')} | {threads} | {note} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description="uvflat vs Blender's unwrap.")
    parser.add_argument("--meshes", default="", help="comma-separated mesh names (default: all)")
    parser.add_argument("--methods", default="", help="comma-separated uvflat methods (default: all)")
    parser.add_argument("--blender-methods", default=",".join(BLENDER_METHODS),
                        help="comma-separated Blender unwrap methods, or 'none'")
    parser.add_argument("--repeat", type=int, default=3, help="repetitions (median reported)")
    parser.add_argument("--out", type=Path, default=None, help="write the markdown table here")
    parser.add_argument("--closed", action="store_true",
                        help="the closed-mesh table instead: automatic seams against Smart UV "
                             "Project + ANGLE_BASED and xatlas (see closed_benchmark.py)")
    parser.add_argument("--open", action="store_true",
                        help="the same table for open and multi-part meshes (bunny_open, "
                             "suzanne, teapot_parts, three_parts); with --closed: both")
    parser.add_argument("--dump-uv", type=Path, default=None,
                        help="with --closed/--open: write every row's map to DIR/<mesh>__<row>.npz")
    parser.add_argument("--phases", action="store_true",
                        help="per-phase seconds of the add-on's operator (read, solve, quality, "
                             "write, pack, mode, other); with --closed/--open: the core's "
                             "pipeline phases (cut planning, first solves, repair rounds and "
                             "pieces, splits) of each mesh and the call against xatlas")
    parser.add_argument("--large", action="store_true",
                        help="also the slow large cases disk_840k and disk_300k (disks of "
                             "839,808 and 294,912 triangles)")
    parser.add_argument("--threads", type=int, default=0,
                        help="threads of the core's pool (RAYON_NUM_THREADS; default: all cores)")
    args = parser.parse_args(argv)
    if args.closed or args.open:
        import closed_benchmark

        names = [n for n in args.meshes.split(",") if n]
        chosen = closed_benchmark.select(names, closed=args.closed, open_=args.open)
        text = closed_benchmark.run(chosen, args.repeat, dump_uv=args.dump_uv, phases=args.phases)
        print()
        print(text)
        if args.out:
            args.out.parent.mkdir(parents=True, exist_ok=True)
            args.out.write_text(text + "\n")
        return 0
    if args.threads > 0:
        # read by the core's thread pool when it starts, so set before the first unwrap
        os.environ["RAYON_NUM_THREADS"] = str(args.threads)
    threads = int(os.environ.get("RAYON_NUM_THREADS") or 0) or len(os.sched_getaffinity(0))

    import uvflat

    addon = common.load_addon()
    # the methods both the core and the add-on's method table know
    known = [m.id for m in addon.methods.METHODS if m.id in uvflat.METHODS]
    not_in_addon = [m for m in uvflat.METHODS if m not in known]
    if not_in_addon:
        print(f"note: the core also has {', '.join(not_in_addon)}, not yet in the add-on's method table")
    methods = [m for m in args.methods.split(",") if m] or known
    unknown = [m for m in methods if m not in known]
    if unknown:
        raise SystemExit(f"unknown uvflat method(s) {unknown}; available: {', '.join(known)}")
    blender_methods = [m for m in args.blender_methods.split(",") if m and m.lower() != "none"]
    unknown = [m for m in blender_methods if m not in BLENDER_METHODS]
    if unknown:
        raise SystemExit(f"unknown Blender method(s) {unknown}; available: "
                         f"{', '.join(BLENDER_METHODS)} or none")
    meshes = mesh_list([n for n in args.meshes.split(",") if n], large=args.large)

    results = []
    for name, path in meshes.items():
        try:
            obj = load(name, path)
        except Exception as ex:
            print(f"{name}: could not load: {ex}", flush=True)
            results.append((name, "?", [{"kind": "uvflat", "method": "load", "error": str(ex)}]))
            continue
        mesh_io = sys.modules[common.ADDON_MODULE].mesh_io
        n_faces = len(obj.data.polygons)
        print(f"{name}: {n_faces} faces, {mesh_io.read_seams(obj.data).shape[0]} seam edges", flush=True)
        rows = []
        for method in blender_methods:
            rows.append(measure(uvflat, mesh_io, obj, "blender", method, args.repeat))
            print(f"  Blender {method:<16} {fmt(rows[-1]['seconds'], '.4f')} s"
                  f"{'  ' + rows[-1]['error'] if rows[-1]['error'] else ''}", flush=True)
        for method in methods:
            rows.append(measure(uvflat, mesh_io, obj, "uvflat", method, args.repeat))
            print(f"  uvflat  {method:<16} {fmt(rows[-1]['seconds'], '.4f')} s"
                  f"{'  ' + rows[-1]['error'] if rows[-1]['error'] else ''}", flush=True)
        results.append((name, n_faces, rows))

    text = table(results, threads, show_phases=args.phases)
    header = (f"uvflat benchmark: Blender {bpy.app.version_string}, uvflat "
              f"{getattr(uvflat, '__version__', '?')}, median of {args.repeat}, margin {MARGIN}, "
              f"{threads} thread(s)\n\n")
    print()
    print(header + text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(header + text + "\n")
        print(f"\n-> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
