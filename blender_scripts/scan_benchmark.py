# SPDX-License-Identifier: GPL-3.0-or-later
"""Automatic seams at scan scale: closed meshes of 100k–600k triangles against an
xatlas-style atlas.

    .venv/bin/python -m pip install uvunwrap      # the xatlas-style atlas (a Rust port of xatlas)
    .venv/bin/python blender_scripts/scan_benchmark.py [--meshes bunny:2,fertility:3] \
        [--methods abf,slim] [--baselines uvunwrap] [--repeat 1] [--out scan.md]

Needs no Blender.  Baselines: ``uvunwrap`` (PyPI: segmentation, flattening and packing of
xatlas, with its defaults) and ``xatlas`` (PyPI ``xatlas``, the C++ library's bindings; slow
at this scale, so not run by default).  A scan is a shared closed mesh subdivided ``L`` times (each triangle into
four at its edge midpoints, so the surface keeps its shape): ``bunny:2`` has 111,456
triangles, ``fertility:3`` 576,000; ``bunny:2:100:3`` loses 100 holes of 30 faces as scans
lose surface (``robustness.holes``, seed 3).  Every row runs in a fresh Python subprocess under
``/usr/bin/time -v``: the child builds the mesh, runs the unwrap (``uvflat.unwrap`` with
automatic seams, or ``xatlas.parametrize``) and prints its wall seconds, islands, whether every
island keeps the atlas rule and the pipeline phases; the parent reads the child's peak
resident memory.  A ``baseline`` child per mesh only builds the mesh, so the unwrap's own
memory shows as the difference (KB per triangle).

Columns: seconds (median of ``--repeat``), the ratio to the first baseline's seconds (the target of the
scan-scale work is at most 1.5), peak memory of the unwrap in KB per triangle (target at most
3), islands, and *rule*: every island solved or mapped by a fallback within the rule (a disk,
no flip, no crossing outline, at most 5% of its area outside [1/2, 2] of its own density).  The phase line gives the seconds of cut
planning, first solves and repair solves, with the rounds, pieces and splits.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SHARED = REPO.parent / "shared" / "meshes"

CHILD = r"""
import json, sys, time
import numpy as np
sys.path.insert(0, {here!r})
import common
name, levels, job, holes = {name!r}, {levels}, {job!r}, {holes!r}
P, cv, fs = common.read_off({path!r})
P = np.asarray(P, float); tri = np.asarray(cv, np.int64).reshape(-1, 3)
for _ in range(levels):
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    mid = len(P) + inv.reshape(3, -1).T
    P = np.vstack([P, 0.5 * (P[uniq[:, 0]] + P[uniq[:, 1]])])
    a, b, c = tri.T
    ab, bc, ca = mid.T
    tri = np.concatenate([np.stack(x, 1) for x in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
if holes:
    import robustness
    count, seed = holes
    P, cv, fs = robustness.holes((P, tri.reshape(-1), np.full(len(tri), 3)), count, HOLE_FACES, seed)
    P = np.asarray(P, float); tri = np.asarray(cv, np.int64).reshape(-1, 3)
out = dict(triangles=len(tri))
if job == "uvunwrap":
    import uvunwrap
    t = time.perf_counter()
    atlas = uvunwrap.generate([uvunwrap.Mesh(P, tri)])
    out["seconds"] = time.perf_counter() - t
    out["islands"] = int(atlas.chart_count)
elif job == "xatlas":
    import xatlas
    t = time.perf_counter()
    vmap, idx, uvs = xatlas.parametrize(P.astype(np.float32), tri.astype(np.uint32))
    out["seconds"] = time.perf_counter() - t
    i = idx.astype(np.int64)
    lab = common.components(len(vmap), np.concatenate([i[:, 0], i[:, 1]]), np.concatenate([i[:, 1], i[:, 2]]))
    out["islands"] = int(len(np.unique(lab[i[:, 0]])))
elif job != "baseline":
    import uvflat
    t = time.perf_counter()
    r = uvflat.unwrap(P, tri.reshape(-1), np.full(len(tri), 3), method=job)
    out["seconds"] = time.perf_counter() - t
    out["islands"] = len(r.charts)
    out["rule"] = all(c.status in ("solved", "fallback") for c in r.charts)
    out["phases"] = dict(r.phases)
print("RESULT " + json.dumps(out))
"""


# Faces of each hole a ``NAME:LEVELS:HOLES[:SEED]`` scan loses.
HOLE_FACES = 30


def parse_spec(spec):
    """``(name, levels, holes, label)`` of ``NAME:LEVELS[:HOLES[:SEED]]``; ``holes`` is
    ``(count, seed)`` or ``None``."""
    parts = spec.split(":")
    if not 2 <= len(parts) <= 4:
        raise SystemExit(f"scan_benchmark: {spec!r} is not NAME:LEVELS[:HOLES[:SEED]]")
    name, levels = parts[0], int(parts[1])
    holes = (int(parts[2]), int(parts[3]) if len(parts) == 4 else 1) if len(parts) >= 3 else None
    label = f"{name}×{levels}" + (f", {holes[0]} holes (seed {holes[1]})" if holes else "")
    return name, levels, holes, label


def run_child(name, levels, job, holes=None):
    code = CHILD.replace("HOLE_FACES", str(HOLE_FACES)).format(
        here=str(HERE), name=name, levels=levels, job=job, holes=holes, path=str(SHARED / f"{name}.off"))
    proc = subprocess.run(["/usr/bin/time", "-v", sys.executable, "-c", code],
                          capture_output=True, text=True)
    result = None
    for line in proc.stdout.splitlines():
        if line.startswith("RESULT "):
            result = json.loads(line[7:])
    if result is None:
        raise RuntimeError(f"{name}:{levels} {job} failed:\n{proc.stderr[-2000:]}")
    for line in proc.stderr.splitlines():
        if "Maximum resident set size" in line:
            result["peak_kb"] = int(line.split()[-1])
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--meshes", default="bunny:2,fertility:3",
                        help="comma-separated NAME:LEVELS[:HOLES[:SEED]] (shared closed .off mesh, "
                             "subdivisions, holes of 30 faces cut in as scans lose surface, their seed)")
    parser.add_argument("--methods", default="abf,slim")
    parser.add_argument("--baselines", default="uvunwrap",
                        help="comma-separated: uvunwrap, xatlas (the first is the ratio's reference)")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if not SHARED.is_dir():
        print(f"scan_benchmark: the shared meshes folder {SHARED} is absent", file=sys.stderr)
        return 2
    baselines = [b for b in args.baselines.split(",") if b]
    lines = [f"| mesh | triangles | unwrap | s | × {baselines[0]} | KB / triangle | islands | rule |",
             "|---|---:|---|---:|---:|---:|---:|---|"]
    phases = []
    for spec in args.meshes.split(","):
        name, levels, holes, label = parse_spec(spec)
        base = run_child(name, levels, "baseline", holes)
        rows = {}
        for job in baselines + args.methods.split(","):
            runs = [run_child(name, levels, job, holes) for _ in range(args.repeat)]
            r = runs[0]
            r["seconds"] = statistics.median(x["seconds"] for x in runs)
            r["peak_kb"] = max(x.get("peak_kb", 0) for x in runs)
            rows[job] = r
        tris = base["triangles"]
        for job, r in rows.items():
            ratio = r["seconds"] / rows[baselines[0]]["seconds"]
            kb = (r.get("peak_kb", 0) - base.get("peak_kb", 0)) / tris
            rule = "—" if job in baselines else ("yes" if r["rule"] else "no")
            islands = "—" if r["islands"] is None else str(r["islands"])
            lines.append(f"| {label} | {tris:,} | {job} | {r['seconds']:.2f} | {ratio:.2f} | "
                         f"{kb:.2f} | {islands} | {rule} |")
            if "phases" in r:
                p = r["phases"]
                phases.append(f"{label} {job}: plan cuts {p['plan_cuts']:.2f} s "
                              f"({p.get('predicted_rounds', 0)} predicted rounds; cutting state "
                              f"{p.get('cut_state', 0):.2f}, cone placement {p.get('cone_placement', 0):.2f}, "
                              f"split plans {p.get('split_plans', 0):.2f}, cut graphs "
                              f"{p.get('cut_graphs', 0):.2f}), first solves "
                              f"{p['solve']:.2f} s, repair solves {p['repair_solve']:.2f} s "
                              f"({p['repair_rounds']} rounds, {p['repair_pieces']} pieces, "
                              f"{p['splits']} splits ({p.get('predicted_splits', 0)} before any solve, "
                              f"{p.get('far_splits', 0)} after one), "
                              f"{p.get('parts', 0)} rounds in parts, "
                              f"{p.get('peels', 0)} peels, {p.get('last_resort', 0)} last-resort solves, "
                              f"{p.get('glued', 0)} small islands glued)")
        print("\n".join(lines[-len(rows):]), flush=True)
    text = "\n".join(lines) + "\n\n" + "\n".join(phases) + "\n"
    print()
    print(text)
    if args.out:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
