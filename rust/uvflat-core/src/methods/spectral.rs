//! Spectral conformal parameterization.
//!
//! Paper: P. Mullen, Y. Tong, P. Alliez, M. Desbrun, "Spectral Conformal Parameterization",
//! SGP 2008. Minimise the LSCM energy `w* Q w` (`w = u + iv`, [`lscm::conformal_hermitian`])
//! subject to `w* B w = 1` and `w` B-orthogonal to the constant maps, with `B` the boundary
//! mass (half the incident boundary edge lengths at each boundary vertex): the smallest
//! eigenvector of `Q w = λ B w`. No pins are needed, so the boundary is free of the arbitrary
//! choice LSCM makes.
//!
//! Solved by Lanczos ([`BoundaryIteration::lanczos`], [`super::boundary_eigen`]) on one sparse
//! Cholesky factorization of the Hermitian `Q + εB`: `max_iterations` bounds its solves, and
//! it has converged when the eigenvector's residual relative to its eigenvalue is at most
//! `tolerance`. The same eigenvector fixes LSCM's free map when no pins are given
//! ([`lscm::solve_free`]).
//!
//! Preconditions: a disk chart (holes allowed: all loops count as boundary). Pins: two or
//! more pinned vertices at distinct UVs make the chart an LSCM solve with those pins (the
//! report says so); one pin translates the result onto it. Failures: the chart has no
//! boundary, the factorization fails even with a larger shift, or the iteration produces
//! non-finite values.

use super::boundary_eigen::BoundaryIteration;
use super::{chart_angles, lscm, ChartFailure, ChartSolution, SpectralOptions};
use crate::charts::Chart;

/// Map one chart.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &SpectralOptions) -> Result<ChartSolution, ChartFailure> {
    if let Some(pinned) = lscm::instead_for_pins(chart, pins, "spectral") {
        return pinned;
    }
    let angles = chart_angles(&chart.positions, &chart.triangles);
    let mut it = BoundaryIteration::new(chart, lscm::conformal_hermitian(&chart.triangles, &angles))?;
    let (iterations, change) = it.lanczos(options.max_iterations, options.tolerance)?;
    let mut uv = it.uv();
    let note = super::nonlinear::pins::translate_onto_single_pin(&mut uv, pins, "spectral");
    let mut s = ChartSolution::direct(uv);
    s.iterations = iterations;
    s.residual = change;
    s.note = note;
    if change > options.tolerance {
        s.note = Some(format!(
            "spectral: not converged after {iterations} solves (relative residual {change:.1e})"
        ));
    }
    Ok(s)
}
