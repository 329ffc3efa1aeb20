//! The solve of the scaffold's global step, regularised by a proximal diagonal shift when
//! round-off makes the positive semi-definite matrix fail Cholesky.
//!
//! Preconditions: `values` in the slots of the pattern, `b` and `uv` over its 2n unknowns.
//! Failures: the factorisation's message when every shift of [`SHIFTS`] fails.

use std::time::Instant;

use crate::methods::nonlinear::pattern::BlockPattern;
use crate::solvers::refined_llt::{self, RefinedLlt};

/// A regularised global step: its solution, the relative shift used (0 when none was needed)
/// and the seconds of its solve (the rest of the call is the factorization).
pub(super) struct Step {
    pub(super) x: Vec<f64>,
    pub(super) shift: f64,
    pub(super) solve_seconds: f64,
}

/// Relative diagonal shifts tried, in order, when the global step's matrix does not factor.
const SHIFTS: [f64; 6] = [0.0, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4];

/// The global step `A x = b` by Cholesky, regularised when it fails: the matrix is symmetric
/// positive semi-definite in exact arithmetic, but on large charts with many holes and
/// near-degenerate triangles round-off can make a pivot non-positive. Then a proximal term
/// δ ‖x − x_k‖² is added (δ on the diagonal, δ x_k on the right-hand side, x_k the current
/// map), with δ = shift × the mean diagonal entry, for the shifts of [`SHIFTS`] in turn; the
/// step still lowers the proxy energy, only more cautiously. `values` and `b` keep the shift
/// that worked. Large systems are factored in single precision and refined
/// ([`crate::solvers::refined_llt`]); its fallback to double precision happens during the
/// solve, so a shift is tried whenever either the factorization or the solve fails.
///
/// Errors: the solver's message when every shift fails.
pub(super) fn solve_regularised(pat: &BlockPattern, values: &mut [f64], b: &mut [f64], uv: &[[f64; 2]]) -> Result<Step, String> {
    let n2 = pat.col_ptr.len() - 1;
    let diag: Vec<usize> = (0..n2).map(|i| pat.slot(i, i).expect("every diagonal entry is in the pattern")).collect();
    let mean = diag.iter().map(|&k| values[k].abs()).sum::<f64>() / n2.max(1) as f64;
    let mean = if mean > 0.0 && mean.is_finite() { mean } else { 1.0 };
    let par = faer::get_global_parallelism();
    let mut mem = faer::dyn_stack::MemBuffer::try_new(RefinedLlt::<f64>::scratch(&pat.symbolic, par, 1)).map_err(|e| format!("{e:?}"))?;
    let mut applied = 0.0;
    let mut last = String::new();
    for &shift in &SHIFTS {
        let delta = (shift - applied) * mean;
        if delta > 0.0 {
            for (i, &k) in diag.iter().enumerate() {
                values[k] += delta;
                b[i] += delta * uv[i / 2][i % 2];
            }
            applied = shift;
        }
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n2, n2, &pat.col_ptr, None, &pat.row_idx);
        let mat = faer::sparse::SparseColMatRef::new(sym, &*values);
        let mut factor = RefinedLlt::new(refined_llt::single_pays(n2));
        if let Err(e) = factor.factor(&pat.symbolic, mat, faer::Side::Lower, par, faer::dyn_stack::MemStack::new(&mut mem)) {
            last = e.to_string();
            continue;
        }
        let t = Instant::now();
        let mut x = b.to_vec();
        let rhs = faer::MatMut::from_column_major_slice_mut(&mut x, n2, 1);
        match factor.solve_in_place(&pat.symbolic, mat, faer::Side::Lower, rhs, par, faer::dyn_stack::MemStack::new(&mut mem)) {
            Ok(()) => return Ok(Step { x, shift, solve_seconds: t.elapsed().as_secs_f64() }),
            Err(e) => last = e.to_string(),
        }
    }
    Err(format!("{last}, even with the diagonal shifted by {:.0e} of its mean", SHIFTS[SHIFTS.len() - 1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::nonlinear::pattern::chart_edges;

    #[test]
    fn a_global_step_that_does_not_factor_is_regularised() {
        // Two triangles; the matrix of the translation-invariant Laplacian alone (no fixed
        // box point) is singular, and with one diagonal entry nudged below zero indefinite.
        let tris = vec![[0u32, 1, 2], [0, 2, 3]];
        let edges = chart_edges(&tris);
        let pat = BlockPattern::new(4, &tris, &edges, &[]).unwrap();
        let uv = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let mut values = vec![0.0; pat.row_idx.len()];
        for &(a, b) in &edges {
            for s in 0..2 {
                let (ia, ib) = (2 * a as usize + s, 2 * b as usize + s);
                values[pat.slot(ia, ia).unwrap()] += 1.0;
                values[pat.slot(ib, ib).unwrap()] += 1.0;
                values[pat.slot(ia, ib).unwrap()] -= 1.0;
            }
        }
        values[pat.slot(0, 0).unwrap()] -= 1e-9;
        let mut b = vec![0.0; 8];
        let before = values.clone();
        let step = solve_regularised(&pat, &mut values, &mut b, &uv).unwrap();
        let shift = step.shift;
        assert!(shift > 0.0 && shift <= 1e-6, "shift {shift}");
        // The shift is a proximal term: the step from the current map solves (A + δI) x = δ x_k,
        // and with b = 0 the current map (a translation-free fit) stays close.
        let x = step.x;
        assert!((0..8).all(|i| x[i].is_finite()));
        let diag_shift = values[pat.slot(3, 3).unwrap()] - before[pat.slot(3, 3).unwrap()];
        assert!(diag_shift > 0.0);
        assert!(b[6] == 0.0 && (b[7] - diag_shift * uv[3][1]).abs() < 1e-3 * diag_shift, "{b:?} {diag_shift}");
    }
}
