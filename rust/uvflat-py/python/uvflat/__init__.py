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
    AUTO_SEAM_OPTIONS,
    METHOD_OPTIONS,
    METHODS,
    AngleSumError,
    Cancelled,
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
    island_box_angles,
    island_hulls,
    metrics,
)
from ._uvflat import unwrap as _native_unwrap

__all__ = [
    "AUTO_SEAM_OPTIONS",
    "METHOD_OPTIONS",
    "METHODS",
    "AngleSumError",
    "Cancelled",
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
    "island_box_angles",
    "island_hulls",
    "metrics",
    "plan_seams",
    "unwrap",
]


def unwrap(positions, corner_verts, face_sizes, *, method="abf", seams=None, selected=None,
           pins=None, pin_uvs=None, fit_to=None, triangles=None, auto_seams=True, max_stretch=2.0,
           max_cones=8, avoid_vertices=None, sharp_angle=None, visibility_weight=1.0,
           symmetry="none", same_seams=False, progress=None, **options):
    """Unwrap the selected faces of a polygon mesh into per-corner UVs.

    The selection is split into charts along seams, non-manifold edges (counted in
    ``UnwrapResult.non_manifold_edges``), edges between faces whose normals point to
    opposite sides (``UnwrapResult.inconsistent_edges``) and the selection border; every
    chart is mapped by ``method`` (charts in parallel, without the GIL). With ``auto_seams`` (the default) every
    chart is held to one rule: each island is a disk, has no flipped triangle, its outline does
    not cross itself, and at most 5% of its area has a texel density outside
    [1/max_stretch, max_stretch] of the island's own. Closed charts, charts with handles and
    charts with holes are cut (cones on the conformal scale factor, holes joined to the
    outline); a chart that breaks the rule gets more cones or is split; the user's seams are
    kept (new ones are in ``UnwrapResult.new_seams``). A chart that still breaks its rule is
    reported ``status == "invalid"`` with ``reason_code`` saying how. Charts that cannot be
    mapped are not errors: they come back with ``status == "failed"`` and a ``reason``, and
    their faces get no UVs.

    Args:
        positions: (V, 3) vertex positions.
        corner_verts: (C,) vertex index of every corner, faces one after another.
        face_sizes: (F,) corners per face (each >= 3), summing to C.
        method: one of :data:`METHODS`: "tutte", "harmonic", "mean_value", "lscm",
            "spectral", "bff", "abf" (default), "arap", "slim", "mips", "scaffold".
        seams: (E, 2) seam edges as vertex pairs (either order).
        selected: (F,) faces to unwrap; default all. Unselected faces get chart -1.
        pins: (P,) corner indices whose UVs are fixed.
        pin_uvs: (P, 2) the UVs of the pinned corners (required with ``pins``).
        fit_to: (C, 2) previous UVs: each unpinned chart is fitted (scale, rotation,
            translation) onto them instead of being area-scaled at the origin.
        triangles: (T, 3) the render triangulation as corner index triples (Blender's
            ``mesh.loop_triangles`` ``loops``): faces of 4+ corners are split this way, so
            flips are counted (and avoided) on the triangles Blender shows; every face needs
            exactly corners - 2 rows. Quads count as folded when either diagonal split has a
            flipped triangle, with or without this argument.
        auto_seams: hold every chart to the atlas rule above, cutting where needed (default
            True); with False nothing is cut, closed and higher-genus charts fail with a
            "mark seams" reason, and a chart with flips or a crossing outline is "invalid".
        max_stretch: Max Stretch s (> 1, default 2.0): at most 5% of an island's area may
            have a texel density outside [1/s, s] of the island's own (``density_outside``
            of the chart reports measures it against s).
        max_cones: most cone singularities per chart (default 8; a closed sphere gets at
            least 2).
        avoid_vertices: (K,) mesh vertex indices where seams must not go (no cut edge touches
            them and none becomes a cone).
        sharp_angle: dihedral angle in radians from which an edge counts as sharp and is
            preferred for seams; default None (no preference).
        visibility_weight: how much dearer a seam is on exposed surface than in hidden
            places, from 0 to 100 (default 1.0: a fully exposed edge costs twice a fully
            occluded one; 0 turns the term off). Exposure is per-vertex ambient occlusion:
            32 rays from each vertex against the mesh near the chart.
        symmetry: mirror plane the seams keep, "none" (default), "x", "y", "z" (the plane
            across that axis through the chart's centre) or "auto" (the first principal axis
            whose plane is a mirror). On a chart that is its own mirror image the cut costs and
            cones are mirrored, and a closed chart without handles is cut on one half and the
            cut mirrored, so its seams map onto themselves (a last-resort split is not); a
            chart that is not symmetric about the plane is cut as without it.
        same_seams: plan the cuts of ``slim``, ``arap`` and ``scaffold`` on the same
            method-independent prediction as the other methods (default False), so switching
            methods keeps the seams wherever the new method keeps the rule on them (a method
            that breaks it there re-cuts through the plan's cones and its own). Off, those
            three start from the cones alone and usually get fewer seams and islands.
        progress: ``callable(charts_done, charts_total)``, called from the worker threads
            with the GIL held, at most every 0.1 s and once after the last chart; returning
            a false value (``False``, ``0``, ``numpy.False_``; ``None`` goes on) cancels the
            unwrap (it raises :class:`Cancelled`); an exception it raises
            cancels too and is re-raised. Cancellation is polled between charts and between
            iterations of the iterative methods.
        **options: the method's own options (any other keyword is an OptionError naming it):

            * tutte, harmonic, mean_value: ``boundary`` "circle" (default), "square" or
              "virtual".
            * lscm, bff: none.
            * spectral: ``max_iterations`` (int >= 1, default 200), ``tolerance`` (float,
              default 1e-10).
            * abf: ``solver`` "abf++" (default) or "abf"; ``boundary`` "free" (default) or
              "convex"; ``max_iterations`` (default 30); ``tolerance`` (default 1e-5);
              ``angle_sums=(vertices, sums)``: (K,) mesh vertex indices and (K,) angle sums
              in radians the flattened map must have there (pi keeps a boundary straight,
              pi/2 makes a right-angled corner; an interior sum other than 2*pi is a cone).
            * arap: ``max_iterations`` (default 100), ``tolerance`` (default 1e-6).
            * slim: ``max_iterations`` (default 15), ``tolerance`` (default 1e-4), ``start``
              "auto" (default) or "mean_value"; ``step`` "newton" (default), projected Newton
              steps after the first, or "proxy", SLIM's own steps throughout.
            * mips: ``max_iterations`` (default 50), ``tolerance`` (default 1e-6).
            * scaffold: ``max_iterations`` (default 100), ``tolerance`` (default 1e-4).

    Returns:
        UnwrapResult: per-corner ``uv``, per-face ``chart`` and ``face_solved``, one
        ``ChartReport`` per chart (with ``cones`` and ``cut_length``), ``seconds``,
        ``new_seams``, ``non_manifold_edges`` and ``inconsistent_edges``.

    Raises:
        InputError: wrong shape, dtype or length; a non-finite ``fit_to`` UV.
        VertexIndexError, NonFiniteError, FaceSizeError, RepeatedVertexError, SeamError:
            malformed mesh (all subclasses of MeshError).
        PinError: a pin names a missing corner or has a non-finite UV.
        OptionError: unknown method, unknown option (``err.option`` names it) or bad value
            (of a method option or an automatic-seams option, see :data:`AUTO_SEAM_OPTIONS`).
        AngleSumError: a bad ``angle_sums`` entry (an OptionError naming entry and vertex).
        Cancelled: the progress callback returned ``False``.
        UvflatError: an internal error (a bug), never a crash.
    """
    return _native_unwrap(positions, corner_verts, face_sizes, method=method, seams=seams,
                          selected=selected, pins=pins, pin_uvs=pin_uvs, fit_to=fit_to,
                          triangles=triangles, auto_seams=auto_seams, max_stretch=max_stretch, max_cones=max_cones,
                          avoid_vertices=avoid_vertices, sharp_angle=sharp_angle,
                          visibility_weight=visibility_weight, symmetry=symmetry,
                          same_seams=same_seams, progress=progress, **options)


def plan_seams(positions, corner_verts, face_sizes, *, method="abf", seams=None, selected=None,
               pins=None, pin_uvs=None, fit_to=None, triangles=None, auto_seams=True,
               max_stretch=2.0, max_cones=8, avoid_vertices=None, sharp_angle=None,
               visibility_weight=1.0, symmetry="none", same_seams=False, progress=None,
               **options):
    """The seams :func:`unwrap` would add with the same arguments, without any UVs: review and
    edit them, then unwrap with them as ``seams``.

    Returns:
        (S, 2) uint32 array of mesh vertex pairs ``[a, b]`` with ``a < b``, sorted: exactly
        ``unwrap(...).new_seams``.

    Raises:
        The errors of :func:`unwrap`.
    """
    return _native_unwrap(positions, corner_verts, face_sizes, method=method, seams=seams,
                          selected=selected, pins=pins, pin_uvs=pin_uvs, fit_to=fit_to,
                          triangles=triangles, auto_seams=auto_seams, max_stretch=max_stretch,
                          max_cones=max_cones, avoid_vertices=avoid_vertices,
                          sharp_angle=sharp_angle, visibility_weight=visibility_weight,
                          symmetry=symmetry, same_seams=same_seams, progress=progress,
                          **options).new_seams
