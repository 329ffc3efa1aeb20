# SPDX-License-Identifier: GPL-3.0-or-later
"""uvflat's SLIM against libigl's SLIM on the same chart, same start, same process.

    python blender_scripts/compare_libigl.py [MESH ...] [--repeat 3] [--max-iterations 100]

Needs no Blender, but a Python with both ``uvflat`` and libigl's Python bindings
(``pip install libigl``; they need numpy 2, so use a separate environment from Blender's):

    python3.11 -m venv /tmp/igl && /tmp/igl/bin/pip install libigl dist/wheels/uvflat-*.whl
    /tmp/igl/bin/python blender_scripts/compare_libigl.py

Meshes default to ``camelhead.off`` from ``../shared/meshes`` (single-disk triangle meshes;
the first chart must be the whole mesh).  For each mesh:

* uvflat: ``uvflat.unwrap(method="slim")`` with its defaults, end to end (start map, SLIM
  iterations, metrics), median of ``--repeat`` runs.  Its symmetric Dirichlet energy is the
  target.
* libigl: the same flip-free start uvflat's SLIM uses when LSCM is not better (mean value map
  on a circle, computed by uvflat and scaled to the 3D area), then ``igl.slim_precompute`` and
  one ``igl.slim_solve`` iteration at a time until its energy is at or below uvflat's (or
  ``--max-iterations``).  Its time counts precomputation and iterations, not the start map
  nor the energy measurements between iterations; best of ``--repeat`` runs.

Both energies are measured by ``uvflat.metrics`` (area-normalised symmetric Dirichlet, 1 is
an isometry), so they compare.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

SHARED = Path(__file__).resolve().parent.parent.parent / "shared" / "meshes"


def energy(uvflat, v, f, uv_vertex):
    corners = f.ravel()
    m = uvflat.metrics(v, corners.astype(np.int32), np.full(len(f), 3, np.int32), uv_vertex[corners])
    return m.symmetric_dirichlet, m.flips


def run_uvflat(uvflat, v, f, repeat):
    corners = f.ravel().astype(np.int32)
    sizes = np.full(len(f), 3, np.int32)
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        r = uvflat.unwrap(v, corners, sizes, method="slim")
        times.append(time.perf_counter() - t)
    m = uvflat.metrics(v, corners, sizes, r.uv)
    chart = r.charts[0]
    return statistics.median(times), m.symmetric_dirichlet, m.flips, chart.iterations


def start_map(uvflat, v, f):
    """uvflat's mean value map on a circle, per vertex, scaled to the 3D area."""
    corners = f.ravel().astype(np.int32)
    r = uvflat.unwrap(v, corners, np.full(len(f), 3, np.int32), method="mean_value")
    uv = np.zeros((len(v), 2))
    uv[corners] = r.uv
    a3 = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()
    e1, e2 = uv[f[:, 1]] - uv[f[:, 0]], uv[f[:, 2]] - uv[f[:, 0]]
    a2 = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    return uv * np.sqrt(a3 / a2)


def run_libigl(igl, uvflat, v, f, target, max_iterations):
    """Seconds and iterations for libigl's SLIM to reach `target`, and its final energy."""
    uv0 = start_map(uvflat, v, f)
    fi = np.asfortranarray(f.astype(np.int32))
    t = time.perf_counter()
    data = igl.slim_precompute(np.asfortranarray(v), fi, np.asfortranarray(uv0), igl.SYMMETRIC_DIRICHLET,
                               np.zeros(0, np.int32), np.zeros((0, 2)), 0.0)
    seconds = time.perf_counter() - t
    e, flips, it = np.inf, 0, 0
    while it < max_iterations:
        t = time.perf_counter()
        uv = igl.slim_solve(data, 1)
        seconds += time.perf_counter() - t
        it += 1
        e, flips = energy(uvflat, v, f, np.asarray(uv)[:, :2])
        if e <= target:
            break
    return seconds, it, e, flips


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("meshes", nargs="*", help="triangle meshes (default: camelhead.off)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--max-iterations", type=int, default=100)
    args = parser.parse_args(argv)
    try:
        import igl
        import uvflat
    except ImportError as ex:
        raise SystemExit(f"needs uvflat and libigl in one Python ({ex}); see the module docs")
    paths = [Path(p) for p in args.meshes] or [SHARED / "camelhead.off"]
    print("| mesh | triangles | uvflat slim s | its | sym. Dirichlet | libigl SLIM s to reach it | its | "
          "its energy | flips (uvflat, libigl) | libigl / uvflat |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for path in paths:
        if not path.is_file():
            print(f"note: {path} not found, skipped", file=sys.stderr)
            continue
        v, f = igl.read_triangle_mesh(str(path))
        v = np.ascontiguousarray(v, dtype=np.float64)
        f = np.ascontiguousarray(f, dtype=np.int64)
        tu, eu, fu, itu = run_uvflat(uvflat, v, f, args.repeat)
        runs = [run_libigl(igl, uvflat, v, f, eu, args.max_iterations) for _ in range(args.repeat)]
        ti, iti, ei, fi = min(runs)
        reached = "" if ei <= eu else " (not reached)"
        print(f"| {path.stem} | {len(f)} | {tu:.3f} | {itu} | {eu:.5f} | {ti:.3f}{reached} | {iti} | "
              f"{ei:.5f} | {fu}, {fi} | {ti / tu:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
