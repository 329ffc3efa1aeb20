# SPDX-License-Identifier: GPL-3.0-or-later
"""``blender_scripts/benchmark.py --open`` on a tiny generated open mesh, run as a user would
(a subprocess, ``--repeat 1``): the table's columns, the texel-density share it prints against
``uvflat.metrics`` computed here on the same maps, and the target lines under it."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

uvflat = pytest.importorskip("uvflat")

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "blender_scripts" / "benchmark.py"
sys.path.insert(0, str(REPO / "blender_scripts"))

COLUMNS = ("mesh", "unwrap", "islands", "seam length / √area", "flips", "overlapping",
           "conformal", "area", "outside [½, 2]", "density p5–p95", "s")
UVFLAT_ROWS = ("uvflat abf (auto seams)", "uvflat slim (auto seams)", "uvflat bff (auto seams)")


def _cup(rings=6, segments=12, depth=1.6):
    """A cup of triangles: a hemisphere stretched in depth, open at the top (a disk)."""
    positions = [[0.0, 0.0, 0.0]]
    for i in range(1, rings + 1):
        t = 0.5 * np.pi * i / rings
        for j in range(segments):
            a = 2.0 * np.pi * j / segments
            positions.append([np.sin(t) * np.cos(a), np.sin(t) * np.sin(a), depth * (1 - np.cos(t))])
    tris = []

    def v(i, j):
        return 1 + (i - 1) * segments + j % segments

    for j in range(segments):
        tris.append([0, v(1, j), v(1, j + 1)])
    for i in range(1, rings):
        for j in range(segments):
            a, b, c, d = v(i, j), v(i, j + 1), v(i + 1, j + 1), v(i + 1, j)
            tris += [[a, d, c], [a, c, b]]
    return np.array(positions), np.array(tris, dtype=np.int64)


def _write_off(path, positions, tris):
    lines = ["OFF", f"{len(positions)} {len(tris)} 0"]
    lines += [" ".join(f"{x:.9f}" for x in p) for p in positions]
    lines += ["3 " + " ".join(str(int(k)) for k in t) for t in tris]
    path.write_text("\n".join(lines) + "\n")


def _table(text):
    """The rows of the markdown table in ``text`` as dicts keyed by the header's columns."""
    lines = [ln for ln in text.splitlines() if ln.startswith("|")]
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    rows = [dict(zip(head, (c.strip() for c in ln.strip("|").split("|")))) for ln in lines[2:]]
    return head, rows


def _percent(cell):
    assert cell.endswith("%"), cell
    return float(cell[:-1]) / 100.0


@pytest.fixture(scope="module")
def bench(tmp_path_factory):
    if importlib.util.find_spec("bpy") is None:
        pytest.skip("the bpy module (Blender as a Python module) is not installed")
    d = tmp_path_factory.mktemp("atlas_benchmark")
    mesh = d / "cup.off"
    _write_off(mesh, *_cup())
    out, dump = d / "table.md", d / "maps"
    r = subprocess.run([sys.executable, str(SCRIPT), "--open", "--meshes", str(mesh),
                        "--repeat", "1", "--out", str(out), "--dump-uv", str(dump)],
                       capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    text = out.read_text()
    head, rows = _table(text)
    return SimpleNamespace(text=text, head=head, rows=rows, dump=dump)


def _row(bench, label):
    found = [r for r in bench.rows if r["unwrap"] == label]
    assert len(found) == 1, (label, bench.text)
    return found[0]


def _metrics(bench, key):
    m = np.load(bench.dump / f"cup__{key}.npz")
    return uvflat.metrics(m["positions"], m["corner_verts"], m["face_sizes"], m["uv"]), m


def test_table_has_the_new_columns(bench):
    assert tuple(bench.head) == COLUMNS, bench.head
    labels = [r["unwrap"] for r in bench.rows]
    assert labels[:4] == [*UVFLAT_ROWS, "Smart UV 66° + ANGLE_BASED"], labels
    for r in bench.rows:
        assert r["mesh"] == "cup 132", r
        share = _percent(r["outside [½, 2]"])
        assert 0.0 <= share <= 1.0
        p5, p95 = map(float, r["density p5–p95"].split("–"))
        assert 0.0 <= p5 <= p95
        assert float(r["s"]) > 0.0


@pytest.mark.parametrize("label,key", [(UVFLAT_ROWS[0], "uvflat_abf"),
                                       (UVFLAT_ROWS[1], "uvflat_slim"),
                                       (UVFLAT_ROWS[2], "uvflat_bff"),
                                       ("Smart UV 66° + ANGLE_BASED", "smart_abf")])
def test_density_share_is_the_one_metrics_gives(bench, label, key):
    """The printed share is ``uvflat.metrics(...).density_outside`` of the map the row made,
    measured here again; the other columns come from the same call."""
    m, data = _metrics(bench, key)
    if not hasattr(m, "density_outside"):
        pytest.skip("the installed uvflat has no Metrics.density_outside")
    row = _row(bench, label)
    uv = data["uv"]
    # the dumped map is an unwrap, packed in the unit square, not the cleared UVs
    assert np.ptp(uv, axis=0).min() > 0.1 and uv.min() >= -1e-6 and uv.max() <= 1 + 1e-6
    assert abs(_percent(row["outside [½, 2]"]) - m.density_outside) <= 0.5e-4 + 1e-12, (
        row, m.density_outside)
    p5, p95 = map(float, row["density p5–p95"].split("–"))
    assert abs(p5 - m.density_p5) <= 0.005 + 1e-12 and abs(p95 - m.density_p95) <= 0.005 + 1e-12
    assert int(row["islands"]) == m.charts
    assert int(row["flips"]) == m.flips
    assert int(row["overlapping"]) == m.overlapping_charts
    assert abs(float(row["area"]) - m.area) <= 0.5e-4 + 1e-12


def test_uvflat_rows_have_a_target_line(bench):
    for label in UVFLAT_ROWS:
        row = _row(bench, label)
        line = next(ln for ln in bench.text.splitlines() if ln.startswith(f"- cup · {label}:"))
        checks = {
            "flips": int(row["flips"]) == 0,
            "overlapping": int(row["overlapping"]) == 0,
            "outside [½, 2]": _percent(row["outside [½, 2]"]) <= 0.05,
            "area": float(row["area"]) <= 1.35,
        }
        for name, ok in checks.items():
            cell = re.search(rf"{re.escape(name)} [^;]*", line)
            assert cell, (name, line)
            assert cell.group(0).endswith("ok" if ok else "MISSED"), (name, ok, line)
        missed = line.count("MISSED") - ("target(s) MISSED" in line)
        assert ("all targets met" in line) == (missed == 0), line


def test_xatlas_row_and_the_targets_against_it(bench):
    pytest.importorskip("xatlas", reason="xatlas is not installed: no xatlas row")
    x = _row(bench, "xatlas")
    m, _ = _metrics(bench, "xatlas")
    if hasattr(m, "density_outside"):
        assert abs(_percent(x["outside [½, 2]"]) - m.density_outside) <= 0.5e-4 + 1e-12
    for label in UVFLAT_ROWS:
        row = _row(bench, label)
        line = next(ln for ln in bench.text.splitlines() if ln.startswith(f"- cup · {label}:"))
        limit = max(0.25 * int(x["islands"]), 1)  # one part
        cell = re.search(r"islands [^;]*", line).group(0)
        assert cell.endswith("ok" if int(row["islands"]) <= limit else "MISSED"), line
        cell = re.search(r"seam [^;]*", line).group(0)
        ok = float(row["seam length / √area"]) <= 0.6 * float(x["seam length / √area"])
        assert cell.endswith("ok" if ok else "MISSED"), line


def _spread_map():
    """The cup (triangles) with a map of two islands whose density spreads well outside
    [½, 2], and four flipped triangles."""
    positions, tris = _cup()
    cv = tris.reshape(-1)
    fs = np.full(len(tris), 3, dtype=np.int64)
    # planar projection: the steep walls get little UV area
    uv = positions[cv][:, :2].copy()
    # a second island: the faces on the x > 0 side, moved and scaled
    right = np.repeat(positions[tris].mean(axis=1)[:, 0] > 0.05, 3)
    uv[right] = uv[right] * 0.5 + 3.0
    # the pole's UV pushed sideways (the same in all its corners of an island): a fold
    uv[cv == 0] += [-0.6, 0.0]
    return positions, cv, fs, uv


def test_numpy_density_spread_matches_metrics():
    """The script's own density spread (used where the module has none) is metrics' one."""
    import closed_benchmark

    positions, cv, fs, uv = _spread_map()
    m = uvflat.metrics(positions, cv, fs, uv)
    if not hasattr(m, "density_outside"):
        pytest.skip("the installed uvflat has no Metrics.density_outside")
    outside, p5, p95 = closed_benchmark.density_spread(positions, cv, fs, uv)
    assert m.charts == 2 and m.flips > 0
    assert 0.05 < m.density_outside < 1.0, m.density_outside
    assert outside == pytest.approx(m.density_outside, abs=1e-9)
    assert p5 == pytest.approx(m.density_p5, abs=1e-9)
    assert p95 == pytest.approx(m.density_p95, abs=1e-9)


def test_a_spread_map_prints_its_share_and_misses_its_targets():
    """The row and target line the script prints for a map whose share is far from 0 (the
    benchmark's own maps may all have 0% there)."""
    import closed_benchmark

    positions, cv, fs, uv = _spread_map()
    m = uvflat.metrics(positions, cv, fs, uv)
    expected = getattr(m, "density_outside", None)
    if expected is None:
        expected = closed_benchmark.density_spread(positions, cv, fs, uv)[0]
    r = dict(closed_benchmark.quality(uvflat, positions, cv, fs, uv), label="uvflat abf (auto seams)",
             seconds=0.0)
    text = closed_benchmark.HEADER + "\n|---|\n" + closed_benchmark.row_line("spread", len(fs), r)
    head, rows = _table(text)
    assert tuple(head) == COLUMNS
    assert abs(_percent(rows[0]["outside [½, 2]"]) - expected) <= 0.5e-4 + 1e-12
    assert int(rows[0]["flips"]) == m.flips > 0
    line, missed = closed_benchmark.targets(r, None, parts=1)
    assert re.search(r"flips [^;]*", line).group(0).endswith("MISSED"), line
    assert re.search(r"outside \[½, 2\] [^;]*", line).group(0).endswith("MISSED"), line
    assert missed >= 2
