# SPDX-License-Identifier: GPL-3.0-or-later
"""The demo (``blender_scripts/demo.py``), run as a user would: a subprocess into a folder.

Checks the pictures (size, red seams on the 3D views) and that every figure in the pictures'
titles is what ``uvflat.metrics`` and an independent seam count say of the UV maps that the
demo saved in its .blend files.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

PIL_Image = pytest.importorskip("PIL.Image", reason="Pillow is not installed")
pytest.importorskip("bpy", reason="the bpy module (Blender as a Python module) is not installed")
uvflat = pytest.importorskip("uvflat", reason="the uvflat module is not installed")

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "blender_scripts" / "demo.py"
SHARED_BUNNY = REPO.parent / "shared" / "meshes" / "bunny.off"
SIZE = 160  # --size: the UV layout panel; the picture is 2 * SIZE wide
EXPECTED = (2 * SIZE, 2 * SIZE + 4 * (SIZE // 8))  # the documented picture size
RED = np.array([255, 0, 0])

# Reads both UV maps back from a saved .blend (as the demo left them in Blender).
READ_BLEND = """
import sys, bpy, numpy as np
bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
mesh = next(o.data for o in bpy.data.objects if o.type == "MESH")
out = {}
for name in ("uvflat", "smart_uv"):
    uv = np.empty(2 * len(mesh.loops), dtype=np.float32)
    mesh.uv_layers[name].uv.foreach_get("vector", uv)
    out[name] = uv.reshape(-1, 2)
out["active"] = np.array(mesh.uv_layers.active.name)
np.savez(sys.argv[2], **out)
"""


def _run_demo(out, *args):
    r = subprocess.run([sys.executable, str(SCRIPT), "--out", str(out), "--size", str(SIZE),
                        *args], capture_output=True, text=True, timeout=900,
                       stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    return r.stdout


def _blend_uvs(tmp_path, blend):
    dump = tmp_path / f"{blend.stem}_uvs.npz"
    r = subprocess.run([sys.executable, "-c", READ_BLEND, str(blend), str(dump)],
                       capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    return np.load(dump)


def _seams_and_islands(positions, corner_verts, face_sizes, uv):
    """``(seam length / √(3D area), island of every face)``: seams are the edges of two faces
    whose UVs differ at either end, islands the faces joined through the other edges.
    Written here plainly (a dict of edges, union-find), apart from the demo's numpy version."""
    sides = {}
    total_area = 0.0
    at = 0
    for face, n in enumerate(face_sizes.tolist()):
        corners = list(range(at, at + n))
        at += n
        pts = positions[corner_verts[corners]]
        total_area += 0.5 * np.linalg.norm(np.cross(pts, np.roll(pts, -1, axis=0)).sum(axis=0))
        for i, c in enumerate(corners):
            d = corners[(i + 1) % n]
            a, b = int(corner_verts[c]), int(corner_verts[d])
            ua, ub = tuple(uv[c]), tuple(uv[d])
            key, ends = ((a, b), (ua, ub)) if a < b else ((b, a), (ub, ua))
            sides.setdefault(key, []).append((face, np.array(ends)))
    parent = list(range(len(face_sizes)))

    def root(f):
        while parent[f] != f:
            parent[f] = parent[parent[f]]
            f = parent[f]
        return f

    length = 0.0
    for (a, b), s in sides.items():
        if len(s) != 2:
            continue
        (f, e), (g, h) = s
        if np.abs(e - h).max() > 1e-6:
            length += float(np.linalg.norm(positions[a] - positions[b]))
        else:
            parent[root(f)] = root(g)
    island = np.array([root(f) for f in range(len(face_sizes))])
    return length / math.sqrt(total_area), island


def _density_outside(positions, corner_verts, face_sizes, uv, island):
    """Per face: (UV area / 3D area) / (island UV area / island 3D area) outside [1/2, 2],
    as a share of the 3D area (for a uvflat module without ``density_outside``)."""
    starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
    a3, a2 = [], []
    for s, n in zip(starts.tolist(), face_sizes.tolist()):
        p, q = positions[corner_verts[s:s + n]], uv[s:s + n]
        a3.append(0.5 * np.linalg.norm(np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)))
        a2.append(0.5 * float(np.sum(q[:, 0] * np.roll(q[:, 1], -1)
                                     - np.roll(q[:, 0], -1) * q[:, 1])))
    a3, a2 = np.array(a3), np.array(a2)
    r = np.zeros(len(a3))
    for i in np.unique(island):
        f = island == i
        sign = -1.0 if a2[f].sum() < 0 else 1.0
        oriented = np.maximum(a2[f] * sign, 0.0)
        r[f] = (oriented / a3[f]) / (oriented.sum() / a3[f].sum())
    return float(a3[(r < 0.5) | (r > 2.0)].sum() / a3.sum())


def _check_mesh(tmp_path, out, name, stdout):
    png, record = out / f"demo_{name}.png", json.loads((out / f"demo_{name}.json").read_text())
    image = np.asarray(PIL_Image.open(png).convert("RGB")).astype(int)
    assert (image.shape[1], image.shape[0]) == EXPECTED, png
    assert tuple(record["picture"]) == EXPECTED
    rows = {r["key"]: r for r in record["rows"]}
    assert list(rows) == ["uvflat", "smart_uv"]

    def red_pixels(box):
        x0, y0, x1, y1 = box
        return int((image[y0:y1, x0:x1] == RED).all(axis=2).sum())

    # the seams are drawn in pure red on every 3D view of both rows, and nowhere else
    for key, row in rows.items():
        assert row["view_names"] == ["front", "side", "back", "top"]
        for view, box in zip(row["view_names"], row["views"]):
            assert red_pixels(box) > 0, f"{name} {key} {view}: no seam pixels"
        assert red_pixels(row["layout"]) == 0
    assert (image == RED).all(axis=2).sum() == sum(
        red_pixels(b) for r in rows.values() for b in r["views"])

    # the title figures are what uvflat.metrics says of the maps saved in the .blend
    arrays = np.load(out / f"demo_{name}.npz")
    positions, corner_verts, face_sizes = (arrays["positions"], arrays["corner_verts"],
                                           arrays["face_sizes"])
    blend = _blend_uvs(tmp_path, out / f"{name}.blend")
    assert str(blend["active"]) == "uvflat"
    for key, row in rows.items():
        uv = arrays[f"uv_{key}"]
        np.testing.assert_array_equal(uv, blend[key].astype(np.float64))
        m = uvflat.metrics(positions, corner_verts, face_sizes, uv)
        fig, line = row["figures"], row["figures_line"]
        assert line in stdout
        assert fig["islands"] == m.charts
        assert line.startswith(f"{m.charts} island")
        assert fig["flips"] == m.flips
        assert f" {m.flips} flip" in line
        seam, island = _seams_and_islands(positions, corner_verts, face_sizes, uv)
        assert len(np.unique(island)) == m.charts
        outside = getattr(m, "density_outside", None)
        if outside is None:  # a uvflat without it: the demo's own per-face share
            outside = _density_outside(positions, corner_verts, face_sizes, uv, island)
        assert fig["outside"] == pytest.approx(outside, abs=1e-9)
        assert f"{100.0 * outside + 0.0:.1f}% of the surface" in line
        assert fig["seam"] == pytest.approx(seam, rel=1e-6)
        assert f"seam length {seam:.2f} × √area" in line
        seconds = fig["seconds"]
        assert seconds > 0
        assert line.endswith(f" · {seconds:.2f} s" if seconds >= 0.1 else
                             f" · {1000 * seconds:.1f} ms")
    # what the picture shows: uvflat makes fewer islands and shorter seams than Smart UV
    assert rows["uvflat"]["figures"]["islands"] < rows["smart_uv"]["figures"]["islands"]
    assert rows["uvflat"]["figures"]["seam"] < rows["smart_uv"]["figures"]["seam"]
    assert rows["uvflat"]["figures"]["flips"] == 0
    return record, (positions, corner_verts, face_sizes)


def test_demo_pictures_and_figures(tmp_path):
    out = tmp_path / "out"
    stdout = _run_demo(out)
    closed = "bunny" if SHARED_BUNNY.is_file() else "suzanne_closed"
    _check_mesh(tmp_path, out, closed, stdout)
    _check_mesh(tmp_path, out, "suzanne", stdout)
    assert sorted(p.name for p in out.glob("*.png")) == sorted(
        [f"demo_{closed}.png", "demo_suzanne.png"])


def test_demo_builtin_closed_model(tmp_path):
    """Without the shared meshes the closed model is a closed Suzanne built in Blender."""
    out = tmp_path / "out"
    stdout = _run_demo(out, "--closed", "builtin")
    _, (positions, corner_verts, face_sizes) = _check_mesh(tmp_path, out, "suzanne_closed",
                                                           stdout)
    # closed: every edge has exactly two faces
    starts = np.concatenate([[0], np.cumsum(face_sizes)[:-1]])
    edges = {}
    for s, n in zip(starts.tolist(), face_sizes.tolist()):
        f = corner_verts[s:s + n].tolist()
        for a, b in zip(f, f[1:] + f[:1]):
            edges[min(a, b), max(a, b)] = edges.get((min(a, b), max(a, b)), 0) + 1
    assert set(edges.values()) == {2}
