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
//! to J ([`density_derivatives`]) with its one possibly negative eigenvalue (the twist) set
//! to 0, mapped to the six corner unknowns, plus `1e-6 ·` the triangle's Laplacian (definite
//! along the global rotation). Its pattern is SLIM's, so the symbolic analysis is shared. The
//! SLIM proxy is a good global step far from the optimum; Newton converges much faster near
//! it (camelhead: symmetric Dirichlet 1.8618 in 8 iterations vs 1.8642 in 13). A Newton step
//! that cannot be factored or finds no descent switches back to SLIM steps for good.
//!
//! Start: a flip-free map. [`SlimStart::Auto`] (default) tries LSCM and the mean value map on
//! a circle (Floater 2003, flip-free by Tutte's theorem) and keeps whichever has no
//! non-positive triangle and the lower energy; [`SlimStart::MeanValue`] uses only the latter.
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
//! Pins: pinned vertices are fixed in every global step. With pins spanning more than a point,
//! the start honours them too (pinned LSCM or pinned mean value); when neither pinned start is
//! flip-free, no flip-free map with those pins is known and the chart falls back to pinned
//! LSCM, saying so ([`ChartSolution::fallback`]).
//!
//! Preconditions: a disk chart, possibly with holes. Failures: once a flip-free start exists
//! none; a global step that cannot be factored or solved ends the iteration with the current
//! (valid) map and says so in the note. Without a start, the LSCM fallback fails like
//! [`lscm::solve`] (singular system of a disconnected chart).

use std::time::Instant;

use rayon::prelude::*;

use super::arap::{anchors, closest_rotation, TriangleOperators};
use super::fixed_boundary::{self, Weights};
use super::{chart_angles, lscm, BoundaryShape, ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, flip_free_line_search, LineSearchOptions};
use crate::solvers::{FixedValueSolver, Symmetry};

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
    /// Stop when the energy decreases by less than this, relative. Default 1e-4: on every disk
    /// mesh of the test set and on Suzanne with her seams, the symmetric Dirichlet reached is
    /// below that of Blender's MINIMUM_STRETCH unwrap, in 10–40% fewer iterations than 1e-5
    /// (1e-3 stops above it on camelhead).
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
    /// Name of the starting map ("lscm" or "mean_value").
    pub start: &'static str,
    /// Seconds spent computing and checking the starting maps.
    pub start_seconds: f64,
}

/// Symmetric Dirichlet energy `Σ A (‖J‖² + ‖J⁻¹‖²) / (4 Σ A)` of `uv`; `+∞` if any triangle
/// has a non-positive Jacobian determinant.
pub fn symmetric_dirichlet(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    let e: f64 = triangles
        .par_iter()
        .enumerate()
        .with_min_len(2048)
        .map(|(f, t)| ops.area[f] * density(ops.jacobian(f, t, uv)))
        .sum();
    e / (4.0 * ops.total_area)
}

/// Symmetric Dirichlet density ‖J‖² (1 + 1/det²) = σ1² + σ2² + σ1⁻² + σ2⁻² of one Jacobian;
/// 4 for a rotation, `+∞` unless det J > 0. Shared with the scaffold method.
#[inline]
pub(crate) fn density(j: [[f64; 2]; 2]) -> f64 {
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    if !(det > 0.0) {
        return f64::INFINITY;
    }
    let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
    fro * (1.0 + 1.0 / (det * det))
}

/// Gradient and Hessian of the symmetric Dirichlet density with respect to the Jacobian's
/// entries `j = (J00, J01, J10, J11)`. With `I2 = ‖J‖²`, `I3 = det J` and `g3 = ∂I3/∂j`,
/// the density is `I2 (1 + I3⁻²)`, so
/// `∇ = 2j (1 + I3⁻²) − 2 I2 I3⁻³ g3` and
/// `∇² = 2 (1 + I3⁻²) Id − 2 I3⁻³ (2j g3ᵀ + g3 2jᵀ) + 6 I2 I3⁻⁴ g3 g3ᵀ − 2 I2 I3⁻³ ∇²I3`.
/// Preconditions: det J > 0.
pub(crate) fn density_derivatives(j: [[f64; 2]; 2]) -> ([f64; 4], [[f64; 4]; 4]) {
    let v = [j[0][0], j[0][1], j[1][0], j[1][1]];
    let i2: f64 = v.iter().map(|x| x * x).sum();
    let i3 = v[0] * v[3] - v[1] * v[2];
    let g3 = [v[3], -v[2], -v[1], v[0]];
    let (r2, r3, r4) = (1.0 / (i3 * i3), 1.0 / (i3 * i3 * i3), 1.0 / (i3 * i3 * i3 * i3));
    let mut g = [0.0; 4];
    let mut h = [[0.0; 4]; 4];
    for a in 0..4 {
        g[a] = 2.0 * v[a] * (1.0 + r2) - 2.0 * i2 * r3 * g3[a];
        for b in 0..4 {
            h[a][b] = -2.0 * r3 * (2.0 * v[a] * g3[b] + g3[a] * 2.0 * v[b]) + 6.0 * i2 * r4 * g3[a] * g3[b];
        }
        h[a][a] += 2.0 * (1.0 + r2);
    }
    // ∇²I3: ∂²(ad − bc) is 1 at (a, d), (d, a) and −1 at (b, c), (c, b).
    h[0][3] -= 2.0 * i2 * r3;
    h[3][0] -= 2.0 * i2 * r3;
    h[1][2] += 2.0 * i2 * r3;
    h[2][1] += 2.0 * i2 * r3;
    (g, h)
}

/// Project the symmetric Dirichlet Hessian of [`density_derivatives`] onto the positive
/// semidefinite cone, analytically (Smith, Goes & Kim, "Analytic eigensystems for isotropic
/// distortion energies", 2019). For `J = U Σ Vᵀ` its eigenvectors are the two scalings
/// `U diag(·) Vᵀ` (eigenvalues `2 + 6σᵢ⁻⁴ > 0`), the flip `U [[0,1],[1,0]] Vᵀ / √2`
/// (eigenvalue `2 + 2(σ₂⁻³ − σ₁⁻³)/(σ₁ − σ₂) > 2`) and the twist `U [[0,−1],[1,0]] Vᵀ / √2
/// = R₉₀ R / √2` (`R = U Vᵀ` the closest rotation) with eigenvalue
/// `λ = 2 − 2(σ₁⁻³ + σ₂⁻³)/(σ₁ + σ₂)`, the only one that can be negative: then `−λ t tᵀ` is
/// added. Preconditions: det J > 0.
pub(crate) fn project_twist(j: [[f64; 2]; 2], h: &mut [[f64; 4]; 4]) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let q = (0.5 * (a + d)).hypot(0.5 * (c - b));
    let r = (0.5 * (a - d)).hypot(0.5 * (c + b));
    let (s1, s2) = (q + r, q - r);
    let lambda = 2.0 - 2.0 * (s1.powi(-3) + s2.powi(-3)) / (s1 + s2);
    if lambda < 0.0 {
        let (rc, rs) = closest_rotation(j);
        let t = [-rs, -rc, rc, -rs].map(|x| x * std::f64::consts::FRAC_1_SQRT_2);
        for x in 0..4 {
            for y in 0..4 {
                h[x][y] -= lambda * t[x] * t[y];
            }
        }
    }
}

/// One triangle's projected Newton block: writes the lower-triangle entries (`local` order)
/// of `A_f Dᵀ P(∇²) D + ε A_f (L_f ⊗ I)` into `vals` and returns the energy gradient per
/// corner (u, v), where `D` maps the six corner unknowns to the Jacobian entries, `P` projects
/// onto the positive semidefinite cone and the small Laplacian term `ε` removes the global
/// rotation's null direction.
fn newton_block(ops: &TriangleOperators, f: usize, t: &[u32; 3], uv: &[[f64; 2]], local: &[(usize, usize)], vals: &mut [f64]) -> [[f64; 2]; 3] {
    let j = ops.jacobian(f, t, uv);
    let (g, mut h) = density_derivatives(j);
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
    for (k, &(p, q)) in local.iter().enumerate() {
        let mut s = 0.0;
        for x in 0..4 {
            if d[x][p] == 0.0 {
                continue;
            }
            for y in 0..4 {
                s += d[x][p] * h[x][y] * d[y][q];
            }
        }
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

/// Scale `uv` about the origin by the factor minimising the symmetric Dirichlet energy
/// (`E(s) = s² P + s⁻² Q`, optimal `s = (Q/P)^{1/4}`). No-op for an invalid map.
fn scale_optimally(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &mut [[f64; 2]]) {
    let s = optimal_scale(triangles.len(), |f| (ops.area[f], ops.jacobian(f, &triangles[f], uv)));
    scale_uv(uv, s);
}

/// The factor `s = (Q/P)^{1/4}` minimising `E(s) = s² P + s⁻² Q`, `P = Σ A ‖J‖²`,
/// `Q = Σ A ‖J‖²/det² = Σ A ‖J⁻¹‖²`, over `n` triangles given as `(area, J)` by
/// `area_and_jacobian`: the best uniform scale of a map for the symmetric Dirichlet energy.
/// Shared with the scaffold method. Not finite for a map with a degenerate triangle.
pub(crate) fn optimal_scale(n: usize, area_and_jacobian: impl Fn(usize) -> (f64, [[f64; 2]; 2]) + Sync) -> f64 {
    let (p, q) = (0..n)
        .into_par_iter()
        .with_min_len(2048)
        .map(|f| {
            let (a, j) = area_and_jacobian(f);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
            (a * fro, a * fro / (det * det))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    (q / p).sqrt().sqrt()
}

/// Multiply every UV by `s` (no-op unless `s` is finite and positive).
pub(crate) fn scale_uv(uv: &mut [[f64; 2]], s: f64) {
    if s.is_finite() && s > 0.0 {
        for x in uv.iter_mut() {
            *x = [s * x[0], s * x[1]];
        }
    }
}

/// The two candidate starting maps of SLIM and scaffold, computed side by side (independent
/// solves): LSCM (if `with_lscm`) and the mean value map on a circle, both honouring
/// `start_pins`. Returns the maps that could be computed, by name, and why the others could not.
pub(crate) fn candidate_starts(
    chart: &Chart,
    start_pins: &[(u32, [f64; 2])],
    with_lscm: bool,
) -> (Vec<(Vec<[f64; 2]>, &'static str)>, Vec<String>) {
    let (lscm_start, mean_value_start) = rayon::join(
        || {
            with_lscm.then(|| {
                let angles = chart_angles(&chart.positions, &chart.triangles);
                lscm::solve_with_angles(chart, &angles, start_pins)
            })
        },
        || fixed_boundary::solve(chart, start_pins, BoundaryShape::Circle, Weights::MeanValue),
    );
    let (mut candidates, mut rejected) = (Vec::new(), Vec::new());
    match lscm_start {
        Some(Ok((uv, _))) => candidates.push((uv, "lscm")),
        Some(Err(e)) => rejected.push(format!("lscm: {}", e.0)),
        None => {}
    }
    match mean_value_start {
        Ok(s) => candidates.push((s.uv, "mean_value")),
        Err(e) => rejected.push(format!("mean_value: {}", e.0)),
    }
    (candidates, rejected)
}

/// Per-triangle local step: `W²` (symmetric, as `[m00, m01, m11]`) and `W² R` (row-major).
/// Shared with the scaffold method.
#[inline]
pub(crate) fn reweight(j: [[f64; 2]; 2]) -> ([f64; 3], [[f64; 2]; 2]) {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    // Singular values (det > 0 on a valid map, so q > r).
    let q = (0.5 * (a + d)).hypot(0.5 * (c - b));
    let r = (0.5 * (a - d)).hypot(0.5 * (c + b));
    let s1 = q + r;
    let s2 = (q - r).max(1e-300);
    let w = |s: f64| (s + 1.0) * (s * s + 1.0) / (s * s * s);
    let (w1, w2) = (w(s1), w(s2));
    // Left singular vector of σ1: principal eigenvector of J Jᵀ.
    let phi = 0.5 * (2.0 * (a * c + b * d)).atan2(a * a + b * b - c * c - d * d);
    let (cp, sp) = (phi.cos(), phi.sin());
    let m = [w1 * cp * cp + w2 * sp * sp, (w1 - w2) * cp * sp, w1 * sp * sp + w2 * cp * cp];
    let (rc, rs) = closest_rotation(j);
    let rot = [[rc, -rs], [rs, rc]];
    let mr = [
        [m[0] * rot[0][0] + m[1] * rot[1][0], m[0] * rot[0][1] + m[1] * rot[1][1]],
        [m[1] * rot[0][0] + m[2] * rot[1][0], m[1] * rot[0][1] + m[2] * rot[1][1]],
    ];
    (m, mr)
}

/// A valid starting map: UVs, its energy and its name.
type Start = (Vec<[f64; 2]>, f64, &'static str);

fn pick_start(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    ops: &TriangleOperators,
    options: &SlimOptions,
) -> Result<(Option<Start>, Vec<String>), ChartFailure> {
    let tris = &chart.triangles;
    let spanning = lscm::pins_span(pins);
    let start_pins: &[(u32, [f64; 2])] = if spanning { pins } else { &[] };
    let (candidates, mut rejected) = candidate_starts(chart, start_pins, options.start == SlimStart::Auto);
    let mut best: Option<(Vec<[f64; 2]>, f64, &'static str, usize)> = None;
    for (mut uv, name) in candidates {
        if !spanning {
            scale_optimally(ops, tris, &mut uv);
            if let Some(&(v, target)) = pins.first() {
                let d = [target[0] - uv[v as usize][0], target[1] - uv[v as usize][1]];
                for p in uv.iter_mut() {
                    *p = [p[0] + d[0], p[1] + d[1]];
                }
            }
        }
        let e = symmetric_dirichlet(ops, tris, &uv);
        if !all_positive(tris, &uv) || !e.is_finite() {
            let bad = tris.iter().filter(|t| {
                let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
                let a = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
                a <= 0.0 || a.is_nan()
            });
            rejected.push(format!("{name}: {} flipped or degenerate triangle(s)", bad.count()));
            continue;
        }
        // Fewer non-convex quads first (the barrier cannot make them convex), then energy.
        let bad = super::nonconvex_quads(chart, &uv);
        if best.as_ref().is_none_or(|b| (bad, e) < (b.3, b.1)) {
            best = Some((uv, e, name, bad));
        }
    }
    Ok((best.map(|(uv, e, name, _)| (uv, e, name)), rejected))
}

/// SLIM of one chart (see the module docs).
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &SlimOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
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
    let n = chart.positions.len();
    let ops = TriangleOperators::new(&chart.positions, &chart.triangles);
    let t_start = Instant::now();
    let (start, rejected) = pick_start(chart, pins, &ops, options)?;
    let start_seconds = t_start.elapsed().as_secs_f64();
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
        let mut ops = TriangleOperators::new(&chart.positions, &barrier);
        for (a, w) in ops.area.iter_mut().zip(&weights) {
            *a *= w;
        }
        ops.total_area = ops.area.iter().sum();
        energy = symmetric_dirichlet(&ops, &barrier, &uv);
        (&barrier, ops)
    };
    let mut history = SlimHistory { energy: vec![energy], start: start_name, start_seconds, ..Default::default() };

    // Fixed pattern: per triangle the 21 lower-triangle entries of its 6 × 6 block over
    // (u, v) of its three vertices.
    let local: Vec<(usize, usize)> = (0..6).flat_map(|p| (0..=p).map(move |q| (p, q))).collect();
    let mut pattern = Vec::with_capacity(tris.len() * local.len());
    for t in tris {
        for &(p, q) in &local {
            let gp = 2 * t[p / 2] + (p % 2) as u32;
            let gq = 2 * t[q / 2] + (q % 2) as u32;
            pattern.push((gp.max(gq), gp.min(gq), 0.0));
        }
    }
    let fixed = anchors(pins, &uv);
    let fixed_ids: Vec<u32> = fixed.iter().flat_map(|p| [2 * p.0, 2 * p.0 + 1]).collect();
    let fixed_vals = vec![fixed.iter().flat_map(|p| [p.1[0], p.1[1]]).collect::<Vec<f64>>()];
    let mut solver: Option<FixedValueSolver> = None;
    let mut values = vec![0.0; pattern.len()];
    let ls = LineSearchOptions::default();
    let mut change = 0.0;
    let mut iterations = 0;
    let mut stopped = None;
    let (mut newton_steps, mut newton_failed) = (0usize, false);
    let zero_fixed = vec![vec![0.0; fixed_ids.len()]];
    let mut newton = false;
    while iterations < options.max_iterations && !crate::progress::cancelled() {
        let t0 = Instant::now();
        if newton {
            // Projected Newton step (module docs): same pattern, same factorization analysis.
            let grads: Vec<[[f64; 2]; 3]> = values
                .par_chunks_mut(local.len())
                .zip(tris.par_iter().enumerate())
                .with_min_len(1024)
                .map(|(vals, (f, t))| newton_block(&ops, f, t, &uv, &local, vals))
                .collect();
            let mut b = vec![0.0; 2 * n];
            for (t, g) in tris.iter().zip(&grads) {
                for i in 0..3 {
                    b[2 * t[i] as usize] -= g[i][0];
                    b[2 * t[i] as usize + 1] -= g[i][1];
                }
            }
            let t1 = Instant::now();
            let s = solver.as_mut().expect("Newton steps follow a SLIM step");
            let factored = s.refactor(&values);
            let t2 = Instant::now();
            match factored.and_then(|()| s.solve(&zero_fixed, &[b])) {
                Ok(x) => {
                    let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[0][2 * i], x[0][2 * i + 1]]).collect();
                    let t3 = Instant::now();
                    let out = flip_free_line_search(tris, &mut uv, &dir, energy, |q| symmetric_dirichlet(&ops, tris, q), &ls);
                    let t4 = Instant::now();
                    history.seconds.push([(t1 - t0).as_secs_f64(), (t2 - t1).as_secs_f64(), (t3 - t2).as_secs_f64(), (t4 - t3).as_secs_f64()]);
                    iterations += 1;
                    newton_steps += 1;
                    if out.step > 0.0 {
                        history.energy.push(out.energy);
                        history.step.push(out.step);
                        change = (energy - out.energy) / energy;
                        energy = out.energy;
                        if change < options.tolerance {
                            break;
                        }
                        continue;
                    }
                }
                Err(_) => {}
            }
            // The Newton step failed (system not definite, or no descent): SLIM again.
            newton = false;
            newton_failed = true;
            continue;
        }
        let rhs_parts: Vec<[[f64; 2]; 3]> = values
            .par_chunks_mut(local.len())
            .zip(tris.par_iter().enumerate())
            .with_min_len(1024)
            .map(|(vals, (f, t))| {
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
            })
            .collect();
        let mut b = vec![0.0; 2 * n];
        for (t, c) in tris.iter().zip(&rhs_parts) {
            for i in 0..3 {
                b[2 * t[i] as usize] += c[i][0];
                b[2 * t[i] as usize + 1] += c[i][1];
            }
        }
        let t1 = Instant::now();
        let factored = match solver.as_mut() {
            None => {
                for (p, v) in pattern.iter_mut().zip(&values) {
                    p.2 = *v;
                }
                FixedValueSolver::new(2 * n, &pattern, &fixed_ids, Symmetry::Symmetric).map(|s| solver = Some(s))
            }
            Some(s) => s.refactor(&values),
        };
        let t2 = Instant::now();
        // A failed global step (extreme weights) ends the iteration; the current map is valid.
        let x = match factored.and_then(|()| solver.as_ref().expect("factored above").solve(&fixed_vals, &[b])) {
            Ok(x) => x,
            Err(e) => {
                stopped = Some(e.to_string());
                break;
            }
        };
        let dir: Vec<[f64; 2]> = (0..n).map(|i| [x[0][2 * i] - uv[i][0], x[0][2 * i + 1] - uv[i][1]]).collect();
        let t3 = Instant::now();
        let out = flip_free_line_search(tris, &mut uv, &dir, energy, |q| symmetric_dirichlet(&ops, tris, q), &ls);
        let t4 = Instant::now();
        history.seconds.push([
            (t1 - t0).as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            (t3 - t2).as_secs_f64(),
            (t4 - t3).as_secs_f64(),
        ]);
        iterations += 1;
        if out.step == 0.0 {
            change = 0.0;
            break;
        }
        history.energy.push(out.energy);
        history.step.push(out.step);
        change = (energy - out.energy) / energy;
        energy = out.energy;
        if change < options.tolerance {
            break;
        }
        newton = !newton_failed && options.step == SlimStep::Newton;
    }
    let mut note = format!("symmetric Dirichlet {energy:.6} after {iterations} iteration(s) ({newton_steps} Newton), started from {start_name}");
    if let Some(reason) = stopped {
        note = format!("{note}; stopped early, the global step failed: {reason}");
    }
    if left_out > 0 {
        note = format!("{note}; {left_out} quad triangle(s) of the other diagonal were not positive at the start, so those quads may stay non-convex");
    }
    let sol = ChartSolution { uv, iterations, residual: change, note: Some(note), fallback: None };
    Ok((sol, history))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn jacobian_of(s1: f64, s2: f64, u: f64, v: f64) -> [[f64; 2]; 2] {
        let ru = [[u.cos(), -u.sin()], [u.sin(), u.cos()]];
        let rv = [[v.cos(), -v.sin()], [v.sin(), v.cos()]];
        let mut j = [[0.0; 2]; 2];
        for a in 0..2 {
            for b in 0..2 {
                j[a][b] = ru[a][0] * s1 * rv[b][0] + ru[a][1] * s2 * rv[b][1];
            }
        }
        j
    }

    #[test]
    fn density_derivatives_match_finite_differences() {
        for &(s1, s2, u, v) in &[(1.0, 1.0, 0.3, -0.2), (2.5, 0.4, 0.7, -1.1), (0.3, 0.2, 2.0, 0.5), (1.2, 0.9, -0.4, 0.0)] {
            let j = jacobian_of(s1, s2, u, v);
            let (g, h) = density_derivatives(j);
            let f = |x: [f64; 4]| density([[x[0], x[1]], [x[2], x[3]]]);
            let x0 = [j[0][0], j[0][1], j[1][0], j[1][1]];
            let eps = 1e-6;
            for a in 0..4 {
                let (mut xp, mut xm) = (x0, x0);
                xp[a] += eps;
                xm[a] -= eps;
                let fd = (f(xp) - f(xm)) / (2.0 * eps);
                assert!((fd - g[a]).abs() <= 1e-6 * (1.0 + g[a].abs()), "gradient {a}: {fd} vs {}", g[a]);
                let (gp, gm) = (density_derivatives([[xp[0], xp[1]], [xp[2], xp[3]]]).0, density_derivatives([[xm[0], xm[1]], [xm[2], xm[3]]]).0);
                for b in 0..4 {
                    let fd = (gp[b] - gm[b]) / (2.0 * eps);
                    assert!((fd - h[a][b]).abs() <= 1e-5 * (1.0 + h[a][b].abs()), "Hessian {a}{b}: {fd} vs {}", h[a][b]);
                }
            }
        }
    }

    #[test]
    fn analytic_projection_equals_the_eigen_decomposition() {
        let mut negative_seen = false;
        for k in 0..200 {
            let t = k as f64;
            let (s1, s2) = (0.15 + 3.0 * (0.37 * t).sin().abs(), 0.1 + 2.0 * (0.61 * t + 0.3).cos().abs());
            let j = jacobian_of(s1.max(s2), s1.min(s2), 0.13 * t, -0.29 * t);
            let (_, h) = density_derivatives(j);
            let want = crate::methods::mips::project_psd4(&h);
            let mut got = h;
            project_twist(j, &mut got);
            negative_seen |= got != h;
            let scale = h.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
            for a in 0..4 {
                for b in 0..4 {
                    assert!((got[a][b] - want[a][b]).abs() <= 1e-8 * scale, "{k}: ({a},{b}) {} vs {}", got[a][b], want[a][b]);
                }
            }
        }
        assert!(negative_seen, "no Jacobian with a negative twist eigenvalue was tested");
    }

    #[test]
    fn reweighting_matches_the_svd_and_the_energy_matches_singular_values() {
        // J = U diag(s1, s2) Vᵀ with known factors.
        let (s1, s2) = (2.5, 0.4);
        let (u, v) = (0.7f64, -1.1f64);
        let ru = [[u.cos(), -u.sin()], [u.sin(), u.cos()]];
        let rv = [[v.cos(), -v.sin()], [v.sin(), v.cos()]];
        let mut j = [[0.0; 2]; 2];
        for a in 0..2 {
            for b in 0..2 {
                // (U Σ Vᵀ)_ab = Σ_k U_ak σ_k V_bk
                j[a][b] = ru[a][0] * s1 * rv[b][0] + ru[a][1] * s2 * rv[b][1];
            }
        }
        let (m, mr) = reweight(j);
        let w = |s: f64| (s + 1.0) * (s * s + 1.0) / (s * s * s);
        // W² has eigenvalues w(s1), w(s2) with eigenvector U e1 for w(s1).
        let e1 = [ru[0][0], ru[1][0]];
        let me1 = [m[0] * e1[0] + m[1] * e1[1], m[1] * e1[0] + m[2] * e1[1]];
        assert!((me1[0] - w(s1) * e1[0]).abs() < 1e-12 && (me1[1] - w(s1) * e1[1]).abs() < 1e-12);
        assert!((m[0] + m[2] - w(s1) - w(s2)).abs() < 1e-12);
        // R = U Vᵀ, so W² R = W² U Vᵀ.
        let r = [[ru[0][0] * rv[0][0] + ru[0][1] * rv[0][1], ru[0][0] * rv[1][0] + ru[0][1] * rv[1][1]],
                 [ru[1][0] * rv[0][0] + ru[1][1] * rv[0][1], ru[1][0] * rv[1][0] + ru[1][1] * rv[1][1]]];
        let mm = [[m[0], m[1]], [m[1], m[2]]];
        for a in 0..2 {
            for b in 0..2 {
                let want = mm[a][0] * r[0][b] + mm[a][1] * r[1][b];
                assert!((mr[a][b] - want).abs() < 1e-12);
            }
        }
        // Energy of one triangle mapped by J equals (σ1² + σ2² + σ1⁻² + σ2⁻²)/4.
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.8, 0.0]];
        let ops = TriangleOperators::new(&p, &[[0, 1, 2]]);
        let uv: Vec<[f64; 2]> = p.iter().map(|z| [j[0][0] * z[0] + j[0][1] * z[1], j[1][0] * z[0] + j[1][1] * z[1]]).collect();
        let e = symmetric_dirichlet(&ops, &[[0, 1, 2]], &uv);
        let want = 0.25 * (s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2));
        assert!((e - want).abs() < 1e-12, "{e} vs {want}");
        // Mirrored: infinite.
        let mirrored: Vec<[f64; 2]> = uv.iter().map(|z| [z[0], -z[1]]).collect();
        assert_eq!(symmetric_dirichlet(&ops, &[[0, 1, 2]], &mirrored), f64::INFINITY);
        // The optimal scale of an isotropic map s·I is 1/s.
        let mut scaled: Vec<[f64; 2]> = p.iter().map(|z| [3.0 * z[0], 3.0 * z[1]]).collect();
        scale_optimally(&ops, &[[0, 1, 2]], &mut scaled);
        assert!((symmetric_dirichlet(&ops, &[[0, 1, 2]], &scaled) - 1.0).abs() < 1e-12);
    }
}
