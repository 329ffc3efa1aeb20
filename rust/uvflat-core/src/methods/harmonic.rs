//! `harmonic`: fixed-boundary barycentric map with cotangent weights ½(cot α + cot β), the discrete Dirichlet energy. Weights are negative across obtuse angle pairs, so unlike Tutte and mean value there is no no-flip guarantee; the report counts flips.
//!
//! Paper: M. Eck, T. DeRose, T. Duchamp, H. Hoppe, M. Lounsbery, W. Stuetzle, "Multiresolution analysis of arbitrary meshes", SIGGRAPH 1995 (discrete harmonic map).
//!
//! Preconditions: a disk chart (holes are filled virtually, see [`super::fixed_boundary`]).
//! Failures: a singular system (disconnected chart) becomes a chart failure.

use super::fixed_boundary::{self, Weights};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::methods::BoundaryShape;

/// Map one chart; the outer boundary goes to `shape`.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], shape: BoundaryShape) -> Result<ChartSolution, ChartFailure> {
    fixed_boundary::solve(chart, pins, shape, Weights::Cotangent)
}
