//! The Newton–Lagrange iteration of ABF and ABF++ (an SQP iteration; for the convex boundary
//! a primal-dual interior-point iteration on the same system): steps by the reduced system
//! (ABF++) or the full KKT system (plain ABF), chord steps reusing the last factorisation
//! while they contract, and the update of angles, multipliers and slacks.
//!
//! Preconditions: a problem and a state of positive angles. Failures: a system that cannot be
//! factored (singular, or for ABF++ not positive definite even with the diagonal shifts of
//! [`Reduced::factor`]); non-convergence is reported by the run, not as an error.

use super::*;

/// The Newton step of one triangle: its angle updates and its triangle multiplier update.
#[derive(Clone, Copy, Default)]
pub(super) struct FaceStep {
    pub(super) da: [f64; 3],
    pub(super) dt: f64,
}

/// The Newton step: per triangle, and the vertex multiplier updates per row.
pub(super) type Step = (Vec<FaceStep>, Vec<f64>);

/// How a Newton step solves its linear system.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Mode {
    /// Factor the current matrix.
    Factor,
    /// A chord step: the Newton system of the last factorization (its matrix, and its
    /// Jacobian and Hessian in the elimination) with the current residuals.
    Chord,
}

/// The linear algebra of one Newton step, keeping its factorization pattern across steps.
pub(super) enum Linear {
    PlusPlus(Box<PlusPlus>),
    Plain(Box<Option<FixedValueSolver>>),
}

impl Linear {
    /// The linear algebra of `solver` for a chart of `nf` triangles.
    pub(super) fn new(solver: AbfSolver, nf: usize) -> Self {
        match solver {
            AbfSolver::AbfPlusPlus => Linear::PlusPlus(Box::new(PlusPlus { lean: nf >= LEAN_EVAL_FACES, ..Default::default() })),
            AbfSolver::Plain => Linear::Plain(Box::new(None)),
        }
    }

    /// After a step that refactored, taken from the state `e` evaluates: keep `e`'s
    /// Jacobian for chord steps (ABF++; stored only once the step is taken and freed, which
    /// keeps it out of the step's peak memory).
    pub(super) fn keep_jacobian(&mut self, e: &Eval) {
        if let Linear::PlusPlus(w) = self {
            w.jac = Vec::with_capacity(e.faces.len());
            w.jac.extend(e.faces.iter().map(|fe| (fe.cot, fe.hess)));
        }
    }

    /// The step at `e`, the evaluation of `s` (ABF++ frees and recomputes it around a
    /// factorization: [`PlusPlus`]); after a refactoring step, [`Linear::keep_jacobian`].
    pub(super) fn step(&mut self, p: &Problem<'_>, s: &State, e: &mut Eval, mode: Mode) -> Result<Step, SolveError> {
        match self {
            Linear::PlusPlus(w) => step_plus_plus(w, p, s, e, mode),
            Linear::Plain(slot) => step_plain(slot, p, e, mode),
        }
    }
}

/// ABF++ linear algebra state kept across Newton steps: the factorization and the Jacobian
/// it was computed with.
///
/// Memory: the factor is the largest allocation of the solve and stays for chord steps, so
/// what only one step needs is allocated per step and freed as early as possible: the
/// factorization's workspace after it ([`Reduced::factor`]); the
/// per-triangle elimination terms are recomputed where used. The Jacobian of the previous
/// factorization is freed before the next one and stored once the step is taken. The matrix
/// values stay with the factor: its solves refine a single-precision factor against them
/// ([`crate::solvers::refined_llt`], half the factor's memory from its size on).
/// On charts of at least [`LEAN_EVAL_FACES`] triangles the per-triangle evaluation is also
/// freed while the matrix is factored and recomputed from the state after (bit for bit the
/// same; one more evaluation per factorization: 3 % more time at 90k triangles, within the
/// noise at 1M, where it is 80 MB less peak memory).
///
/// [`LEAN_EVAL_FACES`]: LEAN_EVAL_FACES
#[derive(Default)]
pub(super) struct PlusPlus {
    pub(super) reduced: Option<Reduced>,
    /// Per triangle, the cotangents and Hessian of the last factorization (chord steps).
    pub(super) jac: Vec<([f64; 3], [f64; 3])>,
    /// Free the evaluation while factoring (charts of [`LEAN_EVAL_FACES`] triangles or more).
    pub(super) lean: bool,
    /// Factorizations that needed a diagonal shift ([`Reduced::factor`]), and the largest
    /// relative shift used.
    pub(super) shifted: usize,
    pub(super) largest_shift: f64,
}

/// Charts of at least this many triangles free their per-triangle evaluation while the
/// reduced matrix is factored ([`PlusPlus`]).
pub(super) const LEAN_EVAL_FACES: usize = 200_000;

/// ABF++: eliminate dα and dλ_tri per triangle, solve the reduced vertex system.
pub(super) fn step_plus_plus(w: &mut PlusPlus, p: &Problem<'_>, s: &State, e: &mut Eval, mode: Mode) -> Result<Step, SolveError> {
    let refresh = mode == Mode::Factor;
    let nf = p.tris.len();
    let m = p.m();
    let mut rhs = e.c_newton.clone();
    // Reduced matrix values on the pattern (refactoring steps only).
    let mut vals = Vec::new();
    if refresh {
        // This step's Jacobian is `e`'s, kept once the step is taken ([`Linear::keep_jacobian`]).
        w.jac = Vec::new();
        vals.resize(p.row_idx.len(), 0.0);
        for (r, &d) in e.diag.iter().enumerate() {
            if d != 0.0 {
                vals[p.diagonal_slot(r)] += d;
            }
        }
    }
    let jac_of = |e: &Eval, f: usize| if mode == Mode::Chord { w.jac[f] } else { (e.faces[f].cot, e.faces[f].hess) };
    for f in 0..nf {
        let fe = &e.faces[f];
        let (cot, hess) = jac_of(e, f);
        let (li, lb, di, rr) = eliminate(fe, &hess);
        let fr = p.face_rows(f);
        let len = fr.len as usize;
        let mut g = [[0.0; 3]; MAX_FACE_ROWS];
        let mut u = [[0.0; 3]; MAX_FACE_ROWS];
        let mut sj = [0.0; MAX_FACE_ROWS];
        for j in 0..len {
            let (r, wheel, k) = fr.rows[j];
            g[j] = row_grad(wheel, k as usize, &cot);
            u[j] = [li[0] * g[j][0], li[1] * g[j][1], li[2] * g[j][2]];
            sj[j] = u[j][0] + u[j][1] + u[j][2];
            rhs[r as usize] -= g[j][0] * lb[0] + g[j][1] * lb[1] + g[j][2] * lb[2] + sj[j] * rr * di;
        }
        if refresh {
            let slots = &p.slots[p.slot_start[f] as usize..p.slot_start[f + 1] as usize];
            let mut q = 0;
            for i in 0..len {
                for j in 0..=i {
                    vals[p.slot(fr.rows[i].0, fr.rows[j].0, slots[q])] += g[i][0] * u[j][0] + g[i][1] * u[j][1] + g[i][2] * u[j][2] - sj[i] * sj[j] * di;
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
        let shift = if refresh && w.lean {
            // Not needed while the matrix is factored: evaluated again after.
            e.faces = Vec::new();
            let factored = red.factor(p, vals);
            evaluate_into(p, s, e);
            factored?
        } else if refresh {
            red.factor(p, vals)?
        } else {
            0.0
        };
        if shift > 0.0 {
            w.shifted += 1;
            w.largest_shift = w.largest_shift.max(shift);
        }
        red.solve(p, &mut rhs)?;
        rhs
    } else {
        Vec::new()
    };
    let e: &Eval = e;
    let mut steps = vec![FaceStep::default(); nf];
    for_faces(&mut steps, |f, st| {
        let fe = &e.faces[f];
        let (cot, hess) = jac_of(e, f);
        let fr = p.face_rows(f);
        let mut jt = [0.0; 3]; // J₂ᵀ dλ on this triangle
        for &(r, wheel, k) in &fr.rows[..fr.len as usize] {
            let g = row_grad(wheel, k as usize, &cot);
            let x = dl[r as usize];
            for q in 0..3 {
                jt[q] += g[q] * x;
            }
        }
        let (li, _, di, rr) = eliminate(fe, &hess);
        let ej = li[0] * jt[0] + li[1] * jt[1] + li[2] * jt[2];
        let dtf = (rr - ej) * di;
        st.dt = dtf;
        for q in 0..3 {
            st.da[q] = -li[q] * (fe.grad[q] + dtf + jt[q]);
        }
    });
    Ok((steps, dl))
}

/// One triangle's elimination terms for its Hessian `hess`: `Λ⁻¹` (per corner), `Λ⁻¹∇α L`,
/// `1 / 1ᵀΛ⁻¹1` and `C_tri − 1ᵀΛ⁻¹∇α L`. Computed where used (assembly and back-substitution,
/// the same arithmetic), not stored.
#[inline]
fn eliminate(fe: &FaceEval, hess: &[f64; 3]) -> ([f64; 3], [f64; 3], f64, f64) {
    let li = [1.0 / hess[0], 1.0 / hess[1], 1.0 / hess[2]];
    let lb = [li[0] * fe.grad[0], li[1] * fe.grad[1], li[2] * fe.grad[2]];
    let dinv = 1.0 / (li[0] + li[1] + li[2]);
    let rr = fe.c_tri - (lb[0] + lb[1] + lb[2]);
    (li, lb, dinv, rr)
}

/// Plain ABF: the full KKT system by sparse LU.
pub(super) fn step_plain(slot: &mut Option<FixedValueSolver>, p: &Problem<'_>, e: &Eval, mode: Mode) -> Result<Step, SolveError> {
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
        let fr = p.face_rows(f);
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
pub(super) struct Run {
    pub(super) iterations: usize,
    pub(super) factorizations: usize,
    pub(super) converged: bool,
    pub(super) residual: f64,
    pub(super) stationarity: f64,
    /// Factorizations regularised by a diagonal shift, and the largest relative shift.
    pub(super) shifted: usize,
    pub(super) largest_shift: f64,
}

pub(super) fn newton(p: &Problem<'_>, s: &mut State, opts: &AbfOptions) -> Result<Run, SolveError> {
    let stat_tol = opts.tolerance.sqrt();
    let mut lin = Linear::new(opts.solver, p.tris.len());
    let mut it = 0;
    let mut factorizations = 0;
    let mut refactor_next = false;
    let mut e = evaluate(p, s);
    loop {
        let (shifted, largest_shift) = match &lin {
            Linear::PlusPlus(w) => (w.shifted, w.largest_shift),
            Linear::Plain(_) => (0, 0.0),
        };
        let run = |converged| Run { iterations: it, factorizations, converged, residual: e.residual, stationarity: e.stationarity, shifted, largest_shift };
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
            let step = lin.step(p, s, &mut e, Mode::Chord)?;
            let mut trial = s.clone();
            apply_step(p, &mut trial, &step, &e, opts.tolerance);
            drop(step);
            // One evaluation alive at a time: the trial's replaces the current one, which is
            // evaluated again if the chord step is rejected.
            let (residual, stationarity) = (e.residual, e.stationarity);
            evaluate_into(p, &trial, &mut e);
            let et = &e;
            let cut = |new: f64, old: f64, tol: f64| new <= CHORD_CONTRACTION * old || new < tol;
            if cut(et.residual, residual, opts.tolerance) && cut(et.stationarity, stationarity, stat_tol) {
                // Chord steps converge linearly: when this rate needs more than
                // CHORD_MAX_PREDICTED more of them, refactor next instead.
                let needed = |new: f64, old: f64, tol: f64| {
                    if new < tol {
                        0.0
                    } else {
                        (tol / new).ln() / (new / old).ln()
                    }
                };
                let more = needed(et.residual, residual, opts.tolerance).max(needed(et.stationarity, stationarity, stat_tol));
                refactor_next = more > CHORD_MAX_PREDICTED;
                *s = trial;
                it += 1;
                continue;
            }
            drop(trial);
            evaluate_into(p, s, &mut e);
        }
        let step = lin.step(p, s, &mut e, Mode::Factor)?;
        factorizations += 1;
        refactor_next = false;
        apply_step(p, s, &step, &e, opts.tolerance);
        drop(step);
        lin.keep_jacobian(&e);
        evaluate_into(p, s, &mut e);
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
pub(super) fn apply_step(p: &Problem<'_>, s: &mut State, (steps, dl): &Step, e: &Eval, tolerance: f64) {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 6 × 6 grid of vertices on a bumpy surface's angles: 16 interior vertices.
    fn grid_problem(tris: &[[u32; 3]]) -> (Vec<f64>, Vec<bool>) {
        let n = 6u32;
        let interior: Vec<bool> = (0..n * n).map(|v| (1..n - 1).contains(&(v / n)) && (1..n - 1).contains(&(v % n))).collect();
        let beta = tris.iter().enumerate().flat_map(|(f, _)| {
            let w = 0.08 * ((f as f64) * 0.7).sin();
            [PI / 4.0 + w, PI / 2.0 - w, PI / 4.0]
        });
        (beta.collect(), interior)
    }

    /// Freeing the evaluation while factoring and recomputing it gives the same steps, bit for
    /// bit, through factorizations and chord steps.
    #[test]
    fn lean_steps_equal_the_kept_evaluation_steps() {
        let tris = super::super::problem::grid_triangles(6);
        let (beta, interior) = grid_problem(&tris);
        let nv = interior.len();
        let sum_target: Vec<Option<f64>> = interior.iter().map(|&i| i.then_some(2.0 * PI)).collect();
        let p = Problem::new(&tris, beta.clone(), &interior, &sum_target, &vec![false; nv]);
        let state = || State {
            alpha: beta.clone(),
            lam_tri: vec![0.0; tris.len()],
            lam_sum: vec![0.0; nv],
            lam_wheel: vec![0.0; nv],
            slack: vec![0.0; nv],
            mu: 0.0,
            z_lo: Vec::new(),
        };
        let mut runs = Vec::new();
        for lean in [false, true] {
            let mut w = PlusPlus { lean, ..Default::default() };
            let mut s = state();
            let mut e = evaluate(&p, &s);
            let mut bits = Vec::new();
            for mode in [Mode::Factor, Mode::Chord, Mode::Factor, Mode::Chord] {
                let (steps, dl) = step_plus_plus(&mut w, &p, &s, &mut e, mode).expect("step");
                bits.extend(steps.iter().flat_map(|st| st.da.iter().chain([&st.dt]).map(|x| x.to_bits())));
                bits.extend(dl.iter().map(|x| x.to_bits()));
                bits.extend(e.faces.iter().flat_map(|fe| fe.grad.iter().chain(&fe.hess).map(|x| x.to_bits())));
                apply_step(&p, &mut s, &(steps, dl), &e, 1e-9);
                if mode == Mode::Factor {
                    w.jac = e.faces.iter().map(|fe| (fe.cot, fe.hess)).collect();
                }
                evaluate_into(&p, &s, &mut e);
            }
            assert!(e.residual < 1e-6, "the steps converge (residual {:.3e})", e.residual);
            runs.push(bits);
        }
        assert_eq!(runs[0], runs[1]);
    }
}
