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

use super::nonlinear::hessian::{mips_derivatives, project_psd4};
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
    let lscm_start = super::lscm::solve_with_angles(chart, &super::chart_angles(&chart.positions, &chart.triangles), start_pins)
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
        let b: Vec<f64> = grad.iter().map(|g| -g).collect();
        let zeros = vec![0.0; fixed.len()];
        let x = solver.solve_inexact(&zeros, &b, &vec![0.0; 2 * n], super::slim::INEXACT)?;
        let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
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
    let pinned = if spanning { Some(format!("{} pinned vertex(es) held fixed", pins.len())) } else { translate_onto_single_pin(&mut sol.uv, pins, "MIPS") };
    sol.note = Some(match pinned {
        Some(pinned) => format!("{started}; {pinned}"),
        None => started,
    });
    Ok((sol, it.history))
}
