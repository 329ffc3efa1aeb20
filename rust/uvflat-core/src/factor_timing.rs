//! How long one sparse factorization of each chart's own linear system takes: the yardstick
//! the linear methods are measured against ("an unwrap costs about one factorization").

use crate::charts::build_charts;
use crate::error::Result;
use crate::methods::fixed_boundary::{fill_holes, laplacian_triplets, Weights};
use crate::methods::{chart_angles, lscm, require_disk, Method};
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};
use crate::unwrap::MeshInput;

/// Seconds spent by one symbolic analysis plus numeric factorization of the system each
/// linear method solves, summed over the mappable charts of the selection: the Laplacian with
/// the outer boundary fixed (Cholesky for tutte/harmonic/bff, LU for mean value), or the complex
/// LSCM matrix with two pins (Cholesky). Assembly is not included.
///
/// Returns `None` for methods that are not a single linear solve. Errors: the input validation
/// errors of [`crate::unwrap`]. Charts that cannot be mapped are skipped.
pub fn factorization_seconds(input: &MeshInput<'_>, method: &Method) -> Result<Option<f64>> {
    let mesh = crate::validate::validate_input(input, None, Some(method))?;
    let weights = match method {
        Method::Tutte { .. } => Some(Weights::Uniform),
        Method::Harmonic { .. } | Method::Bff => Some(Weights::Cotangent),
        Method::MeanValue { .. } => Some(Weights::MeanValue),
        Method::Lscm => None,
        _ => return Ok(None),
    };
    let mut total = 0.0;
    for chart in build_charts(&mesh, input.seams, input.selected) {
        if require_disk(&chart).is_err() {
            continue;
        }
        match weights {
            Some(w) => {
                let ext = fill_holes(&chart);
                let trip = laplacian_triplets(&ext.positions, &ext.triangles, w);
                let sym = if w == Weights::MeanValue { Symmetry::General } else { Symmetry::Symmetric };
                let t = std::time::Instant::now();
                let ok = FixedValueSolver::with_ordering(ext.positions.len(), &trip, &ext.outer, sym, OrderingKind::Amd).is_ok();
                if ok {
                    total += t.elapsed().as_secs_f64();
                }
            }
            None => {
                let angles = chart_angles(&chart.positions, &chart.triangles);
                let trip = lscm::conformal_hermitian(&chart.triangles, &angles);
                let pins = lscm::auto_pins(&chart);
                let t = std::time::Instant::now();
                let ok = FixedValueSolver::with_ordering(chart.positions.len(), &trip, &[pins[0].0, pins[1].0], Symmetry::Symmetric, OrderingKind::Amd).is_ok();
                if ok {
                    total += t.elapsed().as_secs_f64();
                }
            }
        }
    }
    Ok(Some(total))
}
