"""uvflat: fast UV unwrapping (parameterization) of polygon meshes.

The numerical work runs in a Rust core without holding the GIL, so several unwraps can run
in parallel Python threads. Inputs are plain numpy arrays describing a polygon soup:

* ``positions`` -- (V, 3) float vertex positions,
* ``corner_verts`` -- (C,) int vertex index of every face corner, faces one after another,
* ``face_sizes`` -- (F,) int number of corners of every face (summing to C).

UVs are per corner (Blender's "loop"), so a seam can give one vertex several UVs.

>>> import numpy as np, uvflat
>>> positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
>>> result = uvflat.unwrap(positions, [0, 1, 2, 3], [4], method="lscm")
>>> result.uv.shape, result.charts[0].status
((4, 2), 'solved')
"""

from ._uvflat import (
    METHODS,
    AngleSumError,
    ChartReport,
    FaceSizeError,
    InputError,
    MeshError,
    Metrics,
    NonFiniteError,
    OptionError,
    PinError,
    RepeatedVertexError,
    SeamError,
    TriangleError,
    UnwrapResult,
    UvflatError,
    VertexIndexError,
    __version__,
    factorization_seconds,
    metrics,
    unwrap,
)

__all__ = [
    "METHODS",
    "AngleSumError",
    "ChartReport",
    "FaceSizeError",
    "InputError",
    "MeshError",
    "Metrics",
    "NonFiniteError",
    "OptionError",
    "PinError",
    "RepeatedVertexError",
    "SeamError",
    "TriangleError",
    "UnwrapResult",
    "UvflatError",
    "VertexIndexError",
    "__version__",
    "factorization_seconds",
    "metrics",
    "unwrap",
]
