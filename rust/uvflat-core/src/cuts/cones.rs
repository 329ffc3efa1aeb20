//! Greedy cone placement on the linearised conformal scale factor.
//!
//! Paper: Springborn, Schröder, Pinkall 2008 (CETM) §5.1 and Ben-Chen, Gotsman, Bunin 2008
//! (conformal flattening by curvature prescription): with cone vertices `C` (and the chart's
//! boundary, if any) held at `u = 0`, the log scale factor `u` of the conformal metric that is
//! flat away from the cones solves the discrete Yamabe equation
//!
//! ```text
//! (L u)_i = −K_i   at every other vertex,
//! ```
//!
//! `L` the cotangent Laplacian (positive semi-definite, weights ½(cot α + cot β)) and `K_i`
//! the angle defect (2π − Σ angles). Lengths scale by `e^u`, so `max |u| ≤ ln(max_stretch)`
//! bounds the stretch of the flattening. A new cone goes where `|u|` is largest; one pass
//! then moves each cone to where `|u|` peaks without it. The curvature each cone ends up with
//! is `K̂_c = K_c + (L u)_c`; the cone curvatures (with the boundary's) add up to 2πχ.
//!
//! Linear algebra: the Dirichlet vertices are held by a large diagonal penalty so the sparsity
//! pattern never changes: one symbolic Cholesky analysis per chart, in the chart's shared
//! vertex order ([`Chart::vertex_order`], which the method's systems on the chart's large
//! pieces inherit, [`Chart::inherit_vertex_order`]), and one numeric factorization with the
//! boundary held (and, on a closed chart, a ground vertex: the vertex of largest curvature).
//! Cones are held on top of that factor by the capacitance method: with `g_c = L₀⁻¹ e_c` (one
//! pair of triangular solves per cone, remembered; the new cones of a call are solved
//! together, one pass over the factor), the scale factor with cones `C` is
//! `u = u₀ + Σ_c λ_c g_c` where `G_CC λ = −u₀|_C` (a small dense system), so trying a cone
//! costs two triangular solves, not a factorization. A closed chart's one cone is not moved
//! (without it the system is singular). A closed chart whose cone
//! set leaves out the ground vertex gets a second base factor grounded at the set's first cone
//! (kept: later rounds keep their first cone), and the capacitance method on it. A system
//! with many vertices held at once (a whole cut, [`ScaleSolver::solve_refactored`]) is
//! factored anew with them eliminated instead of penalised, in single precision with
//! iterative refinement.
//!
//! Preconditions: a chart without defects. Degenerate triangles are safe: cotangents come
//! from clamped angles (every triangle contributes the stiffness of a valid triangle, so `L`
//! stays positive semi-definite) and `1e-8 · mean diagonal` is added to the diagonal.
//!
//! Failures: none; if the factorization fails (it should not), the cones found so far are
//! returned with `u` zero.

use std::f64::consts::PI;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::{Pair, SparseColMat, SymbolicSparseColMat};
use faer::{MatMut, Side};

use crate::charts::Chart;
use crate::geometry::clamped_angles;
use crate::solvers::refined_llt::{single_pays, RefinedLlt};

/// Most Green's functions `L₀⁻¹ e_c` solved in one pass over the factor (a repair or
/// prediction round adds up to [`crate::pipeline::repair::CONES_PER_ROUND`] cones at once).
const GREEN_BATCH: usize = 8;

/// Result of [`place_cones`].
#[derive(Debug, Clone)]
pub struct Cones {
    /// Cone vertices (chart vertex ids), in the order they were placed.
    pub vertices: Vec<u32>,
    /// Curvature `K̂` concentrated at each cone (radians; the cone angle is 2π − K̂).
    pub curvature: Vec<f64>,
    /// Log scale factor per chart vertex with these cones.
    pub u: Vec<f64>,
    /// Largest `|u|` over the chart.
    pub max_u: f64,
}

/// The Laplace system of one chart, analysed once.
pub struct ScaleSolver {
    n: usize,
    /// Lower-triangle values of `L` in pattern order (before penalty).
    base: Vec<f64>,
    /// Position of each vertex's diagonal in `base`.
    diag: Vec<usize>,
    /// `(row, col, value)` of `L` (lower triangle incl. diagonal), to compute `L u`.
    entries: Vec<(u32, u32, f64)>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: faer::sparse::Argsort<usize>,
    llt: SymbolicCholesky<usize>,
    penalty: f64,
    /// Angle defect per vertex.
    pub defect: Vec<f64>,
    /// Whether each vertex is on the chart's boundary.
    pub boundary: Vec<bool>,
    /// The factor with the boundary (and the ground vertex) held, made on first use.
    base_factor: std::sync::OnceLock<Option<BaseFactor>>,
    /// On a closed chart, a second base factor grounded at another vertex (the first cone of
    /// cone sets that leave out the default ground), made on first use.
    other_base: std::sync::Mutex<Option<std::sync::Arc<BaseFactor>>>,
}

/// [`ScaleSolver`]'s factor with the boundary and ground held, its solution and the cones'
/// columns of its inverse.
struct BaseFactor {
    llt: Factor,
    /// On a closed chart, the vertex held to make the system definite.
    ground: Option<u32>,
    /// `u` with only the boundary and ground held.
    u0: Vec<f64>,
    /// `L₀⁻¹ e_c` per cone tried so far.
    green: std::sync::Mutex<std::collections::HashMap<u32, std::sync::Arc<Vec<f64>>>>,
}

impl ScaleSolver {
    /// Assemble the cotangent Laplacian and curvature of `chart` and analyse the pattern.
    pub fn new(chart: &Chart) -> Option<ScaleSolver> {
        let n = chart.positions.len();
        let (entries, sums) = cotan_laplacian(chart);
        let boundary = chart.boundary_mask();
        let defect: Vec<f64> =
            (0..n).map(|v| if boundary[v] { PI - sums[v] } else { 2.0 * PI - sums[v] }).collect();
        let mean_diag = entries.iter().filter(|e| e.0 == e.1).map(|e| e.2.abs()).sum::<f64>() / n.max(1) as f64;
        let max_diag = entries.iter().filter(|e| e.0 == e.1).map(|e| e.2.abs()).fold(0.0, f64::max);
        let eps = 1e-8 * mean_diag.max(1e-300);
        let (symbolic, argsort, llt) = analyse_in_vertex_order(chart, &entries)?;
        let mut diag = vec![0usize; n];
        let mut base = Vec::with_capacity(entries.len());
        for (k, e) in entries.iter().enumerate() {
            if e.0 == e.1 {
                diag[e.0 as usize] = k;
                base.push(e.2 + eps);
            } else {
                base.push(e.2);
            }
        }
        Some(ScaleSolver { n, base, diag, entries, symbolic, argsort, llt, penalty: 1e8 * max_diag.max(1e-300), defect, boundary, base_factor: std::sync::OnceLock::new(), other_base: Default::default() })
    }

    /// Free the base factors and the Green's functions remembered on them (made again on
    /// the next solve that needs them; the symbolic analysis is kept).
    pub fn release_factors(&mut self) {
        self.base_factor = std::sync::OnceLock::new();
        self.other_base = Default::default();
    }

    /// Solve for `u` with `fixed` vertices (and the boundary) held at zero.
    pub fn solve(&self, fixed: &[u32]) -> Option<Vec<f64>> {
        match self.base() {
            Some(base) if base.ground.is_none_or(|g| fixed.contains(&g)) => self.solve_on_base(base, fixed),
            // A closed chart whose cones leave out the ground: a base grounded at the first
            // cone (repair rounds keep their first cone, so one such factor serves them all).
            Some(_) if !fixed.is_empty() => match self.other_base(fixed[0]) {
                Some(base) => self.solve_on_base(&base, fixed),
                None => self.solve_refactored(fixed),
            },
            _ => self.solve_refactored(fixed),
        }
    }

    /// The base factor of a closed chart grounded at `ground`, kept until another ground is
    /// asked for.
    fn other_base(&self, ground: u32) -> Option<std::sync::Arc<BaseFactor>> {
        let mut slot = self.other_base.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(b) = slot.as_ref().filter(|b| b.ground == Some(ground)) {
            return Some(b.clone());
        }
        let (llt, u0) = self.factor_and_solve(&[ground])?;
        let b = std::sync::Arc::new(BaseFactor { llt, ground: Some(ground), u0, green: Default::default() });
        *slot = Some(b.clone());
        Some(b)
    }

    /// `u` with only the boundary (or, on a closed chart, the ground vertex) held: on a disk,
    /// the log scale factor of the conformal flattening that keeps the outline's lengths
    /// (Sawhney & Crane 2017, boundary first flattening with `u = 0` on the boundary, the
    /// flattening of least area distortion among those). `None` if the factorization failed.
    pub fn base_u(&self) -> Option<&[f64]> {
        self.base().map(|b| b.u0.as_slice())
    }

    /// The base factor (boundary and ground held), made once.
    fn base(&self) -> Option<&BaseFactor> {
        self.base_factor
            .get_or_init(|| {
                let ground = if self.boundary.iter().any(|&b| b) {
                    None
                } else {
                    (0..self.n).max_by(|&a, &b| self.defect[a].total_cmp(&self.defect[b]).then(b.cmp(&a))).map(|v| v as u32)
                };
                let held: Vec<u32> = ground.into_iter().collect();
                let (llt, u0) = self.factor_and_solve(&held)?;
                Some(BaseFactor { llt, ground, u0, green: Default::default() })
            })
            .as_ref()
    }

    /// `u` with `fixed` held, by the capacitance method on the base factor (module docs).
    fn solve_on_base(&self, base: &BaseFactor, fixed: &[u32]) -> Option<Vec<f64>> {
        let mut cones: Vec<u32> = Vec::with_capacity(fixed.len());
        for &c in fixed {
            if !self.boundary[c as usize] && Some(c) != base.ground && !cones.contains(&c) {
                cones.push(c);
            }
        }
        let mut u = base.u0.clone();
        if !cones.is_empty() {
            let columns = self.greens(base, &cones);
            let k = cones.len();
            // G_CC λ = −u₀|_C, G_CC symmetric positive definite (Cholesky, by hand: k is small).
            let mut g: Vec<f64> = (0..k * k).map(|ij| columns[ij % k][cones[ij / k] as usize]).collect();
            let mut lambda: Vec<f64> = cones.iter().map(|&c| -base.u0[c as usize]).collect();
            if !dense_cholesky_solve(&mut g, &mut lambda, k) {
                return self.solve_refactored(fixed);
            }
            for (col, l) in columns.iter().zip(&lambda) {
                for (x, gc) in u.iter_mut().zip(col.iter()) {
                    *x += l * gc;
                }
            }
            // Held vertices are exactly zero (the penalty leaves them at ~1e-8 of the rest).
            for &c in &cones {
                u[c as usize] = 0.0;
            }
            if let Some(g) = base.ground {
                u[g as usize] = 0.0;
            }
            for (x, &b) in u.iter_mut().zip(&self.boundary) {
                if b {
                    *x = 0.0;
                }
            }
        }
        u.iter().all(|x| x.is_finite()).then_some(u)
    }

    /// `L₀⁻¹ e_c` for every cone `c` of `cones`, remembered; the ones not known yet are solved
    /// together (one pass over the factor for all of them: the solves are bound by reading
    /// the factor, so four columns at once cost little more than one).
    fn greens(&self, base: &BaseFactor, cones: &[u32]) -> Vec<std::sync::Arc<Vec<f64>>> {
        let mut known = base.green.lock().unwrap_or_else(|e| e.into_inner());
        let mut missing: Vec<u32> = cones.iter().copied().filter(|c| !known.contains_key(c)).collect();
        missing.sort_unstable();
        missing.dedup();
        let n = self.n;
        for chunk in missing.chunks(GREEN_BATCH) {
            let mut rhs = vec![0.0; n * chunk.len()];
            for (j, &c) in chunk.iter().enumerate() {
                rhs[j * n + c as usize] = 1.0;
            }
            base.llt.solve_columns_in_place(&self.llt, &mut rhs, chunk.len());
            for (j, &c) in chunk.iter().enumerate() {
                known.insert(c, std::sync::Arc::new(rhs[j * n..(j + 1) * n].to_vec()));
            }
        }
        cones.iter().map(|c| known[c].clone()).collect()
    }

    /// `u` with `fixed` held, by a numeric factorization of its own: the reference
    /// [`Self::solve`] agrees with, and the prediction of a cut chart (its cut's vertices
    /// held, [`super::ChartCutter::predicted_ratios_after`]). The held vertices are eliminated
    /// (their rows and columns made the identity, on the same pattern), so the system keeps
    /// the Laplacian's conditioning and a large one is factored in single precision and
    /// refined to double ([`crate::solvers::refined_llt`]: about half the factorization's
    /// time, which a prediction round is mostly made of).
    pub fn solve_refactored(&self, fixed: &[u32]) -> Option<Vec<f64>> {
        let n = self.n;
        let mut held = self.boundary.clone();
        for &c in fixed {
            held[c as usize] = true;
        }
        // The identity's scale: the mean diagonal, so the matrix's norm and condition do not
        // change.
        let unit = self.diag.iter().map(|&k| self.base[k]).sum::<f64>() / n.max(1) as f64;
        let values: Vec<f64> = self
            .entries
            .iter()
            .zip(&self.base)
            .map(|(e, &x)| match (held[e.0 as usize] || held[e.1 as usize], e.0 == e.1) {
                (false, _) => x,
                (true, true) => unit,
                (true, false) => 0.0,
            })
            .collect();
        let mat = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &values).ok()?;
        drop(values);
        let par = faer::get_global_parallelism();
        let mut factor = RefinedLlt::<f64>::new(single_pays(n));
        let mut mem = MemBuffer::try_new(RefinedLlt::<f64>::scratch(&self.llt, par, 1)).ok()?;
        factor.factor(&self.llt, mat.as_ref(), Side::Lower, par, MemStack::new(&mut mem)).ok()?;
        let mut u: Vec<f64> = (0..n).map(|i| if held[i] { 0.0 } else { -self.defect[i] }).collect();
        factor
            .solve_in_place(&self.llt, mat.as_ref(), Side::Lower, MatMut::from_column_major_slice_mut(&mut u, n, 1), par, MemStack::new(&mut mem))
            .ok()?;
        for (x, &h) in u.iter_mut().zip(&held) {
            if h {
                *x = 0.0;
            }
        }
        u.iter().all(|x| x.is_finite()).then_some(u)
    }

    /// Factor `L` with `fixed` and the boundary held, and solve for `u`.
    fn factor_and_solve(&self, fixed: &[u32]) -> Option<(Factor, Vec<f64>)> {
        let mut values = self.base.clone();
        let mut held = self.boundary.clone();
        for &c in fixed {
            held[c as usize] = true;
        }
        for v in 0..self.n {
            if held[v] {
                values[self.diag[v]] += self.penalty;
            }
        }
        let mat = SparseColMat::new_from_argsort(self.symbolic.clone(), &self.argsort, &values).ok()?;
        let f = Factor::new(&self.llt, &mat)?;
        let mut u: Vec<f64> = (0..self.n).map(|i| if held[i] { 0.0 } else { -self.defect[i] }).collect();
        f.solve_in_place(&self.llt, &mut u);
        for (x, &h) in u.iter_mut().zip(&held) {
            if h {
                *x = 0.0;
            }
        }
        u.iter().all(|x| x.is_finite()).then_some((f, u))
    }

    /// `K_v + (L u)_v`: the curvature left at `v` by the scale factor `u`.
    pub fn curvature_at(&self, u: &[f64], v: u32) -> f64 {
        let mut lu = 0.0;
        for &(r, c, w) in &self.entries {
            if r == v && c == v {
                lu += w * u[v as usize];
            } else if r == v {
                lu += w * u[c as usize];
            } else if c == v {
                lu += w * u[r as usize];
            }
        }
        self.defect[v as usize] + lu
    }
}

/// The cotangent Laplacian of `chart` (weights ½(cot α + cot β) from clamped angles, positive
/// semi-definite): its lower triangle `(row, col, value)`, row ≥ col, sorted by column then
/// row, with every diagonal present; and each vertex's angle sum. Shared by [`ScaleSolver`]
/// and [`super::fiedler`].
///
/// The diagonal is summed per vertex in triangle order; the off-diagonal terms (three per
/// triangle, two per interior edge, whose sum does not depend on their order) are merged by
/// sorting packed `(col, row)` keys, then each column's diagonal is put before its rows (a
/// stable sort of all nine terms per triangle was 8% of the CPU time of 3holes subdivided
/// three times, 460k triangles, with `abf`).
pub(crate) fn cotan_laplacian(chart: &Chart) -> (Vec<(u32, u32, f64)>, Vec<f64>) {
    let n = chart.positions.len();
    let mut sums = vec![0.0f64; n];
    let mut diag = vec![0.0f64; n];
    let mut off: Vec<(u64, f64)> = Vec::with_capacity(3 * chart.triangles.len());
    for t in &chart.triangles {
        let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
        let a = clamped_angles(p);
        for k in 0..3 {
            sums[t[k] as usize] += a[k];
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            let w = 0.5 / a[k].tan();
            off.push((((i.min(j) as u64) << 32) | i.max(j) as u64, -w));
            diag[i as usize] += w;
            diag[j as usize] += w;
        }
    }
    off.sort_unstable_by_key(|e| e.0);
    let mut entries: Vec<(u32, u32, f64)> = Vec::with_capacity(off.len() / 2 + n);
    let mut next = 0usize;
    for (c, &d) in diag.iter().enumerate() {
        entries.push((c as u32, c as u32, d));
        while next < off.len() && (off[next].0 >> 32) as usize == c {
            let (key, w) = off[next];
            let r = key as u32;
            match entries.last_mut() {
                Some(last) if last.0 == r && last.1 == c as u32 => last.2 += w,
                _ => entries.push((r, c as u32, w)),
            }
            next += 1;
        }
    }
    (entries, sums)
}

/// The symbolic Cholesky analysis of a lower-triangle pattern over `chart`'s vertices
/// (`entries` as [`cotan_laplacian`] gives them) in the chart's shared vertex order
/// ([`Chart::vertex_order`]): the pattern, the argsort that loads values into it, and the
/// analysis. `None` when the pattern is invalid.
pub(crate) fn analyse_in_vertex_order(
    chart: &Chart,
    entries: &[(u32, u32, f64)],
) -> Option<(SymbolicSparseColMat<usize>, faer::sparse::Argsort<usize>, SymbolicCholesky<usize>)> {
    let n = chart.positions.len();
    let pairs: Vec<Pair<usize, usize>> = entries.iter().map(|e| Pair { row: e.0 as usize, col: e.1 as usize }).collect();
    let (symbolic, argsort) = SymbolicSparseColMat::try_new_from_indices(n, n, &pairs).ok()?;
    let fwd: Vec<usize> = chart.vertex_order().iter().map(|&v| v as usize).collect();
    if fwd.len() != n {
        return None;
    }
    let mut inv = vec![0usize; n];
    for (new, &old) in fwd.iter().enumerate() {
        inv[old] = new;
    }
    let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
    let llt = factorize_symbolic_cholesky(symbolic.as_ref(), Side::Lower, SymmetricOrdering::Custom(perm), Default::default()).ok()?;
    Some((symbolic, argsort, llt))
}

/// A numeric Cholesky factor on [`ScaleSolver`]'s analysis.
pub(crate) struct Factor {
    values: Vec<f64>,
}

impl Factor {
    /// Factor `mat` (lower triangle, the analysed pattern); `None` when it is not positive
    /// definite or memory runs out.
    pub(crate) fn new(symbolic: &SymbolicCholesky<usize>, mat: &SparseColMat<usize, f64>) -> Option<Factor> {
        let par = faer::get_global_parallelism();
        let mut values = Vec::new();
        values.try_reserve_exact(symbolic.len_val()).ok()?;
        values.resize(symbolic.len_val(), 0.0);
        let mut mem = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default())).ok()?;
        symbolic
            .factorize_numeric_llt(&mut values, mat.as_ref(), Side::Lower, Default::default(), par, MemStack::new(&mut mem), Default::default())
            .ok()?;
        Some(Factor { values })
    }

    /// `x ← A⁻¹ x`.
    fn solve_in_place(&self, symbolic: &SymbolicCholesky<usize>, x: &mut [f64]) {
        self.solve_columns_in_place(symbolic, x, 1);
    }

    /// `X ← A⁻¹ X` for `X` of `k` columns (column-major in `x`).
    pub(crate) fn solve_columns_in_place(&self, symbolic: &SymbolicCholesky<usize>, x: &mut [f64], k: usize) {
        let par = faer::get_global_parallelism();
        let n = x.len() / k.max(1);
        let mut mem = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(k, par));
        LltRef::new(symbolic, &self.values).solve_in_place_with_conj(faer::Conj::No, MatMut::from_column_major_slice_mut(x, n, k), par, MemStack::new(&mut mem));
    }
}

/// Where the surface is most crushed (`−u` largest) among `allowed` vertices (not held);
/// ties to the lower id.
///
/// Only crushed regions take cones: `u < 0` comes from positive curvature, and a cone there
/// opens the surface with an angle below 2π. A cone where `u > 0` would carry negative
/// curvature, an angle above 2π at the tip of its slit, and a free-boundary flattening
/// overlaps its slit's sides there; such regions are split instead.
fn peak(u: &[f64], allowed: &[bool], held: &[u32]) -> Option<(u32, f64)> {
    let mut best: Option<(u32, f64)> = None;
    for (v, &x) in u.iter().enumerate() {
        if !allowed[v] || held.contains(&(v as u32)) {
            continue;
        }
        if best.is_none_or(|b| -x > b.1) {
            best = Some((v as u32, -x));
        }
    }
    best
}

/// Place cones on `chart` (see the module docs).
///
/// * `allowed[v]`: whether vertex `v` may become a cone (boundary vertices and vertices the
///   user asked to keep free of seams are not).
/// * `min_cones`: cones placed whatever the bound (a closed sphere needs 2 to be cut).
/// * `max_cones`: most cones (at least `min_cones` are placed).
/// * `bound`: stop once `max |u| ≤ bound` (`ln(max_stretch)`).
/// * `seed`: cones that must be present (from an earlier repair round).
pub fn place_cones(
    solver: &ScaleSolver,
    allowed: &[bool],
    min_cones: usize,
    max_cones: usize,
    bound: f64,
    seed: &[u32],
) -> Cones {
    let max_cones = max_cones.max(min_cones).max(seed.len());
    let mut cones: Vec<u32> = seed.to_vec();
    let has_boundary = solver.boundary.iter().any(|&b| b);
    if cones.is_empty() && !has_boundary && max_cones > 0 {
        // A closed chart needs one held vertex for the system to be definite: the vertex of
        // largest curvature.
        let first = (0..solver.n)
            .filter(|&v| allowed[v])
            .max_by(|&a, &b| solver.defect[a].total_cmp(&solver.defect[b]).then(b.cmp(&a)))
            .or_else(|| (0..solver.n).max_by(|&a, &b| solver.defect[a].total_cmp(&solver.defect[b]).then(b.cmp(&a))));
        if let Some(v) = first {
            cones.push(v as u32);
        }
    }
    let zero = || vec![0.0; solver.n];
    let mut u = solver.solve(&cones).unwrap_or_else(zero);
    loop {
        let Some((v, m)) = peak(&u, allowed, &cones) else { break };
        if cones.len() >= max_cones || (m <= bound && cones.len() >= min_cones) {
            break;
        }
        cones.push(v);
        match solver.solve(&cones) {
            Some(x) => u = x,
            None => break,
        }
    }
    // Re-placement pass: move each cone (not the seeds) to the peak of |u| without it, keeping
    // a move only when the overall peak drops. One pass: on bunny, cow, decimated-max and
    // fertility a second pass moved no cone.
    let max_abs = |u: &[f64]| u.iter().fold(0.0f64, |m, x| m.max(-x));
    let mut best = max_abs(&u);
    for _pass in 0..1 {
        let mut moved = false;
        for i in seed.len()..cones.len() {
            if !has_boundary && cones.len() == 1 {
                // A closed chart with no cone has no scale factor (its system is singular):
                // its one cone stays where the curvature peaks.
                continue;
            }
            let mut trial = cones.clone();
            trial.remove(i);
            let Some(without) = solver.solve(&trial) else { continue };
            let Some((v, _)) = peak(&without, allowed, &trial) else { continue };
            if v == cones[i] {
                continue;
            }
            trial.insert(i, v);
            if let Some(x) = solver.solve(&trial) {
                let m = max_abs(&x);
                if m < best * (1.0 - 1e-9) {
                    best = m;
                    cones = trial;
                    u = x;
                    moved = true;
                }
            }
        }
        if !moved {
            break;
        }
    }
    let curvature = cones.iter().map(|&c| solver.curvature_at(&u, c)).collect();
    Cones { vertices: cones, curvature, max_u: max_abs(&u), u }
}

/// Solve `A x = b` in place (`a`: `k × k` row-major, symmetric positive definite; `b` becomes
/// `x`). `false` when `A` is not numerically positive definite.
fn dense_cholesky_solve(a: &mut [f64], b: &mut [f64], k: usize) -> bool {
    for j in 0..k {
        let mut d = a[j * k + j];
        for p in 0..j {
            d -= a[j * k + p] * a[j * k + p];
        }
        if !(d > 0.0) || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j * k + j] = d;
        for i in j + 1..k {
            let mut x = a[i * k + j];
            for p in 0..j {
                x -= a[i * k + p] * a[j * k + p];
            }
            a[i * k + j] = x / d;
        }
    }
    for i in 0..k {
        let mut x = b[i];
        for p in 0..i {
            x -= a[i * k + p] * b[p];
        }
        b[i] = x / a[i * k + i];
    }
    for i in (0..k).rev() {
        let mut x = b[i];
        for p in i + 1..k {
            x -= a[p * k + i] * b[p];
        }
        b[i] = x / a[i * k + i];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Laplacian assembled edge by edge in a map keyed `(col, row)`, each corner's
    /// cotangent from the dot and cross products of its sides: the reference
    /// [`cotan_laplacian`] is checked against.
    fn by_map(chart: &Chart) -> (Vec<(u32, u32, f64)>, Vec<f64>) {
        use crate::geometry::{cross, dot, norm, sub};
        let mut sums = vec![0.0f64; chart.positions.len()];
        let mut m: std::collections::BTreeMap<(u32, u32), f64> =
            (0..chart.positions.len() as u32).map(|v| ((v, v), 0.0)).collect();
        for t in &chart.triangles {
            for k in 0..3 {
                let (o, i, j) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let at = |v: u32| chart.positions[v as usize];
                let (a, b) = (sub(at(i), at(o)), sub(at(j), at(o)));
                let (c, d) = (norm(cross(a, b)), dot(a, b));
                sums[o as usize] += c.atan2(d);
                let half_cot = 0.5 * d / c;
                *m.entry((i.min(j), i.max(j))).or_insert(0.0) -= half_cot;
                for v in [i, j] {
                    *m.get_mut(&(v, v)).unwrap() += half_cot;
                }
            }
        }
        (m.into_iter().map(|((c, r), w)| (r, c, w)).collect(), sums)
    }

    #[test]
    fn the_laplacian_merged_by_sorting_is_the_one_summed_term_by_term() {
        for k in [2u32, 3, 7, 20] {
            let chart = crate::charts::bumpy_grid_chart(k);
            let (entries, sums) = cotan_laplacian(&chart);
            let (want, want_sums) = by_map(&chart);
            assert!(sums.iter().zip(&want_sums).all(|(a, b)| (a - b).abs() < 1e-12));
            assert_eq!(entries.len(), want.len(), "k = {k}");
            for (e, w) in entries.iter().zip(&want) {
                assert_eq!((e.0, e.1), (w.0, w.1), "k = {k}");
                assert!(e.0 >= e.1);
                assert!((e.2 - w.2).abs() <= 1e-12 * w.2.abs().max(1.0), "k = {k}: {e:?} against {w:?}");
            }
            // Rows sum to zero (a Laplacian), with each off-diagonal counted in both its rows.
            let mut row = vec![0.0f64; chart.positions.len()];
            for &(r, c, w) in &entries {
                row[r as usize] += w;
                if r != c {
                    row[c as usize] += w;
                }
            }
            assert!(row.iter().all(|x| x.abs() < 1e-9), "k = {k}");
        }
    }
}
