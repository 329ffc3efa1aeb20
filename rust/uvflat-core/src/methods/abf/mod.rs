//! Angle Based Flattening (ABF) and ABF++.
//!
//! Papers: A. Sheffer, E. de Sturler, "Parameterization of Faceted Surfaces for Meshing using
//! Angle-Based Flattening", Engineering with Computers 17, 2001 (ABF); A. Sheffer, B. Lévy,
//! M. Mogilnitsky, A. Bogomyakov, "ABF++: Fast and Robust Angle Based Flattening", ACM TOG
//! 24(2), 2005 (ABF++).
//!
//! The unknowns are the corner angles α of every chart triangle. The targets β are the 3D
//! corner angles (clamped to valid triangles, see [`crate::geometry::clamped_angles`]), scaled
//! at every interior vertex so that they sum to 2π there. ABF minimises
//!
//! ```text
//! E(α) = Σ_c (α_c − β_c)² / β_c²
//! ```
//!
//! subject to
//! * triangle: every triangle's angles sum to π;
//! * planarity: the angles around every interior vertex sum to 2π;
//! * wheel (sine law, log form): around every interior vertex v, over its triangles (v, a, b)
//!   in their own orientation, `Σ log sin α_b − Σ log sin α_a = 0` (the edge-length ratios
//!   |va|/|vb| = sin α_b / sin α_a multiply to one around v);
//! * with [`AbfBoundary::Convex`], every vertex of the outer boundary loop has angle sum at
//!   most the cap `π − π/n` (n outer vertices), every angle is at least a small lower bound,
//!   and holes are closed (see "Convex boundary" below).
//!
//! Angles satisfying these are those of a planar triangulation (locally injective when all are
//! in (0, π)), so the UVs follow by a least-squares reconstruction: LSCM driven by the solved
//! angles ([`super::lscm::solve_with_angles`]), exact for exactly consistent angles on a disk.
//!
//! The solve is Newton's method on the Lagrangian (an SQP iteration). The Hessian of the
//! Lagrangian in the angles is diagonal, `2/β² ∓ λ_wheel/sin²α` (log form of the wheel
//! condition), and on curved charts it has negative entries at near-degenerate corners. It is
//! used exactly in every triangle whose Hessian restricted to angle changes that keep the
//! triangle's sum is positive definite (all entries positive, or exactly one negative with
//! `Σ 1/h < 0`, checked with a relative margin); that keeps the reduced ABF++ matrix positive
//! definite and gives quadratic convergence (camelhead to 1e-9: 6 steps with 4 matrix
//! factorizations, against 9 steps with 5 for the energy Hessian `2/β²` alone, which ABF++
//! uses and which converges only linearly). Other triangles use `2/β²`. The first step, from
//! α = β with zero multipliers, is exactly the Linear ABF solve (R. Zayer, C. Rössl,
//! H.-P. Seidel, "Linear angle based parameterization", SGP 2007: the energy under the
//! constraints linearised at β). Linear constraints hold after every full step. Steps are
//! shortened so that no angle leaves (0, π) (fraction to the boundary 0.9). Once the
//! constraint residual is below `CHORD_RESIDUAL` (1e-2), a step first tries the last factorization
//! (a chord step: the linear system of that factorization, with the current residuals) and
//! keeps it when it cuts both errors by `CHORD_CONTRACTION` (half); otherwise, or when the chord
//! rate predicts more than `CHORD_MAX_PREDICTED` (3) further chord steps, it refactors.
//!
//! * [`AbfSolver::AbfPlusPlus`] (default): the ABF++ block elimination. The angle updates and
//!   the triangle multipliers are eliminated per triangle (Λ and the triangle Jacobian's
//!   Gram matrix `J₁Λ⁻¹J₁ᵀ` are diagonal), leaving a system over the vertex multipliers only
//!   (planarity and wheel, two per interior vertex): `J₂ P J₂ᵀ`, with `P` per triangle the
//!   projection `Λ⁻¹ − Λ⁻¹11ᵀΛ⁻¹ / 1ᵀΛ⁻¹1`. `P = Z(ZᵀΛZ)⁻¹Zᵀ` for a basis `Z` of the
//!   sum-keeping angle changes, so by the Hessian test above it is positive semidefinite with
//!   kernel the constant vectors, and the reduced matrix is symmetric positive definite whenever the
//!   vertex constraints are independent of the triangle constraints (always for a chart with
//!   boundary; a Cholesky failure is reported). It has the sparsity of the vertex adjacency in
//!   2×2 blocks; its pattern, value slots and symbolic analysis (approximate minimum degree
//!   on the vertex graph, expanded to each vertex's rows) are computed once per constraint set,
//!   and each Newton step sums straight into the pattern's values and refactors.
//! * [`AbfSolver::Plain`]: the original ABF step, the full sparse KKT system (angles, triangle
//!   and vertex multipliers) solved by sparse LU each iteration. A reference; much slower.
//!
//! Convergence: the iteration stops when the largest constraint residual (radians, or log
//! units for the wheel condition) is below `tolerance` and the Lagrangian gradient, scaled to
//! angle units (`|∂L/∂α_c| β_c² / 2`), is below `√tolerance` (3e-3 rad by default), so that
//! the angles are near the optimum, not merely consistent.
//!
//! The default tolerance, 1e-5, is set by what a UV map can show: on the shared meshes
//! (camelhead whole and cut by Smart UV Project, beetle and 3holes cut so, halftunnel, lion,
//! and bunny, fertility and cow with automatic seams) every UV is within 3.1e-7 of the chart's
//! extent of the UVs reached at 1e-9, a couple of float32 steps (the UVs Blender stores), the
//! conformal and area distortion agree to six digits and flips and overlaps are the same,
//! while the solve takes 5–15 % less CPU time. Blender's own ABF stops far earlier (squared
//! gradient norm below 1).
//!
//! Convex boundary ([`AbfBoundary::Convex`], in the spirit of R. Zayer, C. Rössl, H.-P. Seidel,
//! "Convex boundary angle based flattening", VMV 2003: ABF with every boundary angle sum
//! bounded by π). A triangulated disk whose angles satisfy the ABF constraints,
//! all in (0, π), with every outer angle sum below π is a locally injective map with a
//! strictly convex outline, hence globally bijective. Three points make this well posed:
//! * Holes: every boundary loop but the outer (longest) one is filled with a virtual fan
//!   ([`super::fixed_boundary::fill_holes`]); the fan's centre is an interior vertex with the
//!   planarity and wheel conditions, so the holes close up exactly and the filled chart is a
//!   disk. Only the outer loop is convexified (a hole's own angle sums are ≥ π by nature);
//!   the virtual triangles are dropped before the reconstruction.
//! * Cap below π: with every sum ≤ π exactly, the optimum of a wiggly outline (alligator)
//!   straightens long runs of the boundary, and a triangle with two vertices on one straight
//!   run (a chord of the boundary) must be flat: the problem has no solution with positive
//!   angles. The cap `π − π/n` ([`convex_cap`]) makes the outline strictly convex, every outer
//!   vertex turning by at least half the mean turning `2π/n`. Gauss–Bonnet (the turnings of a
//!   disk's outline add up to 2π) stays satisfiable: `n · π/n = π < 2π`.
//! * Lower bound on angles: the energy is finite at α = 0, and on triangles with all three
//!   vertices on the boundary (ears, fins) no wheel condition keeps angles away from 0, so the
//!   convex optimum can degenerate there. Every angle is bounded below by
//!   `min(π/(4n), min β / 2)` ([`convex_lower_bound`]); an ear at the cap keeps angles ≥ this
//!   bound at its two other corners, and the bound sums to at most π/2 over the outline.
//!
//! The inequalities are solved by a primal-dual interior-point Newton iteration on the same
//! system, with no active set. Each outer vertex gets the row `sum + s = cap` with a slack
//! `s > 0` and multiplier `λ > 0`; each angle the bound `α ≥ lower` with multiplier `z > 0`;
//! the complementarity conditions `λ s = μ`, `z (α − lower) = μ` are linearised and the slack
//! and bound multipliers eliminated, which adds `s/λ` to the diagonal of the reduced ABF++
//! matrix (or `−s/λ` to the KKT matrix of plain ABF) and `z/(α − lower)` to the diagonal
//! angle Hessian: the ABF++ structure and its single symbolic analysis are unchanged, and the
//! reduced matrix stays positive definite. Steps keep slacks and multipliers positive
//! (fraction to the boundary 0.995); μ starts at `CONVEX_MU_START` and falls superlinearly
//! (`min(0.2 m, m^1.5)` for the mean complementarity product m). An active-set iteration
//! (fixing violated sums at π, releasing negative multipliers) was tried first and fails on
//! alligator: fixing a run of chord-connected vertices at π drives an ear's angles to 0
//! and Newton never converges. Convergence additionally needs every complementarity product
//! below `tolerance`. Chord steps are not used with inequalities. The result: every outer
//! sum ≤ cap + residual < π.
//!
//! Regularisation: a reduced ABF++ matrix that fails Cholesky (near-degenerate corners, or
//! vertex rows nearly dependent on irregular boundaries) gets its diagonal shifted and is
//! factored again (`reduced.rs`), so the iteration goes on; the report notes it.
//!
//! Failure modes: no convergence within `max_iterations` Newton steps,
//! a linear system that cannot be factored even so, or solved angles outside (0, π); and, on
//! a disk without holes or pins, a layout with a flipped triangle. [`solve`] then falls back
//! to LSCM with the 3D angles when that has no flip and a moderate area distortion
//! ([`FALLBACK_AREA_LIMIT`]), else to SLIM (flip-free) when it has fewer flips or less area
//! distortion, and says why in [`ChartSolution::fallback`] ([`solve_with_sums`]).
//!
//! Preconditions: a chart that is a disk (possibly with holes). Holes with a free boundary
//! are left open, as in the papers, and their angles are not constrained to close up, so the
//! least-squares layout can fold near them (halftunnel). When it does (a flipped triangle or
//! a self-crossing outline), [`solve`] solves the angles again with every hole filled by a
//! virtual fan ([`super::fixed_boundary::filled_chart`]) whose centre carries the interior
//! constraints, so the holes close up and the layout is exact, and keeps that map if it folds
//! less (the note says so). The second solve is skipped when it cannot fold less: no flipped
//! triangle and the outer loop itself crossing ([`lscm::filling_may_help`]; a filled solve
//! often costs several times the open one, and filled holes distort the chart far more, so
//! the holes are not filled first). A prescribed sum at a hole vertex keeps the holes open.
//!
//! Files: `problem.rs` (constraint rows and the Lagrangian's evaluation), `reduced.rs`
//! (ABF++'s reduced system), `newton.rs` (the Newton / interior-point iteration), `angles.rs`
//! (target angles, convex caps); the public API is here.

use std::f64::consts::PI;

use super::{chart_angles, lscm, ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};

mod angles;
mod newton;
mod problem;
mod reduced;

use angles::*;
use newton::*;
use problem::*;
use reduced::*;

pub use angles::{convex_cap, convex_lower_bound, target_angles, target_angles_with_sums};

/// Below this constraint residual, a step first tries the last factorization (a chord step)
/// and keeps it when it cuts both the residual and the stationarity error by
/// [`CHORD_CONTRACTION`]; otherwise the matrix is refactored.
const CHORD_RESIDUAL: f64 = 1e-2;
/// Least error reduction of an accepted chord step.
const CHORD_CONTRACTION: f64 = 0.5;
/// After an accepted chord step, refactor next when its rate predicts more than this many
/// further chord steps to the tolerances (a chord step costs roughly a third of a step that
/// refactors).
const CHORD_MAX_PREDICTED: f64 = 3.0;

/// Interior-point start of [`AbfBoundary::Convex`]: least initial slack of an outer vertex
/// (radians) ...
const CONVEX_SLACK_START: f64 = 0.05;
/// ... its initial multiplier (on the scale of the energy gradient `2(α − β)/β²` for angle
/// changes of a sizeable fraction of a radian) ...
const CONVEX_DUAL_START: f64 = 5.0;
/// ... and the initial barrier parameter (the corner lower bounds start at multiplier
/// `CONVEX_MU_START / (β − lower)`).
const CONVEX_MU_START: f64 = 1e-2;
/// An outer vertex whose sum is within this of the cap is reported in
/// [`AbfAngles::convex_active`].
const CONVEX_ACTIVE: f64 = 1e-6;

/// Which linear algebra performs each Newton step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AbfSolver {
    /// ABF++ block elimination, Cholesky of the reduced vertex system. Default.
    #[default]
    AbfPlusPlus,
    /// Full KKT system by sparse LU each step (the original ABF; a reference).
    Plain,
}

impl AbfSolver {
    /// Option value naming the solver: `"abf++"` or `"abf"`.
    pub fn name(self) -> &'static str {
        match self {
            AbfSolver::AbfPlusPlus => "abf++",
            AbfSolver::Plain => "abf",
        }
    }
}

/// Constraint on the boundary angles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AbfBoundary {
    /// No constraint on boundary vertices. Default.
    #[default]
    Free,
    /// Every vertex of the outer boundary loop has an angle sum ≤ π − π/n: the UV outline is
    /// strictly convex and the map bijective; holes are closed (see the module docs).
    Convex,
}

impl AbfBoundary {
    /// Option value: `"free"` or `"convex"`.
    pub fn name(self) -> &'static str {
        match self {
            AbfBoundary::Free => "free",
            AbfBoundary::Convex => "convex",
        }
    }
}

/// Options of [`solve`] and [`solve_angles`].
#[derive(Debug, Clone, PartialEq)]
pub struct AbfOptions {
    /// Linear algebra of the Newton step. Default [`AbfSolver::AbfPlusPlus`].
    pub solver: AbfSolver,
    /// Most Newton iterations. Default 30.
    pub max_iterations: usize,
    /// Stop when the largest constraint residual is below this. Default 1e-5 (module docs).
    pub tolerance: f64,
    /// Boundary constraint. Default [`AbfBoundary::Free`].
    pub boundary: AbfBoundary,
    /// Prescribed angle sums `(mesh vertex, sum in radians)`, used by [`solve`] (see
    /// [`solve_with_sums`]): every chart vertex of a listed mesh vertex gets the sum, so a mesh
    /// vertex split by a seam has it on each side. Default empty.
    pub angle_sums: Vec<(u32, f64)>,
}

impl Default for AbfOptions {
    fn default() -> Self {
        AbfOptions {
            solver: AbfSolver::AbfPlusPlus,
            max_iterations: 30,
            tolerance: 1e-5,
            boundary: AbfBoundary::Free,
            angle_sums: Vec::new(),
        }
    }
}

/// Solved angles of one chart (see [`solve_angles`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AbfAngles {
    /// Solved corner angles, per chart triangle in its vertex order.
    pub alpha: Vec<[f64; 3]>,
    /// Target angles β (3D angles, interior vertices scaled to 2π).
    pub beta: Vec<[f64; 3]>,
    /// Newton iterations done, chord steps included.
    pub iterations: usize,
    /// Matrix factorizations done: the dominant cost.
    pub factorizations: usize,
    /// Largest constraint residual at the end (convex boundary: `sum + slack − cap` rows too).
    pub residual: f64,
    /// Largest scaled Lagrangian gradient `|∂L/∂α_c| β_c² / 2` at the end (radians).
    pub stationarity: f64,
    /// Whether the tolerances were met (convex boundary: complementarity products too).
    pub converged: bool,
    /// Outer-boundary vertices whose angle sum ended within 1e-6 of the cap [`convex_cap`]
    /// (convex boundary only), ascending.
    pub convex_active: Vec<u32>,
    /// Factorizations of the reduced ABF++ matrix that were not positive definite and were
    /// regularised by a diagonal shift (see `reduced.rs`), and the largest shift used,
    /// relative to the mean diagonal entry.
    pub regularised: usize,
    pub largest_shift: f64,
}

/// Solve the ABF angle problem of one chart (see the module docs).
///
/// Preconditions: a chart with at least one triangle and a boundary (a disk, possibly with
/// holes). Returns the angles whether or not they converged ([`AbfAngles::converged`]).
///
/// Failures: a linear system that cannot be factored (singular, or for ABF++ not positive
/// definite), reported as a [`ChartFailure`].
pub fn solve_angles(chart: &Chart, options: &AbfOptions) -> Result<AbfAngles, ChartFailure> {
    solve_angles_with_sums(chart, options, &[])
}

/// [`solve_angles`] with prescribed angle sums at chosen chart vertices: `(chart vertex, sum)`.
///
/// At an interior vertex the sum replaces 2π (a cone singularity in the sense of Kharevych,
/// Springborn, Schröder 2006: a sum other than 2π cannot be flattened without a cut through
/// it, so the LSCM reconstruction is then least squares); at a boundary vertex it constrains
/// the boundary angle (π keeps the boundary straight there, π/2 makes a right-angled corner).
/// With [`AbfBoundary::Convex`], a prescribed outer vertex keeps its prescribed sum instead of
/// the cap, and a prescribed hole vertex is refused (holes are filled; a [`ChartFailure`]).
/// With a free boundary the holes are left open here ([`solve`] closes them when the layout
/// folds; module docs).
///
/// Preconditions: as [`solve_angles`]; every sum in (0, 2π·valence) and finite (a sum the
/// triangles cannot reach leaves the solve unconverged, and the caller falls back). For a
/// flat disk, Gauss–Bonnet requires Σ over boundary vertices of (π − sum) = 2π; when every
/// boundary vertex is prescribed, one of them (the last given) is implied and left free.
pub fn solve_angles_with_sums(
    chart: &Chart,
    options: &AbfOptions,
    prescribed: &[(u32, f64)],
) -> Result<AbfAngles, ChartFailure> {
    if options.boundary == AbfBoundary::Convex && chart.boundary_loops.len() > 1 {
        if let Some(&(v, _)) = prescribed_on_hole(chart, prescribed) {
            return Err(ChartFailure(format!(
                "abf: a prescribed angle sum at hole vertex {v} cannot be combined with boundary=\"convex\" (holes are filled)"
            )));
        }
        return solve_angles_holes_filled(chart, options, prescribed);
    }
    solve_filled(chart, options, prescribed)
}

/// The first prescribed sum at a vertex of a hole (a boundary loop but the outer one).
fn prescribed_on_hole<'a>(chart: &Chart, prescribed: &'a [(u32, f64)]) -> Option<&'a (u32, f64)> {
    let outer = chart.outer_loop();
    prescribed.iter().find(|(v, _)| chart.boundary_loops.iter().enumerate().any(|(l, lp)| Some(l) != outer && lp.contains(v)))
}

/// The angles of `chart` solved with every hole filled by a virtual fan: the fan centres
/// carry the interior constraints, so the holes close up; the chart's own triangles (the
/// first ones of the filled chart) are returned.
fn solve_angles_holes_filled(chart: &Chart, options: &AbfOptions, prescribed: &[(u32, f64)]) -> Result<AbfAngles, ChartFailure> {
    let filled = super::fixed_boundary::filled_chart(chart);
    let nf = chart.triangles.len();
    let mut a = solve_filled(&filled, options, prescribed)?;
    a.alpha.truncate(nf);
    a.beta.truncate(nf);
    Ok(a)
}

/// [`solve_angles_with_sums`] on a chart whose holes, if any, are not to be closed.
fn solve_filled(chart: &Chart, options: &AbfOptions, prescribed: &[(u32, f64)]) -> Result<AbfAngles, ChartFailure> {
    let tris = &chart.triangles;
    let nf = tris.len();
    let n = chart.positions.len();
    let mut fixed_sum: Vec<Option<f64>> = vec![None; n];
    for &(v, t) in prescribed {
        if (v as usize) < n && t.is_finite() && t > 0.0 {
            fixed_sum[v as usize] = Some(t);
        }
    }
    // With every vertex's sum fixed, the vertex sums and the triangle sums both add up to the
    // total angle: one constraint is redundant and the reduced system singular. The last
    // prescribed boundary vertex is then left free (its sum follows from the others when they
    // are consistent; Gauss–Bonnet for a flat disk).
    let boundary = chart.boundary_mask();
    if (0..n).all(|v| !boundary[v] || fixed_sum[v].is_some()) {
        if let Some(&(v, _)) = prescribed.iter().rev().find(|&&(v, _)| boundary.get(v as usize) == Some(&true)) {
            fixed_sum[v as usize] = None;
        }
    }
    let beta: Vec<f64> = target_angles_with_sums(chart, prescribed).into_iter().flatten().collect();
    let interior: Vec<bool> = chart.boundary_mask().iter().map(|b| !b).collect();
    let outer: Vec<u32> = match (options.boundary, chart.outer_loop()) {
        (AbfBoundary::Convex, Some(l)) => chart.boundary_loops[l].clone(),
        _ => Vec::new(),
    };
    let cap = convex_cap(outer.len());
    let mut ineq = vec![false; n];
    for &v in &outer {
        ineq[v as usize] = fixed_sum[v as usize].is_none();
    }
    let sum_target: Vec<Option<f64>> = (0..n)
        .map(|v| fixed_sum[v].or(if interior[v] { Some(2.0 * PI) } else if ineq[v] { Some(cap) } else { None }))
        .collect();
    // Interior-point start for the inequality rows: slack = distance of the target sum below
    // the cap (at least CONVEX_SLACK_START), multiplier CONVEX_DUAL_START.
    let beta_sums = vertex_sums(chart, &beta);
    let mut slack = vec![0.0; n];
    let mut lam_sum = vec![0.0; n];
    for v in 0..n {
        if ineq[v] {
            slack[v] = (cap - beta_sums[v]).max(CONVEX_SLACK_START);
            lam_sum[v] = CONVEX_DUAL_START;
        }
    }
    drop(beta_sums);
    let mut p = Problem::new(tris, beta, &interior, &sum_target, &ineq);
    drop((interior, sum_target));
    // The reduced system and the LSCM reconstruction share one vertex order.
    if let crate::solvers::ordering::Ordering::Vertices { order, .. } = chart.ordering(crate::solvers::ordering::OrderingKind::Auto) {
        p.vertex_order = Some(order);
    }
    let mut z_lo = Vec::new();
    if p.has_ineq {
        let beta_min = p.beta.iter().copied().fold(f64::INFINITY, f64::min);
        p.lower = convex_lower_bound(outer.len()).min(0.5 * beta_min);
        if p.lower > 0.0 {
            z_lo = p.beta.iter().map(|&b| CONVEX_MU_START / (b - p.lower).max(CONVEX_SLACK_START)).collect();
        }
    }
    let mut s = State { alpha: p.beta.clone(), lam_tri: vec![0.0; nf], lam_sum, lam_wheel: vec![0.0; n], slack, mu: CONVEX_MU_START, z_lo };
    let run = newton(&p, &mut s, options).map_err(|e| ChartFailure(format!("abf: {e}")))?;
    let (iterations, factorizations, converged, residual, stationarity) =
        (run.iterations, run.factorizations, run.converged, run.residual, run.stationarity);
    let (regularised, largest_shift) = (run.shifted, run.largest_shift);
    let sums = vertex_sums(chart, &s.alpha);
    let active = |v: usize| ineq[v] && sums[v] > cap - CONVEX_ACTIVE;
    let beta3: Vec<[f64; 3]> = p.beta.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    drop(p);
    let alpha: Vec<[f64; 3]> = s.alpha.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let convex_active = (0..n as u32).filter(|&v| active(v as usize)).collect();
    Ok(AbfAngles { alpha, beta: beta3, iterations, factorizations, residual, stationarity, converged, convex_active, regularised, largest_shift })
}

/// ABF / ABF++ of one chart: solve the angles, then reconstruct UVs with LSCM driven by them
/// (pins as in [`lscm::solve_with_angles`]). [`AbfOptions::angle_sums`] (mesh vertices) are
/// applied to every chart vertex of a listed mesh vertex (see [`solve_with_sums`]).
///
/// When the angle solve fails (no convergence, a linear system that cannot be factored, or
/// angles outside (0, π)), the chart is mapped by plain LSCM with its 3D angles and the
/// solution carries a [`Fallback`] saying why. Failures: those of the LSCM solve.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &AbfOptions) -> Result<ChartSolution, ChartFailure> {
    if options.angle_sums.is_empty() {
        return solve_with_sums(chart, pins, options, &[]);
    }
    let by_mesh_vertex: std::collections::HashMap<u32, f64> = options.angle_sums.iter().copied().collect();
    let prescribed: Vec<(u32, f64)> = chart
        .mesh_vertex
        .iter()
        .enumerate()
        .filter_map(|(cv, mv)| by_mesh_vertex.get(mv).map(|&t| (cv as u32, t)))
        .collect();
    solve_with_sums(chart, pins, options, &prescribed)
}

/// Check prescribed angle sums `(mesh vertex, sum)` against a mesh whose vertex `v` has
/// `corners[v]` face corners: the vertex exists and is used by a face, is listed once, and the
/// sum is finite with `0 < sum < 2π · corners[v]` (every polygon corner angle is below 2π).
/// Without a mesh (`corners` empty) only the sum's finiteness and sign and duplicates are
/// checked.
///
/// Errors: [`crate::UvError::AngleSum`] naming the entry and the vertex.
pub fn validate_angle_sums(sums: &[(u32, f64)], corners: &[u32]) -> crate::error::Result<()> {
    use crate::error::UvError;
    let bad = |entry: usize, vertex: u32, value: f64, reason: String| UvError::AngleSum { entry, vertex: vertex as u64, value, reason };
    let mut seen = std::collections::HashMap::new();
    for (i, &(v, t)) in sums.iter().enumerate() {
        if let Some(first) = seen.insert(v, i) {
            return Err(bad(i, v, t, format!("vertex given twice (entries {first} and {i})")));
        }
        if !t.is_finite() {
            return Err(bad(i, v, t, "the sum is not finite".into()));
        }
        if t <= 0.0 {
            return Err(bad(i, v, t, "the sum must be positive (radians)".into()));
        }
        if !corners.is_empty() {
            let Some(&k) = corners.get(v as usize) else {
                return Err(bad(i, v, t, format!("vertex index out of range (mesh has {} vertices)", corners.len())));
            };
            if k == 0 {
                return Err(bad(i, v, t, "the vertex is not used by any face".into()));
            }
            let most = 2.0 * PI * k as f64;
            if t >= most {
                return Err(bad(i, v, t, format!("the sum must be below 2π × {k} corners = {most:.6} radians")));
            }
        }
    }
    Ok(())
}

/// [`solve`] with prescribed angle sums (see [`solve_angles_with_sums`]).
///
/// Fallbacks are flip-free where LSCM is not: when the angle solve fails, or when its layout
/// folds a chart on which ABF promises no flips (a disk without holes and without pins; the
/// least-squares layout of nearly consistent angles around near-degenerate corners can fold),
/// the chart is mapped by LSCM with the 3D angles if that has no flipped triangle and a
/// moderate area distortion, else by SLIM ([`super::slim`], flip-free by its line search) when
/// it folds less or distorts area less (`flip_free_fallback`); the fallback's reason says why.
pub fn solve_with_sums(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &AbfOptions,
    prescribed: &[(u32, f64)],
) -> Result<ChartSolution, ChartFailure> {
    let reason = match solve_angles_with_sums(chart, options, prescribed) {
        Ok(a) => {
            let valid = a.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI);
            if a.converged && valid {
                let (uv, note) = lscm::solve_with_angles(chart, &a.alpha, pins)?;
                let note = with_regularised_note(note, &a);
                let open_holes = options.boundary == AbfBoundary::Free && chart.boundary_loops.len() > 1;
                let open = if open_holes { lscm::folds(chart, &uv) } else { (0, false) };
                if lscm::filling_may_help(chart, &uv, open) && prescribed_on_hole(chart, prescribed).is_none() {
                    // The open holes folded in a way closing them can mend: close them
                    // (module docs) and keep that if better.
                    if let Ok(b) = solve_angles_holes_filled(chart, options, prescribed) {
                        if b.converged && b.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI) {
                            let (closed_uv, closed_note) = lscm::solve_with_angles(chart, &b.alpha, pins)?;
                            if lscm::folds(chart, &closed_uv) < open {
                                let note = with_regularised_note(Some(lscm::holes_filled_note(open, closed_note)), &b);
                                return Ok(ChartSolution {
                                    uv: closed_uv,
                                    iterations: a.iterations + b.iterations,
                                    residual: b.residual,
                                    note,
                                    fallback: None,
                                });
                            }
                        }
                    }
                }
                // Where ABF promises no flips, a folded layout is not returned as solved.
                // (Quads are made convex afterwards, see `super::convex_quads_or_slim`.)
                let flips = if chart.kind == crate::unwrap::ChartKind::Disk && pins.is_empty() { crate::metrics::count_flips(&chart.triangles, &uv) } else { 0 };
                if flips > 0 {
                    let why = format!("the ABF layout has {flips} flipped triangle(s) (residual {:.3e})", a.residual);
                    let mut sol = flip_free_fallback(chart, pins, why)?;
                    sol.iterations = a.iterations;
                    return Ok(sol);
                }
                return Ok(ChartSolution { uv, iterations: a.iterations, residual: a.residual, note, fallback: None });
            }
            let what = if !a.converged { "did not converge" } else { "produced an angle outside (0, π)" };
            let regularised = regularised_note(&a).map(|n| format!(" ({n})")).unwrap_or_default();
            let mut sol = flip_free_fallback(chart, pins, format!("abf {what}: residual {:.3e} after {} iterations{regularised}", a.residual, a.iterations))?;
            sol.iterations = a.iterations;
            sol.residual = a.residual;
            return Ok(sol);
        }
        Err(ChartFailure(r)) => r,
    };
    flip_free_fallback(chart, pins, format!("abf failed: {reason}"))
}

/// Flipped triangles and folded quads of `uv`.
fn count_flips(chart: &Chart, uv: &[[f64; 2]]) -> usize {
    crate::metrics::count_flips_with_quads(&chart.triangles, &chart.quads, uv)
}

/// The report's words for a solve whose reduced matrix needed regularising, if it did.
fn regularised_note(a: &AbfAngles) -> Option<String> {
    (a.regularised > 0).then(|| {
        format!(
            "{} factorization(s) of the ABF++ system regularised by a diagonal shift of up to {:.0e} of its mean",
            a.regularised, a.largest_shift
        )
    })
}

/// `note` with [`regularised_note`] appended.
fn with_regularised_note(note: Option<String>, a: &AbfAngles) -> Option<String> {
    match (note, regularised_note(a)) {
        (Some(n), Some(r)) => Some(format!("{n}; {r}")),
        (n, r) => n.or(r),
    }
}

/// A fallback LSCM map whose area distortion ([`crate::metrics::Distortion::area`], 1 for
/// an area-preserving map) is above this is compared with SLIM too: on charts far from
/// developable (a cow cut along one ring: the angle solve stalls there) LSCM's conformal map
/// shrinks whole parts to nothing (area distortion 10⁷ and more) while SLIM stays near 1–10.
pub const FALLBACK_AREA_LIMIT: f64 = 4.0;

/// The fallback of an ABF solve that failed or folded (see [`solve_with_sums`]): LSCM with
/// the 3D angles when it has no flipped triangle and an area distortion at most
/// [`FALLBACK_AREA_LIMIT`]; else SLIM when it has fewer flipped triangles and folded quads,
/// or as many and a lower area distortion; else LSCM. Pins are honoured by either.
/// Failures: those of the LSCM solve.
fn flip_free_fallback(chart: &Chart, pins: &[(u32, [f64; 2])], why: String) -> Result<ChartSolution, ChartFailure> {
    let mut sol = lscm::solve(chart, pins)?;
    let quality = |uv: &[[f64; 2]]| {
        let area = crate::metrics::chart_metrics(&chart.positions, &chart.triangles, uv, &[]).distortion.area;
        (count_flips(chart, uv), if area.is_nan() { f64::INFINITY } else { area })
    };
    let (lscm_flips, lscm_area) = quality(&sol.uv);
    if lscm_flips > 0 || lscm_area > FALLBACK_AREA_LIMIT {
        if let Ok(mut slim) = super::slim::solve(chart, pins, &super::slim::SlimOptions::default()) {
            let (slim_flips, slim_area) = quality(&slim.uv);
            if (slim_flips, slim_area) < (lscm_flips, lscm_area) {
                let detail = match (slim.fallback.take(), slim.note.take()) {
                    (Some(f), _) => format!(" ({} instead: {})", f.method, f.reason),
                    (None, Some(n)) => format!(" ({n})"),
                    (None, None) => String::new(),
                };
                let lscm_was = if lscm_flips > 0 {
                    format!("has {lscm_flips} flipped triangle(s)")
                } else {
                    format!("has area distortion {lscm_area:.3e}")
                };
                slim.fallback = Some(Fallback {
                    method: "slim",
                    reason: format!("{why}; LSCM with the 3D angles {lscm_was}, so SLIM was used (area distortion {slim_area:.3}){detail}"),
                });
                return Ok(slim);
            }
        }
    }
    sol.fallback = Some(Fallback { method: "lscm", reason: why });
    Ok(sol)
}
