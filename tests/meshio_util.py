"""Minimal OBJ/OFF readers producing uvflat's polygon-soup arrays.

Only what the test meshes need: vertex positions and polygon faces (OBJ ``v``/``f`` records
with ``i``, ``i/t``, ``i//n``, ``i/t/n`` and negative indices; OFF with optional comments and
per-face colors). Returns ``(positions (V,3) float64, corner_verts (C,) int64, face_sizes (F,) int64)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

MESH_DIR = Path(__file__).resolve().parent.parent.parent / "shared" / "meshes"
"""``<repo root>/../shared/meshes``: the shared real-mesh folder (may be absent)."""


def mesh_path(name: str) -> Path:
    """Path of a shared mesh; skips the calling test when the folder or file is absent."""
    import pytest

    path = MESH_DIR / name
    if not path.is_file():
        pytest.skip(f"shared test mesh {name!r} not found (looked in {MESH_DIR}); "
                    "these tests need the project's ../shared/meshes folder")
    return path


def _soup(positions, faces):
    pos = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    sizes = np.fromiter((len(f) for f in faces), dtype=np.int64, count=len(faces))
    corners = np.fromiter((i for f in faces for i in f), dtype=np.int64, count=int(sizes.sum()))
    return pos, corners, sizes


def read_obj(path: str | Path):
    """Read the vertices and polygons of a Wavefront OBJ file."""
    positions: list[list[float]] = []
    faces: list[list[int]] = []
    with open(path, encoding="utf-8", errors="replace") as fh:
        for line in fh:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                positions.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                face = []
                for tok in parts[1:]:
                    i = int(tok.split("/")[0])
                    face.append(i - 1 if i > 0 else len(positions) + i)
                faces.append(face)
    return _soup(positions, faces)


def read_off(path: str | Path):
    """Read the vertices and polygons of an OFF file."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        lines = [ln.split("#", 1)[0].split() for ln in fh]
    lines = [ln for ln in lines if ln]
    header = lines[0]
    if not header[0].endswith("OFF"):
        raise ValueError(f"{path}: not an OFF file")
    rest = lines[1:]
    if len(header) > 1:  # counts on the OFF line itself
        counts, body = header[1:], rest
    else:
        counts, body = rest[0], rest[1:]
    nv, nf = int(counts[0]), int(counts[1])
    positions = [[float(x) for x in ln[:3]] for ln in body[:nv]]
    faces = []
    for ln in body[nv:nv + nf]:
        n = int(ln[0])
        faces.append([int(x) for x in ln[1:1 + n]])
    return _soup(positions, faces)


def read_mesh(name: str):
    """Read a shared test mesh by file name (skips the test when it is absent)."""
    path = mesh_path(name)
    if path.suffix.lower() == ".obj":
        return read_obj(path)
    return read_off(path)
