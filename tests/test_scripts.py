"""The headless batch script, run as a user would: a subprocess on real files."""

from __future__ import annotations

import json
import os
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


def _obj_density(path: Path):
    """sqrt(UV area / surface area) of every face of an OBJ file written with UVs (each face
    as a fan from its first corner), as (surface area, UV area) per face."""
    lines = path.read_text().splitlines()
    v = np.array([ln.split()[1:4] for ln in lines if ln.startswith("v ")], dtype=float)
    vt = np.array([ln.split()[1:3] for ln in lines if ln.startswith("vt ")], dtype=float)
    area3, area_uv = [], []
    for ln in lines:
        if not ln.startswith("f "):
            continue
        corners = [tok.split("/") for tok in ln.split()[1:]]
        p = v[[int(c[0]) - 1 for c in corners]]
        q = vt[[int(c[1]) - 1 for c in corners]]
        a3 = sum(0.5 * np.linalg.norm(np.cross(p[k] - p[0], p[k + 1] - p[0]))
                 for k in range(1, len(p) - 1))
        a2 = sum(0.5 * abs((q[k, 0] - q[0, 0]) * (q[k + 1, 1] - q[0, 1])
                           - (q[k, 1] - q[0, 1]) * (q[k + 1, 0] - q[0, 0]))
                 for k in range(1, len(q) - 1))
        area3.append(a3)
        area_uv.append(a2)
    return np.array(area3), np.array(area_uv)


@pytest.mark.parametrize("pack", ["around", "off"])
def test_batch_texel_density_gives_the_pixels_per_metre(tmp_path, pack):
    """--texel-density 150 --texture-size 512: every face of the output gets 150 px per metre
    of a 512 px texture (the 6 m grid then spans more than the tile, which the summary says),
    and --report lists each island's density."""
    src, out, report = tmp_path / "grid.obj", tmp_path / "out.obj", tmp_path / "report.json"
    _grid_obj(src)
    r = _run(src, out, "--method", "abf", "--pack", pack, "--texel-density", "150",
             "--texture-size", "512", "--report", report)
    assert r.returncode == 0, r.stdout + r.stderr
    area3, area_uv = _obj_density(out)
    assert len(area3) == 36
    assert np.sqrt(area_uv.sum() / area3.sum()) * 512 == pytest.approx(150.0, rel=0.02)
    assert "texel density 150 px/m at 512 px: islands larger than their tile" in r.stdout
    data = json.loads(report.read_text())
    assert data["texture_size"] == 512
    charts = [c for charts in data["objects"].values() for c in charts]
    assert charts and all(c["texel_density"] == pytest.approx(150.0, rel=0.02) for c in charts)


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
# ---------------------------------------------------------------------------------------------
# Every bad argument: one clear line naming it, exit status 1, nothing written


def _bad_args_cases(tmp_path):
    src = tmp_path / "grid.obj"
    _grid_obj(src)
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    (tmp_path / "mesh.stl").write_text("solid x\nendsolid x\n")
    out = tmp_path / "out" / "out.obj"
    return [
        ([src, out, "--margin", "-5"], "--margin"),
        ([src, out, "--margin", "2"], "--margin"),
        ([src, out, "--method", "spectral", "--max-iterations", "0"], "--max-iterations"),
        ([src, out, "--method", "slim", "--tolerance-exponent", "5"], "--tolerance-exponent"),
        ([src, out, "--method", "lscm", "--max-iterations", "5"], "--max-iterations"),
        ([src, out, "--method", "abf", "--boundary", "circle"], "--boundary"),
        ([src, out, "--method", "frob"], "--method"),
        ([src, out, "--size", "0"], "--size"),
        ([src, out, "--max-iterations", "many"], "--max-iterations"),
        ([src, out, "--pack", "around", "--no-pack"], "--no-pack"),
        ([tmp_path / "missing.obj", out], "missing.obj"),
        ([tmp_path / "mesh.stl", out], ".stl"),
        ([src, tmp_path / "out" / "out.fbx"], ".fbx"),
        ([src, locked / "sub" / "out.obj"], "not writable"),
        ([src, src / "sub" / "out.obj"], "not a folder"),
        ([src, out, "--png", tmp_path / "layout.jpg"], "--png"),
    ]


def test_bad_arguments_one_line_exit_1_nothing_written(tmp_path):
    for args, named in _bad_args_cases(tmp_path):
        if "not writable" == named and os.geteuid() == 0:
            continue  # root writes anywhere
        r = _run(*args)
        text = (r.stdout + r.stderr).strip()
        assert r.returncode == 1, f"{args}: exit {r.returncode}\n{text}"
        assert "Traceback" not in text, f"{args}:\n{text}"
        errors = [line for line in text.splitlines() if "error" in line.lower()]
        assert len(errors) == 1 and named in errors[0], f"{args}: {text}"
        assert not (tmp_path / "out").exists(), f"{args}: something was written"


def test_uv_name_is_the_active_and_render_map_of_the_glb(tmp_path):
    import bpy

    sys.path.insert(0, str(REPO / "blender_scripts"))
    import common

    # An input with an existing UV map ("Old", planar projection) that the glb must not carry
    # as TEXCOORD_0 once --uv-name wrote "Fresh".
    src = tmp_path / "grid.obj"
    _grid_obj(src)
    lines = src.read_text().splitlines()
    verts = [line for line in lines if line.startswith("v ")]
    uv_lines = [f"vt {0.01 * k:.4f} 0.0" for k in range(len(verts))]
    faces = [" ".join(["f"] + [f"{i}/{i}" for i in line.split()[1:]])
             for line in lines if line.startswith("f ")]
    src.write_text("\n".join(verts + uv_lines + faces) + "\n")
    out = tmp_path / "out.glb"
    r = _run(src, out, "--uv-name", "Fresh", "--pack", "all")
    assert r.returncode == 0, r.stdout + r.stderr
    blend = tmp_path / "out.blend"
    r = _run(src, blend, "--uv-name", "Fresh", "--pack", "all")
    assert r.returncode == 0, r.stdout + r.stderr

    common.reset_scene()
    import addon_utils

    addon_utils.enable("io_scene_gltf2", default_set=False)
    bpy.ops.import_scene.gltf(filepath=str(out))
    obj = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    layers = obj.data.uv_layers
    first = np.empty(2 * len(obj.data.loops), dtype=np.float32)
    layers[0].uv.foreach_get("vector", first)  # TEXCOORD_0
    first = first.reshape(-1, 2)
    # The old map is a line (v = 0 after the glTF flip: v = 1); uvflat's is a 2D disk.
    assert np.ptp(first, axis=0).min() > 0.1, "TEXCOORD_0 is still the old UV map"

    with bpy.data.libraries.load(str(blend)) as (src_data, dst_data):
        dst_data.meshes = list(src_data.meshes)
    mesh = dst_data.meshes[0]
    assert mesh.uv_layers.active.name == "Fresh"
    assert next(layer for layer in mesh.uv_layers if layer.active_render).name == "Fresh"


# ---------------------------------------------------------------------------------------------
# Batch over a folder


def _two_object_obj(path: Path) -> None:
    """Two separate quad grids as two OBJ objects."""
    lines = []
    for k, name in enumerate(("Left", "Right")):
        lines.append(f"o {name}")
        base = k * 16
        for j in range(4):
            for i in range(4):
                lines.append(f"v {i + 10 * k} {j} {0.2 * np.sin(i + j):.5f}")
        for j in range(3):
            for i in range(3):
                a = base + j * 4 + i + 1
                lines.append(f"f {a} {a + 1} {a + 5} {a + 4}")
    path.write_text("\n".join(lines) + "\n")


def _off(path: Path) -> None:
    path.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0.2\n0 1 0\n3 0 1 2\n3 0 2 3\n")


def test_batch_over_a_folder_of_mixed_files(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _grid_obj(src / "grid.obj")
    _two_object_obj(src / "pair.obj")
    _off(src / "square.off")
    (src / "broken.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    (src / "notes.txt").write_text("not a mesh")
    out, report = tmp_path / "out", tmp_path / "report.json"
    r = _run(src, out, "--jobs", "2", "--format", "glb", "--report", report, "--method", "lscm")
    text = r.stdout + r.stderr
    assert r.returncode == 1, text  # broken.ply failed
    for name in ("grid.obj", "pair.obj", "square.off", "broken.ply"):
        assert sum(line.split("] ")[-1].startswith(f"{name}:") for line in r.stdout.splitlines()) == 1, text
    assert "notes.txt" not in text
    table = r.stdout[r.stdout.index("file "):]
    assert "4 files, 3 ok, 1 not" in table, table
    for stem in ("grid", "pair", "square"):
        assert (out / f"{stem}.glb").stat().st_size > 0
        assert (out / f"{stem}_uv.png").is_file()
    import json

    data = json.loads(report.read_text())
    by_file = {Path(d["file"]).name: d for d in data["files"]}
    assert set(by_file) == {"grid.obj", "pair.obj", "square.off"}
    assert len(by_file["pair.obj"]["objects"]) == 2, "every mesh object of a file is unwrapped"
    for d in by_file.values():
        for charts in d["objects"].values():
            assert charts and all(c["status"] == "solved" for c in charts)
    broken = next(row for row in data["table"] if row["file"] == "broken.ply")
    assert broken["status"] == "error"


def test_batch_refuses_bad_arguments_before_running(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _grid_obj(src / "grid.obj")
    for args, named in (([src, tmp_path / "out", "--jobs", "0"], "--jobs"),
                        ([tmp_path / "empty*.obj", tmp_path / "out"], "empty*.obj"),
                        ([src, src / "grid.obj", "--method", "lscm"], "output folder")):
        r = _run(*args)
        assert r.returncode == 1 and named in r.stderr, (args, r.stdout + r.stderr)
        assert not (tmp_path / "out").exists()


def test_batch_options_follow_the_core_contract():
    """The script's method options exist in uvflat.METHOD_OPTIONS with the same choices."""
    import importlib.util

    import uvflat

    spec = importlib.util.spec_from_file_location("uvflat_unwrap_script", SCRIPT)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    args = script.parse_args(["in.obj", "out.obj"])
    declared = {}
    for specs in uvflat.METHOD_OPTIONS.values():
        for s in specs:
            declared.setdefault(s["name"], set()).update(s["choices"] or ())
    by_dest = {a.dest: a for a in args.parser._actions}
    for dest in ("boundary", "solver"):
        assert set(by_dest[dest].choices) == declared[dest], dest
    for dest in ("max_iterations", "tolerance_exponent"):
        assert by_dest[dest].default is None, f"--{dest}: the method's own default applies"
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
    (["--max-iterations", "1000000000000", "--method", "slim"], "--max-iterations"),
    (["--max-iterations", "1000000000000", "--method", "spectral"], "--max-iterations"),
    (["--max-iterations", "2147483648", "--method", "abf"], "--max-iterations"),
    (["--texel-density", "0"], "--texel-density"),
    (["--texel-density", "-300"], "--texel-density"),
    (["--texel-density", "nan"], "--texel-density"),
    (["--texel-density", "inf"], "--texel-density"),
    (["--texel-density", "many"], "--texel-density"),
    (["--texel-density", "300", "--texture-size", "0"], "--texture-size"),
    (["--texel-density", "300", "--texture-size", "1e3"], "--texture-size"),
    (["--texture-size", "100000"], "--texture-size"),
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


def test_benchmark_floor_is_the_ratio_a_zero_second_solve_would_leave():
    """The benchmark's ``floor × family`` column: uvflat's seconds outside the solve over the
    Blender method's seconds, for uvflat rows only."""
    sys.path.insert(0, str(REPO / "blender_scripts"))
    import benchmark

    phases = {"read": 0.01, "solve": 0.3, "quality": 0.0, "write": 0.02, "pack": 0.05,
              "mode": 0.02, "other": 0.0}
    rows = [
        {"kind": "blender", "method": "ANGLE_BASED", "seconds": 2.0, "error": None},
        {"kind": "blender", "method": "CONFORMAL", "seconds": 1.0, "error": None},
        {"kind": "uvflat", "method": "abf", "seconds": 0.4, "error": None, "phases": phases},
        {"kind": "uvflat", "method": "lscm", "seconds": 0.4, "error": None, "phases": phases},
    ]
    text = benchmark.table([("m", 10, rows)], 2, show_phases=True)
    lines = text.splitlines()
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    col = head.index("floor × family")
    cells = {line.split("|")[3].strip(): [c.strip() for c in line.strip("|").split("|")]
             for line in lines[2:]}
    assert float(cells["abf"][col]) == pytest.approx((0.4 - 0.3) / 2.0, abs=1e-3)
    assert float(cells["lscm"][col]) == pytest.approx((0.4 - 0.3) / 1.0, abs=1e-3)
    assert cells["Blender ANGLE_BASED"][col] == "–"
    # Every row has as many cells as the header.
    assert all(len(c) == len(head) for c in cells.values())


# ---------------------------------------------------------------------------------------------
# Hostile input: one clear line naming the file (or, for a face naming a vertex twice, a
# repair that is reported)

_PLY_HEADER = ("ply\nformat ascii 1.0\nelement vertex {v}\nproperty float x\nproperty float y\n"
               "property float z\nelement face {f}\nproperty list uchar int vertex_indices\n"
               "end_header\n")


@pytest.mark.parametrize("name,text,needle", [
    ("empty.off", "", "empty file"),
    ("blank.off", "\n  \n# only a comment\n", "empty file"),
    ("header.off", "OFF\n", "no vertex and face counts"),
    ("words.off", "OFF\nfour two zero\n", "not integers"),
    ("short.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n", "announces 4 vertices"),
    ("faces.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "announces 2 faces"),
    ("corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "face 0"),
    ("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "no faces"),
    ("nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
    ("empty.obj", "", "no faces"),
    ("nofaces.ply", _PLY_HEADER.format(v=3, f=0) + "0 0 0\n1 0 0\n0 1 0\n", "no faces"),
])
def test_hostile_file_is_one_line_naming_it(tmp_path, name, text, needle):
    src, out = tmp_path / name, tmp_path / "out.obj"
    src.write_text(text)
    r = _run(src, out)
    _one_line_error(r, str(src), needle)
    assert not out.exists() and not (tmp_path / "out_uv.png").exists()


def test_batch_reports_a_hostile_file_as_one_line_and_goes_on(tmp_path):
    src = tmp_path / "in"
    src.mkdir()
    _grid_obj(src / "grid.obj")
    (src / "empty.off").write_text("")
    (src / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    out = tmp_path / "out"
    r = _run(src, out, "--jobs", "2")
    text = r.stdout + r.stderr
    assert r.returncode == 1, text
    assert "Traceback" not in text
    lines = {name: [ln for ln in r.stdout.splitlines() if ln.split("] ")[-1].startswith(name + ":")]
             for name in ("grid.obj", "empty.off", "flat.obj")}
    assert all(len(found) == 1 for found in lines.values()), text
    assert "empty file" in lines["empty.off"][0] and "no faces" in lines["flat.obj"][0], text
    assert "3 files, 1 ok, 2 not" in r.stdout, text
    assert sorted(p.name for p in out.iterdir()) == ["grid.obj", "grid_uv.png"]


def _write_soup(path: Path, positions, faces) -> None:
    """``positions`` and ``faces`` (vertex indices from 0) as .obj, .off or ascii .ply."""
    if path.suffix == ".obj":
        text = ("".join(f"v {x} {y} {z}\n" for x, y, z in positions)
                + "".join("f " + " ".join(str(i + 1) for i in f) + "\n" for f in faces))
    elif path.suffix == ".off":
        text = (f"OFF\n{len(positions)} {len(faces)} 0\n"
                + "".join(f"{x} {y} {z}\n" for x, y, z in positions)
                + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces))
    else:
        text = (_PLY_HEADER.format(v=len(positions), f=len(faces))
                + "".join(f"{x} {y} {z}\n" for x, y, z in positions)
                + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in faces))
    path.write_text(text)


def _obj_faces(path: Path):
    """The faces of an OBJ file, each as the sorted list of its vertices (from 0)."""
    return sorted(sorted(int(tok.split("/")[0]) - 1 for tok in ln.split()[1:])
                  for ln in path.read_text().splitlines() if ln.startswith("f "))


@pytest.mark.parametrize("suffix", [".obj", ".off", ".ply"])
def test_face_naming_a_vertex_twice_is_repaired_the_same_way_and_reported(tmp_path, suffix):
    positions = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0.3), (2, 1, 0.3)]
    faces = [[0, 1, 1, 2, 3],   # a quad with a corner written twice: merged back to a quad
             [1, 4, 5, 2],      # a plain quad
             [1, 4, 1],         # two distinct vertices: removed
             [4, 5, 2, 5]]      # vertex 5 twice, apart: removed
    src, out, report = tmp_path / f"rep{suffix}", tmp_path / "out.obj", tmp_path / "r.json"
    _write_soup(src, positions, faces)
    r = _run(src, out, "--report", report)
    assert r.returncode == 0, r.stdout + r.stderr
    # Both kept faces are in the output, whatever the format (the importers differ), on the
    # file's vertices.
    assert len([ln for ln in out.read_text().splitlines() if ln.startswith("v ")]) == 6
    assert _obj_faces(out) == [[0, 1, 2, 3], [1, 2, 4, 5]]
    # Never silent: one line names every repaired face, the report lists them.
    said = [ln for ln in r.stdout.splitlines() if "naming a vertex more than once" in ln]
    assert len(said) == 1, r.stdout
    assert "3 faces" in said[0] and "1 merged, 2 removed" in said[0], said[0]
    base = 1 if suffix == ".obj" else 0  # vertices numbered as the file numbers them
    assert f"face 0 ({' '.join(str(i + base) for i in faces[0])} -> " in said[0], said[0]
    for f in (2, 3):
        assert f"face {f} ({' '.join(str(i + base) for i in faces[f])} -> removed)" in said[0]
    import json

    repairs = json.loads(report.read_text())["repairs"]
    assert [(d["face"], d["kept"] is None) for d in repairs] == [(0, False), (2, True), (3, True)]
    assert sorted(repairs[0]["kept"]) == [i + base for i in (0, 1, 2, 3)]


def test_file_without_repeated_vertices_reports_no_repair(tmp_path):
    src, out, report = tmp_path / "grid.obj", tmp_path / "out.obj", tmp_path / "r.json"
    _grid_obj(src)
    r = _run(src, out, "--report", report)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "naming a vertex" not in r.stdout
    import json

    assert json.loads(report.read_text())["repairs"] == []


def _blend_with_group(path: Path, group: str) -> None:
    """A closed box saved as .blend, with a vertex group ``group`` on its top face."""
    import bpy

    sys.path.insert(0, str(REPO / "blender_scripts"))
    import common

    common.reset_scene()
    obj_path = path.with_suffix(".obj")
    _closed_box_obj(obj_path)
    bpy.ops.wm.obj_import(filepath=str(obj_path))
    obj = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    top = [v.index for v in obj.data.vertices if v.co.z > 3.5]
    obj.vertex_groups.new(name=group).add(top, 1.0, "REPLACE")
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    common.reset_scene()


def test_avoid_group_that_does_not_exist_is_one_line(tmp_path):
    blend, out = tmp_path / "box.blend", tmp_path / "out.obj"
    _blend_with_group(blend, "Face")
    r = _run(blend, out, "--avoid-group", "Nose")
    _one_line_error(r, "--avoid-group", "'Nose'", str(blend), "'Face'")
    assert not out.exists()
    # a format without vertex groups
    src = tmp_path / "box.obj"
    r = _run(src, out, "--avoid-group", "Face")
    _one_line_error(r, "--avoid-group", "'Face'", str(src), "no vertex groups")
    assert not out.exists()
    # a group that steers nothing
    r = _run(blend, out, "--avoid-group", "Face", "--no-auto-seams")
    _one_line_error(r, "--avoid-group", "--no-auto-seams")
    assert not out.exists()
    # the group that exists is used
    r = _run(blend, out, "--avoid-group", "Face", "--method", "lscm")
    assert r.returncode == 0, r.stdout + r.stderr
    assert out.is_file()


def test_seams_only_marks_seams_and_writes_no_uvs(tmp_path):
    """--seams-only: the output .blend carries the planned seams (exactly uvflat.plan_seams of
    the mesh) and no UV map; no layout image is written."""
    src, out = tmp_path / "box.obj", tmp_path / "out.blend"
    _closed_box_obj(src)
    r = _run(src, out, "--method", "abf", "--seams-only")
    assert r.returncode == 0, r.stdout + r.stderr
    assert "seams only" in r.stdout
    assert not (tmp_path / "out_uv.png").exists()
    probe = (
        "import bpy, json\n"
        f"bpy.ops.wm.open_mainfile(filepath={str(out)!r})\n"
        "o = [o for o in bpy.data.objects if o.type == 'MESH'][0]\n"
        "me = o.data\n"
        "print(json.dumps({'uv_maps': [l.name for l in me.uv_layers],\n"
        "  'seams': sorted(sorted(e.vertices[:]) for e in me.edges if e.use_seam),\n"
        "  'positions': [v.co[:] for v in me.vertices],\n"
        "  'corner_verts': [l.vertex_index for l in me.loops],\n"
        "  'face_sizes': [p.loop_total for p in me.polygons]}))\n"
    )
    p = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout.strip().splitlines()[-1])
    uv_maps_before = 0 if "vt " not in src.read_text() else 1
    assert len(data["uv_maps"]) <= uv_maps_before, data["uv_maps"]
    assert len(data["seams"]) > 0
    import uvflat

    planned = uvflat.plan_seams(np.array(data["positions"]), np.array(data["corner_verts"]),
                                np.array(data["face_sizes"]), method="abf")
    assert {tuple(s) for s in data["seams"]} == {tuple(map(int, s)) for s in planned}


@pytest.mark.parametrize("extra,needle", [(["--no-auto-seams"], "--no-auto-seams"),
                                          (["--no-mark-seams"], "--no-mark-seams")])
def test_seams_only_contradictions_are_one_line(tmp_path, extra, needle):
    src = tmp_path / "box.obj"
    _closed_box_obj(src)
    r = _run(src, tmp_path / "out.blend", "--seams-only", *extra)
    assert r.returncode == 1 and needle in r.stderr + r.stdout and "Traceback" not in r.stderr
    r = _run(src, tmp_path / "out.obj", "--seams-only")
    assert r.returncode == 1 and ".blend" in r.stderr + r.stdout and "Traceback" not in r.stderr


# ---------------------------------------------------------------------------------------------
# Automatic-seams flags from the core's table (uvflat.AUTO_SEAM_OPTIONS)


def _script():
    import importlib.util

    spec = importlib.util.spec_from_file_location("uvflat_unwrap_script", SCRIPT)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script


def test_batch_auto_seam_flags_follow_the_core_table():
    """A flag for every declared automatic-seams option (but the two given another way), with
    the declared default and choices."""
    import uvflat

    script = _script()
    args = script.parse_args(["in.obj", "out.obj"])
    by_dest = {a.dest: a for a in args.parser._actions}
    by_hand = {"avoid_vertices": "--avoid-group", "sharp_angle": "--sharp-angle"}
    for s in uvflat.AUTO_SEAM_OPTIONS:
        if s["name"] in by_hand:
            assert by_hand[s["name"]] in by_dest[by_hand[s["name"]][2:].replace("-", "_")].option_strings
            continue
        action = by_dest[s["name"]]
        assert "--" + s["name"].replace("_", "-") in action.option_strings, s["name"]
        assert action.default == s["default"] == getattr(args, s["name"]), s["name"]
        if s["type"] == "choice":
            assert tuple(action.choices) == s["choices"]
    assert by_dest["symmetry"].option_strings == ["--symmetry"]
    assert by_dest["visibility_weight"].option_strings == ["--visibility-weight"]
    text = args.parser.format_help()
    assert "--symmetry" in text and "--visibility-weight" in text
    args = script.parse_args(["in.obj", "out.obj", "--symmetry", "auto", "--visibility-weight", "3"])
    assert (args.symmetry, args.visibility_weight) == ("auto", 3.0)


@pytest.mark.parametrize("args,needle", [
    (["--symmetry", "w"], "--symmetry"),
    (["--visibility-weight", "-1"], "--visibility-weight"),
    (["--visibility-weight", "101"], "--visibility-weight"),
    (["--visibility-weight", "nan"], "--visibility-weight"),
    (["--visibility-weight", "a"], "--visibility-weight"),
])
def test_batch_refuses_bad_symmetry_and_visibility_in_one_line(tmp_path, args, needle):
    src, out = tmp_path / "box.obj", tmp_path / "out.obj"
    _closed_box_obj(src)
    r = _run(src, out, *args)
    _one_line_error(r, needle)
    assert sorted(tmp_path.iterdir()) == [src]


def test_batch_symmetry_marks_mirrored_seams(tmp_path):
    """--seams-only --symmetry x: the .blend carries the seams uvflat.plan_seams(symmetry="x")
    plans, and they map onto themselves under the mirror across the box's middle."""
    import uvflat
    from test_auto_seams import mirror_of, mirrored

    src, out = tmp_path / "box.obj", tmp_path / "out.blend"
    _closed_box_obj(src)
    r = _run(src, out, "--method", "abf", "--seams-only", "--symmetry", "x",
             "--visibility-weight", "2")
    assert r.returncode == 0, r.stdout + r.stderr
    probe = (
        "import bpy, json\n"
        f"bpy.ops.wm.open_mainfile(filepath={str(out)!r})\n"
        "me = [o for o in bpy.data.objects if o.type == 'MESH'][0].data\n"
        "print(json.dumps({'seams': sorted(sorted(e.vertices[:]) for e in me.edges if e.use_seam),\n"
        "  'positions': [v.co[:] for v in me.vertices],\n"
        "  'corner_verts': [l.vertex_index for l in me.loops],\n"
        "  'face_sizes': [p.loop_total for p in me.polygons]}))\n"
    )
    p = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    data = json.loads(p.stdout.strip().splitlines()[-1])
    pos = np.array(data["positions"])
    seams = {tuple(s) for s in data["seams"]}
    assert len(seams) > 0 and mirrored(seams, mirror_of(pos, axis=0)) == seams
    planned = uvflat.plan_seams(pos, np.array(data["corner_verts"]), np.array(data["face_sizes"]),
                                method="abf", symmetry="x", visibility_weight=2.0)
    assert seams == {tuple(map(int, s)) for s in planned}
    # and a full unwrap with it writes UVs for every face
    r = _run(src, tmp_path / "full.obj", "--method", "abf", "--symmetry", "x")
    assert r.returncode == 0, r.stdout + r.stderr
    faces = [ln for ln in (tmp_path / "full.obj").read_text().splitlines() if ln.startswith("f ")]
    assert len(faces) == 96 and all("/" in f for f in faces)


def test_robustness_variants_are_valid_meshes_of_the_promised_kind():
    """The variants of ``blender_scripts/robustness.py`` are what its docs say: holes remove at
    most the faces asked, quads and n-gons merge faces into polygons of distinct vertices,
    collapsed leaves triangles without area, and
    every variant is a mesh uvflat accepts (deterministic: the same twice)."""
    sys.path.insert(0, str(REPO / "blender_scripts"))
    import robustness
    import uvflat
    from meshio_util import read_mesh
    mesh = read_mesh("cow.off")
    n = len(mesh[2])
    holes = robustness.holes(mesh, 6, 60, 1)
    assert n - 6 * 60 <= len(holes[2]) < n
    quads = robustness.quads(mesh, 3)
    assert set(quads[2].tolist()) == {3, 4} and (quads[2] == 4).sum() > n // 4
    assert 2 * (quads[2] == 4).sum() + (quads[2] == 3).sum() == n
    ngons = robustness.ngons(mesh, 0.3, 7)
    big = ngons[2][ngons[2] > 3]
    assert len(big) > 0 and big.min() >= 5 and big.max() <= 8
    assert big.sum() + (ngons[2] == 3).sum() == n  # each n-gon replaces its n triangles
    # Collapsed: the faces as they were, 1% of the triangles (at least) without area.
    squashed = robustness.collapsed(mesh, 0.01, 5)
    assert np.array_equal(squashed[1], mesh[1]) and np.array_equal(squashed[2], mesh[2])
    t = np.asarray(mesh[1]).reshape(-1, 3)
    q = squashed[0][t]
    zero = (np.linalg.norm(np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), axis=1) == 0).sum()
    assert zero >= n // 100
    assert np.array_equal(robustness.collapsed(mesh, 0.01, 5)[0], squashed[0])
    for p, c, s in (holes, quads, ngons, squashed):
        starts = np.concatenate([[0], np.cumsum(s)[:-1]])
        assert all(len(set(c[a:a + k].tolist())) == k for a, k in zip(starts, s))
        assert c.max() < len(p)
        r = uvflat.unwrap(p, c, s, method="abf")
        assert all(ch.status in ("solved", "fallback") for ch in r.charts), [ch.reason for ch in r.charts]
    again = robustness.quads(mesh, 3)
    assert all(np.array_equal(x, y) for x, y in zip(quads, again))
    parts = robustness.side_by_side([mesh, quads])
    assert len(parts[2]) == n + len(quads[2]) and np.ptp(parts[0][:, 1]) <= 1.0 + 1e-9
