//! What happened to one chart: a typed status and reason ([`ChartStatus`], [`Problem`]) beside
//! the prose for people, and the chart's measured quality ([`ChartReport`]).

use crate::charts::ChartKind;
use crate::metrics::{DensitySpread, Distortion};

/// Outcome of one chart.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ChartStatus {
    /// Mapped by the requested method, and the result keeps its promise (see [`Problem`]).
    Solved,
    /// Mapped, but by a fallback method; the report's `reason` says why.
    Fallback,
    /// Mapped (the UVs are written), but the result breaks the rule the chart was held to:
    /// flipped triangles, an outline that crosses itself, a chart that is not a disk, or
    /// (with automatic seams) texel density beyond Max Stretch. [`ChartReport::problem`] says
    /// which, the `reason` says how much.
    Invalid,
    /// Not mapped; the chart's corners carry no UVs and the report's `reason` says why.
    Failed,
}

impl ChartStatus {
    /// Stable lower-case name used by the Python layer.
    pub fn name(self) -> &'static str {
        match self {
            ChartStatus::Solved => "solved",
            ChartStatus::Fallback => "fallback",
            ChartStatus::Invalid => "invalid",
            ChartStatus::Failed => "failed",
        }
    }

    /// Whether the chart's corners received UVs.
    pub fn mapped(self) -> bool {
        self != ChartStatus::Failed
    }
}

/// Why a chart is not simply [`ChartStatus::Solved`]: one typed value, from which the stable
/// [`ChartReport::reason_code`] follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Problem {
    /// Failed: a closed surface with no boundary to open it along (automatic seams off).
    ClosedSurface,
    /// Failed: the surface has handles that seams must cut (automatic seams off).
    Handles,
    /// Failed: non-orientable, or a non-manifold vertex inside the chart.
    Defect,
    /// Failed: the method could not map the chart.
    Solver,
    /// Failed: every face of the chart is degenerate (no 3D area).
    NoArea,
    /// Mapped by a fallback method.
    FellBack,
    /// Invalid: flipped or zero-area UV triangles (on the triangles Blender renders; a quad
    /// counts when either diagonal split folds).
    Flips,
    /// Invalid: the island's outline crosses itself.
    Overlap,
    /// Invalid: the island is not a disk (it kept holes or handles).
    NotDisk,
    /// Invalid: more than the allowed share of the island has a texel density outside
    /// `[1/Max Stretch, Max Stretch]` of the island's own.
    Stretch,
}

impl Problem {
    /// Stable code of the problem (see [`ChartReport::reason_code`]).
    pub fn code(self) -> &'static str {
        match self {
            Problem::ClosedSurface => "failed_closed",
            Problem::Handles => "failed_genus",
            Problem::Defect => "failed_defect",
            Problem::Solver => "failed_solver",
            Problem::NoArea => "failed_no_area",
            Problem::FellBack => "fallback",
            Problem::Flips => "invalid_flips",
            Problem::Overlap => "invalid_overlap",
            Problem::NotDisk => "invalid_not_disk",
            Problem::Stretch => "invalid_stretch",
        }
    }
}

/// Per-chart report: what was done and how good the result is.
#[derive(Debug, Clone)]
pub struct ChartReport {
    /// Chart id, as in [`crate::Unwrapped::face_chart`].
    pub id: usize,
    /// Method that produced the UVs (the fallback's name when a fallback was used).
    pub method: &'static str,
    /// Number of input faces (polygons) in the chart.
    pub faces: usize,
    /// Number of triangles after n-gon triangulation.
    pub triangles: usize,
    /// Number of chart vertices (a vertex split by a seam counts once per side).
    pub vertices: usize,
    /// Number of boundary loops.
    pub boundary_loops: usize,
    /// Genus from the Euler characteristic.
    pub genus: usize,
    /// Topological class.
    pub kind: ChartKind,
    /// Solved, fallback, invalid or failed.
    pub status: ChartStatus,
    /// Why the chart is not simply solved (`None` when it is).
    pub problem: Option<Problem>,
    /// Why the chart failed, fell back or is invalid, or a note on how pins were honoured.
    pub reason: Option<String>,
    /// Iterations of an iterative method (0 for direct solves).
    pub iterations: usize,
    /// Final residual or energy change reported by the method (0 for direct solves).
    pub residual: f64,
    /// Flipped or zero-area UV triangles (see `metrics`). 0 for failed charts.
    pub flips: usize,
    /// Whether the chart's UV boundary crosses itself. `false` for failed charts.
    pub overlap: bool,
    /// Distortion of the solved map (all 1.0 is perfect); NaN for failed charts.
    pub distortion: Distortion,
    /// Texel-density spread against `[1/Max Stretch, Max Stretch]` (the automatic seams'
    /// `max_stretch`, also when they are off); NaN for failed charts.
    pub density: DensitySpread,
    /// Wall-clock seconds spent mapping this chart.
    pub seconds: f64,
    /// Cone singularities placed by automatic seams in this chart (0 when it was not cut).
    pub cones: usize,
    /// Total 3D length of the automatic seams made for this chart (0 when it was not cut).
    pub cut_length: f64,
}

impl ChartReport {
    /// Stable code of the chart's outcome, for programs (the prose `reason` is for people):
    /// `"solved"`, `"solved_with_note"` (e.g. how pins were honoured), or the code of its
    /// [`Problem`]: `"fallback"`, `"invalid_flips"`, `"invalid_overlap"`,
    /// `"invalid_not_disk"`, `"invalid_stretch"`, `"failed_closed"` (a closed surface: no
    /// boundary to open it along), `"failed_genus"` (handles: seams must cut them),
    /// `"failed_defect"` (non-orientable or a non-manifold vertex inside the chart),
    /// `"failed_no_area"`, `"failed_solver"` (the method could not map the chart).
    pub fn reason_code(&self) -> &'static str {
        match self.problem {
            Some(p) => p.code(),
            None if self.reason.is_none() => "solved",
            None => "solved_with_note",
        }
    }

    /// An empty report of `chart` (status failed, nothing measured), for `method`.
    pub(crate) fn new(chart: &crate::charts::Chart, method: &'static str) -> ChartReport {
        ChartReport {
            id: 0,
            method,
            faces: chart.faces.len(),
            triangles: chart.triangles.len(),
            vertices: chart.positions.len(),
            boundary_loops: chart.boundary_loops.len(),
            genus: chart.genus,
            kind: chart.kind,
            status: ChartStatus::Failed,
            problem: None,
            reason: None,
            iterations: 0,
            residual: 0.0,
            flips: 0,
            overlap: false,
            distortion: Distortion::nan(),
            density: DensitySpread::nan(),
            seconds: 0.0,
            cones: 0,
            cut_length: 0.0,
        }
    }
}
