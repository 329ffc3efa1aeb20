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
//! angle units (`|∂L/∂α_c| β_c² / 2`), is below `√tolerance` (3e-5 rad by default), so that
//! the angles are near the optimum, not merely consistent.
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
//! Failure modes: no convergence within `max_iterations` Newton steps,
//! a singular or indefinite linear system, or solved angles outside (0, π). [`solve`] then
//! falls back to plain LSCM with the 3D angles and says why in [`ChartSolution::fallback`].
//!
//! Preconditions: a chart that is a disk (possibly with holes). Holes with a free boundary
//! are left open, as in the papers, and their angles are not constrained to close up, so the
//! least-squares layout can fold near them (halftunnel). When it does (a flipped triangle or
//! a self-crossing outline), [`solve`] solves the angles again with every hole filled by a
//! virtual fan ([`super::fixed_boundary::filled_chart`]) whose centre carries the interior
//! constraints, so the holes close up and the layout is exact, and keeps that map if it folds
//! less (the note says so). A prescribed sum at a hole vertex keeps the holes open.

use std::f64::consts::PI;

use super::{chart_angles, lscm, ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};

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
    /// Stop when the largest constraint residual is below this. Default 1e-9.
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
            tolerance: 1e-9,
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
}

/// One vertex constraint row: (vertex, wheel?) — the sum row when `wheel` is false.
#[derive(Clone, Copy)]
struct Row {
    vertex: u32,
    wheel: bool,
    /// A sum row that is the inequality "sum ≤ target" (convex boundary), by a slack.
    ineq: bool,
}

/// Most constraint rows touching one triangle (sum and wheel rows of its three vertices).
const MAX_FACE_ROWS: usize = 6;

/// Constraint rows touching one triangle: (row, kind wheel?, local corner of the vertex).
#[derive(Clone, Copy, Default)]
struct FaceRows {
    len: u8,
    rows: [(u32, bool, u8); MAX_FACE_ROWS],
}

/// The rows' gradient on the triangle's three corners.
#[inline]
fn row_grad(wheel: bool, k: usize, cot: &[f64; 3]) -> [f64; 3] {
    let mut g = [0.0; 3];
    if wheel {
        // log sin α_{k+2} − log sin α_{k+1}
        g[(k + 1) % 3] = -cot[(k + 1) % 3];
        g[(k + 2) % 3] = cot[(k + 2) % 3];
    } else {
        g[k] = 1.0;
    }
    g
}

/// Below this many triangles a chart's per-triangle loops run sequentially (charts themselves
/// run in parallel).
const PAR_MIN_FACES: usize = 4096;
/// Triangles per parallel work item.
const PAR_CHUNK: usize = 1024;

/// Run `f(face, item)` over per-face items, in parallel for large charts.
fn for_faces<T: Send>(items: &mut [T], f: impl Fn(usize, &mut T) + Sync + Send) {
    use rayon::prelude::*;
    if items.len() < PAR_MIN_FACES {
        items.iter_mut().enumerate().for_each(|(i, x)| f(i, x));
    } else {
        items.par_iter_mut().with_min_len(PAR_CHUNK).enumerate().for_each(|(i, x)| f(i, x));
    }
}

struct Problem<'a> {
    tris: &'a [[u32; 3]],
    beta: Vec<f64>,
    w: Vec<f64>,
    rows: Vec<Row>,
    /// Sum target per row (2π interior, π active boundary; unused for wheel rows).
    target: Vec<f64>,
    face_rows: Vec<FaceRows>,
    /// Reduced ABF++ matrix pattern, upper triangle by columns (the lower triangle by rows):
    /// column `j` holds rows `row_idx[col_ptr[j]..col_ptr[j + 1]]`, ascending, all ≤ j.
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// Per triangle, for each pair (i, j ≤ i) of its rows in order, the index of its entry in
    /// `row_idx`; triangle `f`'s pairs start at `slot_start[f]`.
    slots: Vec<u32>,
    slot_start: Vec<u32>,
    /// Whether any row is an inequality (interior-point iteration).
    has_ineq: bool,
    /// Lower bound of every angle (interior-point iteration), or 0 for none.
    lower: f64,
}

impl<'a> Problem<'a> {
    /// `sum_target[v]`: the angle sum vertex `v` must reach (2π at interior vertices unless
    /// prescribed, any prescribed value, the convex cap at outer-loop vertices), or `None`;
    /// `ineq[v]`: the sum of `v` need only stay at or below its target.
    fn new(tris: &'a [[u32; 3]], beta: Vec<f64>, interior: &[bool], sum_target: &[Option<f64>], ineq: &[bool]) -> Self {
        let n = interior.len();
        let mut sum_row = vec![u32::MAX; n];
        let mut wheel_row = vec![u32::MAX; n];
        let mut rows = Vec::new();
        let mut target = Vec::new();
        for v in 0..n {
            if let Some(t) = sum_target[v] {
                sum_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: false, ineq: ineq[v] });
                target.push(t);
            }
            if interior[v] {
                wheel_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: true, ineq: false });
                target.push(0.0);
            }
        }
        let face_rows: Vec<FaceRows> = tris
            .iter()
            .map(|t| {
                let mut fr = FaceRows::default();
                for k in 0..3 {
                    let v = t[k] as usize;
                    for (r, wheel) in [(sum_row[v], false), (wheel_row[v], true)] {
                        if r != u32::MAX {
                            fr.rows[fr.len as usize] = (r, wheel, k as u8);
                            fr.len += 1;
                        }
                    }
                }
                fr
            })
            .collect();
        let w = beta.iter().map(|b| 1.0 / (b * b)).collect();
        let m = rows.len();
        let (col_ptr, row_idx, slots, slot_start) = reduced_pattern(m, &face_rows);
        let has_ineq = rows.iter().any(|r| r.ineq);
        Problem { tris, beta, w, rows, target, face_rows, col_ptr, row_idx, slots, slot_start, has_ineq, lower: 0.0 }
    }

    fn m(&self) -> usize {
        self.rows.len()
    }

    /// Index in `row_idx` of the diagonal entry of row `r` (the last of its column).
    fn diagonal_slot(&self, r: usize) -> usize {
        self.col_ptr[r + 1] - 1
    }
}

/// The unique entries (row ≤ column) of `Σ_f (rows of f) × (rows of f)` by columns, built
/// once per constraint set, and for every triangle the entries its pairs of rows sum into, so
/// that every Newton step sums straight into a fixed value array (count, fill, sort and
/// deduplicate each column, then look every pair up).
fn reduced_pattern(m: usize, face_rows: &[FaceRows]) -> (Vec<usize>, Vec<usize>, Vec<u32>, Vec<u32>) {
    let mut count = vec![0usize; m + 1];
    for fr in face_rows {
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                count[a.max(b) as usize + 1] += 1;
            }
        }
    }
    for r in 0..m {
        count[r + 1] += count[r];
    }
    let mut fill = count.clone();
    let mut cols = vec![0u32; count[m]];
    for fr in face_rows {
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                let r = a.max(b) as usize;
                cols[fill[r]] = a.min(b);
                fill[r] += 1;
            }
        }
    }
    // Sort and deduplicate each column in place.
    let mut col_ptr = vec![0usize; m + 1];
    let mut row_idx = Vec::with_capacity(count[m] / 2);
    for r in 0..m {
        let seg = &mut cols[count[r]..count[r + 1]];
        seg.sort_unstable();
        let mut k = 0;
        for q in 0..seg.len() {
            if q == 0 || seg[q] != seg[k - 1] {
                seg[k] = seg[q];
                k += 1;
            }
        }
        row_idx.extend(seg[..k].iter().map(|&c| c as usize));
        col_ptr[r + 1] = row_idx.len();
    }
    let mut slots = Vec::with_capacity(count[m]);
    let mut slot_start = Vec::with_capacity(face_rows.len() + 1);
    for fr in face_rows {
        slot_start.push(slots.len() as u32);
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                let (r, c) = (a.max(b) as usize, a.min(b) as usize);
                let seg = &row_idx[col_ptr[r]..col_ptr[r + 1]];
                let pos = seg.binary_search(&c).expect("entry in pattern");
                slots.push((col_ptr[r] + pos) as u32);
            }
        }
    }
    slot_start.push(slots.len() as u32);
    (col_ptr, row_idx, slots, slot_start)
}

/// Newton state: angles and multipliers (vertex multipliers per vertex so that they survive a
/// change of the constraint set).
#[derive(Clone)]
struct State {
    alpha: Vec<f64>,
    lam_tri: Vec<f64>,
    lam_sum: Vec<f64>,
    lam_wheel: Vec<f64>,
    /// Slack of every inequality sum row, per vertex (sum + slack = target, slack > 0); the
    /// row's multiplier `lam_sum` is then its dual variable, > 0.
    slack: Vec<f64>,
    /// Barrier parameter: the target of every product slack × multiplier.
    mu: f64,
    /// Multiplier of every corner's lower bound `α ≥ lower` (empty without bounds).
    z_lo: Vec<f64>,
}

/// Residual and Newton ingredients of one triangle at the current state.
#[derive(Clone, Copy, Default)]
struct FaceEval {
    cot: [f64; 3],
    /// ∂L/∂α per corner.
    grad: [f64; 3],
    /// Diagonal Hessian of L in α per corner (see [`evaluate`]).
    hess: [f64; 3],
    /// Triangle residual: angle sum − π.
    c_tri: f64,
    /// This triangle's terms of its rows' residuals, in [`FaceRows`] order.
    row_terms: [f64; MAX_FACE_ROWS],
    /// Largest scaled Lagrangian gradient of the triangle's corners.
    stationarity: f64,
}

/// Residuals and Newton ingredients at the current state.
struct Eval {
    faces: Vec<FaceEval>,
    /// Right-hand side residual of the Newton system per row: `c_row`, except on inequality
    /// rows `sum − target + μ/λ` (the slack eliminated through its complementarity equation).
    c_newton: Vec<f64>,
    /// Per row, `slack/λ` on inequality rows (the eliminated slack's diagonal), else 0; empty
    /// without inequality rows.
    diag: Vec<f64>,
    residual: f64,
    stationarity: f64,
    /// Largest product slack × multiplier of the inequality rows (0 without).
    complementarity: f64,
}

/// Residuals, Lagrangian gradient and Hessian at the state.
///
/// The Hessian of the Lagrangian in α is diagonal: `2/β² ∓ λ_wheel / sin²α` (log-sine wheel
/// rows). It is used exactly where the triangle's projected Hessian (on angle changes that
/// keep its sum) is positive definite — all three entries positive, or exactly one negative
/// with `Σ 1/h < 0` (with a margin) — which keeps the reduced ABF++ matrix positive definite
/// and gives Newton's quadratic convergence; other triangles use the energy's `2/β²`.
fn evaluate(p: &Problem<'_>, s: &State) -> Eval {
    let nf = p.tris.len();
    let mut faces = vec![FaceEval::default(); nf];
    for_faces(&mut faces, |f, fe| {
        let a = [s.alpha[3 * f], s.alpha[3 * f + 1], s.alpha[3 * f + 2]];
        let mut sn = [0.0; 3];
        let mut ct = [0.0; 3];
        let mut ls = [0.0; 3];
        for k in 0..3 {
            let (si, co) = a[k].sin_cos();
            sn[k] = si;
            ct[k] = co / si;
            ls[k] = si.ln();
        }
        let mut grad = [0.0; 3];
        let mut hess = [0.0; 3];
        let mut energy_hess = [0.0; 3];
        for k in 0..3 {
            let c = 3 * f + k;
            grad[k] = 2.0 * p.w[c] * (a[k] - p.beta[c]) + s.lam_tri[f];
            energy_hess[k] = 2.0 * p.w[c];
            hess[k] = energy_hess[k];
        }
        let fr = &p.face_rows[f];
        for (j, &(_, wheel, k)) in fr.rows[..fr.len as usize].iter().enumerate() {
            let k = k as usize;
            let v = p.tris[f][k] as usize;
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            if wheel {
                fe.row_terms[j] = ls[k2] - ls[k1];
                let l = s.lam_wheel[v];
                grad[k1] -= l * ct[k1];
                grad[k2] += l * ct[k2];
                hess[k1] += l / (sn[k1] * sn[k1]);
                hess[k2] -= l / (sn[k2] * sn[k2]);
            } else {
                fe.row_terms[j] = a[k];
                grad[k] += s.lam_sum[v];
            }
        }
        let mut stat: f64 = 0.0;
        let mut fallback_hess = energy_hess;
        if p.lower > 0.0 {
            // Lower bounds α ≥ lower, primal-dual: the bound's multiplier z enters the
            // gradient as −z; the Newton system, with dz eliminated through z (α − lower) = μ,
            // sees the Hessian + z/(α − lower) and the gradient with −μ/(α − lower) for −z.
            for k in 0..3 {
                let c = 3 * f + k;
                let gap = a[k] - p.lower;
                let z = s.z_lo[c];
                stat = stat.max((grad[k] - z).abs() / energy_hess[k]);
                hess[k] += z / gap;
                fallback_hess[k] += z / gap;
                grad[k] -= s.mu / gap;
            }
        } else {
            for k in 0..3 {
                stat = stat.max(grad[k].abs() / energy_hess[k]);
            }
        }
        // Exact Hessian where the triangle's projected Hessian is safely positive definite.
        let neg = hess.iter().filter(|&&h| h <= 0.0).count();
        let exact_ok = neg == 0 || {
            let inv = [1.0 / hess[0], 1.0 / hess[1], 1.0 / hess[2]];
            let largest = inv.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            neg == 1 && inv.iter().all(|x| x.is_finite()) && inv[0] + inv[1] + inv[2] < -PROJECTED_HESSIAN_MARGIN * largest
        };
        if !exact_ok {
            hess = fallback_hess;
        }
        fe.cot = ct;
        fe.grad = grad;
        fe.hess = hess;
        fe.c_tri = a[0] + a[1] + a[2] - PI;
        fe.stationarity = stat;
    });
    let mut c_row: Vec<f64> = p.rows.iter().zip(&p.target).map(|(row, t)| if row.wheel { 0.0 } else { -t }).collect();
    for (fe, fr) in faces.iter().zip(&p.face_rows) {
        for (term, row) in fe.row_terms.iter().zip(&fr.rows[..fr.len as usize]) {
            c_row[row.0 as usize] += term;
        }
    }
    let mut complementarity: f64 = 0.0;
    if p.lower > 0.0 {
        for (a, z) in s.alpha.iter().zip(&s.z_lo) {
            complementarity = complementarity.max(z * (a - p.lower));
        }
    }
    let (mut c_newton, mut diag) = (Vec::new(), Vec::new());
    if p.has_ineq {
        c_newton = c_row.clone();
        diag = vec![0.0; c_row.len()];
        for (r, row) in p.rows.iter().enumerate() {
            if row.ineq {
                let v = row.vertex as usize;
                let (sl, z) = (s.slack[v], s.lam_sum[v]);
                c_newton[r] = c_row[r] + s.mu / z;
                c_row[r] += sl;
                diag[r] = sl / z;
                complementarity = complementarity.max(sl * z);
            }
        }
    }
    let residual = faces.iter().map(|fe| fe.c_tri).chain(c_row.iter().copied()).fold(0.0f64, |m, x| m.max(x.abs()));
    let stationarity = faces.iter().fold(0.0f64, |m, fe| m.max(fe.stationarity));
    if !p.has_ineq {
        c_newton = c_row;
    }
    Eval { faces, c_newton, diag, residual, stationarity, complementarity }
}

/// Relative margin of the projected-Hessian test in [`evaluate`].
const PROJECTED_HESSIAN_MARGIN: f64 = 0.1;


/// Sparse Cholesky of the reduced ABF++ matrix on its fixed pattern: the symbolic analysis
/// (with a fill-reducing ordering of the vertices, expanded to their constraint rows) once,
/// then numeric factorizations straight from the pattern's value array, reusing all buffers.
struct Reduced {
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    mem: faer::dyn_stack::MemBuffer,
}

impl Reduced {
    fn new(p: &Problem<'_>) -> Result<Self, SolveError> {
        use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, CholeskySymbolicParams, SymmetricOrdering};
        let m = p.m();
        let other = |e: &dyn std::fmt::Debug| SolveError::Other(format!("{e:?}"));
        let a = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &p.col_ptr, None, &p.row_idx);
        let (fwd, inv) = vertex_ordering(p).map_err(|e| other(&e))?;
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, m);
        let symbolic = factorize_symbolic_cholesky(a, faer::Side::Upper, SymmetricOrdering::Custom(perm), CholeskySymbolicParams::default())
            .map_err(|e| other(&e))?;
        // Sequential: faer's supernodal Cholesky is left-looking and parallel only inside its
        // dense blocks, which measured slower than sequential at 22k and 363k triangles.
        let par = faer::Par::Seq;
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()).or(symbolic.solve_in_place_scratch::<f64>(1, par));
        let mem = faer::dyn_stack::MemBuffer::try_new(req).map_err(|e| other(&e))?;
        let l_values = vec![0.0; symbolic.len_val()];
        Ok(Reduced { symbolic, l_values, mem })
    }

    /// Numeric factorization for `values` on the pattern of `p`.
    fn factor(&mut self, p: &Problem<'_>, values: &[f64]) -> Result<(), SolveError> {
        let m = p.m();
        let a = faer::sparse::SparseColMatRef::new(
            faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &p.col_ptr, None, &p.row_idx),
            values,
        );
        let stack = faer::dyn_stack::MemStack::new(&mut self.mem);
        self.symbolic
            .factorize_numeric_llt(&mut self.l_values, a, faer::Side::Upper, Default::default(), faer::Par::Seq, stack, Default::default())
            .map(|_| ())
            .map_err(|_| SolveError::NotPositiveDefinite)
    }

    /// Solve with the last factorization, in place.
    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        let m = rhs.len();
        let llt = faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &self.l_values);
        let stack = faer::dyn_stack::MemStack::new(&mut self.mem);
        llt.solve_in_place_with_conj(faer::Conj::No, faer::MatMut::from_column_major_slice_mut(rhs, m, 1), faer::Par::Seq, stack);
        if rhs.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFinite)
        }
    }
}

/// A fill-reducing ordering of the reduced matrix: approximate minimum degree (nested
/// dissection for large charts) on the graph of the constrained vertices (half the size of
/// the matrix), each vertex's rows kept together.
fn vertex_ordering(p: &Problem<'_>) -> Result<(Vec<usize>, Vec<usize>), faer::sparse::FaerError> {
    let m = p.m();
    // Group of every row: the rows of one vertex are consecutive.
    let mut group = vec![0usize; m];
    let mut start = vec![0usize];
    for r in 0..m {
        if r > 0 && p.rows[r].vertex != p.rows[r - 1].vertex {
            start.push(r);
        }
        group[r] = start.len() - 1;
    }
    let g = start.len();
    start.push(m);
    // Group graph, upper triangle by columns.
    let mut col_ptr = vec![0usize; g + 1];
    let mut row_idx = Vec::new();
    let mut mark = vec![usize::MAX; g];
    for gc in 0..g {
        for c in start[gc]..start[gc + 1] {
            for &r in &p.row_idx[p.col_ptr[c]..p.col_ptr[c + 1]] {
                let gr = group[r];
                if mark[gr] != gc {
                    mark[gr] = gc;
                    row_idx.push(gr);
                }
            }
        }
        row_idx[col_ptr[gc]..].sort_unstable();
        col_ptr[gc + 1] = row_idx.len();
    }
    // AMD, or nested dissection for large charts (see `solvers::ordering`).
    let gfwd = crate::solvers::ordering::fill_reducing(crate::solvers::ordering::OrderingKind::Auto, g, &col_ptr, &row_idx)?.fwd;
    let mut fwd = Vec::with_capacity(m);
    for &gv in &gfwd {
        fwd.extend(start[gv]..start[gv + 1]);
    }
    let mut inv = vec![0usize; m];
    for (i, &r) in fwd.iter().enumerate() {
        inv[r] = i;
    }
    Ok((fwd, inv))
}

/// The Newton step of one triangle: its angle updates and its triangle multiplier update.
#[derive(Clone, Copy, Default)]
struct FaceStep {
    da: [f64; 3],
    dt: f64,
}

/// The Newton step: per triangle, and the vertex multiplier updates per row.
type Step = (Vec<FaceStep>, Vec<f64>);

/// How a Newton step solves its linear system.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    /// Factor the current matrix.
    Factor,
    /// A chord step: the Newton system of the last factorization (its matrix, and its
    /// Jacobian and Hessian in the elimination) with the current residuals.
    Chord,
}

/// The linear algebra of one Newton step, keeping its factorization pattern across steps.
enum Linear {
    PlusPlus(Box<PlusPlus>),
    Plain(Box<Option<FixedValueSolver>>),
}

impl Linear {
    fn new(solver: AbfSolver) -> Self {
        match solver {
            AbfSolver::AbfPlusPlus => Linear::PlusPlus(Box::default()),
            AbfSolver::Plain => Linear::Plain(Box::new(None)),
        }
    }

    /// The step at `e`.
    fn step(&mut self, p: &Problem<'_>, e: &Eval, mode: Mode) -> Result<Step, SolveError> {
        match self {
            Linear::PlusPlus(w) => step_plus_plus(w, p, e, mode),
            Linear::Plain(slot) => step_plain(slot, p, e, mode),
        }
    }
}

/// ABF++ linear algebra state kept across Newton steps: the factorization and buffers.
#[derive(Default)]
struct PlusPlus {
    reduced: Option<Reduced>,
    /// Reduced matrix values on the pattern.
    vals: Vec<f64>,
    /// Per triangle: 1 / 1ᵀΛ⁻¹1 and C_tri − 1ᵀΛ⁻¹∇α L.
    dinv: Vec<f64>,
    r1: Vec<f64>,
    /// Per triangle, the cotangents and Hessian of the last factorization (chord steps).
    jac: Vec<([f64; 3], [f64; 3])>,
}

/// ABF++: eliminate dα and dλ_tri per triangle, solve the reduced vertex system.
fn step_plus_plus(w: &mut PlusPlus, p: &Problem<'_>, e: &Eval, mode: Mode) -> Result<Step, SolveError> {
    let refresh = mode == Mode::Factor;
    let nf = p.tris.len();
    let m = p.m();
    let mut rhs = e.c_newton.clone();
    if refresh {
        w.vals.clear();
        w.vals.resize(p.row_idx.len(), 0.0);
        for (r, &d) in e.diag.iter().enumerate() {
            if d != 0.0 {
                w.vals[p.diagonal_slot(r)] += d;
            }
        }
    }
    w.dinv.resize(nf, 0.0);
    w.r1.resize(nf, 0.0);
    if mode == Mode::Factor {
        w.jac.clear();
        w.jac.extend(e.faces.iter().map(|fe| (fe.cot, fe.hess)));
    }
    let jac_of = |f: usize| if mode == Mode::Chord { w.jac[f] } else { (e.faces[f].cot, e.faces[f].hess) };
    for f in 0..nf {
        let fe = &e.faces[f];
        let (cot, hess) = jac_of(f);
        let li = [1.0 / hess[0], 1.0 / hess[1], 1.0 / hess[2]];
        let lb = [li[0] * fe.grad[0], li[1] * fe.grad[1], li[2] * fe.grad[2]];
        let dinv = 1.0 / (li[0] + li[1] + li[2]);
        let rr = fe.c_tri - (lb[0] + lb[1] + lb[2]);
        w.dinv[f] = dinv;
        w.r1[f] = rr;
        let fr = &p.face_rows[f];
        let len = fr.len as usize;
        let mut g = [[0.0; 3]; MAX_FACE_ROWS];
        let mut u = [[0.0; 3]; MAX_FACE_ROWS];
        let mut sj = [0.0; MAX_FACE_ROWS];
        for j in 0..len {
            let (r, wheel, k) = fr.rows[j];
            g[j] = row_grad(wheel, k as usize, &cot);
            u[j] = [li[0] * g[j][0], li[1] * g[j][1], li[2] * g[j][2]];
            sj[j] = u[j][0] + u[j][1] + u[j][2];
            rhs[r as usize] -= g[j][0] * lb[0] + g[j][1] * lb[1] + g[j][2] * lb[2] + sj[j] * rr * dinv;
        }
        if refresh {
            let slots = &p.slots[p.slot_start[f] as usize..p.slot_start[f + 1] as usize];
            let mut q = 0;
            for i in 0..len {
                for j in 0..=i {
                    w.vals[slots[q] as usize] += g[i][0] * u[j][0] + g[i][1] * u[j][1] + g[i][2] * u[j][2] - sj[i] * sj[j] * dinv;
                    q += 1;
                }
            }
        }
    }
    let dl = if m > 0 {
        if w.reduced.is_none() {
            w.reduced = Some(Reduced::new(p)?);
        }
        let red = w.reduced.as_mut().expect("analysed");
        if refresh {
            red.factor(p, &w.vals)?;
        }
        red.solve(&mut rhs)?;
        rhs
    } else {
        Vec::new()
    };
    let mut steps = vec![FaceStep::default(); nf];
    let (dinv, r1) = (&w.dinv, &w.r1);
    for_faces(&mut steps, |f, st| {
        let fe = &e.faces[f];
        let (cot, hess) = jac_of(f);
        let fr = &p.face_rows[f];
        let mut jt = [0.0; 3]; // J₂ᵀ dλ on this triangle
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let g = row_grad(wheel, k as usize, &cot);
            let x = dl[r as usize];
            for q in 0..3 {
                jt[q] += g[q] * x;
            }
        }
        let li = [1.0 / hess[0], 1.0 / hess[1], 1.0 / hess[2]];
        let ej = li[0] * jt[0] + li[1] * jt[1] + li[2] * jt[2];
        let dtf = (r1[f] - ej) * dinv[f];
        st.dt = dtf;
        for q in 0..3 {
            st.da[q] = -li[q] * (fe.grad[q] + dtf + jt[q]);
        }
    });
    Ok((steps, dl))
}

/// Plain ABF: the full KKT system by sparse LU.
fn step_plain(slot: &mut Option<FixedValueSolver>, p: &Problem<'_>, e: &Eval, mode: Mode) -> Result<Step, SolveError> {
    let nf = p.tris.len();
    let m = p.m();
    let n = 4 * nf + m;
    let mut trip = Vec::with_capacity(9 * nf + 6 * nf * 3);
    for (f, fe) in e.faces.iter().enumerate() {
        for q in 0..3 {
            let c = (3 * f + q) as u32;
            trip.push((c, c, fe.hess[q]));
            trip.push(((3 * nf + f) as u32, c, 1.0));
            trip.push((c, (3 * nf + f) as u32, 1.0));
        }
        let fr = &p.face_rows[f];
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let g = row_grad(wheel, k as usize, &fe.cot);
            let row = (4 * nf) as u32 + r;
            let k = k as usize;
            let qs: &[usize] = if wheel { &[(k + 1) % 3, (k + 2) % 3] } else { &[k] };
            for &q in qs {
                let c = (3 * f + q) as u32;
                trip.push((row, c, g[q]));
                trip.push((c, row, g[q]));
            }
        }
    }
    for (r, &d) in e.diag.iter().enumerate() {
        if d != 0.0 {
            let row = (4 * nf + r) as u32;
            trip.push((row, row, -d));
        }
    }
    let mut rhs = Vec::with_capacity(n);
    rhs.extend(e.faces.iter().flat_map(|fe| fe.grad.map(|x| -x)));
    rhs.extend(e.faces.iter().map(|fe| -fe.c_tri));
    rhs.extend(e.c_newton.iter().map(|x| -x));
    match slot {
        Some(_) if mode == Mode::Chord => {}
        Some(s) => {
            let vals: Vec<f64> = trip.iter().map(|t| t.2).collect();
            s.refactor(&vals)?;
        }
        None => *slot = Some(FixedValueSolver::new(n, &trip, &[], Symmetry::General)?),
    }
    let x = slot.as_ref().expect("factored").solve(&[vec![]], &[rhs])?.pop().expect("one column");
    let steps = (0..nf).map(|f| FaceStep { da: [x[3 * f], x[3 * f + 1], x[3 * f + 2]], dt: x[3 * nf + f] }).collect();
    Ok((steps, x[4 * nf..].to_vec()))
}

/// Outcome of one Newton run on a fixed constraint set.
struct Run {
    iterations: usize,
    factorizations: usize,
    converged: bool,
    residual: f64,
    stationarity: f64,
}

fn newton(p: &Problem<'_>, s: &mut State, opts: &AbfOptions) -> Result<Run, SolveError> {
    let stat_tol = opts.tolerance.sqrt();
    let mut lin = Linear::new(opts.solver);
    let mut it = 0;
    let mut factorizations = 0;
    let mut refactor_next = false;
    let mut e = evaluate(p, s);
    loop {
        let run = |converged| Run { iterations: it, factorizations, converged, residual: e.residual, stationarity: e.stationarity };
        if !(e.residual.is_finite() && e.stationarity.is_finite()) {
            return Ok(run(false));
        }
        if e.residual < opts.tolerance && e.stationarity < stat_tol && e.complementarity < opts.tolerance {
            return Ok(run(true));
        }
        if it >= opts.max_iterations || crate::progress::cancelled() {
            return Ok(run(false));
        }
        // Near the solution try a chord step first; keep it if it cuts both errors enough.
        if factorizations > 0 && e.residual < CHORD_RESIDUAL && !refactor_next && !p.has_ineq {
            let step = lin.step(p, &e, Mode::Chord)?;
            let mut trial = s.clone();
            apply_step(p, &mut trial, &step, &e, opts.tolerance);
            let et = evaluate(p, &trial);
            let cut = |new: f64, old: f64, tol: f64| new <= CHORD_CONTRACTION * old || new < tol;
            if cut(et.residual, e.residual, opts.tolerance) && cut(et.stationarity, e.stationarity, stat_tol) {
                // Chord steps converge linearly: when this rate needs more than
                // CHORD_MAX_PREDICTED more of them, refactor next instead.
                let needed = |new: f64, old: f64, tol: f64| {
                    if new < tol {
                        0.0
                    } else {
                        (tol / new).ln() / (new / old).ln()
                    }
                };
                let more = needed(et.residual, e.residual, opts.tolerance).max(needed(et.stationarity, e.stationarity, stat_tol));
                refactor_next = more > CHORD_MAX_PREDICTED;
                *s = trial;
                e = et;
                it += 1;
                continue;
            }
        }
        let step = lin.step(p, &e, Mode::Factor)?;
        factorizations += 1;
        refactor_next = false;
        apply_step(p, s, &step, &e, opts.tolerance);
        e = evaluate(p, s);
        it += 1;
    }
}

/// Take the step, shortened so that no angle leaves (0, π) (fraction to the boundary 0.9) and
/// no slack or inequality multiplier reaches 0 (fraction to the boundary 0.995); then lower
/// the barrier parameter.
///
/// The slack step follows from the linearised complementarity `λ s = μ`:
/// `ds = μ/λ − s − (s/λ) dλ`. The new barrier parameter is `min(0.2 m, m^1.5)` for the mean
/// product `m` of slack and multiplier (superlinear once `m` is small), at least `tolerance/10`.
fn apply_step(p: &Problem<'_>, s: &mut State, (steps, dl): &Step, e: &Eval, tolerance: f64) {
    let mut t: f64 = 1.0;
    // Angles stay in (lower, π): fraction to the boundary 0.9, or 0.995 with bounds.
    let ftb = if p.lower > 0.0 { 0.995 } else { 0.9 };
    for (a, st) in s.alpha.chunks_exact(3).zip(steps) {
        for q in 0..3 {
            let d = st.da[q];
            if d < 0.0 {
                t = t.min(ftb * (a[q] - p.lower) / -d);
            } else if d > 0.0 {
                t = t.min(0.9 * (PI - a[q]) / d);
            }
        }
    }
    // Bound multipliers: dz = μ/gap − z − (z/gap) dα, kept positive.
    let mut dz = Vec::new();
    if p.lower > 0.0 {
        dz.reserve(s.alpha.len());
        for (f, st) in steps.iter().enumerate() {
            for q in 0..3 {
                let c = 3 * f + q;
                let gap = s.alpha[c] - p.lower;
                let z = s.z_lo[c];
                let d = s.mu / gap - z - z / gap * st.da[q];
                if d < 0.0 {
                    t = t.min(0.995 * z / -d);
                }
                dz.push(d);
            }
        }
    }
    let mut ds = Vec::new();
    if p.has_ineq {
        ds.resize(p.m(), 0.0);
        for (r, row) in p.rows.iter().enumerate() {
            if row.ineq {
                let v = row.vertex as usize;
                let (sl, z) = (s.slack[v], s.lam_sum[v]);
                ds[r] = s.mu / z - sl - e.diag[r] * dl[r];
                if ds[r] < 0.0 {
                    t = t.min(0.995 * sl / -ds[r]);
                }
                if dl[r] < 0.0 {
                    t = t.min(0.995 * z / -dl[r]);
                }
            }
        }
    }
    for ((a, l), st) in s.alpha.chunks_exact_mut(3).zip(s.lam_tri.iter_mut()).zip(steps) {
        for q in 0..3 {
            a[q] += t * st.da[q];
        }
        *l += t * st.dt;
    }
    let (mut prod, mut count) = (0.0, 0usize);
    for (c, d) in dz.iter().enumerate() {
        s.z_lo[c] += t * d;
        prod += s.z_lo[c] * (s.alpha[c] - p.lower);
        count += 1;
    }
    for (r, row) in p.rows.iter().enumerate() {
        let lam = if row.wheel { &mut s.lam_wheel } else { &mut s.lam_sum };
        lam[row.vertex as usize] += t * dl[r];
        if row.ineq {
            let v = row.vertex as usize;
            s.slack[v] += t * ds[r];
            prod += s.slack[v] * s.lam_sum[v];
            count += 1;
        }
    }
    if count > 0 {
        let m = prod / count as f64;
        s.mu = (0.2 * m).min(m.powf(1.5)).max(0.1 * tolerance);
    }
}

/// Largest angle sum of an outer-loop vertex under [`AbfBoundary::Convex`] on a loop of
/// `n` vertices: `π − π/n`, so that every outer vertex turns by at least half the mean turning
/// `2π/n` (a strictly convex outline; see the module docs).
pub fn convex_cap(n: usize) -> f64 {
    PI - PI / n.max(1) as f64
}

/// Lower bound of every angle under [`AbfBoundary::Convex`] on an outer loop of `n` vertices:
/// a quarter of the least turning `π/n` (see [`convex_cap`] and the module docs).
pub fn convex_lower_bound(n: usize) -> f64 {
    0.25 * PI / n.max(1) as f64
}

/// Targets β: the clamped 3D angles, scaled at every interior vertex to sum to 2π.
pub fn target_angles(chart: &Chart) -> Vec<[f64; 3]> {
    target_angles_with_sums(chart, &[])
}

/// Targets β scaled at every interior vertex to 2π, and at every vertex of `prescribed`
/// (chart vertex, angle sum) to its prescribed sum.
pub fn target_angles_with_sums(chart: &Chart, prescribed: &[(u32, f64)]) -> Vec<[f64; 3]> {
    let mut beta = chart_angles(&chart.positions, &chart.triangles);
    let mut goal: Vec<Option<f64>> = chart.boundary_mask().iter().map(|&b| if b { None } else { Some(2.0 * PI) }).collect();
    for &(v, t) in prescribed {
        goal[v as usize] = Some(t);
    }
    let mut sum = vec![0.0; chart.positions.len()];
    for (t, a) in chart.triangles.iter().zip(&beta) {
        for k in 0..3 {
            sum[t[k] as usize] += a[k];
        }
    }
    for (t, a) in chart.triangles.iter().zip(beta.iter_mut()) {
        for k in 0..3 {
            let v = t[k] as usize;
            if let (Some(g), true) = (goal[v], sum[v] > 0.0) {
                a[k] *= g / sum[v];
            }
        }
    }
    beta
}

/// Angle sum at every chart vertex.
fn vertex_sums(chart: &Chart, alpha: &[f64]) -> Vec<f64> {
    let mut sum = vec![0.0; chart.positions.len()];
    for (f, t) in chart.triangles.iter().enumerate() {
        for k in 0..3 {
            sum[t[k] as usize] += alpha[3 * f + k];
        }
    }
    sum
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
    let beta3 = target_angles_with_sums(chart, prescribed);
    let beta: Vec<f64> = beta3.iter().flatten().copied().collect();
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
    let mut p = Problem::new(tris, beta.clone(), &interior, &sum_target, &ineq);
    let mut z_lo = Vec::new();
    if p.has_ineq {
        let beta_min = beta.iter().copied().fold(f64::INFINITY, f64::min);
        p.lower = convex_lower_bound(outer.len()).min(0.5 * beta_min);
        if p.lower > 0.0 {
            z_lo = beta.iter().map(|&b| CONVEX_MU_START / (b - p.lower).max(CONVEX_SLACK_START)).collect();
        }
    }
    let mut s = State { alpha: beta.clone(), lam_tri: vec![0.0; nf], lam_sum, lam_wheel: vec![0.0; n], slack, mu: CONVEX_MU_START, z_lo };
    let run = newton(&p, &mut s, options).map_err(|e| ChartFailure(format!("abf: {e}")))?;
    let (iterations, factorizations, converged, residual, stationarity) =
        (run.iterations, run.factorizations, run.converged, run.residual, run.stationarity);
    let sums = vertex_sums(chart, &s.alpha);
    let active = |v: usize| ineq[v] && sums[v] > cap - CONVEX_ACTIVE;
    let alpha: Vec<[f64; 3]> = s.alpha.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let convex_active = (0..n as u32).filter(|&v| active(v as usize)).collect();
    Ok(AbfAngles { alpha, beta: beta3, iterations, factorizations, residual, stationarity, converged, convex_active })
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
/// Errors: [`UvError::AngleSum`] naming the entry and the vertex.
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
                let open_holes = options.boundary == AbfBoundary::Free && chart.boundary_loops.len() > 1;
                let open = if open_holes { lscm::folds(chart, &uv) } else { (0, false) };
                if open != (0, false) && prescribed_on_hole(chart, prescribed).is_none() {
                    // The open holes folded: close them (module docs) and keep that if better.
                    if let Ok(b) = solve_angles_holes_filled(chart, options, prescribed) {
                        if b.converged && b.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI) {
                            let (closed_uv, closed_note) = lscm::solve_with_angles(chart, &b.alpha, pins)?;
                            if lscm::folds(chart, &closed_uv) < open {
                                let note = Some(lscm::holes_filled_note(open, closed_note));
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
                return Ok(ChartSolution { uv, iterations: a.iterations, residual: a.residual, note, fallback: None });
            }
            let what = if !a.converged { "did not converge" } else { "produced an angle outside (0, π)" };
            let mut sol = lscm::solve(chart, pins)?;
            sol.iterations = a.iterations;
            sol.residual = a.residual;
            sol.fallback = Some(Fallback {
                method: "lscm",
                reason: format!("abf {what}: residual {:.3e} after {} iterations", a.residual, a.iterations),
            });
            return Ok(sol);
        }
        Err(ChartFailure(r)) => r,
    };
    let mut sol = lscm::solve(chart, pins)?;
    sol.fallback = Some(Fallback { method: "lscm", reason: format!("abf failed: {reason}") });
    Ok(sol)
}
