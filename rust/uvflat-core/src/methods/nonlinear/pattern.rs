//! Sparsity patterns of the 2×2-block systems of the nonlinear methods: 2n unknowns, the
//! (u, v) of every chart vertex, coupled within every triangle (a 6×6 block per triangle).
//!
//! * [`block_triplets`]: the lower-triangle entries of every triangle's block, as zero-valued
//!   triplets in [`BLOCK`] order, for [`crate::solvers::FixedValueSolver`] (SLIM, MIPS), which
//!   analyses the pattern once; a method then writes the 21 values of triangle f at
//!   `21 f .. 21 f + 21` of its value array and refactors. [`analysed_beside`] runs that
//!   analysis beside the computation of the starting map.
//! * [`BlockPattern`]: the same vertex-graph pattern in compressed columns, plus extra u–u /
//!   v–v couplings ("chords", the scaffold's edges between chart vertices), the value slot of
//!   every triangle entry, and its symbolic Cholesky analysis (approximate minimum degree).
//!
//! Unknown numbering: [`interleaved`] (`u0, v0, u1, v1, …`: local index p is corner p / 2,
//! component p % 2) or [`by_component`] (local index k is corner k % 3, component k / 3,
//! i.e. `(u0, u1, u2, v0, v1, v2)` within a triangle, interleaved globally).
//!
//! Preconditions: triangle indices below n. Failures: [`BlockPattern::new`] reports a failed
//! symbolic analysis (out of memory, index overflow).

use rayon::prelude::*;

use crate::solvers::ordering::Ordering;
use crate::solvers::{FixedValueSolver, Symmetry};

/// The `(p, q)`, `p ≥ q`, entries of a triangle's 6 × 6 block, row by row.
pub const BLOCK: [(usize, usize); 21] = {
    let mut out = [(0, 0); 21];
    let mut k = 0;
    let mut p = 0;
    while p < 6 {
        let mut q = 0;
        while q <= p {
            out[k] = (p, q);
            k += 1;
            q += 1;
        }
        p += 1;
    }
    out
};

/// Global unknown of local index `p` of triangle `t`, `(u, v)` per corner: `2 t[p/2] + p%2`.
#[inline]
pub fn interleaved(t: &[u32; 3], p: usize) -> u32 {
    2 * t[p / 2] + (p % 2) as u32
}

/// Global unknown of local index `k` of triangle `t`, corners per component:
/// `2 t[k%3] + k/3`.
#[inline]
pub fn by_component(t: &[u32; 3], k: usize) -> u32 {
    2 * t[k % 3] + (k / 3) as u32
}

/// Lower-triangle triplets `(row, column, 0.0)` of every triangle's block, 21 per triangle in
/// [`BLOCK`] order, with the local-to-global numbering `unknown`.
pub fn block_triplets(tris: &[[u32; 3]], unknown: fn(&[u32; 3], usize) -> u32) -> Vec<(u32, u32, f64)> {
    let mut out = Vec::with_capacity(tris.len() * BLOCK.len());
    for t in tris {
        for &(p, q) in &BLOCK {
            let (gp, gq) = (unknown(t, p), unknown(t, q));
            out.push((gp.max(gq), gp.min(gq), 0.0));
        }
    }
    out
}

/// Charts with at least this many triangles analyse their global step's system
/// ([`analysed_beside`]) while their starting map is computed: on camelhead (22,704
/// triangles) the pattern, ordering and symbolic factorization of SLIM's system take
/// 0.02–0.03 s, a tenth of the whole solve, and the starts leave a thread free for part of
/// their time. Smaller charts gain nothing worth a task.
///
/// Charts of [`super::start::SEQUENTIAL_STARTS_FROM`] triangles or more compute their starts
/// one after the other on one thread, and their analysis (a nested dissection) is long: 2.2–2.4
/// s of the first iteration on fertility subdivided three times and cut by automatic seams
/// (576,000 triangles). It runs beside the mean value start, after the LSCM start
/// ([`super::start::pick_staged`]), or after both when that map is not needed: beside the
/// whole start, the LSCM factorization and the analysis's triplets were alive at once, and the
/// peak rose from 1.02 to 1.33 GB on 3holes subdivided three times (460,800 triangles).
pub const ANALYSE_BESIDE_FROM: usize = 2_000;

/// The analysis ([`FixedValueSolver::analyse_with`], with `ordering`) of the symmetric
/// 2n-unknown block system over `tris` with the unknowns `fixed` held, numbered by `unknown`;
/// `None` when it fails (the method then analyses as usual and meets the failure itself).
pub fn analyse_blocks(
    n_unknowns: usize,
    tris: &[[u32; 3]],
    unknown: fn(&[u32; 3], usize) -> u32,
    fixed: &[u32],
    ordering: Ordering<'_>,
) -> Option<FixedValueSolver> {
    let triplets = block_triplets(tris, unknown);
    FixedValueSolver::analyse_with(n_unknowns, &triplets, fixed, Symmetry::Symmetric, ordering).ok()
}

/// `start()` and, for a chart of [`ANALYSE_BESIDE_FROM`] triangles up to
/// [`super::start::SEQUENTIAL_STARTS_FROM`], beside it the system's [`analyse_blocks`]. The analysis
/// runs on the calling thread, also outside rayon's pool (so that it sees this thread's
/// settings), and `start` on whichever thread of the pool is free. `None` for other charts
/// (larger ones analyse beside their mean value start, see [`ANALYSE_BESIDE_FROM`]), and when
/// the analysis fails.
pub fn analysed_beside<S: Send>(
    n_unknowns: usize,
    tris: &[[u32; 3]],
    unknown: fn(&[u32; 3], usize) -> u32,
    fixed: &[u32],
    ordering: Ordering<'_>,
    start: impl FnOnce() -> S + Send,
) -> (S, Option<FixedValueSolver>) {
    if !(ANALYSE_BESIDE_FROM..super::start::SEQUENTIAL_STARTS_FROM).contains(&tris.len()) {
        return (start(), None);
    }
    let analyse = || analyse_blocks(n_unknowns, tris, unknown, fixed, ordering);
    let (started, analysis) = super::start::next_to(start, Some(analyse));
    (started, analysis.flatten())
}

/// Vertex pairs `(a, b)`, `a > b`, of all triangle edges, sorted and unique.
pub fn chart_edges(tris: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.max(b), a.min(b)))
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Lower-triangle compressed-column pattern of a 2×2-block system over 2n interleaved
/// unknowns, with the value slot of every triangle's [`BLOCK`] entries and the symbolic
/// Cholesky analysis (see the module docs).
pub struct BlockPattern {
    /// Column pointers (2n + 1).
    pub col_ptr: Vec<usize>,
    /// Row indices, sorted within every column.
    pub row_idx: Vec<usize>,
    /// Value slot of every [`BLOCK`] entry of every triangle.
    pub chart_slots: Vec<[u32; 21]>,
    /// Symbolic analysis of the pattern, on the fill-reducing ordering of
    /// [`crate::solvers::ordering`] (AMD, nested dissection for large charts).
    pub symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
}

impl BlockPattern {
    /// Pattern of the triangles (`edges`: their vertex pairs `(a, b)`, `a > b`, sorted, see
    /// [`chart_edges`]) plus the u–u and v–v entries of `chords`, and its symbolic analysis.
    pub fn new(n: usize, tris: &[[u32; 3]], edges: &[(u32, u32)], chords: &[(u32, u32)]) -> Result<BlockPattern, String> {
        let n2 = 2 * n;
        // Entries per column: the 2 × 2 diagonal block of every vertex (3 lower entries), the
        // full 2 × 2 block of every edge (u and v couple through a triangle's weights), and the
        // u–u and v–v entries of every chord.
        let mut count = vec![0usize; n2 + 1];
        for v in 0..n {
            count[2 * v] += 2;
            count[2 * v + 1] += 1;
        }
        for &(_, b) in edges {
            count[2 * b as usize] += 2;
            count[2 * b as usize + 1] += 2;
        }
        for &(_, b) in chords {
            count[2 * b as usize] += 1;
            count[2 * b as usize + 1] += 1;
        }
        let mut col_ptr = vec![0usize; n2 + 1];
        for c in 0..n2 {
            col_ptr[c + 1] = col_ptr[c] + count[c];
        }
        let mut row_idx = vec![0usize; col_ptr[n2]];
        let mut fill = col_ptr[..n2].to_vec();
        let mut put = |r: usize, c: usize| {
            row_idx[fill[c]] = r;
            fill[c] += 1;
        };
        for v in 0..n {
            put(2 * v, 2 * v);
            put(2 * v + 1, 2 * v);
            put(2 * v + 1, 2 * v + 1);
        }
        for &(a, b) in edges {
            let (a, b) = (a as usize, b as usize);
            for s in 0..2 {
                for s2 in 0..2 {
                    put(2 * a + s, 2 * b + s2);
                }
            }
        }
        for &(a, b) in chords {
            let (a, b) = (a as usize, b as usize);
            put(2 * a, 2 * b);
            put(2 * a + 1, 2 * b + 1);
        }
        for c in 0..n2 {
            row_idx[col_ptr[c]..col_ptr[c + 1]].sort_unstable();
        }
        let sym = faer::sparse::SymbolicSparseColMatRef::new_checked(n2, n2, &col_ptr, None, &row_idx);
        let perm = crate::solvers::ordering::fill_reducing(crate::solvers::ordering::OrderingKind::Auto, n2, &col_ptr, &row_idx)
            .map_err(|e| format!("ordering failed: {e:?}"))?;
        let perm_ref = faer::perm::PermRef::new_checked(&perm.fwd, &perm.inv, n2);
        let symbolic = faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(
            sym,
            faer::Side::Lower,
            faer::sparse::linalg::cholesky::SymmetricOrdering::Custom(perm_ref),
            crate::solvers::ordering::symbolic_params(&perm),
        )
        .map_err(|e| format!("symbolic analysis failed: {e:?}"))?;
        let mut pattern = BlockPattern { col_ptr, row_idx, chart_slots: Vec::new(), symbolic };
        let slots: Option<Vec<[u32; 21]>> = tris
            .par_iter()
            .with_min_len(2048)
            .map(|t| {
                let mut out = [0u32; 21];
                for (k, &(p, q)) in BLOCK.iter().enumerate() {
                    let (gp, gq) = (interleaved(t, p) as usize, interleaved(t, q) as usize);
                    out[k] = pattern.slot(gp.max(gq), gp.min(gq))? as u32;
                }
                Some(out)
            })
            .collect();
        pattern.chart_slots = slots.ok_or("a chart entry is missing from the pattern")?;
        Ok(pattern)
    }

    /// Value slot of the lower entry `(r, c)`, `r ≥ c`, if it is in the pattern.
    #[inline]
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        let (lo, hi) = (self.col_ptr[c], self.col_ptr[c + 1]);
        self.row_idx[lo..hi].binary_search(&r).ok().map(|k| lo + k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_block_entry_has_a_slot_and_chords_only_couple_like_components() {
        let tris = [[0u32, 1, 2], [0, 2, 3]];
        let edges = chart_edges(&tris);
        assert_eq!(edges, vec![(1, 0), (2, 0), (2, 1), (3, 0), (3, 2)]);
        let pat = BlockPattern::new(4, &tris, &edges, &[(3, 1)]).unwrap();
        let trip = block_triplets(&tris, interleaved);
        assert_eq!(trip.len(), 42);
        for (f, t) in tris.iter().enumerate() {
            for (k, &(p, q)) in BLOCK.iter().enumerate() {
                let (r, c, _) = trip[21 * f + k];
                assert!(r >= c);
                assert_eq!(pat.slot(r as usize, c as usize), Some(pat.chart_slots[f][k] as usize));
                assert_eq!((r, c), (interleaved(t, p).max(interleaved(t, q)), interleaved(t, p).min(interleaved(t, q))));
            }
        }
        assert!(pat.slot(6, 2).is_some() && pat.slot(7, 3).is_some());
        assert!(pat.slot(7, 2).is_none() && pat.slot(6, 3).is_none());
        // Both numberings cover the same global entries of a triangle.
        let mut a: Vec<_> = block_triplets(&tris[..1], interleaved);
        let mut b: Vec<_> = block_triplets(&tris[..1], by_component);
        let key = |x: &(u32, u32, f64)| (x.0, x.1);
        a.sort_by_key(key);
        b.sort_by_key(key);
        assert_eq!(a, b);
    }
}
