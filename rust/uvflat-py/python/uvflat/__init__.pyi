"""uvflat: fast UV unwrapping (parameterization) of polygon meshes.

Inputs describe a polygon soup: ``positions`` (V, 3) float, ``corner_verts`` (C,) int (the
vertex of every face corner, faces one after another) and ``face_sizes`` (F,) int (corners per
face, summing to C). UVs are per corner. Any integer dtype is accepted for indices and any
float (or integer) dtype for coordinates; everything is converted to uint32 / float64.
"""

from typing import Any, Callable, Final, Literal, TypedDict

from typing_extensions import Unpack

import numpy as np
import numpy.typing as npt

__version__: Final[str]

METHODS: Final[tuple[str, ...]]
"""Names accepted by ``unwrap(method=...)``, e.g. ``("tutte", "harmonic", "mean_value", "lscm", "spectral")``."""

class OptionSpec(TypedDict):
    """One declared option of a method or of automatic seams (see :data:`METHOD_OPTIONS`,
    :data:`AUTO_SEAM_OPTIONS`). Absent bounds and choices are None; a default of None means
    the option is off or empty."""

    name: str
    type: Literal["bool", "int", "float", "choice", "vertices", "vertex_values"]
    default: bool | int | float | str | None
    min: int | float | None
    max: int | float | None
    min_exclusive: bool
    max_exclusive: bool
    choices: tuple[str, ...] | None
    doc: str

METHOD_OPTIONS: Final[dict[str, tuple[OptionSpec, ...]]]
"""Every method's options as the core declares them: name, type, default, range, choices, doc.
The single source the add-on, the batch script and this stub are tested against."""

AUTO_SEAM_OPTIONS: Final[tuple[OptionSpec, ...]]
"""The automatic-seams keywords of :func:`unwrap` and :func:`plan_seams` as the core declares
them (``auto_seams``, ``max_stretch``, ``max_cones``, ``avoid_vertices``, ``sharp_angle``,
``visibility_weight``, ``symmetry``, ``same_seams``), in the order front ends show them."""

Symmetry = Literal["none", "x", "y", "z", "auto"]
"""Mirror planes automatic seams can keep (``unwrap(symmetry=...)``)."""

Method = Literal["tutte", "harmonic", "mean_value", "lscm", "spectral", "bff", "abf", "arap",
                 "slim", "mips", "scaffold"]
"""Every method of :data:`METHODS`."""

class UnwrapOptions(TypedDict, total=False):
    """Keyword options of :func:`unwrap`; each method takes only the ones listed for it, any
    other keyword is an :class:`OptionError` naming it."""

    boundary: Literal["circle", "square", "virtual", "free", "convex"]
    """tutte, harmonic, mean_value: "circle" (default), "square" or "virtual";
    abf: "free" (default) or "convex"."""
    max_iterations: int
    """spectral (200), abf (30), arap (100), slim (15), mips (50), scaffold (100); >= 1."""
    tolerance: float
    """spectral (1e-10), abf (1e-5), arap (1e-6), slim (1e-4), mips (1e-6), scaffold (1e-4)."""
    solver: Literal["abf++", "abf"]
    """abf: "abf++" (default, block elimination) or "abf" (the full system by sparse LU)."""
    angle_sums: tuple[npt.ArrayLike, npt.ArrayLike]
    """abf: ((K,) mesh vertex indices, (K,) angle sums in radians)."""
    start: Literal["auto", "mean_value"]
    """slim: flip-free start, "auto" (default) or "mean_value"."""
    step: Literal["newton", "proxy"]
    """slim: steps after the first, "newton" (default, projected Newton) or "proxy" (SLIM's own)."""

_ChartKind = Literal["disk", "disk_with_holes", "closed", "higher_genus"]
_ChartStatus = Literal["solved", "fallback", "invalid", "failed"]

_Floats = npt.ArrayLike
_Ints = npt.ArrayLike
_Bools = npt.ArrayLike

class ChartReport:
    """Report of one chart (island) of an unwrap: topology, outcome and quality."""

    @property
    def id(self) -> int:
        """Chart id, as in ``UnwrapResult.chart``."""
    @property
    def method(self) -> str:
        """Method that produced the UVs (the fallback's name when ``status == "fallback"``)."""
    @property
    def faces(self) -> int:
        """Number of input faces (polygons) in the chart."""
    @property
    def triangles(self) -> int:
        """Number of triangles after n-gon triangulation."""
    @property
    def vertices(self) -> int:
        """Number of chart vertices (a vertex split by a seam counts once per side)."""
    @property
    def boundary_loops(self) -> int:
        """Number of boundary loops."""
    @property
    def genus(self) -> int:
        """Genus, from the Euler characteristic."""
    @property
    def kind(self) -> _ChartKind:
        """Topological class: "disk", "disk_with_holes", "closed" or "higher_genus"."""
    @property
    def status(self) -> _ChartStatus:
        """"solved", "fallback" (mapped by another method, see ``reason``), "invalid" (UVs
        written, but the chart breaks its rule: see ``reason_code``) or "failed" (no UVs)."""
    @property
    def reason(self) -> str | None:
        """Why the chart failed or fell back, or a note on how pins were honoured."""
    @property
    def iterations(self) -> int:
        """Iterations of an iterative method (0 for direct solves)."""
    @property
    def residual(self) -> float:
        """Final residual or energy change of the method (0 for direct solves)."""
    @property
    def flips(self) -> int:
        """Flipped or zero-area UV triangles (0 for failed charts); a quad that is not
        strictly convex in UV counts as folded (either diagonal split flips)."""
    @property
    def overlap(self) -> bool:
        """Whether the chart's UV boundary crosses or touches itself (the two sides of one cut
        lying on each other, triangles apart, do not count)."""
    @property
    def conformal(self) -> float:
        """Conformal distortion, area-weighted mean of sigma1/sigma2 (1 is perfect; NaN if failed)."""
    @property
    def area(self) -> float:
        """Area distortion, area-weighted mean of max(J, 1/J) (1 is perfect; NaN if failed)."""
    @property
    def symmetric_dirichlet(self) -> float:
        """Symmetric Dirichlet energy (1 is perfect; NaN if failed)."""
    @property
    def seconds(self) -> float:
        """Wall-clock seconds spent mapping this chart."""
    @property
    def cones(self) -> int:
        """Cone singularities placed by automatic seams in this chart (0 if it was not cut)."""
    @property
    def cut_length(self) -> float:
        """Total 3D length of the automatic seams made for this chart (0 if it was not cut)."""
    @property
    def reason_code(self) -> Literal["solved", "solved_with_note", "fallback", "invalid_flips",
                                     "invalid_overlap", "invalid_not_disk", "invalid_stretch",
                                     "failed_closed", "failed_genus", "failed_defect",
                                     "failed_no_area", "failed_solver"]:
        """Stable code of the outcome, beside the prose ``reason``."""
    @property
    def density_p5(self) -> float:
        """Area-weighted 5th percentile of the texel-density ratio (a triangle's UV area per
        3D area over the island's; NaN if failed)."""
    @property
    def density_p95(self) -> float:
        """Area-weighted 95th percentile of the texel-density ratio (NaN if failed)."""
    @property
    def density_outside(self) -> float:
        """Share of the island's 3D area (0 to 1) with a density ratio outside
        [1/max_stretch, max_stretch] (NaN if failed)."""
    def as_dict(self) -> dict[str, Any]:
        """All fields as a plain dict."""

class UnwrapResult:
    """Result of :func:`unwrap`."""

    @property
    def uv(self) -> npt.NDArray[np.float64]:
        """UV of every corner, shape (C, 2), float64; (0, 0) where a face got no UVs."""
    @property
    def chart(self) -> npt.NDArray[np.int32]:
        """Chart id of every face, shape (F,), int32; -1 for unselected faces."""
    @property
    def face_solved(self) -> npt.NDArray[np.bool_]:
        """Whether each face received UVs (its chart was solved or fell back), shape (F,)."""
    @property
    def charts(self) -> list[ChartReport]:
        """One report per chart, indexed by chart id."""
    @property
    def seconds(self) -> float:
        """Wall-clock seconds of the whole unwrap in the core."""
    @property
    def method(self) -> str:
        """Name of the requested method."""
    @property
    def new_seams(self) -> npt.NDArray[np.uint32]:
        """Seams added by automatic seams, shape (K, 2), vertex pairs (a < b), sorted."""
    @property
    def closed_seams(self) -> npt.NDArray[np.uint32]:
        """Of ``new_seams``, those whose two sides keep the same UVs, shape (J, 2), sorted: the
        paths that join small holes (filled for the unwrap) to their islands' outlines. They
        make each island a disk but show no texture seam."""
    @property
    def non_manifold_edges(self) -> int:
        """Edges of the selection used by three or more selected faces; each was treated as a
        seam (many of them shred a mesh into many small charts)."""
    @property
    def inconsistent_edges(self) -> int:
        """Edges of two selected faces whose normals point to opposite sides (both faces run
        the edge in the same direction); each was treated as a seam. Recalculating the normals
        joins them again, except on a one-sided surface such as a Möbius strip."""
    @property
    def face_conformal(self) -> npt.NDArray[np.float64]:
        """Conformal distortion of every face that received UVs, shape (F,), NaN elsewhere
        (the per-face measure of :func:`metrics`, on the returned UVs)."""
    @property
    def face_area(self) -> npt.NDArray[np.float64]:
        """Area distortion of every face that received UVs, shape (F,), NaN elsewhere."""
    @property
    def face_flips(self) -> npt.NDArray[np.uint32]:
        """Flipped or zero-area UV triangles of every face, shape (F,), exactly as the chart
        reports count them (the render ``triangles`` when given; a quad counts the flips of
        its worse diagonal split): each report's ``flips`` is the sum over its faces, and
        ``face_flips > 0`` marks the flipped faces. 0 for faces without UVs."""
    @property
    def phases(self) -> dict[str, float | int]:
        """Where the time went: ``build_charts``, ``plan_cuts``, ``solve``, ``repair_solve``,
        ``measure`` (seconds; per-chart steps summed over threads), the parts of
        ``plan_cuts`` (``cut_state``, ``cone_placement``, ``split_plans``, ``cut_graphs``:
        each chart's cutting state, the cones placed on a predicted flattening, the split's
        candidate loops, every round's cut graph with its pieces) and the counts
        ``predicted_rounds``, ``repair_rounds``, ``repair_pieces``, ``splits``,
        ``crease_cuts`` (hard-surface charts cut along their creases first),
        ``predicted_splits`` (splits made before any solve, the chart's predicted mean area
        distortion being too high), ``far_splits`` (charts split after one solve, the method's
        map being far from a plan predicted to keep the rule, or a large chart's map beyond the
        rule under a method that does not balance area), ``peels`` (pieces whose outline crossed itself, or that
        folded at a few faces, made valid by making the faces there islands of their own), ``last_resort`` (solves of the last resort, the method's flip-free kin then ``scaffold``,
        for pieces whose repair still broke the atlas rule), ``glued`` (small islands whose
        faces were laid on the islands around them), ``glue`` (its seconds),
        ``holes_filled`` (small holes filled for the unwrap and joined to the outlines by
        closed seams after it) and ``fill_undone`` (seconds of an unwrap with holes filled
        that was undone, an island breaking the rule without its fills)."""
    def as_dict(self) -> dict[str, Any]:
        """All fields as a plain dict (arrays included, chart reports as dicts)."""

class _ChartMetricsDict(TypedDict):
    """One entry of ``Metrics.per_chart``."""

    faces: int
    flips: int
    overlap: bool
    conformal: float
    area: float
    symmetric_dirichlet: float
    area_3d: float
    """3D surface area of the island (its weight in the whole-map averages)."""

class Metrics:
    """Quality of a given UV map, from :func:`metrics`.

    Each chart's UVs are scaled so its UV area equals its 3D area before measuring, and
    averages are weighted by 3D triangle area.
    """

    @property
    def charts(self) -> int:
        """Number of UV islands (faces connected through edges whose UVs agree at both ends)."""
    @property
    def flips(self) -> int:
        """Triangles whose signed UV area opposes their chart's majority, plus zero-area ones."""
    @property
    def density_outside(self) -> float:
        """Share of the 3D area (0 to 1) whose texel density is outside [1/2, 2] of its own
        island's."""
    @property
    def density_p5(self) -> float:
        """Area-weighted 5th percentile of the texel-density ratio (each triangle against its
        island)."""
    @property
    def density_p95(self) -> float:
        """Area-weighted 95th percentile of the texel-density ratio."""
    @property
    def overlapping_charts(self) -> int:
        """Charts whose UV boundary crosses itself."""
    @property
    def conformal(self) -> float:
        """Conformal distortion, area-weighted mean of sigma1/sigma2 (1 is perfect)."""
    @property
    def area(self) -> float:
        """Area distortion, area-weighted mean of max(sigma1*sigma2, 1/(sigma1*sigma2)) (1 is perfect)."""
    @property
    def symmetric_dirichlet(self) -> float:
        """Symmetric Dirichlet energy, mean of (s1^2 + s2^2 + s1^-2 + s2^-2)/4 (1 is perfect)."""
    @property
    def per_chart(self) -> list[_ChartMetricsDict]:
        """Per-island faces, flips, overlap, distortions and 3D area."""
    @property
    def face_conformal(self) -> npt.NDArray[np.float64]:
        """Conformal distortion of every face, shape (F,): 3D-area-weighted mean of
        sigma1/sigma2 over its triangles; NaN for faces not measured or without 3D area,
        inf where a UV triangle has zero area."""
    @property
    def face_area(self) -> npt.NDArray[np.float64]:
        """Area distortion of every face, shape (F,), as ``face_conformal``."""
    @property
    def face_flips(self) -> npt.NDArray[np.uint32]:
        """Flipped or zero-area UV triangles of every face, shape (F,), counted as ``flips``
        counts them (``flips`` is their sum); 0 for faces not measured. ``face_flips > 0``
        marks the flipped faces (what the add-on's *Select Flipped Faces* selects)."""
    def as_dict(self) -> dict[str, Any]:
        """All fields as a plain dict."""

def unwrap(
    positions: _Floats,
    corner_verts: _Ints,
    face_sizes: _Ints,
    *,
    method: Method = "abf",
    seams: _Ints | None = None,
    selected: _Bools | None = None,
    pins: _Ints | None = None,
    pin_uvs: _Floats | None = None,
    fit_to: _Floats | None = None,
    triangles: _Ints | None = None,
    auto_seams: bool = True,
    max_stretch: float = 2.0,
    max_cones: int = 8,
    avoid_vertices: _Ints | None = None,
    sharp_angle: float | None = None,
    visibility_weight: float = 1.0,
    symmetry: Symmetry = "none",
    same_seams: bool = False,
    progress: Callable[[int, int], bool | None] | None = None,
    **options: Unpack[UnwrapOptions],
) -> UnwrapResult:
    """Unwrap the selected faces of a polygon mesh into per-corner UVs.

    The selection is split into charts along seams, non-manifold edges and the selection
    border; every chart is mapped by ``method`` (charts in parallel, without the GIL).
    With ``auto_seams`` (the default), a closed chart or a chart with handles is cut open
    through a few cone singularities (its new seams are in ``new_seams``; a chart whose
    flattening still flips, overlaps or stretches beyond ``max_stretch`` gets more cones or is
    split). Charts that cannot be mapped are not errors: they come back with
    ``status == "failed"`` and a ``reason``, and their faces get no UVs.

    Args:
        positions: (V, 3) vertex positions.
        corner_verts: (C,) vertex index of every corner, faces one after another.
        face_sizes: (F,) corners per face (each >= 3), summing to C.
        method: one of :data:`METHODS`.
        seams: (E, 2) seam edges as vertex pairs (either order).
        selected: (F,) faces to unwrap; default all. Unselected faces get chart -1.
        pins: (P,) corner indices whose UVs are fixed.
        pin_uvs: (P, 2) the UVs of the pinned corners (required with ``pins``).
        fit_to: (C, 2) previous UVs: each unpinned chart is fitted (scale, rotation,
            translation) onto them instead of being area-scaled at the origin.
        triangles: (T, 3) the render triangulation as corner index triples (Blender's
            ``mesh.loop_triangles`` ``loops``): faces of 4+ corners are split this way
            instead of by the core's own ear clipping, so flips are counted (and avoided)
            on the triangles Blender shows. Every face needs exactly corners - 2 rows.
            Quads count as folded (``flips``) when either diagonal split has a flipped
            triangle, with or without this argument.
        **options: the method's own options, see :class:`UnwrapOptions`: tutte, harmonic,
            mean_value: ``boundary``; lscm, bff: none; spectral, arap, mips, scaffold:
            ``max_iterations``, ``tolerance``; slim: those and ``start``; abf: ``solver``,
            ``boundary``, ``max_iterations``, ``tolerance`` and ``angle_sums=(vertices, sums)``
            ((K,) mesh vertex indices and (K,) angle sums in radians that the flattened map
            must have there; every chart copy of a vertex split by a seam gets the sum; on the
            boundary pi keeps the outline straight and pi/2 makes a right-angled corner; at an
            interior vertex a sum other than 2*pi is a cone, realised exactly when a seam runs
            from it to the boundary).
        progress: ``callable(charts_done, charts_total)`` called from the worker threads with
            the GIL held, at most every 0.1 s and after the last chart; returning ``False``
            cancels (raises :class:`Cancelled`), an exception it raises cancels and is
            re-raised. Polled between charts and between iterations of iterative methods.
        auto_seams: cut closed and higher-genus charts automatically (default True); with
            False they fail with a "mark seams" reason.
        max_stretch: how much the length scale may vary inside one island before another
            cone (or, past ``max_cones``, a split) is added; > 1, default 2.0.
        max_cones: most cone singularities per chart (default 8; a closed sphere gets at
            least 2).
        avoid_vertices: (K,) mesh vertex indices where seams must not go (no cut edge touches
            them and none becomes a cone).
        sharp_angle: dihedral angle in radians from which an edge counts as sharp and is
            preferred for seams; default None (no preference).
        visibility_weight: how much dearer a seam is on exposed surface than in hidden
            places, 0 to 100 (default 1.0: a fully exposed edge costs twice a fully occluded
            one; 0 turns it off). Exposure is per-vertex ambient occlusion (32 rays from each
            vertex against the mesh near the chart).
        symmetry: mirror plane the seams keep: "none" (default), "x", "y", "z" (across that
            axis through the chart's centre) or "auto" (a principal axis). On a chart that is
            its own mirror image cut costs and cones are mirrored, and a closed chart without
            handles is cut on one half and the cut mirrored, so its seams map onto themselves
            (a last-resort split is not); other charts are cut as without it.
        same_seams: plan the cuts of "slim", "arap" and "scaffold" on the same
            method-independent prediction as the other methods (default False), so switching
            methods keeps the seams wherever the new method keeps the rule on them. Off, those
            three start from the cones alone and usually get fewer seams and islands.

    Raises:
        InputError: wrong shape, dtype or length; a non-finite ``fit_to`` UV.
        VertexIndexError, NonFiniteError, FaceSizeError, RepeatedVertexError, SeamError:
            malformed mesh (all subclasses of MeshError).
        TriangleError: a ``triangles`` row names a missing corner, corners of two faces,
            or a face does not get exactly corners - 2 rows triangulating it (a MeshError).
        PinError: a pin names a missing corner or has a non-finite UV.
        OptionError: unknown method, unknown option or bad option value (``err.option``
            names it; the automatic-seams options' domains are in :data:`AUTO_SEAM_OPTIONS`).
        AngleSumError: a bad ``angle_sums`` entry (an OptionError naming entry and vertex).
        Cancelled: the progress callback returned ``False``.
        UvflatError: an internal error (a bug), never a crash.
    """

def factorization_seconds(
    positions: _Floats,
    corner_verts: _Ints,
    face_sizes: _Ints,
    *,
    method: str = "lscm",
    seams: _Ints | None = None,
    selected: _Bools | None = None,
    **options: bool | int | float | str,
) -> float | None:
    """Seconds of one sparse factorization (symbolic analysis + numeric) of the linear system
    each chart's unwrap solves with ``method``, summed over the charts that can be mapped.

    ``None`` for methods that are not a single linear solve (only ``tutte``, ``harmonic``,
    ``mean_value``, ``lscm`` and ``bff`` are). Assembly is not included: an unwrap that costs about
    this much is dominated by the factorization.
    """

def island_hulls(
    uv: _Floats,
    face_sizes: _Ints,
    face_island: _Ints,
    *,
    selected: _Bools | None = None,
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Convex hull of every island of a per-corner UV map, for island packing.

    Island ``k`` holds the faces with ``face_island == k`` (and ``selected``, if given; a
    negative ``face_island`` puts a face in no island, like ``UnwrapResult.chart``); its
    hull is the convex hull of all their corner UVs, counter-clockwise, without collinear or
    repeated vertices (Andrew's monotone chain). Islands run in parallel.

    Args:
        uv: (C, 2) UV of every corner.
        face_sizes: (F,) corners per face.
        face_island: (F,) island of every face, numbered below ``F``.
        selected: (F,) faces that belong to their island; default all.

    Returns:
        ``(offsets, points)``: island ``k``'s hull is ``points[offsets[k]:offsets[k + 1]]``
        (``offsets`` has one more entry than the largest island number). A hull is empty when
        its island spans no area or holds a non-finite UV.

    Raises:
        InputError: wrong shape, dtype or length, or an island number not below ``F`` (the
            message names the face).
    """

def island_box_angles(
    uv: _Floats,
    face_sizes: _Ints,
    face_island: _Ints,
    *,
    selected: _Bools | None = None,
) -> npt.NDArray[np.float64]:
    """The turn of every island of a per-corner UV map to its bounding box of least area.

    Islands are numbered as in :func:`island_hulls`, and each is measured by its convex hull:
    the least-area box of a convex polygon has a side along one of its edges, and rotating
    calipers find it in one walk round the hull (Freeman & Shapira 1975; Toussaint 1983).
    Islands run in parallel.

    Args:
        uv: (C, 2) UV of every corner.
        face_sizes: (F,) corners per face.
        face_island: (F,) island of every face, numbered below ``F``.
        selected: (F,) faces that belong to their island; default all.

    Returns:
        float64 rotation of every island (one more than the largest island number, one per
        hull of ``island_hulls``), radians counter-clockwise, in ``[-pi/4, pi/4)`` (a quarter
        turn more or less gives the same box on its side). Exactly 0 for an island whose box
        as it lies is within a factor ``1 + 1e-6`` of the least, and for one whose hull is
        empty (no area, or a non-finite UV).

    Raises:
        InputError: wrong shape, dtype or length, or an island number not below ``F`` (the
            message names the face).
    """

def plan_seams(
    positions: _Floats,
    corner_verts: _Ints,
    face_sizes: _Ints,
    *,
    method: Method = "abf",
    seams: _Ints | None = None,
    selected: _Bools | None = None,
    pins: _Ints | None = None,
    pin_uvs: _Floats | None = None,
    fit_to: _Floats | None = None,
    triangles: _Ints | None = None,
    auto_seams: bool = True,
    max_stretch: float = 2.0,
    max_cones: int = 8,
    avoid_vertices: _Ints | None = None,
    sharp_angle: float | None = None,
    visibility_weight: float = 1.0,
    symmetry: Symmetry = "none",
    same_seams: bool = False,
    progress: Callable[[int, int], bool | None] | None = None,
    **options: Unpack[UnwrapOptions],
) -> npt.NDArray[np.uint32]:
    """The seams :func:`unwrap` would add with the same arguments, without any UVs: (S, 2)
    mesh vertex pairs ``[a, b]``, ``a < b``, sorted (exactly ``unwrap(...).new_seams``).
    Raises the errors of :func:`unwrap`."""

def metrics(
    positions: _Floats,
    corner_verts: _Ints,
    face_sizes: _Ints,
    uv: _Floats,
    *,
    selected: _Bools | None = None,
    triangles: _Ints | None = None,
) -> Metrics:
    """Measure a per-corner UV map: islands, flipped triangles, overlaps and distortion.

    Islands are faces connected through edges whose two corner UVs agree at both ends.
    Uses the same definitions as the per-chart reports of :func:`unwrap`, so numbers compare.

    Args:
        positions: (V, 3) vertex positions.
        corner_verts: (C,) vertex index of every corner.
        face_sizes: (F,) corners per face.
        uv: (C, 2) UV of every corner.
        selected: (F,) faces to measure; default all.
        triangles: (T, 3) the render triangulation (see :func:`unwrap`); n-gons are
            measured on these triangles. A quad counts as folded when either of its
            diagonal splits has a flipped triangle (not strictly convex in UV).

    Raises:
        InputError: wrong shape, dtype or length; a non-finite UV (``err.corner``).
        MeshError: malformed mesh (see :func:`unwrap`).
    """

class UvflatError(Exception):
    """Base class of every error raised by uvflat."""

class InputError(UvflatError, ValueError):
    """An argument has the wrong type, dtype, shape or length, or a UV is not finite."""

    argument: str | None
    """Name of the offending argument."""
    shape: tuple[int, ...] | None
    """Shape received, for shape errors."""
    corner: int | None
    """Corner of a non-finite UV, if that is the problem."""

class MeshError(UvflatError, ValueError):
    """The mesh itself is malformed; the subclass says how."""

class VertexIndexError(MeshError):
    """A corner refers to a vertex index outside 0..n_vertices."""

    face: int | None
    corner: int
    vertex: int
    """The bad vertex index as given (may be negative)."""
    n_vertices: int

class NonFiniteError(MeshError):
    """A vertex position is NaN or infinite."""

    vertex: int
    value: float

class FaceSizeError(MeshError):
    """A face has fewer than three corners (or an impossible size)."""

    face: int
    size: int

class RepeatedVertexError(MeshError):
    """A face uses the same vertex more than once."""

    face: int
    vertex: int

class SeamError(MeshError):
    """A seam refers to a vertex index outside 0..n_vertices."""

    seam: int
    """Row of ``seams``."""
    vertex: int
    n_vertices: int

class TriangleError(MeshError):
    """A row of ``triangles`` names a missing corner, corners of two faces or one corner
    twice, or a face is not triangulated by exactly corners - 2 of its rows."""

    triangle: int
    """Row of ``triangles``."""
    corners: list[int] | None
    """The row's corners."""
    reason: str
    """What is wrong."""

class PinError(UvflatError, ValueError):
    """A pin refers to a corner that does not exist, or its UV is not finite."""

    pin: int
    """Row of ``pins``."""
    corner: int
    n_corners: int | None

class OptionError(UvflatError, ValueError):
    """Unknown method, unknown option, or an option value outside its domain."""

    option: str
    """Name of the option ("method" for an unknown method)."""
    reason: str

class AngleSumError(OptionError):
    """A prescribed angle sum (abf's ``angle_sums``) names a vertex that does not exist, is not
    used by a face or is listed twice, or its sum is not finite, not positive, or not below
    2*pi times the vertex's number of face corners."""

    entry: int
    """Position in the ``angle_sums`` arrays."""
    vertex: int
    """The mesh vertex named by that entry."""
    value: float | None
    """The prescribed sum (None when the index itself could not be read)."""

class Cancelled(UvflatError):
    """The unwrap was cancelled by its progress callback (it returned False); no UVs."""

    charts_done: int
    charts_total: int
