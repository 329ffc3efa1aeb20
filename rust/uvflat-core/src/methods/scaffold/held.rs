//! Pinned vertices as fixed values of the scaffold's global step, on the step's own pattern.
//!
//! The global step solves `A x = b` for the positions of all chart vertices. A held unknown
//! `i` at value `x_i` is eliminated in place: its column's contributions move to the right-hand
//! side (`b_j −= A_ji x_i` for every free `j`), its off-diagonal entries become 0, and its
//! diagonal entry becomes the mean diagonal of the free unknowns (with `b_i` set so that the
//! solution is `x_i`). The free unknowns then solve exactly the constrained problem, the
//! pattern (hence the symbolic analysis) is unchanged, and the matrix stays positive definite
//! wherever it was on the free unknowns. [`restore`] writes the held values back bit for bit
//! after the solve, so the step moves no held vertex.
//!
//! Preconditions: `held` and `values`/`b` over the pattern's 2n unknowns; `uv` the current map
//! (the held vertices at their pinned UVs). Failures: none.

use crate::methods::nonlinear::pattern::BlockPattern;

/// Eliminate the `held` unknowns (true per unknown) at their values in `uv` from the lower
/// compressed-column system `values`, `b` of `pat` (module docs). No-op when nothing is held.
pub(super) fn eliminate(pat: &BlockPattern, values: &mut [f64], b: &mut [f64], held: &[bool], uv: &[[f64; 2]]) {
    if !held.iter().any(|&h| h) {
        return;
    }
    let n2 = pat.col_ptr.len() - 1;
    let value_of = |i: usize| uv[i / 2][i % 2];
    let (mut sum, mut count) = (0.0, 0usize);
    for c in (0..n2).filter(|&c| !held[c]) {
        if let Some(k) = pat.slot(c, c) {
            sum += values[k].abs();
            count += 1;
        }
    }
    let diag = if count > 0 && sum > 0.0 && sum.is_finite() { sum / count as f64 } else { 1.0 };
    for c in 0..n2 {
        for k in pat.col_ptr[c]..pat.col_ptr[c + 1] {
            let r = pat.row_idx[k];
            if r == c {
                if held[c] {
                    values[k] = diag;
                    b[c] = diag * value_of(c);
                }
                continue;
            }
            match (held[r], held[c]) {
                (false, false) => {}
                (true, true) => values[k] = 0.0,
                (false, true) => {
                    b[r] -= values[k] * value_of(c);
                    values[k] = 0.0;
                }
                (true, false) => {
                    b[c] -= values[k] * value_of(r);
                    values[k] = 0.0;
                }
            }
        }
    }
}

/// Write the held unknowns' values back into the step's solution `x` (bit for bit).
pub(super) fn restore(x: &mut [f64], held: &[bool], uv: &[[f64; 2]]) {
    for (i, _) in held.iter().enumerate().filter(|(_, &h)| h) {
        x[i] = uv[i / 2][i % 2];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::nonlinear::pattern::chart_edges;

    /// A path Laplacian over four vertices with vertex 1 held: the free unknowns solve the
    /// constrained problem, the held ones keep their values.
    #[test]
    fn held_unknowns_keep_their_values_and_the_rest_solve_the_constrained_problem() {
        let tris = vec![[0u32, 1, 2], [1, 3, 2]];
        let edges = chart_edges(&tris);
        let pat = BlockPattern::new(4, &tris, &edges, &[]).unwrap();
        let mut values = vec![0.0; pat.row_idx.len()];
        for &(a, b) in &edges {
            for s in 0..2 {
                let (ia, ib) = (2 * a as usize + s, 2 * b as usize + s);
                values[pat.slot(ia, ia).unwrap()] += 1.0;
                values[pat.slot(ib, ib).unwrap()] += 1.0;
                values[pat.slot(ia.max(ib), ia.min(ib)).unwrap()] -= 1.0;
            }
        }
        // Vertex 0 also tied to the origin (so the free system is definite).
        for s in 0..2 {
            values[pat.slot(s, s).unwrap()] += 1.0;
        }
        let uv = vec![[0.0, 0.0], [0.3, -0.7], [0.0, 0.0], [0.0, 0.0]];
        let held: Vec<bool> = (0..8).map(|i| i / 2 == 1).collect();
        let mut b = vec![0.0; 8];
        eliminate(&pat, &mut values, &mut b, &held, &uv);
        // Dense solve of the eliminated system.
        let mut a = vec![vec![0.0; 8]; 8];
        for c in 0..8 {
            for k in pat.col_ptr[c]..pat.col_ptr[c + 1] {
                let r = pat.row_idx[k];
                a[r][c] = values[k];
                a[c][r] = values[k];
            }
        }
        let mut x = b.clone();
        for i in 0..8 {
            let p = a[i][i];
            assert!(p > 0.0);
            for j in i + 1..8 {
                let f = a[j][i] / p;
                for k in i..8 {
                    a[j][k] -= f * a[i][k];
                }
                x[j] -= f * x[i];
            }
        }
        for i in (0..8).rev() {
            let s: f64 = (i + 1..8).map(|k| a[i][k] * x[k]).sum();
            x[i] = (x[i] - s) / a[i][i];
        }
        restore(&mut x, &held, &uv);
        assert_eq!([x[2], x[3]], uv[1]);
        // Vertex 3 touches only 1 and 2, vertex 2 touches 0, 1, 3, vertex 0 touches 1, 2 and the
        // origin: each free vertex is the mean of its neighbours (and the origin for vertex 0).
        for s in 0..2 {
            let (x0, x1, x2, x3) = (x[s], x[2 + s], x[4 + s], x[6 + s]);
            assert!((3.0 * x0 - x1 - x2).abs() < 1e-12);
            assert!((3.0 * x2 - x0 - x1 - x3).abs() < 1e-12);
            assert!((2.0 * x3 - x1 - x2).abs() < 1e-12);
        }
    }
}
