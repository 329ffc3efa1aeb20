//! `tutte`: fixed-boundary barycentric map with uniform weights (every neighbour counts 1). Guarantee: on the default circle boundary no triangle flips (Tutte's embedding theorem; positive weights, strictly convex boundary). The weights live on the polygon graph (an n-gon's diagonals are not edges), so quads and n-gons come out convex, positive under any triangulation (see [`super::fixed_boundary::laplacian_triplets_with_polygons`]).
//!
//! Paper: W. T. Tutte, "How to draw a graph", Proc. London Math. Soc. 1963.
//!
//! Preconditions: a disk chart (holes are filled virtually, see [`super::fixed_boundary`]).
//! Failures: a singular system (disconnected chart) becomes a chart failure.

use super::fixed_boundary::{self, Weights};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::methods::BoundaryShape;

/// Map one chart; the outer boundary goes to `shape`.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], shape: BoundaryShape) -> Result<ChartSolution, ChartFailure> {
    fixed_boundary::solve(chart, pins, shape, Weights::Uniform)
}
