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


def _one_line_error(r, *needles):
    """Exit status 1, one line on stderr holding every needle, no traceback."""
    assert r.returncode == 1, (r.returncode, r.stdout + r.stderr)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert "Traceback" not in r.stderr
    for n in needles:
        assert n in lines[0], (n, lines[0])


@pytest.mark.parametrize("args,needle", [
    (["--margin", "nan"], "--margin"),
    (["--margin", "inf"], "--margin"),
    (["--margin", "-0.5"], "--margin"),
    (["--size", "0"], "--size"),
    (["--max-iterations", "0", "--method", "slim"], "--max-iterations"),
    (["--tolerance-exponent", "5", "--method", "slim"], "--tolerance-exponent"),
    (["--max-iterations", "nan", "--method", "slim"], "--max-iterations"),
])
def test_batch_unwrap_rejects_bad_arguments_before_writing(tmp_path, args, needle):
    src, out = tmp_path / "grid.obj", tmp_path / "out.obj"
    _grid_obj(src)
    r = _run(src, out, *args)
    _one_line_error(r, needle)
    assert list(tmp_path.iterdir()) == [src]


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply"])
@pytest.mark.parametrize("defect", ["nan_vertex", "bad_index"])
def test_batch_unwrap_rejects_a_broken_mesh_file_naming_the_element(tmp_path, suffix, defect):
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]], dtype=float)
    faces = [[0, 1, 2, 3], [1, 4, 2]]
    if defect == "nan_vertex":
        positions[3, 1] = np.nan
        needle = "vertex 3"
    else:
        faces[1][1] = 9
        needle = "face 1"
    src, out = tmp_path / f"broken{suffix}", tmp_path / "out.obj"
    if suffix == ".obj":
        src.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in positions)
                       + "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in faces))
    elif suffix == ".off":
        src.write_text(f"OFF\n{len(positions)} {len(faces)} 0\n"
                       + "".join(f"{x} {y} {z}\n" for x, y, z in positions)
                       + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces))
    else:
        header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(positions)}\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        body = positions.astype("<f4").tobytes()
        for f in faces:
            body += np.uint8(len(f)).tobytes() + np.array(f, dtype="<i4").tobytes()
        src.write_bytes(header.encode() + body)
    r = _run(src, out)
    _one_line_error(r, str(src), needle)
    assert not out.exists()
