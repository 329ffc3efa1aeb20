//! `mips`: the most isometric parameterization energy, minimised by a projected Newton method
//! from a flip-free start with a flip-free line search; free (natural) boundary, no flips.
//!
//! Paper: K. Hormann, G. Greiner, "MIPS: An efficient global parametrization method", in
//! Curve and Surface Design: Saint-Malo 1999, Vanderbilt University Press, 2000.
//!
//! Energy: for a triangle with Jacobian J (3D triangle in a local 2D frame → UV triangle) and
//! singular values σ1 ≥ σ2, the MIPS energy is σ1/σ2 + σ2/σ1 = ‖J‖²_F / det J, 2 for a
//! conformal triangle and +∞ as the triangle degenerates (a barrier against flips). The chart
//! energy is the 3D-area-weighted mean, normalised so a conformal map has energy 1:
//! E = Σ A_t ‖J_t‖² / det J_t / (2 Σ A_t). It is invariant under similarities of the UVs.
//!
//! Minimisation:
//! * start: LSCM ([`super::lscm`]) when every one of its triangles is positively oriented (it
//!   minimises a conformal energy too, so Newton starts next to the minimiser), otherwise mean
//!   value weights with the boundary on a circle (Floater 2003): every triangle positively
//!   oriented, so E is finite;
//! * Newton direction: the Hessian of f(J) = ‖J‖²/det J with respect to the four entries of J
//!   is projected onto the positive semidefinite cone per triangle (eigen-decomposition of the
//!   4×4 matrix, negative eigenvalues set to zero), then pulled back by the linear map from the
//!   triangle's six UV coordinates to J, which keeps each 6×6 block PSD (Teran et al. 2005's
//!   per-element projection, applied in J-space where the matrix is smaller);
//! * gauge: E is similarity invariant, so two boundary vertices are held fixed in the Newton
//!   system (exactly the four similarity degrees of freedom; the minimiser is unaffected), plus
//!   a tiny diagonal shift raised only if the Cholesky factorisation fails;
//! * the global system goes through [`FixedValueSolver`]: the sparsity pattern is analysed
//!   once, every iteration refactors numerically;
//! * step: [`flip_free_line_search`] (largest step keeping every triangle positive, then
//!   halving until E decreases), so no triangle ever flips and E decreases monotonically.
//!
//! Quads: the energy and the line search also cover the other diagonal's two triangles of
//! every quad ([`super::barrier_triangles`]), so quads stay strictly convex; an LSCM start
//! with a non-convex quad is not used.
//!
//! Pins: the energy does not see them; the result is moved onto the pins by the least-squares
//! similarity (exact for one or two pins) and the report says so.
//!
//! Failures: a chart that is not a disk (see [`super::require_disk`]); a singular start or
//! Newton system becomes a chart failure. A start with a degenerate UV triangle (infinite
//! energy) returns the mean value map as a fallback.

use super::nonlinear::iterate::{quads_left_out_note, Change, Iteration};
use super::nonlinear::jacobian::flat;
use super::nonlinear::pattern::{block_triplets, by_component, BLOCK};
use super::nonlinear::pins::gauge_vertices;
use super::nonlinear::TriangleOperators;
use super::{ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, LineSearchOptions};
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};
use rayon::prelude::*;

pub use super::nonlinear::energy::{mips_density, mips_energy};
pub(crate) use super::nonlinear::pins::honour_pins_by_similarity;
pub(crate) use super::nonlinear::start::flip_free_start;

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MipsOptions {
    /// Most Newton iterations. Default 50.
    pub max_iterations: usize,
    /// Stop when the energy changes by less than this, relative to the energy. Default 1e-6.
    pub tolerance: f64,
}

impl Default for MipsOptions {
    fn default() -> Self {
        MipsOptions { max_iterations: 50, tolerance: 1e-6 }
    }
}

/// Gradient and Hessian of ‖J‖²/det J with respect to (J00, J01, J10, J11), for det J > 0.
fn mips_derivatives(j: [f64; 4]) -> ([f64; 4], [[f64; 4]; 4]) {
    let n: f64 = j.iter().map(|x| x * x).sum();
    let d = j[0] * j[3] - j[1] * j[2];
    let g = [j[3], -j[2], -j[1], j[0]]; // ∇ det
    let mut grad = [0.0; 4];
    for k in 0..4 {
        grad[k] = 2.0 * j[k] / d - n * g[k] / (d * d);
    }
    let mut h = [[0.0; 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            let mut v = -2.0 * (j[a] * g[b] + g[a] * j[b]) / (d * d) + 2.0 * n * g[a] * g[b] / (d * d * d);
            if a == b {
                v += 2.0 / d;
            }
            h[a][b] = v;
        }
    }
    // ∂² det: entries (0,3), (3,0) = 1; (1,2), (2,1) = −1.
    let s = n / (d * d);
    h[0][3] -= s;
    h[3][0] -= s;
    h[1][2] += s;
    h[2][1] += s;
    (grad, h)
}

/// Project a symmetric 4×4 matrix onto the positive semidefinite cone (cyclic Jacobi
/// eigen-decomposition, negative eigenvalues set to zero).
pub(crate) fn project_psd4(a: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let mut m = *a;
    let mut v = [[0.0; 4]; 4];
    for i in 0..4 {
        v[i][i] = 1.0;
    }
    let scale: f64 = m.iter().flatten().map(|x| x.abs()).fold(0.0, f64::max);
    if !(scale > 0.0) || !scale.is_finite() {
        return [[0.0; 4]; 4];
    }
    for _sweep in 0..30 {
        let off: f64 = (0..4).flat_map(|p| (0..4).filter(move |&q| q != p).map(move |q| (p, q))).map(|(p, q)| m[p][q] * m[p][q]).sum();
        if off <= 1e-30 * scale * scale {
            break;
        }
        for p in 0..3 {
            for q in p + 1..4 {
                if m[p][q].abs() <= 1e-300 {
                    continue;
                }
                let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..4 {
                    let (mkp, mkq) = (m[k][p], m[k][q]);
                    m[k][p] = c * mkp - s * mkq;
                    m[k][q] = s * mkp + c * mkq;
                }
                for k in 0..4 {
                    let (mpk, mqk) = (m[p][k], m[q][k]);
                    m[p][k] = c * mpk - s * mqk;
                    m[q][k] = s * mpk + c * mqk;
                }
                for k in 0..4 {
                    let (vkp, vkq) = (v[k][p], v[k][q]);
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let lam: [f64; 4] = [m[0][0].max(0.0), m[1][1].max(0.0), m[2][2].max(0.0), m[3][3].max(0.0)];
    let mut out = [[0.0; 4]; 4];
    for a in 0..4 {
        for b in 0..4 {
            out[a][b] = (0..4).map(|k| v[a][k] * lam[k] * v[b][k]).sum();
        }
    }
    out
}

/// Map one chart; see the module docs.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &MipsOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
}

/// [`solve`], also returning the normalised energy before the first iteration and after
/// every iteration (non-increasing by construction of the line search).
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &MipsOptions,
) -> Result<(ChartSolution, Vec<f64>), ChartFailure> {
    super::require_disk(chart)?;
    let n = chart.positions.len();
    let chart_ops = TriangleOperators::local_frames(&chart.positions, &chart.triangles);
    // LSCM minimises a conformal energy too, so when it is flip-free (quads strictly convex
    // included) it starts Newton next to the MIPS minimiser; otherwise the mean value map,
    // flip-free with convex quads by Floater's theorem on the polygon graph.
    let lscm_start = super::lscm::solve_with_angles(chart, &super::chart_angles(&chart.positions, &chart.triangles), &[])
        .ok()
        .map(|(uv, _)| uv)
        .filter(|uv| {
            all_positive(&chart.triangles, uv)
                && mips_energy(&chart_ops, &chart.triangles, uv).is_finite()
                && super::nonconvex_quads(chart, uv) == 0
        });
    let start_name = if lscm_start.is_some() { "lscm" } else { "mean_value" };
    let mut uv = match lscm_start {
        Some(uv) => uv,
        None => flip_free_start(chart)?,
    };
    // The barrier covers both diagonal splits of every quad (see `barrier_triangles`).
    let (barrier, weights, left_out) = super::barrier_triangles(chart, &uv);
    let tris = &barrier;
    let ops = TriangleOperators::local_frames(&chart.positions, tris).weighted(&weights);
    let energy = mips_energy(&ops, tris, &uv);
    if !energy.is_finite() {
        let mut sol = ChartSolution::direct(uv);
        sol.fallback = Some(Fallback {
            method: "mean_value",
            reason: "the flip-free start has a degenerate UV triangle, so the MIPS energy is infinite".into(),
        });
        return Ok((sol, vec![energy]));
    }

    // Pattern: per triangle the 21 lower-triangle entries of its 6×6 block over
    // (u0, u1, u2, v0, v1, v2), then the diagonal.
    let mut triplets = block_triplets(tris, by_component);
    triplets.extend((0..2 * n as u32).map(|i| (i, i, 1.0)));
    let [g0, g1] = gauge_vertices(chart, &uv);
    let fixed: Vec<u32> = if g0 == g1 { vec![2 * g0, 2 * g0 + 1] } else { vec![2 * g0, 2 * g0 + 1, 2 * g1, 2 * g1 + 1] };
    let mut solver = FixedValueSolver::new(2 * n, &triplets, &fixed, Symmetry::Symmetric)?;
    let mut values = vec![0.0; triplets.len()];
    let mut grad = vec![0.0; 2 * n];
    let ls = LineSearchOptions::default();
    let total_area = ops.total_area.max(f64::MIN_POSITIVE);
    let mut it = Iteration::new(energy, options.max_iterations, options.tolerance, Change::OfNew, f64::INFINITY);
    let mut shift = 1e-10;
    // A cancelled unwrap discards this chart.
    while it.go_on() {
        // Per-triangle gradient and projected Hessian blocks (normalised like the energy).
        let blocks: Vec<([f64; 6], [f64; 21])> = tris
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .map(|(f, t)| {
                if ops.area[f] == 0.0 {
                    return ([0.0; 6], [0.0; 21]);
                }
                let j = flat(ops.jacobian(f, t, &uv));
                let (gj, hj) = mips_derivatives(j);
                let w = ops.area[f] / (2.0 * total_area);
                let g6 = ops.pull_gradient(f, gj).map(|x| w * x);
                let h6 = ops.pull_hessian(f, &project_psd4(&hj));
                let mut low = [0.0; 21];
                for (m, &(k, l)) in BLOCK.iter().enumerate() {
                    low[m] = w * h6[k][l];
                }
                (g6, low)
            })
            .collect();
        grad.iter_mut().for_each(|g| *g = 0.0);
        let mut diag_mean = 0.0;
        for (ti, (t, (g6, low))) in tris.iter().zip(&blocks).enumerate() {
            for k in 0..6 {
                grad[by_component(t, k) as usize] += g6[k];
            }
            values[ti * 21..ti * 21 + 21].copy_from_slice(low);
            for (m, &(k, l)) in BLOCK.iter().enumerate() {
                if k == l {
                    diag_mean += low[m];
                }
            }
        }
        diag_mean /= (2 * n) as f64;
        // Factor, raising the diagonal shift until the matrix is positive definite.
        let base = tris.len() * 21;
        let mut factored = false;
        for _ in 0..8 {
            for v in &mut values[base..] {
                *v = shift * diag_mean.max(f64::MIN_POSITIVE);
            }
            match solver.refactor(&values) {
                Ok(()) => {
                    factored = true;
                    break;
                }
                Err(SolveError::NotPositiveDefinite) => shift *= 100.0,
                Err(e) => return Err(e.into()),
            }
        }
        if !factored {
            return Err(ChartFailure("the MIPS Newton system stays singular after regularisation".into()));
        }
        let b = [grad.iter().map(|g| -g).collect::<Vec<_>>()];
        let zeros = vec![0.0; fixed.len()];
        let x = solver.solve(&[zeros], &b)?;
        let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[0][2 * i], x[0][2 * i + 1]]).collect();
        let out = flip_free_line_search(tris, &mut uv, &dir, it.energy(), |q| mips_energy(&ops, tris, q), &ls);
        if out.step == 0.0 {
            it.stalled();
            break;
        }
        if it.record(out.energy) {
            break;
        }
    }
    let (energy, iterations) = (it.energy(), it.iterations);
    let mut sol = ChartSolution::direct(uv);
    sol.iterations = iterations;
    sol.residual = it.change;
    let mut started = format!("MIPS energy {energy:.6} after {iterations} iteration(s), started from {start_name}");
    if let Some(q) = quads_left_out_note(left_out) {
        started = format!("{started}; {q}");
    }
    sol.note = Some(match honour_pins_by_similarity(&mut sol.uv, pins, "MIPS") {
        Some(pinned) => format!("{started}; {pinned}"),
        None => started,
    });
    Ok((sol, it.history))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psd_projection_keeps_psd_matrices_and_clips_negative_eigenvalues() {
        let a = [[2.0, 1.0, 0.0, 0.0], [1.0, 2.0, 0.0, 0.0], [0.0, 0.0, 3.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        let p = project_psd4(&a);
        for i in 0..4 {
            for j in 0..4 {
                assert!((p[i][j] - a[i][j]).abs() < 1e-12);
            }
        }
        // diag(1, −2, 3, −4) rotated: projection is diag(1, 0, 3, 0) rotated the same way.
        let (c, s) = (0.6f64, 0.8f64);
        let q = [[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, c, s], [0.0, 0.0, -s, c]];
        let d = [1.0, -2.0, 3.0, -4.0];
        let mk = |d: [f64; 4]| {
            let mut m = [[0.0; 4]; 4];
            for i in 0..4 {
                for j in 0..4 {
                    m[i][j] = (0..4).map(|k| q[i][k] * d[k] * q[j][k]).sum();
                }
            }
            m
        };
        let p = project_psd4(&mk(d));
        let want = mk([1.0, 0.0, 3.0, 0.0]);
        for i in 0..4 {
            for j in 0..4 {
                assert!((p[i][j] - want[i][j]).abs() < 1e-12, "{p:?}");
            }
        }
    }

    fn density4(j: [f64; 4]) -> f64 {
        mips_density([[j[0], j[1]], [j[2], j[3]]])
    }

    #[test]
    fn mips_derivatives_match_finite_differences() {
        let j = [1.3, 0.4, -0.2, 0.9];
        let (g, h) = mips_derivatives(j);
        let eps = 1e-6;
        for k in 0..4 {
            let (mut jp, mut jm) = (j, j);
            jp[k] += eps;
            jm[k] -= eps;
            let fd = (density4(jp) - density4(jm)) / (2.0 * eps);
            assert!((fd - g[k]).abs() < 1e-6, "gradient {k}: {fd} vs {}", g[k]);
            let (gp, _) = mips_derivatives(jp);
            let (gm, _) = mips_derivatives(jm);
            for l in 0..4 {
                let fd = (gp[l] - gm[l]) / (2.0 * eps);
                assert!((fd - h[l][k]).abs() < 1e-5, "hessian {l},{k}: {fd} vs {}", h[l][k]);
            }
        }
        // Conformal J (a scaled rotation): energy 2, gradient zero.
        let (c, s) = (0.8 * 1.7, 0.6 * 1.7);
        let jc = [c, -s, s, c];
        assert!((density4(jc) - 2.0).abs() < 1e-12);
        assert!(mips_derivatives(jc).0.iter().all(|x| x.abs() < 1e-12));
    }
}
