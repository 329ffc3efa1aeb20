//! `mean_value`: fixed-boundary barycentric map with mean value weights (tan(γ/2) + tan(δ/2)) / |x_j − x_i|: positive for every triangulation, so on the default circle boundary no triangle flips, while staying closer to conformal than Tutte. Quads and n-gons use their corner angles as polygons (their diagonals are not edges), so they come out convex, positive under any triangulation (see [`super::fixed_boundary::laplacian_triplets_with_polygons`]). The system is not symmetric and is solved by sparse LU.
//!
//! Paper: M. S. Floater, "Mean value coordinates", CAGD 20(1), 2003.
//!
//! Preconditions: a disk chart (holes are filled virtually, see [`super::fixed_boundary`]).
//! Failures: a singular system (disconnected chart) becomes a chart failure.

use super::fixed_boundary::{self, Weights};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::methods::BoundaryShape;

/// Map one chart; the outer boundary goes to `shape`.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], shape: BoundaryShape) -> Result<ChartSolution, ChartFailure> {
    fixed_boundary::solve(chart, pins, shape, Weights::MeanValue)
}
