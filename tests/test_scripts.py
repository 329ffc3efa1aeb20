"""The headless batch script, run as a user would: a subprocess on real files."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "blender_scripts" / "unwrap.py"


def _grid_obj(path: Path, n: int = 6) -> None:
    """A wavy n×n quad grid (a disk) as OBJ."""
    lines = []
    for j in range(n + 1):
        for i in range(n + 1):
            lines.append(f"v {i} {j} {0.3 * np.sin(i) * np.cos(j):.6f}")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            lines.append(f"f {a} {a + 1} {a + n + 2} {a + n + 1}")
    path.write_text("\n".join(lines) + "\n")


def _run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                          text=True, timeout=600, stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("method,extra", [("lscm", []), ("slim", ["--max-iterations", "5"]),
                                          ("mean_value", ["--boundary", "virtual"])])
def test_batch_unwrap_writes_uvs_and_a_layout(tmp_path, method, extra):
    src, out = tmp_path / "grid.obj", tmp_path / "out.obj"
    _grid_obj(src)
    r = _run(src, out, "--method", method, *extra)
    assert r.returncode == 0, r.stdout + r.stderr
    text = out.read_text()
    vts = [line.split()[1:3] for line in text.splitlines() if line.startswith("vt ")]
    faces = [line for line in text.splitlines() if line.startswith("f ")]
    assert len(faces) == 36
    uv = np.array(vts, dtype=float)
    # A disk unwrapped and packed: UVs inside the unit square and not collapsed.
    assert uv.min() >= -1e-6 and uv.max() <= 1 + 1e-6
    assert np.ptp(uv, axis=0).min() > 0.1
    # Every face references UVs.
    assert all("/" in f for f in faces)
    assert (tmp_path / "out_uv.png").stat().st_size > 0


def test_batch_unwrap_refuses_an_option_the_method_does_not_take(tmp_path):
    src = tmp_path / "grid.obj"
    _grid_obj(src)
    r = _run(src, tmp_path / "out.obj", "--method", "abf", "--boundary", "circle")
    assert r.returncode != 0
    assert "not an option of abf" in (r.stdout + r.stderr)
    assert not (tmp_path / "out.obj").exists()


def _closed_box_obj(path: Path, n: int = 4) -> None:
    """A closed box of 6·n² quads (no seams: needs automatic seams to unwrap)."""
    verts, index, faces = [], {}, []

    def vid(p):
        if p not in index:
            index[p] = len(verts) + 1
            verts.append(p)
        return index[p]

    for axis in range(3):
        for side in (0, n):
            for i in range(n):
                for j in range(n):
                    def mk(a, b):
                        p = [0, 0, 0]
                        p[axis], p[(axis + 1) % 3], p[(axis + 2) % 3] = side, a, b
                        return tuple(p)
                    q = [mk(i, j), mk(i + 1, j), mk(i + 1, j + 1), mk(i, j + 1)]
                    if side == 0:
                        q.reverse()
                    faces.append([vid(p) for p in q])
    lines = [f"v {x} {y} {z}" for x, y, z in verts] + ["f " + " ".join(map(str, f)) for f in faces]
    path.write_text("\n".join(lines) + "\n")


def test_batch_unwraps_a_closed_scan_with_auto_seams(tmp_path):
    src, out = tmp_path / "box.obj", tmp_path / "out.obj"
    _closed_box_obj(src)
    r = _run(src, out, "--method", "abf")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "auto seams" in r.stdout
    text = out.read_text()
    faces = [line for line in text.splitlines() if line.startswith("f ")]
    assert len(faces) == 96 and all("/" in f for f in faces)
    uv = np.array([line.split()[1:3] for line in text.splitlines() if line.startswith("vt ")], float)
    assert np.all(np.isfinite(uv)) and np.ptp(uv, axis=0).min() > 0.1
    # Without automatic seams the closed box is refused: exit status 2 (charts not solved).
    r = _run(src, tmp_path / "off.obj", "--method", "abf", "--no-auto-seams")
    assert r.returncode == 2, r.stdout + r.stderr
    assert "not solved" in r.stdout


@pytest.mark.parametrize("flag", [["--max-stretch", "1"], ["--max-stretch", "nan"],
                                  ["--max-cones", "-1"], ["--sharp-angle", "200"]])
def test_batch_refuses_bad_auto_seam_arguments_before_writing(tmp_path, flag):
    src, out = tmp_path / "box.obj", tmp_path / "out.obj"
    _closed_box_obj(src)
    r = _run(src, out, *flag)
    assert r.returncode == 1, r.stdout + r.stderr
    assert flag[0] in (r.stdout + r.stderr)
    assert not out.exists()
