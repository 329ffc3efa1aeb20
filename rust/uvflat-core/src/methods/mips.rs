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
//!   is made positive semidefinite per triangle (eigen-decomposition of the 4×4 matrix,
//!   negative eigenvalues mirrored to their absolute values), then pulled back by the linear
//!   map from the triangle's six UV coordinates to J, which keeps each 6×6 block PSD (Teran et
//!   al. 2005's per-element projection, applied in J-space where the matrix is smaller). Near
//!   the minimum (the last step was a full Newton step and lowered E by at most [`NEAR`] of
//!   it) the exact Hessian is tried first and used when it is positive definite: the
//!   trust-region eigenvalue filtering of Chen et al. 2024 ("Trust-region eigenvalue filtering
//!   for projected Newton", SIGGRAPH Asia). Projected Hessians alone converge linearly there
//!   (runs of 50 iterations gaining 1e-5 of E each); mirrored eigenvalues far from it take
//!   longer steps than eigenvalues set to zero. Over the robustness sweep
//!   (`blender_scripts/robustness.py --methods mips`, 49 meshes) the two together took 75 s
//!   against 112 s with zeroed eigenvalues alone;
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
//! Pins: with two or more pinned vertices at distinct UVs the pins replace the gauge: they are
//! fixed values of every Newton step (the line search moves only the free vertices), so they
//! hold exactly, and the start honours them (pinned LSCM, else the pinned mean value map).
//! The energy is scale invariant, so the pins set the scale. A single pin is reached by
//! translating the result (exact).
//!
//! Failures: a chart that is not a disk (see [`super::require_disk`]); a singular start or
//! Newton system becomes a chart failure. A start with a degenerate UV triangle (infinite
//! energy) returns the mean value map as a fallback; with pins and no flip-free start honouring
//! them, the chart falls back to a pinned map
//! ([`super::nonlinear::pins::pinned_fallback`]), which holds the pins.

use super::nonlinear::hessian::{mips_derivatives, project_abs4, project_psd4};
use super::nonlinear::iterate::{quads_left_out_note, Change, Iteration};
use super::nonlinear::jacobian::flat;
use super::nonlinear::pattern::{block_triplets, by_component, BLOCK};
use super::lscm::pins_span;
use super::nonlinear::pins::{gauge_vertices, pinned_fallback, translate_onto_first_pin, translate_onto_single_pin};
use super::nonlinear::start::mean_value_start;
use super::nonlinear::TriangleOperators;
use super::{ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, LineSearchOptions};
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};
use rayon::prelude::*;

pub use super::nonlinear::energy::{mips_density, mips_energy};
pub(crate) use super::nonlinear::start::flip_free_start;

/// A step that is a full Newton step and lowers the energy by at most this share of it says
/// the minimum is near: the next step tries the exact Hessian.
pub const NEAR: f64 = 1e-3;

/// Which Newton matrices [`solve_newton`] builds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Newton {
    /// Projected by [`Curvature::Mirrored`], exact near the minimum (the solver's own).
    TrustRegion,
    /// Projected by [`Curvature::Clamped`] at every step (for comparison in tests).
    #[cfg_attr(not(test), allow(dead_code))]
    Clamped,
}

/// How a triangle's Hessian (in J) enters the Newton matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Curvature {
    /// Negative eigenvalues set to zero.
    Clamped,
    /// Negative eigenvalues replaced by their absolute values.
    Mirrored,
    /// As it is (positive definite only near a minimum).
    Exact,
}

impl Curvature {
    fn filter(self, h: &[[f64; 4]; 4]) -> [[f64; 4]; 4] {
        match self {
            Curvature::Clamped => project_psd4(h),
            Curvature::Mirrored => project_abs4(h),
            Curvature::Exact => *h,
        }
    }
}

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
    solve_newton(chart, pins, options, Newton::TrustRegion)
}

fn solve_newton(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &MipsOptions,
    newton: Newton,
) -> Result<(ChartSolution, Vec<f64>), ChartFailure> {
    let far = if newton == Newton::Clamped { Curvature::Clamped } else { Curvature::Mirrored };
    super::require_disk(chart)?;
    let n = chart.positions.len();
    let chart_ops = TriangleOperators::local_frames(&chart.positions, &chart.triangles);
    // Pins spanning more than a point are fixed values of every Newton step, so the start must
    // honour them too; a single pin is reached by a translation at the end.
    let spanning = pins_span(pins);
    let start_pins: &[(u32, [f64; 2])] = if spanning { pins } else { &[] };
    let valid = |uv: &[[f64; 2]]| {
        all_positive(&chart.triangles, uv) && mips_energy(&chart_ops, &chart.triangles, uv).is_finite() && super::nonconvex_quads(chart, uv) == 0
    };
    // LSCM minimises a conformal energy too, so when it is flip-free (quads strictly convex
    // included) it starts Newton next to the MIPS minimiser; otherwise the mean value map,
    // flip-free with convex quads by Floater's theorem on the polygon graph (with pins only
    // when they are consistent enough).
    let angles = super::chart_angles(&chart.positions, &chart.triangles);
    let lscm_start = super::lscm::solve_free(chart, &angles, start_pins)
        .ok()
        .map(|(uv, _)| uv)
        .filter(|uv| valid(uv));
    let start_name = if lscm_start.is_some() { "lscm" } else { "mean_value" };
    let mut uv = match lscm_start {
        Some(uv) => uv,
        None if spanning => match mean_value_start(chart, pins).map(|s| s.uv) {
            Ok(uv) if valid(&uv) => uv,
            _ => {
                let sol = pinned_fallback(chart, pins, "no flip-free starting map honours the pins; MIPS needs one")?;
                return Ok((sol, Vec::new()));
            }
        },
        None => flip_free_start(chart)?,
    };
    // The barrier covers both diagonal splits of every quad (see `barrier_triangles`).
    let (barrier, weights, left_out) = super::barrier_triangles(chart, &uv);
    let tris = &barrier;
    let ops = TriangleOperators::local_frames(&chart.positions, tris).weighted(&weights);
    let energy = mips_energy(&ops, tris, &uv);
    if !energy.is_finite() {
        let mut sol = ChartSolution::direct(uv);
        translate_onto_first_pin(&mut sol.uv, pins);
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
    // The gauge: the pins when they span more than a point (they never move), else two
    // far-apart boundary vertices (the energy is similarity invariant).
    let fixed: Vec<u32> = if spanning {
        pins.iter().flat_map(|p| [2 * p.0, 2 * p.0 + 1]).collect()
    } else {
        let [g0, g1] = gauge_vertices(chart, &uv);
        if g0 == g1 { vec![2 * g0, 2 * g0 + 1] } else { vec![2 * g0, 2 * g0 + 1, 2 * g1, 2 * g1 + 1] }
    };
    let mut solver = FixedValueSolver::new(2 * n, &triplets, &fixed, Symmetry::Symmetric)?;
    let mut values = vec![0.0; triplets.len()];
    let mut grad = vec![0.0; 2 * n];
    let ls = LineSearchOptions::default();
    let total_area = ops.total_area.max(f64::MIN_POSITIVE);
    let mut it = Iteration::new(energy, options.max_iterations, options.tolerance, Change::OfNew, f64::INFINITY);
    let mut shift = 1e-10;
    // Whether the last step says the minimum is near (see [`Curvature`]).
    let mut near = false;
    // A cancelled unwrap discards this chart.
    while it.go_on() {
        // The exact Hessian near the minimum when it is positive definite there, else the
        // projected one.
        let kinds: &[Curvature] = if near && newton == Newton::TrustRegion { &[Curvature::Exact, far] } else { &[far] };
        let mut factored = false;
        for &kind in kinds {
            // Per-triangle gradient and Hessian blocks (normalised like the energy).
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
                    let h6 = ops.pull_hessian(f, &kind.filter(&hj));
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
            // Factor, raising the diagonal shift until the matrix is positive definite (the
            // exact Hessian gets one try at the smallest shift: indefinite, it is not used).
            let base = tris.len() * 21;
            let mut trial = if kind == Curvature::Exact { 1e-10 } else { shift };
            for _ in 0..if kind == Curvature::Exact { 1 } else { 8 } {
                for v in &mut values[base..] {
                    *v = trial * diag_mean.max(f64::MIN_POSITIVE);
                }
                match solver.refactor(&values) {
                    Ok(()) => {
                        factored = true;
                        break;
                    }
                    Err(SolveError::NotPositiveDefinite) => trial *= 100.0,
                    Err(e) => return Err(e.into()),
                }
            }
            if kind != Curvature::Exact {
                shift = trial;
            }
            if factored {
                break;
            }
        }
        if !factored {
            return Err(ChartFailure("the MIPS Newton system stays singular after regularisation".into()));
        }
        let b: Vec<f64> = grad.iter().map(|g| -g).collect();
        let zeros = vec![0.0; fixed.len()];
        let x = solver.solve_inexact(&zeros, &b, &vec![0.0; 2 * n], super::slim::INEXACT)?;
        let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
        let before = it.energy();
        let out = flip_free_line_search(tris, &mut uv, &dir, before, |q| mips_energy(&ops, tris, q), &ls);
        near = out.step == 1.0 && before - out.energy <= NEAR * before;
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
    let pinned = if spanning { Some(format!("{} pinned vertex(es) held fixed", pins.len())) } else { translate_onto_single_pin(&mut sol.uv, pins, "MIPS") };
    sol.note = Some(match pinned {
        Some(pinned) => format!("{started}; {pinned}"),
        None => started,
    });
    Ok((sol, it.history))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::build_charts;
    use crate::mesh::PolyMesh;

    /// An `n` by `n` grid of quads over a bumpy height field (not developable, with quads
    /// that must stay convex): MIPS has to iterate.
    fn bumpy_quads(n: usize) -> Chart {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                let (u, v) = (x as f64 / n as f64, y as f64 / n as f64);
                let z = 0.6 * (7.0 * u).sin() * (6.0 * v + 0.5).cos() + 0.2 * (13.0 * u * v).sin();
                positions.push([u, v, z]);
            }
        }
        let mut corners = Vec::new();
        for y in 0..n as u32 {
            for x in 0..n as u32 {
                let a = y * (n as u32 + 1) + x;
                corners.extend([a, a + 1, a + n as u32 + 2, a + n as u32 + 1]);
            }
        }
        let sizes = vec![4u32; n * n];
        let mesh = PolyMesh::new(&positions, &corners, &sizes).unwrap();
        build_charts(&mesh, &[], None).remove(0)
    }

    /// Near the minimum the exact Hessian converges where projected ones crawl: the solver
    /// stops on its tolerance in fewer iterations than zeroed eigenvalues alone, at an energy
    /// no higher, with every step lowering it and no triangle flipped.
    #[test]
    fn the_exact_hessian_near_the_minimum_converges_in_fewer_steps() {
        let chart = bumpy_quads(16);
        let options = MipsOptions::default();
        let (trust, th) = solve_newton(&chart, &[], &options, Newton::TrustRegion).unwrap();
        let (clamped, ch) = solve_newton(&chart, &[], &options, Newton::Clamped).unwrap();
        assert!(th.windows(2).all(|w| w[1] <= w[0]), "{th:?}");
        assert!(trust.iterations < options.max_iterations && trust.residual <= options.tolerance, "{th:?}");
        let (te, ce) = (*th.last().unwrap(), *ch.last().unwrap());
        assert!(trust.iterations < clamped.iterations, "{} vs {} iterations", trust.iterations, clamped.iterations);
        assert!(te <= ce * (1.0 + 1e-9), "{te} vs {ce}");
        assert!(all_positive(&chart.triangles, &trust.uv));
        assert_eq!(crate::methods::nonconvex_quads(&chart, &trust.uv), 0);
    }
}
