//! The smallest eigenvector of the conformal energy against the boundary mass, the map of
//! spectral conformal parameterization ([`super::spectral`]) and LSCM's free map without pins
//! ([`super::lscm::solve_free`]).
//!
//! Paper: P. Mullen, Y. Tong, P. Alliez, M. Desbrun, "Spectral Conformal Parameterization",
//! SGP 2008. For a Hermitian conformal energy `w* Q w` (`w = u + iv` per vertex,
//! [`super::lscm::conformal_hermitian`]) and the boundary mass `B` (half the incident boundary
//! edge lengths at each boundary vertex), the eigenvector of `Q w = λ B w` with the smallest
//! λ, B-orthogonal to the constant maps. In the complex form a rotation and scaling of the
//! plane is a complex scalar, so the eigenvalue is simple.
//!
//! One sparse Cholesky factorization of `Q + εB` (ε small and relative to Q's diagonal: the
//! shifted pencil has exactly the same eigenvectors and is positive definite, since no
//! conformal map vanishes on the boundary), then either inverse iteration
//! ([`BoundaryIteration::run`]) or Lanczos ([`BoundaryIteration::lanczos`]), both keeping the
//! iterate B-orthogonal to the constants. The start is the chart's projection onto the plane
//! of its two longest bounding-box axes.
//!
//! Preconditions: a chart with a boundary (holes allowed: all loops count). Failures: no
//! boundary length, the factorization fails even with a larger shift, the start has no
//! extent on the boundary, or the iteration produces non-finite values.

use crate::charts::Chart;
use crate::geometry::{norm, sub};
use crate::methods::ChartFailure;
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};
use faer::c64;

/// The search for the smallest eigenvector of `Q w = λ B w` (module docs): the factored
/// shifted system and the current B-normalised iterate.
pub(crate) struct BoundaryIteration {
    factor: FixedValueSolver<c64>,
    /// Boundary mass per vertex (0 inside).
    b: Vec<f64>,
    /// The vertices with boundary mass, ascending.
    boundary: Vec<u32>,
    /// The iterate, B-orthogonal to the constants and B-normalised.
    w: Vec<c64>,
}

/// Whether `x` is greater than 0 (false for NaN).
fn positive(x: f64) -> bool {
    x > 0.0
}

/// Lanczos steps between restarts ([`BoundaryIteration::lanczos`]).
pub const LANCZOS_BLOCK: usize = 24;

/// The largest eigenvalue of the symmetric tridiagonal matrix with diagonal `alpha` and
/// off-diagonal `beta` (one shorter), and its unit eigenvector, by cyclic Jacobi rotations
/// (Golub & Van Loan, §8.5; the matrix has at most [`LANCZOS_BLOCK`] rows).
fn top_eigenpair(alpha: &[f64], beta: &[f64]) -> (f64, Vec<f64>) {
    let k = alpha.len();
    let mut a = vec![vec![0.0f64; k]; k];
    for i in 0..k {
        a[i][i] = alpha[i];
        if i + 1 < k {
            a[i][i + 1] = beta[i];
            a[i + 1][i] = beta[i];
        }
    }
    let mut v: Vec<Vec<f64>> = (0..k).map(|i| (0..k).map(|j| if i == j { 1.0 } else { 0.0 }).collect()).collect();
    let scale: f64 = alpha.iter().chain(beta).map(|x| x * x).sum::<f64>().sqrt();
    for _sweep in 0..64 {
        let off: f64 = (0..k).map(|i| (0..k).filter(|&j| j != i).map(|j| a[i][j].powi(2)).sum::<f64>()).sum();
        if off.is_nan() || off.sqrt() <= 1e-15 * scale {
            break;
        }
        for p in 0..k {
            for q in p + 1..k {
                if a[p][q] == 0.0 {
                    continue;
                }
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let (c, s) = (1.0 / (t * t + 1.0).sqrt(), t / (t * t + 1.0).sqrt());
                for r in 0..k {
                    let (arp, arq) = (a[r][p], a[r][q]);
                    a[r][p] = c * arp - s * arq;
                    a[r][q] = s * arp + c * arq;
                }
                for r in 0..k {
                    let (apr, aqr) = (a[p][r], a[q][r]);
                    a[p][r] = c * apr - s * aqr;
                    a[q][r] = s * apr + c * aqr;
                }
                for r in 0..k {
                    let (vrp, vrq) = (v[r][p], v[r][q]);
                    v[r][p] = c * vrp - s * vrq;
                    v[r][q] = s * vrp + c * vrq;
                }
            }
        }
    }
    let top = (0..k).max_by(|&i, &j| a[i][i].total_cmp(&a[j][j])).unwrap_or(0);
    (a[top][top], (0..k).map(|r| v[r][top]).collect())
}

impl BoundaryIteration {
    /// Factor `Q + εB` for `chart` with the energy `q` (lower-triangle triplets over the
    /// chart's vertices), and start from the chart's projection onto the plane of its two
    /// longest bounding-box axes. Failures: see the module docs.
    pub(crate) fn new(chart: &Chart, q: Vec<(u32, u32, c64)>) -> Result<Self, ChartFailure> {
        let n = chart.positions.len();
        let mut b = vec![0.0; n];
        for lp in &chart.boundary_loops {
            for i in 0..lp.len() {
                let (a, c) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
                let l = 0.5 * norm(sub(chart.positions[c], chart.positions[a]));
                b[a] += l;
                b[c] += l;
            }
        }
        let bsum: f64 = b.iter().sum();
        if !(bsum > 0.0 && bsum.is_finite()) {
            return Err(ChartFailure("spectral: the chart's boundary has zero length".into()));
        }
        let boundary: Vec<u32> = (0..n as u32).filter(|&i| b[i as usize] > 0.0).collect();
        let trace: f64 = q.iter().filter(|t| t.0 == t.1).map(|t| t.2.re).sum();
        let mean_diag = trace / n.max(1) as f64;
        // Shift by a multiple of B: (Q + εB) w = μ B w has exactly the eigenvectors of
        // Q w = λ B w (μ = λ + ε) and is positive definite, since no conformal map vanishes on
        // the boundary.
        let mean_b = bsum / n as f64;
        let mut factor = None;
        let energy = q.len();
        let mut k = q;
        for rel in [1e-8, 1e-6, 1e-4] {
            let eps = rel * mean_diag.max(f64::MIN_POSITIVE) / mean_b;
            k.truncate(energy);
            k.extend(boundary.iter().map(|&i| (i, i, c64::new(eps * b[i as usize], 0.0))));
            let ordering = chart.ordering_if_known(OrderingKind::Amd);
            if let Ok(f) = FixedValueSolver::with_ordering(n, &k, &[], Symmetry::Symmetric, ordering) {
                factor = Some(f);
                break;
            }
        }
        let why = "spectral: the conformal energy matrix could not be factored";
        let factor = factor.ok_or_else(|| ChartFailure(why.into()))?;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &chart.positions {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let mut axes = [0usize, 1, 2];
        axes.sort_by(|&a, &c| (hi[c] - lo[c]).total_cmp(&(hi[a] - lo[a])));
        let w: Vec<c64> = chart.positions.iter().map(|p| c64::new(p[axes[0]], p[axes[1]])).collect();
        let mut it = BoundaryIteration { factor, b, boundary, w };
        if !positive(it.normalise()) {
            return Err(ChartFailure("spectral: the chart's projection has no extent on its boundary".into()));
        }
        Ok(it)
    }

    /// Project `self.w` B-orthogonally off the constants and B-normalise it; returns its
    /// B-norm before the scaling (0 or not finite when it collapsed).
    fn normalise(&mut self) -> f64 {
        self.normalise_mean();
        let nb = self.inner(&self.w, &self.w).re.sqrt();
        if nb > 0.0 && nb.is_finite() {
            for w in &mut self.w {
                *w *= 1.0 / nb;
            }
        }
        nb
    }

    /// Up to `max_iterations` steps, stopping once the B-norm change of the normalised iterate
    /// up to a complex scalar is at most `tolerance`. Returns the steps taken and the last
    /// change. Stops early (the caller discards the chart) when the unwrap is cancelled.
    pub(crate) fn run(&mut self, max_iterations: usize, tolerance: f64) -> Result<(usize, f64), ChartFailure> {
        let mut change = f64::INFINITY;
        let mut iterations = 0;
        for it in 0..max_iterations {
            if crate::progress::cancelled() {
                break;
            }
            iterations = it + 1;
            let rhs: Vec<c64> = self.w.iter().zip(&self.b).map(|(w, &bi)| *w * bi).collect();
            let old = std::mem::replace(&mut self.w, self.factor.solve(&[vec![]], &[rhs])?.pop().unwrap_or_default());
            if !positive(self.normalise()) || !self.w.iter().all(|w| w.re.is_finite() && w.im.is_finite()) {
                return Err(ChartFailure("spectral: inverse iteration collapsed".into()));
            }
            // The residual of the new iterate after its B-projection c·old (c = Σ b conj(old) new)
            // vanishes exactly when the two differ by a complex scalar.
            let c = self.inner(&old, &self.w);
            let residual: Vec<c64> = self.w.iter().zip(&old).map(|(w, o)| *w - c * *o).collect();
            change = self.inner(&residual, &residual).re.max(0.0).sqrt();
            if change <= tolerance {
                break;
            }
        }
        Ok((iterations, change))
    }

    /// Lanczos (Lanczos 1950; Parlett, "The Symmetric Eigenvalue Problem", ch. 13) for the
    /// largest eigenvalue of `M = (Q + εB)⁻¹ B`, self-adjoint in the B inner product (a norm on
    /// `M`'s range: a map in it that vanishes on the boundary has no energy, so it is 0). The
    /// basis is kept B-orthogonal in full and the run restarted from the Ritz vector every
    /// [`LANCZOS_BLOCK`] steps. Far fewer solves than [`BoundaryIteration::run`] where the
    /// two smallest eigenvalues are close (large charts). Stops once the Ritz pair's residual
    /// `‖M w − θ w‖_B / θ` is at most `tolerance`, or after `max_solves` solves. Returns the
    /// solves and the last residual; the iterate becomes the Ritz vector.
    pub(crate) fn lanczos(&mut self, max_solves: usize, tolerance: f64) -> Result<(usize, f64), ChartFailure> {
        // The first step puts the start in M's range, where the B inner product is a norm.
        let mut solves = self.run(1, 0.0)?.0;
        let mut residual = f64::INFINITY;
        while solves < max_solves && residual > tolerance {
            let mut basis: Vec<Vec<c64>> = vec![std::mem::take(&mut self.w)];
            let (mut alpha, mut beta): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
            let mut ritz = vec![1.0];
            loop {
                if crate::progress::cancelled() {
                    break;
                }
                let last = basis.last().unwrap();
                let rhs: Vec<c64> = last.iter().zip(&self.b).map(|(w, &bi)| *w * bi).collect();
                let mut z = self.factor.solve(&[vec![]], &[rhs])?.pop().unwrap_or_default();
                solves += 1;
                let mut diagonal = 0.0;
                // Gram–Schmidt against the whole basis, twice (round-off), and the constants.
                for pass in 0..2 {
                    for (k, q) in basis.iter().enumerate() {
                        let c = self.inner(q, &z);
                        if pass == 0 && k + 1 == basis.len() {
                            diagonal = c.re;
                        }
                        for (zi, qi) in z.iter_mut().zip(q) {
                            *zi -= c * *qi;
                        }
                    }
                    self.w = z;
                    self.normalise_mean();
                    z = std::mem::take(&mut self.w);
                }
                if !z.iter().all(|v| v.re.is_finite() && v.im.is_finite()) {
                    return Err(ChartFailure("spectral: Lanczos produced non-finite values".into()));
                }
                alpha.push(diagonal);
                let next = self.inner(&z, &z).re.max(0.0).sqrt();
                let (theta, y) = top_eigenpair(&alpha, &beta);
                residual = if theta > 0.0 { next * y.last().unwrap().abs() / theta } else { f64::INFINITY };
                ritz = y;
                if residual <= tolerance || solves >= max_solves || basis.len() >= LANCZOS_BLOCK || !positive(next) {
                    break;
                }
                beta.push(next);
                for v in &mut z {
                    *v *= 1.0 / next;
                }
                basis.push(z);
            }
            let n = basis[0].len();
            let mut w = vec![c64::new(0.0, 0.0); n];
            for (q, &c) in basis.iter().zip(&ritz) {
                for (wi, qi) in w.iter_mut().zip(q) {
                    *wi += *qi * c;
                }
            }
            self.w = w;
            if !positive(self.normalise()) {
                return Err(ChartFailure("spectral: Lanczos collapsed".into()));
            }
            if crate::progress::cancelled() {
                break;
            }
        }
        Ok((solves, residual))
    }

    /// `Σ b x̄ y`, over the boundary.
    fn inner(&self, x: &[c64], y: &[c64]) -> c64 {
        let mut s = c64::new(0.0, 0.0);
        for &i in &self.boundary {
            s += x[i as usize].conj() * y[i as usize] * self.b[i as usize];
        }
        s
    }

    /// Project `self.w` B-orthogonally off the constants (no scaling).
    fn normalise_mean(&mut self) {
        let (mut s, mut m) = (c64::new(0.0, 0.0), 0.0);
        for &i in &self.boundary {
            s += self.w[i as usize] * self.b[i as usize];
            m += self.b[i as usize];
        }
        let mean = s * (1.0 / m);
        for w in &mut self.w {
            *w -= mean;
        }
    }

    /// The iterate as UVs (B-normalised, its boundary's B-weighted mean at the origin).
    pub(crate) fn uv(&self) -> Vec<[f64; 2]> {
        self.w.iter().map(|w| [w.re, w.im]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tridiagonal matrix with `a` on its diagonal and `b` beside it has eigenvalues
    /// `a + 2b cos(jπ/(k+1))` and eigenvectors `sin(ijπ/(k+1))`: the largest is j = 1.
    #[test]
    fn the_top_eigenpair_of_a_constant_tridiagonal_matrix_is_the_analytic_one() {
        for k in [1usize, 2, 5, 24] {
            let (a, b) = (0.7, -0.3);
            let (theta, y) = top_eigenpair(&vec![a; k], &vec![b; k - 1]);
            let h = std::f64::consts::PI / (k + 1) as f64;
            // b < 0: the largest eigenvalue is j = k.
            let j = k as f64;
            assert!((theta - (a + 2.0 * b * (j * h).cos())).abs() < 1e-12, "k {k}: {theta}");
            let exact: Vec<f64> = (1..=k).map(|i| (i as f64 * j * h).sin()).collect();
            let norm = exact.iter().map(|x| x * x).sum::<f64>().sqrt();
            let dot: f64 = exact.iter().zip(&y).map(|(e, y)| e * y).sum::<f64>() / norm;
            assert!((dot.abs() - 1.0).abs() < 1e-12, "k {k}: {dot}");
        }
    }

    /// On a curved grid chart Lanczos reaches the eigenvector inverse iteration converges to
    /// (equal up to a complex scalar), in fewer solves.
    #[test]
    fn lanczos_reaches_the_eigenvector_of_inverse_iteration_in_fewer_solves() {
        let chart = crate::charts::bumpy_grid_chart(40);
        let angles = crate::methods::chart_angles(&chart.positions, &chart.triangles);
        let q = crate::methods::lscm::conformal_hermitian(&chart.triangles, &angles);
        let mut power = BoundaryIteration::new(&chart, q.clone()).unwrap();
        let (power_solves, change) = power.run(500, 1e-12).unwrap();
        assert!(change <= 1e-12, "inverse iteration converges: {change:e}");
        let mut lanczos = BoundaryIteration::new(&chart, q).unwrap();
        let (solves, residual) = lanczos.lanczos(500, 1e-10).unwrap();
        assert!(residual <= 1e-10, "{residual:e}");
        assert!(solves < power_solves, "Lanczos {solves} solves, inverse iteration {power_solves}");
        // Both B-normalised: |⟨x, y⟩_B| = 1 exactly when they differ by a unit complex scalar.
        let c = lanczos.inner(&power.w, &lanczos.w);
        assert!((c.norm() - 1.0).abs() < 1e-8, "|<power, lanczos>_B| = {}", c.norm());
    }
}
