# SPDX-License-Identifier: GPL-3.0-or-later
"""Meshes nobody tuned for: variants of the shared meshes, every method, the atlas rule checked
on the UVs.

    .venv/bin/python blender_scripts/robustness.py [--methods abf,slim,lscm] \
        [--meshes bunny.off,cow.off] [--variants as_is,holes,quads,ngons,collapsed,parts] [--out rob.md]

Needs no Blender. Each shared mesh is unwrapped as it is and as variants that stand for what
users bring (every variant deterministic, from a fixed seed):

- ``holes``: six patches of 60 faces removed (a breadth-first walk over faces sharing an edge
  from a random face), the way scans lose surface;
- ``big_holes``: three patches of 600 faces (patches that touch leave bow-tie vertices);
- ``quads``: triangles merged in pairs across a random edge order (a triangles-to-quads
  conversion: non-planar quads, vertices shared by only two faces);
- ``ngons``: 30% of the vertices of valence 5 to 8, in random order, dissolved (their fan of
  triangles becomes one n-gon);
- ``collapsed``: in 1% of the triangles, in random order, one corner moved onto another, as a
  careless decimation or a scan's reconstruction leaves them: triangles without area, and the
  moved vertex's other triangles folded over its new neighbours;
- ``parts``: all the chosen meshes side by side in one mesh.

Every run is ``uvflat.unwrap`` with automatic seams and the defaults; the rule is measured on
the returned UVs by ``uvflat.metrics`` (flips, overlapping islands) and the reports (share of
each island outside [1/2, 2] of its density). Columns per variant and method: runs, runs whose
every island keeps the rule, islands, islands mapped by another method than the one asked for
(a fallback: the method's flip-free kin or ``scaffold`` as a last resort, or SLIM where ABF left
quads non-convex), of which by ``scaffold``, islands left invalid, failed charts, median seconds. Rows that break the rule are
listed after the table with their reasons.
"""

import argparse
import random
import statistics
import sys
import time
from collections import deque
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(REPO / "tests"))

from meshio_util import MESH_DIR, read_obj, read_off  # noqa: E402

METHODS = ("abf", "slim", "lscm", "mips", "scaffold", "arap", "spectral", "bff")
MESHES = ("bunny.off", "cow.off", "decimated-max.obj", "fertility.off", "3holes.off",
          "camelhead.off", "lion.off", "beetle.off", "halftunnel.off", "alligator.obj")
VARIANTS = ("as_is", "holes", "big_holes", "quads", "ngons", "collapsed", "parts")


def faces_of(corner_verts, face_sizes):
    starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
    return [list(map(int, corner_verts[a:a + n])) for a, n in zip(starts, face_sizes)]


def soup(positions, faces):
    """Arrays of ``faces`` over ``positions``, unused vertices dropped."""
    corners = np.array([v for f in faces for v in f], dtype=np.int64)
    used = np.unique(corners)
    remap = np.full(len(positions), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return (np.asarray(positions, dtype=np.float64)[used], remap[corners],
            np.array([len(f) for f in faces], dtype=np.int64))


def edge_faces(faces):
    out = {}
    for i, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            out.setdefault((min(a, b), max(a, b)), []).append(i)
    return out


def holes(mesh, count, size, seed):
    positions, faces = mesh[0], faces_of(mesh[1], mesh[2])
    by_edge, rng, dead = edge_faces(faces), random.Random(seed), set()
    for _ in range(count):
        start = rng.randrange(len(faces))
        queue, taken = deque([start]), {start}
        while queue and len(taken) < size:
            f = faces[queue.popleft()]
            for a, b in zip(f, f[1:] + f[:1]):
                for g in by_edge[(min(a, b), max(a, b))]:
                    if g not in taken and len(taken) < size:
                        taken.add(g)
                        queue.append(g)
        dead |= taken
    return soup(positions, [f for i, f in enumerate(faces) if i not in dead])


def quads(mesh, seed):
    positions, faces = mesh[0], faces_of(mesh[1], mesh[2])
    by_edge, rng = edge_faces(faces), random.Random(seed)
    keys = sorted(by_edge)
    rng.shuffle(keys)
    used, out = set(), []
    for a, b in keys:
        pair = by_edge[(a, b)]
        if len(pair) != 2 or pair[0] in used or pair[1] in used:
            continue
        f, g = faces[pair[0]], faces[pair[1]]
        if len(f) != 3 or len(g) != 3:
            continue
        i = next(i for i in range(3) if {f[i], f[(i + 1) % 3]} == {a, b})
        x, y, w = f[i], f[(i + 1) % 3], f[(i + 2) % 3]
        o = next(v for v in g if v not in (a, b))
        out.append([w, x, o, y])
        used.update(pair)
    out += [f for i, f in enumerate(faces) if i not in used]
    return soup(positions, out)


def ngons(mesh, share, seed):
    positions, faces = mesh[0], faces_of(mesh[1], mesh[2])
    around = {}
    for i, f in enumerate(faces):
        for v in f:
            around.setdefault(v, []).append(i)
    verts = sorted(around)
    random.Random(seed).shuffle(verts)
    dead, out = set(), []
    for v in verts[: int(len(verts) * share)]:
        fan = around[v]
        if not 5 <= len(fan) <= 8 or any(f in dead or len(faces[f]) != 3 for f in fan):
            continue
        after = {}
        for f in fan:
            t = faces[f]
            i = t.index(v)
            after[t[(i + 1) % 3]] = t[(i + 2) % 3]
        ring = [next(iter(after))]
        while len(ring) <= len(fan) and after.get(ring[-1]) not in (None, ring[0]):
            ring.append(after[ring[-1]])
        if len(ring) != len(fan) or after.get(ring[-1]) != ring[0]:
            continue  # a vertex on the boundary, or a fan that is not one disk
        dead.update(fan)
        out.append(ring)
    out += [f for i, f in enumerate(faces) if i not in dead]
    return soup(positions, out)


def collapsed(mesh, share, seed):
    positions = np.array(mesh[0], dtype=np.float64)
    faces = faces_of(mesh[1], mesh[2])
    tris = [i for i, f in enumerate(faces) if len(f) == 3]
    rng = random.Random(seed)
    rng.shuffle(tris)
    for i in tris[: max(1, int(len(tris) * share))]:
        a, b = rng.sample(faces[i], 2)
        positions[b] = positions[a]
    return positions, np.asarray(mesh[1]), np.asarray(mesh[2])


def side_by_side(meshes):
    positions, corners, sizes, offset, x = [], [], [], 0, 0.0
    for p, c, s in meshes:
        p = np.array(p, dtype=np.float64)
        extent = p.max(axis=0) - p.min(axis=0)
        p /= max(extent.max(), 1e-300)  # each part about one unit across
        p[:, 0] += x - p[:, 0].min()
        x += 1.2
        positions.append(p)
        corners.append(np.asarray(c) + offset)
        sizes.append(np.asarray(s))
        offset += len(p)
    return np.vstack(positions), np.concatenate(corners), np.concatenate(sizes)


def variants(names, chosen):
    base = {n: (read_obj if n.endswith(".obj") else read_off)(MESH_DIR / n) for n in names}
    for n, m in base.items():
        if "as_is" in chosen:
            yield n, m
        if "holes" in chosen:
            yield f"{n} holes", holes(m, 6, 60, 1)
        if "big_holes" in chosen:
            yield f"{n} big holes", holes(m, 3, 600, 2)
        if "quads" in chosen and all(np.asarray(m[2]) == 3):
            yield f"{n} quads", quads(m, 3)
        if "ngons" in chosen and all(np.asarray(m[2]) == 3):
            yield f"{n} n-gons", ngons(m, 0.3, 7)
        if "collapsed" in chosen:
            yield f"{n} collapsed", collapsed(m, 0.01, 5)
    if "parts" in chosen and len(base) > 1:
        yield "all parts", side_by_side(list(base.values()))


def run(name, method, mesh):
    import uvflat
    positions, corner_verts, face_sizes = mesh
    t = time.perf_counter()
    try:
        r = uvflat.unwrap(positions, corner_verts, face_sizes, method=method)
    except Exception as e:  # an error is a finding, not a crash of the sweep
        return dict(name=name, method=method, seconds=time.perf_counter() - t, error=f"{type(e).__name__}: {e}")
    seconds = time.perf_counter() - t
    m = uvflat.metrics(positions, corner_verts, face_sizes, r.uv)
    charts = r.charts
    broken = [c for c in charts if c.status in ("invalid", "failed")]
    worst = max((c.density_outside for c in charts if c.status != "failed"), default=0.0)
    keeps = not broken and m.flips == 0 and m.overlapping_charts == 0 and worst <= 0.05 + 1e-12
    return dict(name=name, method=method, seconds=seconds, islands=len(charts), keeps=keeps,
                other=sum(c.method != method for c in charts),
                fallback=sum(c.method == "scaffold" and method != "scaffold" for c in charts),
                invalid=sum(c.status == "invalid" for c in charts),
                failed=sum(c.status == "failed" for c in charts),
                reasons=[f"{c.reason_code}: {c.reason}" for c in broken][:3])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--meshes", default=",".join(MESHES))
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--out", help="also write the table to this file")
    a = ap.parse_args(argv)
    if not MESH_DIR.is_dir():
        sys.exit(f"the shared meshes are not in {MESH_DIR}")
    methods = a.methods.split(",")
    chosen = set(a.variants.split(","))
    rows = []
    for name, mesh in variants(a.meshes.split(","), chosen):
        for method in methods:
            r = run(name, method, mesh)
            r["variant"] = next((v for v in ("big holes", "holes", "quads", "n-gons", "collapsed")
                                 if name.endswith(v)),
                                "parts" if name == "all parts" else "as is")
            rows.append(r)
            state = "error" if "error" in r else ("keeps the rule" if r["keeps"] else "BREAKS the rule")
            print(f"{name:28s} {method:9s} {r['seconds']:7.2f} s  {state}", flush=True)
    lines = ["| variant | method | runs | keep the rule | islands | by another method | by scaffold | invalid | failed | median s |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for variant in ("as is", "holes", "big holes", "quads", "n-gons", "collapsed", "parts"):
        for method in methods:
            rs = [r for r in rows if r["variant"] == variant and r["method"] == method]
            if not rs:
                continue
            ok = [r for r in rs if "error" not in r]
            lines.append(
                f"| {variant} | {method} | {len(rs)} | {sum(r['keeps'] for r in ok)} | "
                f"{sum(r['islands'] for r in ok)} | {sum(r['other'] for r in ok)} | {sum(r['fallback'] for r in ok)} | "
                f"{sum(r['invalid'] for r in ok)} | {sum(r['failed'] for r in ok)} | "
                f"{statistics.median(r['seconds'] for r in rs):.2f} |")
    bad = [r for r in rows if "error" in r or not r["keeps"]]
    lines.append("")
    lines.append(f"{len(rows) - len(bad)} of {len(rows)} runs keep the rule on every island.")
    for r in bad:
        lines.append(f"- {r['name']} · {r['method']}: " + (r["error"] if "error" in r else "; ".join(r["reasons"]) or "measured flips or overlap"))
    text = "\n".join(lines)
    print()
    print(text)
    if a.out:
        Path(a.out).write_text(text + "\n")


if __name__ == "__main__":
    main()
