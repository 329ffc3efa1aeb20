//! Typed errors. Every variant names the offending element so a user can find it.

use thiserror::Error;

/// Everything that can go wrong before or around an unwrap.
///
/// Per-chart solve failures are *not* errors: they are reported in
/// [`crate::ChartReport`] with [`crate::ChartStatus::Failed`] and a reason, so one
/// bad chart never loses the others.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum UvError {
    /// An array has the wrong length or shape.
    #[error("{what}: {detail}")]
    Shape { what: &'static str, detail: String },
    /// A face's corner refers to a vertex that does not exist.
    #[error("face {face}, corner {corner}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)")]
    VertexIndex { face: usize, corner: usize, vertex: u64, n_vertices: usize },
    /// A vertex position is NaN or infinite.
    #[error("vertex {vertex}: non-finite coordinate {value}")]
    NonFinitePosition { vertex: usize, value: f64 },
    /// A face has fewer than three corners.
    #[error("face {face}: has {size} corners, at least 3 are needed")]
    FaceTooSmall { face: usize, size: u64 },
    /// A face uses the same vertex twice.
    #[error("face {face}: vertex {vertex} appears more than once")]
    RepeatedVertex { face: usize, vertex: usize },
    /// A seam refers to a vertex that does not exist.
    #[error("seam {seam}: vertex index {vertex} out of range (mesh has {n_vertices} vertices)")]
    SeamIndex { seam: usize, vertex: u64, n_vertices: usize },
    /// A pin refers to a corner that does not exist.
    #[error("pin {pin}: corner index {corner} out of range (mesh has {n_corners} corners)")]
    PinIndex { pin: usize, corner: u64, n_corners: usize },
    /// A pinned UV is NaN or infinite.
    #[error("pin {pin} (corner {corner}): non-finite UV")]
    NonFinitePin { pin: usize, corner: usize },
    /// A UV coordinate handed to a metric or fit is NaN or infinite.
    #[error("corner {corner}: non-finite UV")]
    NonFiniteUv { corner: usize },
    /// An option has a value outside its domain.
    #[error("option {name}: {reason}")]
    Option { name: String, reason: String },
    /// A prescribed angle sum (ABF option `angle_sums`) names a bad vertex or has a bad value.
    #[error("option angle_sums, entry {entry} (vertex {vertex}, sum {value}): {reason}")]
    AngleSum { entry: usize, vertex: u64, value: f64, reason: String },
    /// The unwrap was cancelled through its [`Progress`](crate::Progress); no UVs.
    #[error("cancelled after {charts_done} of {charts_total} charts")]
    Cancelled { charts_done: usize, charts_total: usize },
    /// A triple of the render triangulation (`triangles`) names a bad corner, mixes faces, or
    /// its face is not covered by exactly `corners − 2` triangles.
    #[error("triangles[{triangle}] {corners:?}: {reason}")]
    RenderTriangle { triangle: usize, corners: [u64; 3], reason: String },
}

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, UvError>;
