"""The scaling script: its disk mesh, its exponent fit, and a run on tiny sizes."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "blender_scripts" / "scaling.py"
sys.path.insert(0, str(SCRIPT.parent))

import scaling  # noqa: E402


@pytest.mark.parametrize("asked", [6, 24, 2000, 50_000])
def test_disk_mesh_is_one_oriented_disk_of_6r2_triangles(asked):
    positions, corner_verts, face_sizes = scaling.disk_mesh(asked)
    rings = max(1, round(math.sqrt(asked / 6)))
    tris = corner_verts.reshape(-1, 3)
    assert len(tris) == len(face_sizes) == 6 * rings * rings
    assert len(positions) == 3 * rings * (rings + 1) + 1
    assert np.all(face_sizes == 3)
    # Every vertex used; counter-clockwise seen from +z; the projection tiles the regular
    # 6k-gons inscribed in the unit circle.
    assert np.array_equal(np.unique(tris), np.arange(len(positions)))
    p = positions[tris]
    e1, e2 = p[:, 1, :2] - p[:, 0, :2], p[:, 2, :2] - p[:, 0, :2]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert area.min() > 0
    polygon = 0.5 * 6 * rings * math.sin(2 * math.pi / (6 * rings))
    assert area.sum() == pytest.approx(polygon, rel=1e-12)
    # Not developable: lifted onto z = 0.3 r².
    r2 = positions[:, 0] ** 2 + positions[:, 1] ** 2
    np.testing.assert_allclose(positions[:, 2], 0.3 * r2)
    # A manifold disk: no directed edge twice, and the undirected edges used once form
    # exactly the outer ring (6R edges).
    directed = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    undirected, count = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert count.max() == 2
    boundary = undirected[count == 1]
    assert len(boundary) == 6 * rings
    assert np.allclose(r2[boundary.ravel()], 1.0)


@pytest.mark.parametrize("exponent", [0.5, 1.0, 1.37, 2.0])
def test_fit_exponent_recovers_a_known_power_law(exponent):
    rng = np.random.default_rng(7)
    n = np.array([5e4, 1e5, 2e5, 4e5, 8e5, 1e6])
    exact = 3e-6 * n**exponent
    assert scaling.fit_exponent(n, exact) == pytest.approx(exponent, abs=1e-12)
    # Multiplicative noise of a few percent moves the fit only a little.
    noisy = exact * np.exp(rng.normal(0, 0.03, len(n)))
    assert scaling.fit_exponent(n, noisy) == pytest.approx(exponent, abs=0.1)


def test_fit_exponent_is_nan_without_two_sizes_or_with_a_zero_time():
    assert math.isnan(scaling.fit_exponent([1000], [1.0]))
    assert math.isnan(scaling.fit_exponent([1000, 1000], [1.0, 2.0]))
    assert math.isnan(scaling.fit_exponent([1000, 2000], [0.0, 2.0]))


def test_parse_size():
    assert scaling.parse_size("50k") == 50_000
    assert scaling.parse_size("1M") == 1_000_000
    assert scaling.parse_size("2000") == 2000
    assert scaling.parse_size("0.5m") == 500_000
    for bad in ("k", "-5k", "nan", "3"):
        with pytest.raises(ValueError):
            scaling.parse_size(bad)


@pytest.mark.skipif(not os.access(scaling.TIME, os.X_OK), reason=f"{scaling.TIME} is not installed")
def test_run_on_tiny_sizes_prints_a_sane_table(tmp_path):
    out, js = tmp_path / "scaling.md", tmp_path / "scaling.json"
    r = subprocess.run([sys.executable, str(SCRIPT), "--sizes", "2k,8k", "--methods", "lscm,slim",
                        "--slim-iterations", "3", "--out", str(out), "--json", str(js)],
                       capture_output=True, text=True, timeout=600, stdin=subprocess.DEVNULL)
    assert r.returncode == 0, r.stdout + r.stderr
    report = out.read_text()
    assert report.strip() == r.stdout.strip()
    lines = [line for line in report.splitlines() if line.startswith("|")]
    header = [c.strip() for c in lines[0].strip("|").split("|")]
    assert header[:4] == ["method", "triangles", "seconds", "CPU s"]
    body = [[c.strip() for c in line.strip("|").split("|")] for line in lines[2:]]
    # A baseline row then one row per method, for each size.
    assert [b[0] for b in body] == ["baseline", "lscm", "slim"] * 2
    assert [int(b[1]) for b in body] == [1944] * 3 + [8214] * 3

    data = json.loads(js.read_text())
    rows = data["rows"]
    for row in rows:
        assert row["max_rss_kb"] > 0
        assert math.isfinite(row["kb_per_triangle"]) and row["kb_per_triangle"] > 0
        if row["method"] == "baseline":
            assert row["seconds"] is None
            continue
        assert row["seconds"] > 0 and row["cpu_seconds"] > 0
        assert row["status"] == "solved"
        assert row["flips"] == 0
        # The unwrap's own memory is on top of the baseline's (same mesh, same interpreter).
        if row["triangles"] == 8214:
            assert row["kb_over_baseline"] > 0
        assert row["iterations"] == (3 if row["method"] == "slim" else 0)
    # The exponents printed are the fit of the rows' own times.
    for method in ("lscm", "slim"):
        mine = [r for r in rows if r["method"] == method]
        b = scaling.fit_exponent([r["triangles"] for r in mine], [r["seconds"] for r in mine])
        assert data["summary"][method]["exponent"] == pytest.approx(b)
        assert f"**{method}**: time exponent {b:.3f}" in report
        b_cpu = scaling.fit_exponent([r["triangles"] for r in mine], [r["cpu_seconds"] for r in mine])
        assert f"CPU time exponent {b_cpu:.3f}" in report
    assert "target ≤ 1.2" in report and "target < 3.0" in report
