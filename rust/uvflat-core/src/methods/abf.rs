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
//! * with [`AbfBoundary::Convex`], every vertex of the outer boundary loop has angle sum ≤ π.
//!
//! Angles satisfying these are those of a planar triangulation (locally injective when all are
//! in (0, π)), so the UVs follow by a least-squares reconstruction: LSCM driven by the solved
//! angles ([`super::lscm::solve_with_angles`]), exact for exactly consistent angles on a disk.
//!
//! The solve is Newton's method on the Lagrangian (an SQP iteration), with the Hessian of the
//! Lagrangian in the angles approximated by the energy's, `Λ = diag(2/β²)`, as in ABF++. (With
//! the log form of the wheel condition the exact Hessian is diagonal too, `2/β² ∓ λ/sin²α`, but
//! on curved charts it has negative entries, which makes the reduced system indefinite; clamping
//! them converged more slowly than the energy Hessian in tests on camelhead.) Linear
//! constraints hold after every full step; the wheel residual falls quadratically and the
//! Lagrangian gradient linearly. Steps are shortened so that no angle leaves (0, π) (fraction to
//! the boundary 0.9). Once the constraint residual is below 1e-6, steps reuse the last
//! factorization (chord steps) while they at least halve the error.
//!
//! * [`AbfSolver::AbfPlusPlus`] (default): the ABF++ block elimination. The angle updates and
//!   the triangle multipliers are eliminated per triangle (Λ and the triangle Jacobian's
//!   Gram matrix `J₁Λ⁻¹J₁ᵀ` are diagonal), leaving a system over the vertex multipliers only
//!   (planarity and wheel, two per interior vertex): `J₂ P J₂ᵀ`, with `P` per triangle the
//!   projection `Λ⁻¹ − Λ⁻¹11ᵀΛ⁻¹ / 1ᵀΛ⁻¹1`. `P` is positive semidefinite with kernel the
//!   constant vectors, so the reduced matrix is symmetric positive definite whenever the
//!   vertex constraints are independent of the triangle constraints (always for a chart with
//!   boundary; a Cholesky failure is reported). It has the sparsity of the vertex adjacency in
//!   2×2 blocks; its pattern and symbolic analysis are computed once per constraint set and
//!   each Newton step refactors it.
//! * [`AbfSolver::Plain`]: the original ABF step, the full sparse KKT system (angles, triangle
//!   and vertex multipliers) solved by sparse LU each iteration. A reference; much slower.
//!
//! Convergence: the iteration stops when the largest constraint residual (radians, or log
//! units for the wheel condition) is below `tolerance` and the Lagrangian gradient, scaled to
//! angle units (`|∂L/∂α_c| β_c² / 2`), is below `√tolerance` (3e-5 rad by default), so that
//! the angles are near the optimum, not merely consistent. Convex boundary: an active-set loop; outer-loop vertices whose angle sum
//! exceeds π get the equality "sum = π"; an active vertex whose multiplier turns negative (the
//! inequality would pull the sum below π without it) is released; repeat until the active set
//! is stable (at most [`MAX_ACTIVE_SET_ROUNDS`] rounds).
//!
//! Failure modes: no convergence within `max_iterations` Newton steps (per active-set round),
//! a singular or indefinite linear system, or solved angles outside (0, π). [`solve`] then
//! falls back to plain LSCM with the 3D angles and says why in [`ChartSolution::fallback`].
//!
//! Preconditions: a chart that is a disk (possibly with holes). Holes are not constrained to
//! close up (as in the papers): on a chart with holes the reconstruction is least squares.

use std::f64::consts::PI;

use super::{chart_angles, lscm, ChartFailure, ChartSolution, Fallback};
use crate::charts::Chart;
use crate::solvers::{FixedValueSolver, SolveError, Symmetry};

/// Below this constraint residual, Newton steps reuse the last factorization while they at
/// least halve `residual + stationarity` (chord steps).
const CHORD_RESIDUAL: f64 = 1e-6;

/// Most active-set rounds of [`AbfBoundary::Convex`].
pub const MAX_ACTIVE_SET_ROUNDS: usize = 20;

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
    /// Every vertex of the outer boundary loop has an angle sum ≤ π: the UV outline is convex.
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
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbfOptions {
    /// Linear algebra of the Newton step. Default [`AbfSolver::AbfPlusPlus`].
    pub solver: AbfSolver,
    /// Most Newton iterations (per active-set round for a convex boundary). Default 30.
    pub max_iterations: usize,
    /// Stop when the largest constraint residual is below this. Default 1e-9.
    pub tolerance: f64,
    /// Boundary constraint. Default [`AbfBoundary::Free`].
    pub boundary: AbfBoundary,
}

impl Default for AbfOptions {
    fn default() -> Self {
        AbfOptions { solver: AbfSolver::AbfPlusPlus, max_iterations: 30, tolerance: 1e-9, boundary: AbfBoundary::Free }
    }
}

/// Solved angles of one chart (see [`solve_angles`]).
#[derive(Debug, Clone, PartialEq)]
pub struct AbfAngles {
    /// Solved corner angles, per chart triangle in its vertex order.
    pub alpha: Vec<[f64; 3]>,
    /// Target angles β (3D angles, interior vertices scaled to 2π).
    pub beta: Vec<[f64; 3]>,
    /// Newton iterations done (all active-set rounds).
    pub iterations: usize,
    /// Largest constraint residual at the end (including convex-boundary violations).
    pub residual: f64,
    /// Largest scaled Lagrangian gradient `|∂L/∂α_c| β_c² / 2` at the end (radians).
    pub stationarity: f64,
    /// Whether the tolerances were met (and, for a convex boundary, the active set settled).
    pub converged: bool,
    /// Outer-boundary vertices held at angle sum π (convex boundary only), ascending.
    pub convex_active: Vec<u32>,
}

/// One vertex constraint row: (vertex, wheel?) — the sum row when `wheel` is false.
#[derive(Clone, Copy)]
struct Row {
    vertex: u32,
    wheel: bool,
}

/// Constraint rows touching one triangle: (row, kind wheel?, local corner of the vertex).
#[derive(Clone, Copy, Default)]
struct FaceRows {
    len: u8,
    rows: [(u32, bool, u8); 6],
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

struct Problem<'a> {
    tris: &'a [[u32; 3]],
    beta: Vec<f64>,
    w: Vec<f64>,
    rows: Vec<Row>,
    /// Sum target per row (2π interior, π active boundary; unused for wheel rows).
    target: Vec<f64>,
    face_rows: Vec<FaceRows>,
    /// Lower-triangle pattern of the reduced ABF++ matrix, unique (row ≥ column) entries.
    pattern: Vec<(u32, u32)>,
    /// Per triangle, for each pair (i, j ≤ i) of its rows in order, the entry in `pattern`;
    /// triangle `f` starts at `slot_start[f]`.
    slots: Vec<u32>,
    slot_start: Vec<u32>,
}

impl<'a> Problem<'a> {
    fn new(tris: &'a [[u32; 3]], beta: Vec<f64>, interior: &[bool], convex_active: &[bool]) -> Self {
        let n = interior.len();
        let mut sum_row = vec![u32::MAX; n];
        let mut wheel_row = vec![u32::MAX; n];
        let mut rows = Vec::new();
        let mut target = Vec::new();
        for v in 0..n {
            if interior[v] || convex_active[v] {
                sum_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: false });
                target.push(if interior[v] { 2.0 * PI } else { PI });
            }
            if interior[v] {
                wheel_row[v] = rows.len() as u32;
                rows.push(Row { vertex: v as u32, wheel: true });
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
        let (pattern, slots, slot_start) = reduced_pattern(rows.len(), &face_rows);
        Problem { tris, beta, w, rows, target, face_rows, pattern, slots, slot_start }
    }

    fn m(&self) -> usize {
        self.rows.len()
    }
}

/// The unique lower-triangle entries of `Σ_f (rows of f) × (rows of f)`, built once per
/// constraint set so that every Newton step sums into a fixed value array (compressed rows:
/// count, fill, sort and deduplicate each row's columns, then look every pair up).
fn reduced_pattern(m: usize, face_rows: &[FaceRows]) -> (Vec<(u32, u32)>, Vec<u32>, Vec<u32>) {
    let mut count = vec![0u32; m + 1];
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
    let mut cols = vec![0u32; count[m] as usize];
    for fr in face_rows {
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                let r = a.max(b) as usize;
                cols[fill[r] as usize] = a.min(b);
                fill[r] += 1;
            }
        }
    }
    // Sort and deduplicate each row's columns in place; `ustart[r]` = first unique entry.
    let mut pattern = Vec::new();
    let mut ustart = vec![0u32; m + 1];
    let mut ulen = vec![0u32; m];
    for r in 0..m {
        let seg = &mut cols[count[r] as usize..count[r + 1] as usize];
        seg.sort_unstable();
        let mut k = 0;
        for q in 0..seg.len() {
            if q == 0 || seg[q] != seg[k - 1] {
                seg[k] = seg[q];
                k += 1;
            }
        }
        ustart[r] = pattern.len() as u32;
        ulen[r] = k as u32;
        pattern.extend(seg[..k].iter().map(|&c| (r as u32, c)));
    }
    ustart[m] = pattern.len() as u32;
    let mut slots = Vec::with_capacity(count[m] as usize);
    let mut slot_start = Vec::with_capacity(face_rows.len() + 1);
    for fr in face_rows {
        slot_start.push(slots.len() as u32);
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                let (r, c) = (a.max(b) as usize, a.min(b));
                let seg = &cols[count[r] as usize..count[r] as usize + ulen[r] as usize];
                let pos = seg.binary_search(&c).expect("entry in pattern");
                slots.push(ustart[r] + pos as u32);
            }
        }
    }
    slot_start.push(slots.len() as u32);
    (pattern, slots, slot_start)
}

/// Newton state: angles and multipliers (vertex multipliers per vertex so that they survive a
/// change of the active set).
struct State {
    alpha: Vec<f64>,
    lam_tri: Vec<f64>,
    lam_sum: Vec<f64>,
    lam_wheel: Vec<f64>,
}

/// Residuals and Newton ingredients at the current state.
struct Eval {
    /// Constraint residuals: triangles, then rows.
    c_tri: Vec<f64>,
    c_row: Vec<f64>,
    /// ∂L/∂α per corner.
    grad: Vec<f64>,
    /// Diagonal (approximate) Hessian of L in α: the energy's, 2/β².
    hess: Vec<f64>,
    cot: Vec<f64>,
    residual: f64,
    stationarity: f64,
}

fn evaluate(p: &Problem<'_>, s: &State) -> Eval {
    let nf = p.tris.len();
    let mut cot = vec![0.0; 3 * nf];
    let mut c_tri = vec![0.0; nf];
    let mut c_row: Vec<f64> = p.rows.iter().enumerate().map(|(r, row)| if row.wheel { 0.0 } else { -p.target[r] }).collect();
    let mut grad = vec![0.0; 3 * nf];
    let mut hess = vec![0.0; 3 * nf];
    for f in 0..nf {
        let a = [s.alpha[3 * f], s.alpha[3 * f + 1], s.alpha[3 * f + 2]];
        let sn = [a[0].sin(), a[1].sin(), a[2].sin()];
        let ct = [a[0].cos() / sn[0], a[1].cos() / sn[1], a[2].cos() / sn[2]];
        let ls = [sn[0].ln(), sn[1].ln(), sn[2].ln()];
        cot[3 * f..3 * f + 3].copy_from_slice(&ct);
        c_tri[f] = a[0] + a[1] + a[2] - PI;
        for k in 0..3 {
            let c = 3 * f + k;
            grad[c] = 2.0 * p.w[c] * (a[k] - p.beta[c]) + s.lam_tri[f];
            hess[c] = 2.0 * p.w[c];
        }
        let fr = &p.face_rows[f];
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let (r, k) = (r as usize, k as usize);
            let v = p.rows[r].vertex as usize;
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            if wheel {
                c_row[r] += ls[k2] - ls[k1];
                let l = s.lam_wheel[v];
                grad[3 * f + k1] -= l * ct[k1];
                grad[3 * f + k2] += l * ct[k2];
            } else {
                c_row[r] += a[k];
                grad[3 * f + k] += s.lam_sum[v];
            }
        }
    }
    let mut stationarity: f64 = 0.0;
    for c in 0..3 * nf {
        stationarity = stationarity.max(grad[c].abs() / (2.0 * p.w[c]));
    }
    let residual = c_tri.iter().chain(&c_row).fold(0.0f64, |m, x| m.max(x.abs()));
    Eval { c_tri, c_row, grad, hess, cot, residual, stationarity }
}

/// The Newton step (dα, dλ_tri, dλ_rows).
type Step = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The linear algebra of one Newton step, keeping its factorization pattern across steps.
enum Linear {
    PlusPlus(Option<FixedValueSolver>),
    Plain(Option<FixedValueSolver>),
}

fn factor(slot: &mut Option<FixedValueSolver>, n: usize, trip: Vec<(u32, u32, f64)>, sym: Symmetry, refresh: bool) -> Result<(), SolveError> {
    match slot {
        Some(_) if !refresh => Ok(()),
        Some(s) => {
            let vals: Vec<f64> = trip.iter().map(|t| t.2).collect();
            s.refactor(&vals)
        }
        None => {
            *slot = Some(FixedValueSolver::new(n, &trip, &[], sym)?);
            Ok(())
        }
    }
}

impl Linear {
    fn new(solver: AbfSolver) -> Self {
        match solver {
            AbfSolver::AbfPlusPlus => Linear::PlusPlus(None),
            AbfSolver::Plain => Linear::Plain(None),
        }
    }

    fn step(&mut self, p: &Problem<'_>, e: &Eval, refresh: bool) -> Result<Step, SolveError> {
        match self {
            Linear::PlusPlus(slot) => step_plus_plus(slot, p, e, refresh),
            Linear::Plain(slot) => step_plain(slot, p, e, refresh),
        }
    }
}

/// ABF++: eliminate dα and dλ_tri per triangle, solve the reduced vertex system.
fn step_plus_plus(slot: &mut Option<FixedValueSolver>, p: &Problem<'_>, e: &Eval, refresh: bool) -> Result<Step, SolveError> {
    let nf = p.tris.len();
    let m = p.m();
    let mut rhs = e.c_row.clone();
    let mut vals = if refresh { vec![0.0; p.pattern.len()] } else { Vec::new() };
    // Per triangle: Λ⁻¹, D = 1ᵀΛ⁻¹1, r1 = C_tri − 1ᵀΛ⁻¹∇α L.
    let mut dinv = vec![0.0; nf];
    let mut r1 = vec![0.0; nf];
    for f in 0..nf {
        let li = [1.0 / e.hess[3 * f], 1.0 / e.hess[3 * f + 1], 1.0 / e.hess[3 * f + 2]];
        let b = [e.grad[3 * f], e.grad[3 * f + 1], e.grad[3 * f + 2]];
        let lb = [li[0] * b[0], li[1] * b[1], li[2] * b[2]];
        let d = li[0] + li[1] + li[2];
        let rr = e.c_tri[f] - (lb[0] + lb[1] + lb[2]);
        dinv[f] = 1.0 / d;
        r1[f] = rr;
        let ct = [e.cot[3 * f], e.cot[3 * f + 1], e.cot[3 * f + 2]];
        let fr = &p.face_rows[f];
        let len = fr.len as usize;
        let mut g = [[0.0; 3]; 6];
        let mut u = [[0.0; 3]; 6];
        let mut sj = [0.0; 6];
        for j in 0..len {
            let (r, wheel, k) = fr.rows[j];
            g[j] = row_grad(wheel, k as usize, &ct);
            u[j] = [li[0] * g[j][0], li[1] * g[j][1], li[2] * g[j][2]];
            sj[j] = u[j][0] + u[j][1] + u[j][2];
            let gb = g[j][0] * lb[0] + g[j][1] * lb[1] + g[j][2] * lb[2];
            rhs[r as usize] -= gb + sj[j] * rr / d;
        }
        if refresh {
            let mut q = p.slot_start[f] as usize;
            for i in 0..len {
                for j in 0..=i {
                    vals[p.slots[q] as usize] += g[i][0] * u[j][0] + g[i][1] * u[j][1] + g[i][2] * u[j][2] - sj[i] * sj[j] / d;
                    q += 1;
                }
            }
        }
    }
    let dl = if m > 0 {
        match slot {
            Some(s) if refresh => s.refactor(&vals)?,
            Some(_) => {}
            None => {
                let trip: Vec<(u32, u32, f64)> = p.pattern.iter().zip(&vals).map(|(&(r, c), &v)| (r, c, v)).collect();
                *slot = Some(FixedValueSolver::new(m, &trip, &[], Symmetry::Symmetric)?);
            }
        }
        slot.as_ref().expect("factored").solve(&[vec![]], &[rhs])?.pop().expect("one column")
    } else {
        Vec::new()
    };
    let mut da = vec![0.0; 3 * nf];
    let mut dt = vec![0.0; nf];
    for f in 0..nf {
        let ct = [e.cot[3 * f], e.cot[3 * f + 1], e.cot[3 * f + 2]];
        let fr = &p.face_rows[f];
        let mut jt = [0.0; 3]; // J₂ᵀ dλ on this triangle
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let g = row_grad(wheel, k as usize, &ct);
            let x = dl[r as usize];
            for q in 0..3 {
                jt[q] += g[q] * x;
            }
        }
        let li = [1.0 / e.hess[3 * f], 1.0 / e.hess[3 * f + 1], 1.0 / e.hess[3 * f + 2]];
        let ej = li[0] * jt[0] + li[1] * jt[1] + li[2] * jt[2];
        let dtf = (r1[f] - ej) * dinv[f];
        dt[f] = dtf;
        for q in 0..3 {
            da[3 * f + q] = -li[q] * (e.grad[3 * f + q] + dtf + jt[q]);
        }
    }
    Ok((da, dt, dl))
}

/// Plain ABF: the full KKT system by sparse LU.
fn step_plain(slot: &mut Option<FixedValueSolver>, p: &Problem<'_>, e: &Eval, refresh: bool) -> Result<Step, SolveError> {
    let nf = p.tris.len();
    let m = p.m();
    let n = 4 * nf + m;
    let mut trip = Vec::with_capacity(9 * nf + 6 * nf * 3);
    for f in 0..nf {
        let ct = [e.cot[3 * f], e.cot[3 * f + 1], e.cot[3 * f + 2]];
        for q in 0..3 {
            let c = (3 * f + q) as u32;
            trip.push((c, c, e.hess[3 * f + q]));
            trip.push(((3 * nf + f) as u32, c, 1.0));
            trip.push((c, (3 * nf + f) as u32, 1.0));
        }
        let fr = &p.face_rows[f];
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let g = row_grad(wheel, k as usize, &ct);
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
    let mut rhs = Vec::with_capacity(n);
    rhs.extend(e.grad.iter().map(|x| -x));
    rhs.extend(e.c_tri.iter().map(|x| -x));
    rhs.extend(e.c_row.iter().map(|x| -x));
    factor(slot, n, trip, Symmetry::General, refresh)?;
    let x = slot.as_ref().expect("factored").solve(&[vec![]], &[rhs])?.pop().expect("one column");
    Ok((x[..3 * nf].to_vec(), x[3 * nf..4 * nf].to_vec(), x[4 * nf..].to_vec()))
}

/// Outcome of one Newton run on a fixed constraint set.
struct Run {
    iterations: usize,
    converged: bool,
    residual: f64,
    stationarity: f64,
}

fn newton(p: &Problem<'_>, s: &mut State, opts: &AbfOptions) -> Result<Run, SolveError> {
    let stat_tol = opts.tolerance.sqrt();
    let mut lin = Linear::new(opts.solver);
    let mut it = 0;
    let mut last_merit = f64::INFINITY;
    loop {
        let e = evaluate(p, s);
        let finite = e.residual.is_finite() && e.stationarity.is_finite();
        if !finite {
            return Ok(Run { iterations: it, converged: false, residual: e.residual, stationarity: e.stationarity });
        }
        if e.residual < opts.tolerance && e.stationarity < stat_tol {
            return Ok(Run { iterations: it, converged: true, residual: e.residual, stationarity: e.stationarity });
        }
        if it >= opts.max_iterations {
            return Ok(Run { iterations: it, converged: false, residual: e.residual, stationarity: e.stationarity });
        }
        // Refactor while far from feasibility; near it, keep the last factorization (chord
        // steps, a fraction of the cost) as long as they at least halve the error.
        let merit = e.residual + e.stationarity;
        let refresh = e.residual >= CHORD_RESIDUAL || merit > 0.5 * last_merit;
        last_merit = merit;
        let (da, dt, dl) = lin.step(p, &e, refresh)?;
        // Fraction to the boundary: no angle leaves (0, π).
        let mut t: f64 = 1.0;
        for (a, d) in s.alpha.iter().zip(&da) {
            if *d < 0.0 {
                t = t.min(0.9 * a / -d);
            } else if *d > 0.0 {
                t = t.min(0.9 * (PI - a) / d);
            }
        }
        for (a, d) in s.alpha.iter_mut().zip(&da) {
            *a += t * d;
        }
        for (l, d) in s.lam_tri.iter_mut().zip(&dt) {
            *l += t * d;
        }
        for (r, row) in p.rows.iter().enumerate() {
            let lam = if row.wheel { &mut s.lam_wheel } else { &mut s.lam_sum };
            lam[row.vertex as usize] += t * dl[r];
        }
        it += 1;
    }
}

/// Targets β: the clamped 3D angles, scaled at every interior vertex to sum to 2π.
pub fn target_angles(chart: &Chart) -> Vec<[f64; 3]> {
    let mut beta = chart_angles(&chart.positions, &chart.triangles);
    let interior: Vec<bool> = chart.boundary_mask().iter().map(|b| !b).collect();
    let mut sum = vec![0.0; chart.positions.len()];
    for (t, a) in chart.triangles.iter().zip(&beta) {
        for k in 0..3 {
            sum[t[k] as usize] += a[k];
        }
    }
    for (t, a) in chart.triangles.iter().zip(beta.iter_mut()) {
        for k in 0..3 {
            let v = t[k] as usize;
            if interior[v] && sum[v] > 0.0 {
                a[k] *= 2.0 * PI / sum[v];
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
    let tris = &chart.triangles;
    let nf = tris.len();
    let n = chart.positions.len();
    let beta3 = target_angles(chart);
    let beta: Vec<f64> = beta3.iter().flatten().copied().collect();
    let interior: Vec<bool> = chart.boundary_mask().iter().map(|b| !b).collect();
    let mut active = vec![false; n];
    let outer: Vec<u32> = match (options.boundary, chart.outer_loop()) {
        (AbfBoundary::Convex, Some(l)) => chart.boundary_loops[l].clone(),
        _ => Vec::new(),
    };
    let mut s = State { alpha: beta.clone(), lam_tri: vec![0.0; nf], lam_sum: vec![0.0; n], lam_wheel: vec![0.0; n] };
    let mut iterations = 0;
    let mut rounds = 0;
    let (converged, mut residual, stationarity) = loop {
        let p = Problem::new(tris, beta.clone(), &interior, &active);
        let run = newton(&p, &mut s, options).map_err(|e| ChartFailure(format!("abf: {e}")))?;
        iterations += run.iterations;
        rounds += 1;
        if !run.converged || outer.is_empty() {
            break (run.converged, run.residual, run.stationarity);
        }
        // Active set of the convex boundary.
        let sums = vertex_sums(chart, &s.alpha);
        let mut changed = false;
        for &v in &outer {
            let v = v as usize;
            if !active[v] && sums[v] > PI + options.tolerance {
                active[v] = true;
                s.lam_sum[v] = 0.0;
                changed = true;
            } else if active[v] && s.lam_sum[v] < -1e-12 {
                active[v] = false;
                s.lam_sum[v] = 0.0;
                changed = true;
            }
        }
        if !changed {
            break (true, run.residual, run.stationarity);
        }
        if rounds >= MAX_ACTIVE_SET_ROUNDS {
            break (false, run.residual, run.stationarity);
        }
    };
    if !outer.is_empty() {
        let sums = vertex_sums(chart, &s.alpha);
        for &v in &outer {
            residual = residual.max(sums[v as usize] - PI);
        }
    }
    let alpha: Vec<[f64; 3]> = s.alpha.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let convex_active = (0..n as u32).filter(|&v| active[v as usize]).collect();
    Ok(AbfAngles { alpha, beta: beta3, iterations, residual, stationarity, converged, convex_active })
}

/// ABF / ABF++ of one chart: solve the angles, then reconstruct UVs with LSCM driven by them
/// (pins as in [`lscm::solve_with_angles`]).
///
/// When the angle solve fails (no convergence, a linear system that cannot be factored, or
/// angles outside (0, π)), the chart is mapped by plain LSCM with its 3D angles and the
/// solution carries a [`Fallback`] saying why. Failures: those of the LSCM solve.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &AbfOptions) -> Result<ChartSolution, ChartFailure> {
    let reason = match solve_angles(chart, options) {
        Ok(a) => {
            let valid = a.alpha.iter().flatten().all(|&x| x > 0.0 && x < PI);
            if a.converged && valid {
                let (uv, note) = lscm::solve_with_angles(chart, &a.alpha, pins)?;
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
