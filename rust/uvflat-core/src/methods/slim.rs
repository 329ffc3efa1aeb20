//! Scalable Locally Injective Mappings: symmetric Dirichlet energy, never a flipped triangle.
//!
//! Paper: M. Rabinovich, R. Poranne, D. Panozzo, O. Sorkine-Hornung, "Scalable Locally
//! Injective Mappings", ACM TOG 36(2), 2017. Line search: J. Smith, S. Schaefer, "Bijective
//! parameterization with free boundaries", ACM TOG 34(4), 2015
//! ([`crate::solvers::line_search`]).
//!
//! Energy, over the chart triangles f with reference area A_f and Jacobian singular values
//! σ1, σ2 (see [`TriangleOperators`]):
//!
//! ```text
//! E(x) = Σ_f A_f (σ1² + σ2² + σ1⁻² + σ2⁻²) = Σ_f A_f ‖J_f‖²_F (1 + 1/det(J_f)²)
//! ```
//!
//! and `+∞` as soon as a triangle has `det J_f ≤ 0`. Reported per unit area and divided by 4
//! (1 for an isometry), like the symmetric Dirichlet of [`crate::metrics`].
//!
//! Each iteration:
//! 1. Local step (parallel): the SVD `J = U Σ Vᵀ` of every triangle gives the closest rotation
//!    `R = U Vᵀ` and the reweighting `W² = U diag(w1², w2²) Uᵀ` with
//!    `w² = h'(σ) / (2(σ − 1)) = (σ + 1)(σ² + 1) / σ³` for `h(σ) = σ² + σ⁻²` (paper, eq. 9).
//! 2. Global step: minimise the proxy `Σ A_f tr((J_f − R_f)ᵀ W_f² (J_f − R_f))`, a weighted
//!    least-squares problem over the interleaved unknowns `[u0, v0, u1, v1, …]` with matrix
//!    `Σ A_f (W_f² ⊗ L_f)` (`L_f` the triangle's stiffness). The weights change every
//!    iteration but the sparsity pattern does not: the symbolic analysis is done once and each
//!    iteration is one numeric refactorisation ([`FixedValueSolver::refactor`]) and one solve.
//! 3. Flip-free line search on the true energy from the current map towards the proxy
//!    minimiser: the step never reaches a degenerate triangle and strictly decreases E.
//!
//! After the first iteration, [`SlimStep::Newton`] (default) replaces steps 1–2 by a projected
//! Newton step (Teran, Sifakis, Irving & Fedkiw 2005; the analytic projection of Smith, Goes
//! & Kim 2019, [`project_twist`]): per triangle the exact Hessian of the density with respect
//! to J ([`super::nonlinear::hessian::symmetric_dirichlet_derivatives`]) with its one possibly negative eigenvalue (the twist) set
//! to 0, mapped to the six corner unknowns, plus `1e-6 ·` the triangle's Laplacian (definite
//! along the global rotation). Its pattern is SLIM's, so the symbolic analysis is shared. The
//! SLIM proxy is a good global step far from the optimum; Newton converges much faster near
//! it (camelhead: symmetric Dirichlet 1.8618 in 8 iterations vs 1.8642 in 13). A Newton step
//! that cannot be factored or finds no descent switches back to SLIM steps for good.
//!
//! Start: a flip-free map. [`SlimStart::Auto`] (default) tries LSCM and the mean value map on
//! a circle (Floater 2003, flip-free by Tutte's theorem) and keeps whichever has no
//! non-positive triangle and the lower energy, computing the mean value map only when LSCM is
//! not already within a symmetric Dirichlet energy of 2 ([`start::pick_staged`]);
//! [`SlimStart::MeanValue`] uses only the latter.
//! Without pins (or with pins that do not span more than a point) the start is scaled by the
//! energy-optimal factor `(Σ A ‖J⁻¹‖² / Σ A ‖J‖²)^{1/4}` and translated onto the pin.
//!
//! Quads: the energy and the line search also cover the other diagonal's two triangles of
//! every quad ([`super::barrier_triangles`], each of a quad's four triangles at half weight),
//! so quads stay strictly convex whichever diagonal an exporter picks; starts are ranked by
//! their number of non-convex quads first.
//!
//! Guarantee: every triangle of the result is positively oriented (the start is checked and
//! every accepted step keeps it so); the energy history is strictly decreasing.
//!
//! Pins: pinned vertices are fixed in every global step and every Newton step, so they hold
//! exactly. With pins spanning more than a point, the start honours them too (pinned LSCM or
//! pinned mean value), and the energy's rest shapes are the 3D triangles scaled by the pins'
//! scale ([`super::nonlinear::pins::pins_scale`]): the unpinned part lies at the pins' scale,
//! as in Blender's Minimum Stretch, not at 3D scale around them. When neither pinned start is
//! flip-free, no flip-free map with those pins is known and the chart falls back to pinned
//! LSCM, saying so ([`ChartSolution::fallback`]).
//!
//! Preconditions: a disk chart, possibly with holes. Failures: once a flip-free start exists
//! none; a global step that cannot be factored or solved ends the iteration with the current
//! (valid) map and says so in the note. Without a start, the LSCM fallback fails like
//! [`lscm::solve`] (singular system of a disconnected chart).

use std::time::Instant;

use rayon::prelude::*;

use super::nonlinear::energy::scale_optimally;
use super::nonlinear::hessian::{project_twist, symmetric_dirichlet_derivatives};
use super::nonlinear::iterate::{quads_left_out_note, stopped_early_note, Change, Iteration};
use super::nonlinear::pattern::{analyse_blocks, analysed_beside, block_triplets, interleaved, BLOCK};
use super::nonlinear::pins::{anchor_vertices, anchors, translate_onto_first_pin};
use super::nonlinear::proxy::reweight;
use super::nonlinear::start;
use super::nonlinear::unfold::unfold;
use super::nonlinear::TriangleOperators;
use super::{lscm, ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, LineSearchOptions};
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};

pub use super::nonlinear::energy::symmetric_dirichlet;

/// Weight of the Laplacian added to the projected Hessian (relative to the density's
/// Hessian at a rotation, 8): makes the system definite along the global rotation.
const NEWTON_REGULARISATION: f64 = 1e-6;

/// Which flip-free map SLIM starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlimStart {
    /// LSCM if it is flip-free and has the lower energy, else mean value on a circle. Default.
    #[default]
    Auto,
    /// Mean value map with the boundary on a circle (the paper's Tutte-like start).
    MeanValue,
}

/// Options of the SLIM method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlimOptions {
    /// Most iterations. Default 15 (on camelhead, from the mean value start, enough to reach a
    /// lower symmetric Dirichlet than Blender's MINIMUM_STRETCH unwrap).
    pub max_iterations: usize,
    /// Stop when the energy decreases by less than this, relative, or when the last two
    /// decreases shrink fast enough (each under half the one before) to predict that the next
    /// one would ([`super::nonlinear::iterate::Iteration::extrapolating`]; one iteration fewer
    /// on camelhead, 7 instead of 8, at symmetric Dirichlet 1.86366 instead of 1.86360).
    /// Default 1e-4: on every disk mesh of the test set and on Suzanne with her seams, the
    /// symmetric Dirichlet reached is below that of Blender's MINIMUM_STRETCH unwrap, in 10–40%
    /// fewer iterations than 1e-5 (1e-3 stops above it on camelhead).
    pub tolerance: f64,
    /// Starting map. Default [`SlimStart::Auto`].
    pub start: SlimStart,
    /// Steps after the first. Default [`SlimStep::Newton`].
    pub step: SlimStep,
}

/// The steps SLIM takes after its first (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SlimStep {
    /// Projected Newton steps on the same sparsity pattern, SLIM's proxy step again if one
    /// fails. Default: on camelhead, lion and halftunnel the energy reached is lower in 8–27%
    /// fewer iterations (README's performance section).
    #[default]
    Newton,
    /// SLIM's proxy steps throughout (the paper).
    Proxy,
}

impl Default for SlimOptions {
    fn default() -> Self {
        SlimOptions { max_iterations: 15, tolerance: 1e-4, start: SlimStart::Auto, step: SlimStep::Newton }
    }
}

/// What [`solve_with_history`] reports beside the map.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlimHistory {
    /// Symmetric Dirichlet energy per unit area / 4 of the start and after every iteration.
    pub energy: Vec<f64>,
    /// Accepted line-search step of every iteration.
    pub step: Vec<f64>,
    /// Seconds per iteration: `[assembly (local step, matrix values, right-hand side),
    /// numeric factorisation, solve, line search]`. The first iteration's factorisation
    /// includes the symbolic analysis.
    pub seconds: Vec<[f64; 4]>,
    /// Name of the starting map ("unfold", "lscm" or "mean_value").
    pub start: &'static str,
    /// Seconds spent computing and checking the starting maps.
    pub start_seconds: f64,
}

/// One triangle's projected Newton block: writes the lower-triangle entries (`local` order)
/// of `A_f Dᵀ P(∇²) D + ε A_f (L_f ⊗ I)` into `vals` and returns the energy gradient per
/// corner (u, v), where `D` maps the six corner unknowns to the Jacobian entries, `P` projects
/// onto the positive semidefinite cone and the small Laplacian term `ε` removes the global
/// rotation's null direction.
fn newton_block(ops: &TriangleOperators, f: usize, t: &[u32; 3], uv: &[[f64; 2]], local: &[(usize, usize)], vals: &mut [f64]) -> [[f64; 2]; 3] {
    let j = ops.jacobian(f, t, uv);
    let (g, mut h) = symmetric_dirichlet_derivatives(j);
    project_twist(j, &mut h);
    let a = ops.area[f];
    let gr = &ops.grad[f];
    // d[k][p]: derivative of Jacobian entry k by local unknown p (corner p / 2, u or v).
    let mut d = [[0.0; 6]; 4];
    for i in 0..3 {
        d[0][2 * i] = gr[0][i];
        d[1][2 * i] = gr[1][i];
        d[2][2 * i + 1] = gr[0][i];
        d[3][2 * i + 1] = gr[1][i];
    }
    let l = ops.stiffness(f);
    // Unknown p (component p % 2) moves only the Jacobian entries 2 (p % 2) and 2 (p % 2) + 1.
    let rows = |p: usize| [2 * (p % 2), 2 * (p % 2) + 1];
    // hd[x][q] = Σ_y h[x][y] d[y][q].
    let mut hd = [[0.0; 6]; 4];
    for x in 0..4 {
        for q in 0..6 {
            let [y0, y1] = rows(q);
            hd[x][q] = h[x][y0] * d[y0][q] + h[x][y1] * d[y1][q];
        }
    }
    for (k, &(p, q)) in local.iter().enumerate() {
        let [x0, x1] = rows(p);
        let s = d[x0][p] * hd[x0][q] + d[x1][p] * hd[x1][q];
        let reg = if p % 2 == q % 2 { NEWTON_REGULARISATION * l[p / 2][q / 2] } else { 0.0 };
        vals[k] = a * (s + reg);
    }
    let mut out = [[0.0; 2]; 3];
    for i in 0..3 {
        out[i][0] = a * (g[0] * gr[0][i] + g[1] * gr[1][i]);
        out[i][1] = a * (g[2] * gr[0][i] + g[3] * gr[1][i]);
    }
    out
}

/// Triangles per rayon task of the per-triangle steps; a chart with fewer triangles runs them
/// sequentially (no task overhead for the tiny charts met by the thousand).
const PER_TRIANGLE_MIN_LEN: usize = 1024;

/// `step(values of triangle f, f, triangle f)` for every triangle, writing the triangle's
/// [`BLOCK`] values, with its results in triangle order: in parallel on large charts,
/// sequentially on small ones (same results either way).
fn per_triangle<R: Send>(values: &mut [f64], tris: &[[u32; 3]], step: impl Fn(&mut [f64], usize, &[u32; 3]) -> R + Sync) -> Vec<R> {
    let k = BLOCK.len();
    if tris.len() < PER_TRIANGLE_MIN_LEN {
        return values.chunks_mut(k).zip(tris.iter().enumerate()).map(|(vals, (f, t))| step(vals, f, t)).collect();
    }
    values
        .par_chunks_mut(k)
        .zip(tris.par_iter().enumerate())
        .with_min_len(PER_TRIANGLE_MIN_LEN)
        .map(|(vals, (f, t))| step(vals, f, t))
        .collect()
}

/// A valid starting map: UVs, its energy and its name.
type Start = (Vec<[f64; 2]>, f64, &'static str);

/// The start ([`start::pick`]): LSCM (with [`SlimStart::Auto`]) and the mean value map, both
/// honouring spanning pins; without such pins each is scaled optimally and moved onto the pin.
/// `beside` runs as in [`start::pick_staged`], and not at all when the chart unfolds
/// isometrically (its map is the answer; nothing is iterated, so nothing is factored).
fn pick_start<X: Send>(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    ops: &TriangleOperators,
    options: &SlimOptions,
    beside: Option<impl FnOnce() -> X + Send>,
) -> (Option<Start>, Vec<String>, Option<X>) {
    let tris = &chart.triangles;
    let spanning = lscm::pins_span(pins);
    let start_pins: &[(u32, [f64; 2])] = if spanning { pins } else { &[] };
    let mut prepare = |uv: &mut Vec<[f64; 2]>| {
        if !spanning {
            scale_optimally(ops, tris, uv);
            translate_onto_first_pin(uv, pins);
        }
    };
    let mut assess = |uv: &[[f64; 2]]| {
        let e = symmetric_dirichlet(ops, tris, uv);
        if all_positive(tris, uv) && e.is_finite() {
            return Ok(e);
        }
        let bad = tris.iter().filter(|t| {
            let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            let a = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
            a <= 0.0 || a.is_nan()
        });
        Err(format!("{} flipped or degenerate triangle(s)", bad.count()))
    };
    // A chart without interior vertices unfolds isometrically, the energy's global minimiser
    // ([`unfold`]): no other start is computed unless a quad of it is not convex. Not used
    // when pins constrain the map's shape, nor when the mean value start is asked for.
    let mut rejected = Vec::new();
    if let Some(uv) = if spanning || options.start != SlimStart::Auto { None } else { unfold(chart) } {
        if let Some(best) = start::pick(chart, vec![(uv, "unfold")], &mut rejected, &mut prepare, &mut assess) {
            if super::nonconvex_quads(chart, &best.0) == 0 {
                return (Some(best), rejected, None);
            }
        }
    }
    let auto = options.start == SlimStart::Auto;
    let (best, x) = start::pick_staged(chart, start_pins, auto, &mut rejected, &mut prepare, &mut assess, beside);
    (best, rejected, x)
}

/// SLIM of one chart (see the module docs).
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &SlimOptions) -> Result<ChartSolution, ChartFailure> {
    solve_timed(chart, pins, options, false).map(|(s, _)| s)
}

/// SLIM of one chart, with the energy after every iteration, the accepted steps and the time
/// split of every iteration. When no flip-free start exists (pins, or a chart so degenerate
/// that the mean value map has zero-area triangles in floating point), the solution is pinned
/// LSCM marked as a fallback and the history is empty.
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &SlimOptions,
) -> Result<(ChartSolution, SlimHistory), ChartFailure> {
    solve_timed(chart, pins, options, true)
}

/// Reads the clock only when the time split is wanted: [`solve`] does not report it, and
/// reading the clock ten times per iteration is a noticeable share of a tiny chart's solve.
#[derive(Clone, Copy)]
struct Clock(bool);

impl Clock {
    fn now(self) -> Option<Instant> {
        self.0.then(Instant::now)
    }
}

/// Seconds from `a` to `b`, 0 when the clock was not read.
fn seconds(a: Option<Instant>, b: Option<Instant>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) => (b - a).as_secs_f64(),
        _ => 0.0,
    }
}

/// Accuracy of the projected Newton steps' solves (SLIM's and MIPS's): the residual of the
/// step's linear system at most this fraction of its value at the zero step, the energy's
/// gradient, as in inexact Newton methods (Dembo, Eisenstat, Steihaug, "Inexact Newton
/// methods", SIAM J. Numer. Anal. 19(2), 1982). Systems factored in single precision are
/// solved by conjugate gradients to this accuracy, one or two triangular solves instead of a
/// refinement to double precision ([`FixedValueSolver::solve_inexact`]); on camelhead every
/// iteration's energy is the same to six digits. SLIM's proxy steps are solved accurately.
pub(crate) const INEXACT: f64 = 1e-3;

/// Accuracy of SLIM's proxy steps' solves, as [`INEXACT`] (the residual relative to its value
/// at the current map), but tight: solved like the Newton steps (to [`INEXACT`]), the first
/// step's flip-free bound was three times shorter on camelhead split once, and the iteration
/// took one step more. A single-precision factor reaches it by conjugate gradients, where
/// iterative refinement, which [`FixedValueSolver::solve`] uses, can stop converging on the
/// first step's weights (huge where the start squeezes a triangle) and then refactor in double
/// precision for the rest of the iteration: on fertility subdivided three times and cut by
/// automatic seams (576,000 triangles, LSCM start), refinement gave up on the first step and
/// every Newton step then factored in double precision (1.15–1.37 s each); conjugate
/// gradients took 6 steps (0.9 s against 1.75–2.2 s) and the Newton factorizations stayed
/// single (0.72–0.94 s), to the same energies (1.069259 against 1.069255).
const PROXY_ACCURACY: f64 = 1e-10;

/// [`solve_with_history`]; `timed` says whether the history's seconds are measured (they are
/// 0 otherwise; the energies and steps are the same).
fn solve_timed(chart: &Chart, pins: &[(u32, [f64; 2])], options: &SlimOptions, timed: bool) -> Result<(ChartSolution, SlimHistory), ChartFailure> {
    let clock = Clock(timed);
    let n = chart.positions.len();
    // Pins spanning more than a point fix the map's scale: the energy is measured against the
    // 3D shape at that scale (module docs).
    let (rest, scale) = super::nonlinear::pins::rest_positions(chart, pins);
    let ops = TriangleOperators::new(&rest, &chart.triangles);
    let t_start = clock.now();
    // The global step's system is analysed beside the start (beside its mean value map on
    // large charts), over the barrier of a start that leaves no quad out (the usual case; see
    // below).
    let fixed_ids: Vec<u32> = anchor_vertices(pins).iter().flat_map(|&v| [2 * v, 2 * v + 1]).collect();
    let all_splits = if chart.quads.is_empty() { None } else { Some(chart.triangles_both_splits().0) };
    // One elimination order of the chart's vertices serves the LSCM start and the global step
    // (not computed when neither would use it: a mean value start and a system large enough
    // for nested dissection).
    let shared = options.start == SlimStart::Auto || OrderingKind::Auto.resolve(2 * n) == OrderingKind::Amd;
    let ordering = if shared { chart.ordering(OrderingKind::Auto) } else { OrderingKind::Auto.into() };
    let barrier_all = all_splits.as_deref().unwrap_or(&chart.triangles);
    let (start, rejected, mut analysed) = if chart.triangles.len() >= start::SEQUENTIAL_STARTS_FROM {
        // Beside the mean value start only (`pattern::ANALYSE_BESIDE_FROM`).
        let analyse = || analyse_blocks(2 * n, barrier_all, interleaved, &fixed_ids, ordering);
        let (start, rejected, analysis) = pick_start(chart, pins, &ops, options, Some(analyse));
        (start, rejected, analysis.flatten())
    } else {
        let start = || pick_start(chart, pins, &ops, options, None::<fn()>);
        let ((start, rejected, _), analysis) =
            analysed_beside(2 * n, barrier_all, interleaved, &fixed_ids, ordering, start);
        (start, rejected, analysis)
    };
    drop(all_splits);
    let start_seconds = seconds(t_start, clock.now());
    let Some((mut uv, mut energy, start_name)) = start else {
        let mut sol = lscm::solve(chart, pins)?;
        sol.fallback = Some(Fallback {
            method: "lscm",
            reason: format!(
                "no flip-free starting map{} ({}); SLIM needs one, LSCM used instead",
                if lscm::pins_span(pins) { " honours the pins" } else { "" },
                rejected.join("; ")
            ),
        });
        return Ok((sol, SlimHistory::default()));
    };
    // The barrier covers both diagonal splits of every quad (see `barrier_triangles`).
    let (barrier, weights, left_out) = super::barrier_triangles(chart, &uv);
    let (tris, ops) = if chart.quads.is_empty() {
        (&chart.triangles, ops)
    } else {
        let ops = ops.extended(&rest, &barrier).weighted(&weights);
        energy = symmetric_dirichlet(&ops, &barrier, &uv);
        (&barrier, ops)
    };
    drop(rest);
    let mut history = SlimHistory { start: start_name, start_seconds, ..Default::default() };

    // Fixed pattern: per triangle the 21 lower-triangle entries of its 6 × 6 block over
    // (u, v) of its three vertices.
    let local = &BLOCK;
    let fixed = anchors(pins, &uv);
    debug_assert!(fixed.iter().map(|p| p.0).eq(fixed_ids.iter().step_by(2).map(|&u| u / 2)));
    let fixed_vals: Vec<f64> = fixed.iter().flat_map(|p| [p.1[0], p.1[1]]).collect();
    // The analysis made beside the start holds when the barrier is every triangle of both
    // splits, i.e. no quad's other split was left out.
    if left_out > 0 {
        analysed = None;
    }
    let mut solver: Option<FixedValueSolver> = None;
    let mut values = vec![0.0; tris.len() * BLOCK.len()];
    let ls = LineSearchOptions::default();
    let mut it = Iteration::new(energy, options.max_iterations, options.tolerance, Change::OfPrevious, 0.0).extrapolating();
    let mut stopped = None;
    let (mut newton_steps, mut newton_failed) = (0usize, false);
    let zero_fixed = vec![0.0; fixed_ids.len()];
    let mut newton = false;
    // A start at energy 1 (every triangle isometric, e.g. `unfold`; the energy is normalised) is
    // the global minimiser: there is nothing to iterate.
    let isometric = it.energy() <= 1.0 + 1e-12;
    while !isometric && it.go_on() {
        let t0 = clock.now();
        if newton {
            // Projected Newton step (module docs): same pattern, same factorization analysis.
            let grads = per_triangle(&mut values, tris, |vals, f, t| newton_block(&ops, f, t, &uv, local, vals));
            let mut b = vec![0.0; 2 * n];
            for (t, g) in tris.iter().zip(&grads) {
                for i in 0..3 {
                    b[2 * t[i] as usize] -= g[i][0];
                    b[2 * t[i] as usize + 1] -= g[i][1];
                }
            }
            drop(grads);
            let t1 = clock.now();
            let s = solver.as_mut().expect("Newton steps follow a SLIM step");
            let factored = s.refactor(&values);
            let t2 = clock.now();
            match factored.and_then(|()| s.solve_inexact(&zero_fixed, &b, &vec![0.0; 2 * n], INEXACT)) {
                Ok(x) => {
                    let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
                    let t3 = clock.now();
                    let out = flip_free_line_search(tris, &mut uv, &dir, it.energy(), |q| symmetric_dirichlet(&ops, tris, q), &ls);
                    let t4 = clock.now();
                    history.seconds.push([seconds(t0, t1), seconds(t1, t2), seconds(t2, t3), seconds(t3, t4)]);
                    newton_steps += 1;
                    if out.step > 0.0 {
                        history.step.push(out.step);
                        if it.record(out.energy) {
                            break;
                        }
                        continue;
                    }
                    it.counted();
                }
                Err(_) => {}
            }
            // The Newton step failed (system not definite, or no descent): SLIM again.
            newton = false;
            newton_failed = true;
            continue;
        }
        let rhs_parts = per_triangle(&mut values, tris, |vals, f, t| {
                let (m, mr) = reweight(ops.jacobian(f, t, &uv));
                let l = ops.stiffness(f);
                let a = ops.area[f];
                let mm = [[m[0], m[1]], [m[1], m[2]]];
                for (k, &(p, q)) in local.iter().enumerate() {
                    vals[k] = a * mm[p % 2][q % 2] * l[p / 2][q / 2];
                }
                let g = &ops.grad[f];
                let mut out = [[0.0; 2]; 3];
                for i in 0..3 {
                    for c in 0..2 {
                        out[i][c] = a * (mr[c][0] * g[0][i] + mr[c][1] * g[1][i]);
                    }
                }
                out
            });
        let mut b = vec![0.0; 2 * n];
        for (t, c) in tris.iter().zip(&rhs_parts) {
            for i in 0..3 {
                b[2 * t[i] as usize] += c[i][0];
                b[2 * t[i] as usize + 1] += c[i][1];
            }
        }
        drop(rhs_parts);
        let t1 = clock.now();
        let factored = match solver.as_mut() {
            None if analysed.is_some() => {
                let mut s = analysed.take().expect("checked");
                let made = s.refactor(&values);
                solver = Some(s);
                made
            }
            None => {
                let mut pattern = block_triplets(tris, interleaved);
                for (p, v) in pattern.iter_mut().zip(&values) {
                    p.2 = *v;
                }
                // The first factorization sets the peak memory: the triplets carry the
                // values, so the value array is given back until the solver has its own copy.
                let len = values.len();
                drop(std::mem::take(&mut values));
                let made = FixedValueSolver::with_ordering(2 * n, &pattern, &fixed_ids, Symmetry::Symmetric, ordering).map(|s| solver = Some(s));
                // The solver keeps the pattern; this copy is not needed again.
                drop(pattern);
                values = vec![0.0; len];
                made
            }
            Some(s) => s.refactor(&values),
        };
        let t2 = clock.now();
        // A failed global step (extreme weights) ends the iteration; the current map is valid.
        // The proxy step is solved accurately (to `PROXY_ACCURACY`, see there), from the
        // current map.
        let guess: Vec<f64> = uv.iter().flat_map(|p| [p[0], p[1]]).collect();
        let solved = |s: &FixedValueSolver| s.solve_inexact(&fixed_vals, &b, &guess, PROXY_ACCURACY);
        let x = match factored.and_then(|()| solved(solver.as_ref().expect("factored above"))) {
            Ok(x) => x,
            Err(e) => {
                stopped = Some(e.to_string());
                break;
            }
        };
        let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[2 * i] - uv[i][0], x[2 * i + 1] - uv[i][1]]).collect();
        let t3 = clock.now();
        let out = flip_free_line_search(tris, &mut uv, &dir, it.energy(), |q| symmetric_dirichlet(&ops, tris, q), &ls);
        let t4 = clock.now();
        history.seconds.push([seconds(t0, t1), seconds(t1, t2), seconds(t2, t3), seconds(t3, t4)]);
        if out.step == 0.0 {
            it.stalled();
            break;
        }
        history.step.push(out.step);
        if it.record(out.energy) {
            break;
        }
        newton = !newton_failed && options.step == SlimStep::Newton;
    }
    let (energy, iterations, change) = (it.energy(), it.iterations, it.change);
    history.energy = it.history;
    let mut note = format!("symmetric Dirichlet {energy:.6} after {iterations} iteration(s) ({newton_steps} Newton), started from {start_name}");
    if let Some(reason) = stopped {
        note = format!("{note}; {}", stopped_early_note(&reason));
    }
    if let Some(q) = quads_left_out_note(left_out) {
        note = format!("{note}; {q}");
    }
    if let Some(p) = super::nonlinear::pins::pins_scale_note(pins.len(), scale) {
        note = format!("{note}; {p}");
    }
    let sol = ChartSolution { uv, iterations, residual: change, note: Some(note), fallback: None };
    Ok((sol, history))
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;
    use crate::charts::build_charts;
    use crate::mesh::PolyMesh;
    use crate::solvers::FORCE_SPARSE;

    /// The one chart of the faces `faces` (corner lists) over `positions`.
    fn chart_of(positions: &[[f64; 3]], faces: &[Vec<u32>]) -> Chart {
        let corners: Vec<u32> = faces.iter().flatten().copied().collect();
        let sizes: Vec<u32> = faces.iter().map(|f| f.len() as u32).collect();
        let mesh = PolyMesh::new(positions, &corners, &sizes).unwrap();
        let mut charts = build_charts(&mesh, &[], None);
        assert_eq!(charts.len(), 1);
        charts.remove(0)
    }

    /// A tiny chart: `kind` 0 one bent quad, 1 a strip of two bent quads, 2 a 2 × 2 grid of
    /// quads (one interior vertex), 3 a fan of triangles around a raised interior vertex;
    /// `z` bends it out of the plane, `xy` jitters its corners.
    fn tiny_chart(kind: usize, z: &[f64], xy: &[f64]) -> Chart {
        let jitter = |i: usize| [0.3 * xy[(2 * i) % xy.len()], 0.3 * xy[(2 * i + 1) % xy.len()], z[i % z.len()]];
        let grid = |w: usize, h: usize| -> (Vec<[f64; 3]>, Vec<Vec<u32>>) {
            let mut p = Vec::new();
            for j in 0..=h {
                for i in 0..=w {
                    let d = jitter(p.len());
                    p.push([i as f64 + d[0], j as f64 + d[1], d[2]]);
                }
            }
            let v = |i: usize, j: usize| (j * (w + 1) + i) as u32;
            let faces = (0..h).flat_map(|j| (0..w).map(move |i| vec![v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)])).collect();
            (p, faces)
        };
        let (p, faces) = match kind {
            0 => grid(1, 1),
            1 => grid(2, 1),
            2 => grid(2, 2),
            _ => {
                let k = 5 + xy.len() % 3;
                let mut p = vec![[0.0, 0.0, 0.4 + z[0].abs()]];
                for i in 0..k {
                    let a = (i as f64 + 0.3 * xy[i % xy.len()]) / k as f64 * std::f64::consts::TAU;
                    p.push([a.cos(), a.sin(), 0.5 * z[(i + 1) % z.len()]]);
                }
                let faces = (0..k as u32).map(|i| vec![0, 1 + i, 1 + (i + 1) % k as u32]).collect();
                (p, faces)
            }
        };
        chart_of(&p, &faces)
    }

    fn doubled_area(uv: &[[f64; 2]], t: &[u32; 3]) -> f64 {
        let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
        (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])
    }

    /// A bent quad is not developable with its other diagonal: SLIM iterates, and the dense
    /// path takes the same steps as the general one.
    #[test]
    fn a_bent_quad_iterates_the_same_on_both_paths() {
        let chart = tiny_chart(0, &[0.0, 0.0, 0.0, 0.6], &[0.0]);
        let (dense, h) = solve_with_history(&chart, &[], &SlimOptions::default()).unwrap();
        FORCE_SPARSE.with(|f| f.set(true));
        let (general, hg) = solve_with_history(&chart, &[], &SlimOptions::default()).unwrap();
        FORCE_SPARSE.with(|f| f.set(false));
        assert!(dense.iterations > 0 && dense.iterations == general.iterations, "{} vs {}", dense.iterations, general.iterations);
        assert!(h.energy.last() < h.energy.first(), "{:?}", h.energy);
        for (e, g) in h.energy.iter().zip(&hg.energy) {
            assert!((e - g).abs() < 1e-12, "{:?} vs {:?}", h.energy, hg.energy);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

        /// Tiny charts take the dense path (own Cholesky, no pattern analysis, sequential
        /// per-triangle loops): the same map as the general sparse path to 1e-9, the same
        /// iterations, every triangle positive, quads convex and the energy never above the
        /// start's.
        #[test]
        fn tiny_charts_solve_like_the_general_path(
            kind in 0usize..4,
            z in proptest::collection::vec(-0.8f64..0.8, 3..10),
            xy in proptest::collection::vec(-0.5f64..0.5, 2..12),
            step_proxy in any::<bool>(),
        ) {
            let chart = tiny_chart(kind, &z, &xy);
            let options = SlimOptions { step: if step_proxy { SlimStep::Proxy } else { SlimStep::Newton }, ..Default::default() };
            let (dense, h) = solve_with_history(&chart, &[], &options).unwrap();
            FORCE_SPARSE.with(|f| f.set(true));
            let general = solve_with_history(&chart, &[], &options);
            FORCE_SPARSE.with(|f| f.set(false));
            let (general, hg) = general.unwrap();
            prop_assert_eq!(dense.iterations, general.iterations);
            prop_assert_eq!(h.start, hg.start);
            for (a, b) in dense.uv.iter().zip(&general.uv) {
                prop_assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9, "{:?} vs {:?}", a, b);
            }
            prop_assert!(dense.fallback.is_none());
            for t in &chart.triangles {
                prop_assert!(doubled_area(&dense.uv, t) > 0.0, "flipped {:?}", t);
            }
            prop_assert_eq!(crate::methods::nonconvex_quads(&chart, &dense.uv), 0);
            let (first, last) = (h.energy[0], *h.energy.last().unwrap());
            prop_assert!(last <= first && last >= 1.0 - 1e-12, "energy {} from {}", last, first);
        }
    }
}
