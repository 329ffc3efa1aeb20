//! `mean_value`: fixed-boundary barycentric map with mean value weights (tan(γ/2) + tan(δ/2)) / |x_j − x_i|: positive for every triangulation, so on the default circle boundary no triangle flips, while staying closer to conformal than Tutte. Quads and n-gons use their corner angles as polygons (their diagonals are not edges), so they come out convex, positive under any triangulation (see [`super::fixed_boundary::laplacian_triplets_with_polygons`]). The system is not symmetric and is solved by sparse LU.
//!
//! Paper: M. S. Floater, "Mean value coordinates", CAGD 20(1), 2003.
//!
//! [`solve_lean`] computes the same map without a general LU, for the starts of the barrier
//! methods on large charts: the sparse LU of the non-symmetric system is the largest
//! allocation of such a start (about 1.7 KB per triangle). It factors the symmetric part
//! instead (a graph Laplacian with the averaged weights `(w_ij + w_ji)/2`, positive definite
//! with the boundary fixed, by Cholesky: about a sixth of the LU's memory) and solves the mean
//! value system by iterative refinement preconditioned by it:
//! `x ← x + S⁻¹ (b − A x)` from the symmetric map `x = S⁻¹ b`. The weights of a vertex's two
//! directions differ only by the ratio of the tangent sums of the edge's two ends, so `S⁻¹A`
//! is close to the identity and the iteration contracts fast (a few tens of iterations to the
//! LU's precision on the meshes of the test set). When it does not contract, the LU solve is
//! used after all.
//!
//! Preconditions: a disk chart (holes are filled virtually, see [`super::fixed_boundary`]).
//! Failures: a singular system (disconnected chart) becomes a chart failure.

use super::fixed_boundary::{self, Weights};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::methods::BoundaryShape;
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};

/// Map one chart; the outer boundary goes to `shape`.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], shape: BoundaryShape) -> Result<ChartSolution, ChartFailure> {
    fixed_boundary::solve(chart, pins, shape, Weights::MeanValue)
}

/// Refinement stops when the largest update is below this, relative to the largest |UV|.
pub const REFINEMENT_TOLERANCE: f64 = 1e-12;
/// Most refinement steps before [`solve_lean`] falls back to the LU solve.
pub const MAX_REFINEMENTS: usize = 200;

/// [`solve`] with the boundary on a circle, by iterative refinement on the Cholesky
/// factorization of the system's symmetric part (module docs) instead of sparse LU: the same
/// map to about [`REFINEMENT_TOLERANCE`] relative, with a fraction of the memory. Falls back
/// to [`solve`] when the refinement does not converge in [`MAX_REFINEMENTS`] steps.
///
/// Pins as [`solve`] (the circle map moved onto them by a similarity, then solved again with
/// the pins fixed). Failures: as [`solve`].
pub fn solve_lean(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    match solve_refined(chart, pins) {
        Ok(Some(sol)) => Ok(sol),
        Ok(None) | Err(_) => solve(chart, pins, BoundaryShape::Circle),
    }
}

/// The refinement solve of [`solve_lean`]; `None` when it did not converge.
fn solve_refined(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<Option<ChartSolution>, SolveError> {
    let ext = fixed_boundary::fill_holes(chart);
    let n = ext.positions.len();
    let bnd = fixed_boundary::boundary_positions(&ext.positions, &ext.outer, BoundaryShape::Circle);
    let system = Refinement::new(n, fixed_boundary::laplacian_triplets_with_polygons(&ext.positions, &ext.triangles, &chart.polygons, Weights::MeanValue));
    let Some(mut uv) = system.solve(&ext.outer, &bnd)? else {
        return Ok(None);
    };
    let mut sol = ChartSolution::direct(Vec::new());
    if !pins.is_empty() {
        // As `fixed_boundary::solve`: move the map onto the pins, then fix boundary and pins.
        let mut target = vec![[f64::NAN; 2]; uv.len()];
        for &(v, p) in pins {
            target[v as usize] = p;
        }
        let moved = super::lscm::pins_span(pins) && crate::metrics::fit_similarity_points(&mut uv, &target);
        if !moved {
            let (v, p) = pins[0];
            let d = [p[0] - uv[v as usize][0], p[1] - uv[v as usize][1]];
            for q in uv.iter_mut() {
                *q = [q[0] + d[0], q[1] + d[1]];
            }
        }
        let mut fixed: Vec<u32> = ext.outer.clone();
        let mut vals: Vec<[f64; 2]> = ext.outer.iter().map(|&v| uv[v as usize]).collect();
        for &(v, p) in pins {
            if let Some(k) = fixed.iter().position(|&f| f == v) {
                vals[k] = p;
            } else {
                fixed.push(v);
                vals.push(p);
            }
        }
        let Some(pinned) = system.solve(&fixed, &vals)? else {
            return Ok(None);
        };
        uv = pinned;
        sol.note = Some(format!("{} pinned vertex(es) fixed; the boundary circle was moved onto them by a similarity", pins.len()));
    }
    uv.truncate(chart.positions.len());
    sol.uv = uv;
    Ok(Some(sol))
}

/// A weighted graph Laplacian `A` (rows sum to zero, off-diagonal entries ≤ 0, not
/// necessarily symmetric), kept as its off-diagonal entries by rows and its diagonal.
struct Refinement {
    n: usize,
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
    diag: Vec<f64>,
}

impl Refinement {
    /// From the triplets of `A` (duplicates summed).
    fn new(n: usize, trip: Vec<(u32, u32, f64)>) -> Self {
        let mut row_ptr = vec![0usize; n + 1];
        let mut diag = vec![0.0; n];
        for &(r, c, v) in &trip {
            if r == c {
                diag[r as usize] += v;
            } else {
                row_ptr[r as usize + 1] += 1;
            }
        }
        for r in 0..n {
            row_ptr[r + 1] += row_ptr[r];
        }
        let mut next = row_ptr.clone();
        let (mut col, mut val) = (vec![0u32; row_ptr[n]], vec![0.0; row_ptr[n]]);
        for &(r, c, v) in &trip {
            if r != c {
                let k = &mut next[r as usize];
                col[*k] = c;
                val[*k] = v;
                *k += 1;
            }
        }
        Refinement { n, row_ptr, col, val, diag }
    }

    /// Lower triangle of the symmetric part with zero row sums: off-diagonal entries
    /// `(a_ij + a_ji)/2`, diagonal minus their row sums.
    fn symmetric_part(&self) -> Vec<(u32, u32, f64)> {
        let mut diag = vec![0.0; self.n];
        let mut out = Vec::with_capacity(self.col.len() + self.n);
        for r in 0..self.n {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                let (c, v) = (self.col[k], 0.5 * self.val[k]);
                out.push(((r as u32).max(c), (r as u32).min(c), v));
                diag[r] -= v;
                diag[c as usize] -= v;
            }
        }
        out.extend(diag.iter().enumerate().map(|(i, &d)| (i as u32, i as u32, d)));
        out
    }

    /// Solve `A x = 0` on the unknowns not in `fixed`, with `fixed[k]` at `values[k]`; `None`
    /// when the refinement does not converge.
    fn solve(&self, fixed: &[u32], values: &[[f64; 2]]) -> Result<Option<Vec<[f64; 2]>>, SolveError> {
        let n = self.n;
        let s = FixedValueSolver::new(n, &self.symmetric_part(), fixed, Symmetry::Symmetric)?;
        let cols = vec![values.iter().map(|p| p[0]).collect::<Vec<_>>(), values.iter().map(|p| p[1]).collect::<Vec<_>>()];
        let mut x = s.solve(&cols, &[])?;
        let mut is_fixed = vec![false; n];
        for &f in fixed {
            is_fixed[f as usize] = true;
        }
        let zeros = vec![vec![0.0; fixed.len()]; 2];
        let mut r = vec![vec![0.0; n]; 2];
        let mut last = f64::INFINITY;
        let mut growing = 0;
        for _ in 0..MAX_REFINEMENTS {
            for c in 0..2 {
                let xc = &x[c];
                for i in 0..n {
                    r[c][i] = if is_fixed[i] {
                        0.0
                    } else {
                        let (a, b) = (self.row_ptr[i], self.row_ptr[i + 1]);
                        let off: f64 = self.col[a..b].iter().zip(&self.val[a..b]).map(|(&j, &v)| v * xc[j as usize]).sum();
                        -(self.diag[i] * xc[i] + off)
                    };
                }
            }
            let d = s.solve(&zeros, &r)?;
            let (mut step, mut size) = (0.0f64, 0.0f64);
            for c in 0..2 {
                for i in 0..n {
                    x[c][i] += d[c][i];
                    step = step.max(d[c][i].abs());
                    size = size.max(x[c][i].abs());
                }
            }
            if !step.is_finite() {
                return Ok(None);
            }
            if step <= REFINEMENT_TOLERANCE * size {
                return Ok(Some((0..n).map(|i| [x[0][i], x[1][i]]).collect()));
            }
            // Diverging (S⁻¹A far from the identity): give up early.
            growing = if step > last { growing + 1 } else { 0 };
            if growing >= 3 {
                return Ok(None);
            }
            last = step;
        }
        Ok(None)
    }
}
