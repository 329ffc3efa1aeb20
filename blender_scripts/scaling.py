# SPDX-License-Identifier: GPL-3.0-or-later
"""Time and peak memory of ``uvflat.unwrap`` on one disk chart from 50k to about 1M triangles.

    .venv/bin/python blender_scripts/scaling.py [--methods lscm,abf,slim] \
        [--sizes 50k,100k,200k,400k,800k,1M] [--repeat 1] [--slim-iterations 20] \
        [--threads N] [--out scaling.md]

Needs no Blender: the mesh is built in numpy and unwrapped through the Python API.

The mesh is the regular hexagonal triangulation of a disk: ring ``k`` (``k = 1..R``) holds
``6k`` vertices on the circle of radius ``k/R``, and the ``6(2k - 1)`` triangles between rings
``k - 1`` and ``k`` make ``6 R²`` triangles in all (``R`` is chosen so that ``6 R²`` is the
nearest to the size asked for).  It is lifted onto the paraboloid ``z = 0.3 r²``, so it is not
developable and every method has real work to do.  One chart, one boundary loop.

Every (method, size) runs in a fresh Python subprocess under ``/usr/bin/time -v``: the child
builds the mesh, calls ``uvflat.unwrap`` once and prints the wall seconds of that call; the
parent reads the child's maximum resident set size.  A ``baseline`` child per size only builds
the mesh (and imports uvflat), so the unwrap's own memory shows as the difference.  ``slim``
runs exactly ``--slim-iterations`` iterations (``max_iterations`` set to it and ``tolerance``
to 0; the iterations actually run are in the ``iters`` column).

Columns: triangles, wall seconds and CPU seconds (all threads) of the call (medians of
``--repeat`` runs), peak RSS in MB, KB per triangle of the peak RSS, KB per triangle above the
baseline child's peak, and the iterations run.  Below the table: the exponent ``b`` of
``seconds ≈ a · n^b`` fitted by least squares on log–log per method (and the same fit of the
CPU seconds, steadier than wall time on a busy machine), and pass/fail against the targets
(wall time exponent at most 1.2 for lscm and abf; peak RSS under 1.5 KB per triangle for lscm
and abf and 3 KB per triangle for slim, at the largest size run, where the interpreter's fixed
memory weighs least).

``--child METHOD TRIANGLES`` is the child's entry point (``METHOD`` ``baseline`` builds only).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

TIME = "/usr/bin/time"
# Targets: largest time exponent, and peak KB per triangle.
EXPONENT_TARGET = {"lscm": 1.2, "abf": 1.2}
KB_PER_TRIANGLE_TARGET = {"lscm": 1.5, "abf": 1.5, "slim": 3.0}
DEFAULT_SIZES = "50k,100k,200k,400k,800k,1M"


def disk_mesh(triangles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hexagonal disk of ``6 R²`` triangles nearest to ``triangles`` (``R ≥ 1``), on
    ``z = 0.3 r²``: ``(positions (V, 3) float64, corner_verts (3T,) int32, face_sizes (T,)
    int32)``, faces counter-clockwise seen from +z.  Vertex 0 is the centre; ring ``k``
    starts at vertex ``1 + 3k(k - 1)``."""
    rings = max(1, round(math.sqrt(triangles / 6)))
    radius = [np.zeros(1)]
    angle = [np.zeros(1)]
    for k in range(1, rings + 1):
        j = np.arange(6 * k)
        radius.append(np.full(6 * k, k / rings))
        angle.append(2 * np.pi * j / (6 * k))
    r = np.concatenate(radius)
    a = np.concatenate(angle)
    positions = np.column_stack([r * np.cos(a), r * np.sin(a), 0.3 * r * r])

    tris = []
    for k in range(1, rings + 1):
        outer0 = 1 + 3 * k * (k - 1)
        s = np.repeat(np.arange(6), k)  # sector of every outer vertex
        i = np.tile(np.arange(k), 6)  # its place in the sector
        o = outer0 + s * k + i
        o_next = outer0 + (s * k + i + 1) % (6 * k)
        if k == 1:
            inner = np.zeros(6, dtype=np.int64)
        else:
            inner0 = 1 + 3 * (k - 1) * (k - 2)
            inner = inner0 + (s * (k - 1) + i) % (6 * (k - 1))
        # k triangles per sector with an edge on the outer ring ...
        tris.append(np.column_stack([o, o_next, inner]))
        if k > 1:
            # ... and k - 1 with an edge on the inner ring.
            keep = i < k - 1
            si, ii = s[keep], i[keep]
            inner0 = 1 + 3 * (k - 1) * (k - 2)
            a_in = inner0 + (si * (k - 1) + ii) % (6 * (k - 1))
            b_in = inner0 + (si * (k - 1) + ii + 1) % (6 * (k - 1))
            o_mid = outer0 + (si * k + ii + 1) % (6 * k)
            tris.append(np.column_stack([a_in, o_mid, b_in]))
    faces = np.concatenate(tris).astype(np.int32)
    return positions, faces.reshape(-1), np.full(len(faces), 3, dtype=np.int32)


def parse_size(text: str) -> int:
    """``"50k"`` → 50000, ``"1M"`` → 1000000, ``"2000"`` → 2000."""
    t = text.strip().lower()
    scale = {"k": 1_000, "m": 1_000_000}.get(t[-1:], 1)
    if scale != 1:
        t = t[:-1]
    value = float(t) * scale
    if not math.isfinite(value) or value < 6:
        raise ValueError(f"size {text!r}: expected a number of triangles of at least 6")
    return int(round(value))


def fit_exponent(n, seconds) -> float:
    """Exponent ``b`` of ``seconds ≈ a · n^b``, least squares on ``log seconds`` against
    ``log n``; NaN with fewer than two distinct sizes or a non-positive value."""
    x = np.log(np.asarray(n, dtype=float))
    y = np.asarray(seconds, dtype=float)
    if len(x) < 2 or np.ptp(x) == 0 or not np.all(y > 0):
        return float("nan")
    y = np.log(y)
    xm = x - x.mean()
    return float(np.dot(xm, y - y.mean()) / np.dot(xm, xm))


def child(method: str, triangles: int, slim_iterations: int) -> None:
    """Build the mesh, unwrap it once (unless ``method`` is ``baseline``), print one JSON line."""
    import uvflat

    positions, corner_verts, face_sizes = disk_mesh(triangles)
    out = {"method": method, "triangles": len(face_sizes), "vertices": len(positions)}
    if method != "baseline":
        options = {}
        if method == "slim":
            options = {"max_iterations": slim_iterations, "tolerance": 0.0}
        if method == "abf" and os.environ.get("SCALING_ABF_TOLERANCE"):
            options = {"tolerance": float(os.environ["SCALING_ABF_TOLERANCE"])}
        start, cpu = time.perf_counter(), time.process_time()
        result = uvflat.unwrap(positions, corner_verts, face_sizes, method=method, **options)
        out["seconds"] = time.perf_counter() - start
        out["cpu_seconds"] = time.process_time() - cpu
        out["core_seconds"] = result.seconds
        out["charts"] = len(result.charts)
        out["status"] = [c.status for c in result.charts]
        out["iterations"] = sum(c.iterations for c in result.charts)
        out["flips"] = sum(c.flips for c in result.charts)
        out["finite"] = bool(np.isfinite(result.uv).all())
    print("SCALING " + json.dumps(out), flush=True)


def run_child(method: str, triangles: int, slim_iterations: int) -> dict:
    """One child under ``/usr/bin/time -v``: its JSON line plus ``max_rss_kb``."""
    cmd = [TIME, "-v", sys.executable, str(Path(__file__).resolve()), "--child", method,
           str(triangles), "--slim-iterations", str(slim_iterations)]
    p = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL)
    line = next((s for s in p.stdout.splitlines() if s.startswith("SCALING ")), None)
    if p.returncode != 0 or line is None:
        raise RuntimeError(f"{method} at {triangles} triangles failed (exit {p.returncode}):\n"
                           f"{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
    out = json.loads(line[len("SCALING "):])
    m = re.search(r"Maximum resident set size \(kbytes\):\s*(\d+)", p.stderr)
    if m is None:
        raise RuntimeError(f"no maximum resident set size in the output of {TIME} -v:\n{p.stderr[-2000:]}")
    out["max_rss_kb"] = int(m.group(1))
    return out


def measure(methods, sizes, repeat: int, slim_iterations: int, log=print) -> list[dict]:
    """Rows of the table: one per (method, size), baseline rows first per size."""
    rows = []
    for n in sizes:
        base = [run_child("baseline", n, slim_iterations) for _ in range(repeat)]
        t = base[0]["triangles"]
        base_kb = statistics.median(b["max_rss_kb"] for b in base)
        rows.append({"method": "baseline", "triangles": t, "seconds": None, "cpu_seconds": None, "max_rss_kb": base_kb,
                     "kb_per_triangle": base_kb / t, "kb_over_baseline": 0.0, "iterations": None})
        log(f"baseline {t}: {base_kb / 1024:.1f} MB")
        for method in methods:
            runs = [run_child(method, n, slim_iterations) for _ in range(repeat)]
            bad = [r for r in runs if not r["finite"] or any(s == "failed" for s in r["status"])]
            if bad:
                raise RuntimeError(f"{method} at {t} triangles: {bad[0]}")
            kb = statistics.median(r["max_rss_kb"] for r in runs)
            row = {"method": method, "triangles": t,
                   "seconds": statistics.median(r["seconds"] for r in runs),
                   "cpu_seconds": statistics.median(r["cpu_seconds"] for r in runs),
                   "max_rss_kb": kb, "kb_per_triangle": kb / t,
                   "kb_over_baseline": (kb - base_kb) / t,
                   "iterations": runs[0]["iterations"], "flips": runs[0]["flips"],
                   "status": ",".join(sorted(set(runs[0]["status"])))}
            rows.append(row)
            log(f"{method} {t}: {row['seconds']:.3f} s, {kb / 1024:.1f} MB, "
                f"{row['kb_per_triangle']:.3f} KB/tri")
    return rows


def summarize(rows: list[dict]) -> tuple[dict, list[str]]:
    """Per method: fitted exponent and pass/fail lines against the targets."""
    methods = list(dict.fromkeys(r["method"] for r in rows if r["method"] != "baseline"))
    result, lines = {}, []
    for m in methods:
        mine = [r for r in rows if r["method"] == m]
        b = fit_exponent([r["triangles"] for r in mine], [r["seconds"] for r in mine])
        b_cpu = fit_exponent([r["triangles"] for r in mine], [r["cpu_seconds"] for r in mine])
        largest = max(mine, key=lambda r: r["triangles"])
        result[m] = {"exponent": b, "cpu_exponent": b_cpu, "largest": largest["triangles"],
                     "kb_per_triangle": largest["kb_per_triangle"],
                     "kb_over_baseline": largest["kb_over_baseline"]}
        parts = [f"- **{m}**: time exponent {b:.3f}"]
        if m in EXPONENT_TARGET and math.isfinite(b):
            ok = b <= EXPONENT_TARGET[m]
            result[m]["exponent_ok"] = ok
            parts.append(f"(target ≤ {EXPONENT_TARGET[m]}: {'pass' if ok else 'FAIL'})")
        elif m in EXPONENT_TARGET:
            parts.append("(needs two sizes or more)")
        parts.append(f"(CPU time exponent {b_cpu:.3f})")
        parts.append(f"— at {largest['triangles']} triangles {largest['kb_per_triangle']:.3f} KB/triangle "
                     f"peak ({largest['kb_over_baseline']:.3f} above the baseline)")
        if m in KB_PER_TRIANGLE_TARGET:
            ok = largest["kb_per_triangle"] < KB_PER_TRIANGLE_TARGET[m]
            result[m]["memory_ok"] = ok
            parts.append(f"(target < {KB_PER_TRIANGLE_TARGET[m]}: {'pass' if ok else 'FAIL'})")
        lines.append(" ".join(parts))
    return result, lines


def table(rows: list[dict]) -> str:
    """The markdown table of ``rows``."""
    out = ["| method | triangles | seconds | CPU s | peak MB | KB/triangle | KB/triangle over baseline | iters |",
           "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        sec = "" if r["seconds"] is None else f"{r['seconds']:.3f}"
        cpu = "" if r["cpu_seconds"] is None else f"{r['cpu_seconds']:.3f}"
        it = "" if r["iterations"] is None else str(r["iterations"])
        out.append(f"| {r['method']} | {r['triangles']} | {sec} | {cpu} | {r['max_rss_kb'] / 1024:.1f} | "
                   f"{r['kb_per_triangle']:.3f} | {r['kb_over_baseline']:.3f} | {it} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--methods", default="lscm,abf,slim")
    ap.add_argument("--sizes", default=DEFAULT_SIZES, help="triangle counts, e.g. 50k,100k,1M")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case (median)")
    ap.add_argument("--slim-iterations", type=int, default=20)
    ap.add_argument("--abf-tolerance", type=float, default=None,
                    help="abf's Newton tolerance (default: the method's); 1e-9 makes the smooth disk take a Newton step")
    ap.add_argument("--threads", type=int, default=None, help="RAYON_NUM_THREADS of the children")
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    ap.add_argument("--json", type=Path, default=None, help="also write the rows as JSON here")
    ap.add_argument("--child", nargs=2, metavar=("METHOD", "TRIANGLES"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.abf_tolerance is not None:
        os.environ["SCALING_ABF_TOLERANCE"] = repr(args.abf_tolerance)
    if args.slim_iterations < 1:
        ap.error("--slim-iterations must be at least 1")
    if args.child:
        child(args.child[0], int(args.child[1]), args.slim_iterations)
        return 0
    if args.repeat < 1:
        ap.error("--repeat must be at least 1")
    if not os.access(TIME, os.X_OK):
        ap.error(f"{TIME} is needed to measure the peak memory of every run")
    try:
        sizes = sorted({parse_size(s) for s in args.sizes.split(",") if s.strip()})
    except ValueError as e:
        ap.error(str(e))
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    if args.threads is not None:
        os.environ["RAYON_NUM_THREADS"] = str(args.threads)

    rows = measure(methods, sizes, args.repeat, args.slim_iterations, log=lambda s: print(s, file=sys.stderr))
    summary, lines = summarize(rows)
    cmd = " ".join(["scaling.py", *(argv if argv is not None else sys.argv[1:])])
    report = "\n".join([f"`{cmd}` (threads: {os.environ.get('RAYON_NUM_THREADS', 'all')}, "
                        f"cores: {os.cpu_count()})", "", table(rows), "", *lines, ""])
    print(report)
    if args.out:
        args.out.write_text(report)
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "summary": summary}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
