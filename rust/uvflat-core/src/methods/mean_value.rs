//! `mean_value`: fixed-boundary barycentric map with mean value weights (tan(γ/2) + tan(δ/2)) / |x_j − x_i|: positive for every triangulation, so on the default circle boundary no triangle flips, while staying closer to conformal than Tutte. Quads and n-gons use their corner angles as polygons (their diagonals are not edges), so they come out convex, positive under any triangulation (see [`super::fixed_boundary::laplacian_triplets_with_polygons`]). The system is not symmetric and is solved by sparse LU.
//!
//! Paper: M. S. Floater, "Mean value coordinates", CAGD 20(1), 2003.
//!
//! [`solve_lean`] computes the same map without a general LU, for the starts of the barrier
//! methods on large charts: the sparse LU of the non-symmetric system is the largest
//! allocation of such a start (about 1.7 KB per triangle). It factors the symmetric part
//! instead (a graph Laplacian with the averaged weights `(w_ij + w_ji)/2`, positive definite
//! with the boundary fixed, by Cholesky: a fraction of the LU's memory), starts from its map
//! and solves the mean value system by restarted GMRES (Y. Saad, M. H. Schultz, "GMRES: a
//! generalized minimal residual algorithm for solving nonsymmetric linear systems", SIAM J.
//! Sci. Stat. Comput. 7(3), 1986) right-preconditioned by that factorization, to a residual
//! of [`REFINEMENT_TOLERANCE`] relative to the right-hand side. The weights of an edge's two
//! directions differ only by the ratio of the tangent sums at its two ends, so the
//! preconditioned matrix is close to the identity: a few cycles on the meshes of the test
//! set, camelhead's sliver triangles included (a plain preconditioned Richardson iteration
//! stalls there). When it does not converge, the LU solve is used after all. The barrier
//! methods' start takes [`solve_start`]: the same iteration to [`START_TOLERANCE`] (a start
//! needs to be flip-free, not exact; the map is checked, and solved to full accuracy when the
//! check fails).
//!
//! Preconditions: a disk chart (holes are filled virtually, see [`super::fixed_boundary`]).
//! Failures: a singular system (disconnected chart) becomes a chart failure.

use super::fixed_boundary::{self, Weights};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::methods::BoundaryShape;
use crate::solvers::ordering::{Ordering, OrderingKind};
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};

/// Map one chart; the outer boundary goes to `shape`.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], shape: BoundaryShape) -> Result<ChartSolution, ChartFailure> {
    fixed_boundary::solve(chart, pins, shape, Weights::MeanValue)
}

/// The iteration stops when the residual of the mean value system is below this, relative
/// to its right-hand side (the coupling to the fixed boundary). Residuals stagnate around
/// 2e-14 from the third GMRES cycle on; 1e-14 made the iteration run two to four more cycles
/// to its stagnation test (camelhead split to 363k triangles: 9.2 s, now 6.0 s), and the map
/// stays within 1e-9 of the LU map (tests/lean_starts.rs).
pub const REFINEMENT_TOLERANCE: f64 = 1e-12;
/// Most GMRES restarts before [`solve_lean`] falls back to the LU solve.
pub const MAX_REFINEMENTS: usize = 40;
/// Krylov vectors per GMRES cycle (memory: this many vectors of the chart's size).
pub const GMRES_RESTART: usize = 20;

/// [`solve`] with the boundary on a circle, by GMRES preconditioned with the Cholesky
/// factorization of the system's symmetric part (module docs) instead of sparse LU: the same
/// map up to rounding (residual [`REFINEMENT_TOLERANCE`] relative), with a fraction of the
/// memory. Falls back to [`solve`] when the iteration does not converge in
/// [`MAX_REFINEMENTS`] restarts.
///
/// Pins as [`solve`] (the circle map moved onto them by a similarity, then solved again with
/// the pins fixed). Failures: as [`solve`].
pub fn solve_lean(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    match solve_by_refinement(chart, pins) {
        Ok(Some(sol)) => Ok(sol),
        Ok(None) | Err(_) => solve(chart, pins, BoundaryShape::Circle),
    }
}

/// The iteration of [`solve_start`] stops when the residual is below this, relative to the
/// right-hand side. On camelhead split to 363k triangles the first GMRES cycle ends at 6e-8–7e-8
/// (from 1.7e-2 at the symmetric part's map), a second reaches 4e-13–5e-13; the start's
/// symmetric Dirichlet energy is the same to seven digits (7.903355) and SLIM takes the same 7
/// iterations to the same minimum (1.856991) from either, so the second cycle (2.3 s of the
/// start's 6.0 s) bought nothing.
///
/// A solve to this accuracy factors the symmetric part in single precision on large charts
/// ([`FixedValueSolver::approximate_with`]) and preconditions GMRES with that factor applied
/// once, unrefined ([`FixedValueSolver::apply_factor`]): GMRES, whose residual is computed in
/// double precision at every restart, makes up for the factor's rounding as it does for the
/// system's asymmetry. On the large charts of the bunny subdivided twice and three times and
/// of camelhead subdivided twice, cut by automatic seams (111k–136k triangles), the start took
/// 0.30–0.38 s against 0.35–0.56 s in double precision, and SLIM's iterations did not change.
pub const START_TOLERANCE: f64 = 1e-6;

/// [`solve_lean`] to [`START_TOLERANCE`], for the starting map of the barrier methods (SLIM,
/// scaffold, MIPS) on large charts: a start needs to be flip-free, not exact. The map is
/// checked: when a triangle is not positively oriented, a boundary crosses itself or a quad is
/// not convex (none of which the exact map has), it is solved again by [`solve_lean`].
pub fn solve_start(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    if let Ok(Some(sol)) = solve_refined(chart, pins, START_TOLERANCE) {
        if super::lscm::folds(chart, &sol.uv) == (0, false) && super::nonconvex_quads(chart, &sol.uv) == 0 {
            return Ok(sol);
        }
    }
    solve_lean(chart, pins)
}

/// The iterative solve of [`solve_lean`] alone: `None` when it did not converge in
/// [`MAX_REFINEMENTS`] GMRES restarts. Failures: a symmetric part that cannot be
/// factored (disconnected chart).
pub fn solve_by_refinement(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<Option<ChartSolution>, ChartFailure> {
    solve_refined(chart, pins, REFINEMENT_TOLERANCE).map_err(|e| ChartFailure(format!("mean value: {e}")))
}

/// The map by GMRES to `tolerance` (relative residual), `None` when it did not converge.
fn solve_refined(chart: &Chart, pins: &[(u32, [f64; 2])], tolerance: f64) -> Result<Option<ChartSolution>, SolveError> {
    let ext = fixed_boundary::fill_holes(chart);
    let n = ext.positions.len();
    let bnd = fixed_boundary::boundary_positions(&ext.positions, &ext.outer, BoundaryShape::Circle);
    let system = Refinement::new(n, fixed_boundary::laplacian_triplets_with_polygons(&ext.positions, &ext.triangles, &chart.polygons, Weights::MeanValue));
    // The symmetric part's graph is the chart's vertex graph when no hole was filled: the
    // chart's elimination order, when another system of the chart (LSCM) computed it, serves.
    let ordering =
        if n == chart.positions.len() { chart.ordering_if_known(OrderingKind::Amd) } else { OrderingKind::Amd.into() };
    let Some(mut uv) = system.solve(&ext.outer, &bnd, tolerance, ordering)? else {
        return Ok(None);
    };
    let mut sol = ChartSolution::direct(Vec::new());
    if !pins.is_empty() {
        // As `fixed_boundary::solve`: move the map onto the pins, then fix boundary and pins.
        let (fixed, vals) = super::fixed_boundary::onto_pins(&mut uv, &ext.outer, pins);
        let Some(pinned) = system.solve(&fixed, &vals, tolerance, ordering)? else {
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

    /// `A z` on the rows not fixed (0 on fixed rows).
    fn apply(&self, z: &[f64], is_fixed: &[bool], out: &mut [f64]) {
        for i in 0..self.n {
            out[i] = if is_fixed[i] {
                0.0
            } else {
                let (a, b) = (self.row_ptr[i], self.row_ptr[i + 1]);
                let off: f64 = self.col[a..b].iter().zip(&self.val[a..b]).map(|(&j, &v)| v * z[j as usize]).sum();
                self.diag[i] * z[i] + off
            };
        }
    }

    /// Solve `A x = 0` on the unknowns not in `fixed`, with `fixed[k]` at `values[k]`; `None`
    /// when the iteration does not converge. `ordering`: that of the symmetric part's
    /// Cholesky factorization.
    ///
    /// Start: the symmetric part's solution. Then restarted GMRES (Saad & Schultz 1986) on the
    /// free unknowns, right-preconditioned by the symmetric part's Cholesky factorization,
    /// until the true residual is below `tolerance` relative to the right-hand side (or
    /// stagnates below its square root).
    fn solve(
        &self,
        fixed: &[u32],
        values: &[[f64; 2]],
        tolerance: f64,
        ordering: Ordering<'_>,
    ) -> Result<Option<Vec<[f64; 2]>>, SolveError> {
        let n = self.n;
        // Factored once, solved on every GMRES step: AMD (see `solvers::ordering`), or the
        // chart's own order of its vertices.
        // A start's accuracy: single precision where it pays, see `START_TOLERANCE`.
        let approximate = tolerance >= START_TOLERANCE;
        let symmetric = self.symmetric_part();
        let s = if approximate {
            FixedValueSolver::approximate_with(n, &symmetric, fixed, Symmetry::Symmetric, ordering)?
        } else {
            FixedValueSolver::with_ordering(n, &symmetric, fixed, Symmetry::Symmetric, ordering)?
        };
        drop(symmetric);
        let cols = vec![values.iter().map(|p| p[0]).collect::<Vec<_>>(), values.iter().map(|p| p[1]).collect::<Vec<_>>()];
        let x = if approximate {
            // The symmetric part's map to a few digits: GMRES goes on from there.
            let zero = vec![0.0; n];
            cols.iter().map(|c| s.solve_inexact(c, &[], &zero, 1e-3)).collect::<Result<Vec<_>, _>>()?
        } else {
            s.solve(&cols, &[])?
        };
        let mut is_fixed = vec![false; n];
        for &f in fixed {
            is_fixed[f as usize] = true;
        }
        // Right-hand side scale: A_FC x_C, the coupling to the fixed values.
        let mut out = Vec::with_capacity(2);
        for mut xc in x {
            let mut only_fixed = vec![0.0; n];
            for &f in fixed {
                only_fixed[f as usize] = xc[f as usize];
            }
            let mut b = vec![0.0; n];
            self.apply(&only_fixed, &is_fixed, &mut b);
            drop(only_fixed);
            let scale = b.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !self.gmres(&s, approximate, fixed.len(), &is_fixed, &mut xc, scale, tolerance)? {
                return Ok(None);
            }
            out.push(xc);
        }
        Ok(Some((0..n).map(|i| [out[0][i], out[1][i]]).collect()))
    }

    /// Restarted, right-preconditioned GMRES on `A_FF δ = −(A x)_F`, updating `x` in place;
    /// `once`: the preconditioner is `s`'s factor applied once, unrefined.
    #[allow(clippy::too_many_arguments)]
    fn gmres(
        &self,
        s: &FixedValueSolver,
        once: bool,
        n_fixed: usize,
        is_fixed: &[bool],
        x: &mut [f64],
        scale: f64,
        tolerance: f64,
    ) -> Result<bool, SolveError> {
        let n = self.n;
        let zeros = vec![vec![0.0; n_fixed]];
        let norm = |v: &[f64]| v.iter().map(|a| a * a).sum::<f64>().sqrt();
        let precondition = |v: &[f64]| -> Result<Vec<f64>, SolveError> {
            if once {
                return s.apply_factor(v);
            }
            Ok(s.solve(&zeros, &[v.to_vec()])?.pop().unwrap_or_default())
        };
        let mut r = vec![0.0; n];
        let mut best = f64::INFINITY;
        let mut stalled = 0;
        for _ in 0..MAX_REFINEMENTS {
            self.apply(x, is_fixed, &mut r);
            for v in r.iter_mut() {
                *v = -*v;
            }
            let beta = norm(&r);
            if !beta.is_finite() {
                return Ok(false);
            }
            if beta <= tolerance * scale || beta == 0.0 {
                return Ok(true);
            }
            // Stagnation at rounding level: accept below √tolerance, else give up.
            if beta > 0.5 * best {
                stalled += 1;
                if stalled >= 2 {
                    return Ok(beta <= tolerance.sqrt() * scale);
                }
            } else {
                stalled = 0;
            }
            best = best.min(beta);
            // Arnoldi with modified Gram–Schmidt and Givens rotations.
            let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / beta).collect()];
            let mut h: Vec<Vec<f64>> = Vec::new(); // column j: H[0..=j+1][j]
            let (mut cs, mut sn): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
            let mut g = vec![beta];
            let mut w = vec![0.0; n];
            for j in 0..GMRES_RESTART {
                let z = precondition(&basis[j])?;
                self.apply(&z, is_fixed, &mut w);
                let mut col = vec![0.0; j + 2];
                for (i, q) in basis.iter().enumerate() {
                    let d: f64 = q.iter().zip(&w).map(|(a, b)| a * b).sum();
                    col[i] = d;
                    for (wk, qk) in w.iter_mut().zip(q) {
                        *wk -= d * qk;
                    }
                }
                let wn = norm(&w);
                col[j + 1] = wn;
                for i in 0..j {
                    let t = cs[i] * col[i] + sn[i] * col[i + 1];
                    col[i + 1] = -sn[i] * col[i] + cs[i] * col[i + 1];
                    col[i] = t;
                }
                let d = col[j].hypot(col[j + 1]);
                let (c, sg) = if d > 0.0 { (col[j] / d, col[j + 1] / d) } else { (1.0, 0.0) };
                cs.push(c);
                sn.push(sg);
                col[j] = d;
                col[j + 1] = 0.0;
                g.push(-sg * g[j]);
                g[j] *= c;
                h.push(col);
                let done = g[j + 1].abs() <= 0.1 * tolerance * scale || wn == 0.0;
                if done || j + 1 == GMRES_RESTART {
                    break;
                }
                basis.push(w.iter().map(|v| v / wn).collect());
            }
            // Back substitution for y, then x += M⁻¹ (V y).
            let k = h.len();
            let mut y = vec![0.0; k];
            for i in (0..k).rev() {
                let mut t = g[i];
                for jj in i + 1..k {
                    t -= h[jj][i] * y[jj];
                }
                y[i] = if h[i][i] != 0.0 { t / h[i][i] } else { 0.0 };
            }
            let mut v = vec![0.0; n];
            for (q, yj) in basis.iter().zip(&y) {
                for (vk, qk) in v.iter_mut().zip(q) {
                    *vk += yj * qk;
                }
            }
            let dx = precondition(&v)?;
            for (xi, d) in x.iter_mut().zip(&dx) {
                *xi += d;
            }
        }
        Ok(false)
    }
}
