//! ABF++'s reduced system (Sheffer et al. 2005): with the diagonal angle Hessian and the
//! triangle-sum rows eliminated, the Newton system reduces to one symmetric matrix over the
//! vertex rows, whose pattern is fixed by the chart and analysed once (fill-reducing vertex
//! ordering, symbolic Cholesky), then refactored numerically at every Newton step.
//!
//! Preconditions: the problem's rows and face rows. Failures: a reduced matrix that is not
//! positive definite even with its diagonal shifted ([`Reduced::factor`]), reported by the
//! factorisation.

use super::*;
use crate::solvers::refined_llt::{self, RefinedLlt};

/// The unique entries (row ≤ column) of `Σ_f (rows of f) × (rows of f)` by columns, built
/// once per constraint set, and for every triangle the entries its pairs of rows sum into, so
/// that every Newton step sums straight into a fixed value array (count, fill, sort and
/// deduplicate each column, then look every pair up).
///
/// An entry is stored as its offset in its column, one byte ([`SLOT_SEARCH`] for an offset of
/// 255 or more, around vertices of valence above ~120, which [`Problem::slot`] finds by binary
/// search): a quarter of the memory of a 32-bit position (84 MB at 1M triangles).
pub(super) fn reduced_pattern(m: usize, nf: usize, face_rows: impl Fn(usize) -> FaceRows) -> (Vec<u32>, Vec<u32>, Vec<u8>, Vec<u32>) {
    let mut count = vec![0usize; m + 1];
    for fr in (0..nf).map(&face_rows) {
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
    for fr in (0..nf).map(&face_rows) {
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
    let mut col_ptr = vec![0u32; m + 1];
    let mut row_idx: Vec<u32> = Vec::with_capacity(count[m] / 2);
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
        row_idx.extend_from_slice(&seg[..k]);
        col_ptr[r + 1] = row_idx.len() as u32;
    }
    let mut slots = Vec::with_capacity(count[m]);
    let mut slot_start = Vec::with_capacity(nf + 1);
    for fr in (0..nf).map(&face_rows) {
        slot_start.push(slots.len() as u32);
        for i in 0..fr.len as usize {
            for j in 0..=i {
                let (a, b) = (fr.rows[i].0, fr.rows[j].0);
                let (r, c) = (a.max(b) as usize, a.min(b) as usize);
                let seg = &row_idx[col_ptr[r] as usize..col_ptr[r + 1] as usize];
                let pos = seg.binary_search(&(c as u32)).expect("entry in pattern");
                slots.push(if pos < SLOT_SEARCH as usize { pos as u8 } else { SLOT_SEARCH });
            }
        }
    }
    slot_start.push(slots.len() as u32);
    (col_ptr, row_idx, slots, slot_start)
}

/// Offset stored in [`Problem::slots`] for an entry whose offset in its column does not fit
/// below it: the entry is then found by binary search.
pub(super) const SLOT_SEARCH: u8 = u8::MAX;

/// Relative margin of the projected-Hessian test in [`evaluate`].
pub(super) const PROJECTED_HESSIAN_MARGIN: f64 = 0.1;


/// Most rows of the reduced system (about one triangle each): its indices, and those of its
/// factor (about 130 entries per row on large charts, growing slowly), are 32-bit.
pub(super) const MAX_ROWS: usize = 8_000_000;

/// Sparse Cholesky of the reduced ABF++ matrix on its fixed pattern: the symbolic analysis
/// (with a fill-reducing ordering of the vertices, expanded to their constraint rows) once,
/// then numeric factorizations straight from the pattern's value array, reusing all buffers.
pub(super) struct Reduced {
    pub(super) symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<u32>,
    /// The factor: single precision refined to double from [`refined_llt::MIXED_MIN`] rows
    /// (half the factor's memory, the largest allocation of the solve), double below.
    pub(super) factor: RefinedLlt<f64>,
    /// The values of the factored matrix, kept for the refinement of its solves (chord steps
    /// included); about a tenth of the factor's size.
    pub(super) values: Vec<f64>,
    /// Workspace of the solves (small); the factorization's own (about 100 bytes per row on
    /// large charts) is allocated by [`Reduced::factor`] and freed when it returns, so that it
    /// is not kept beside the factor through the rest of the step.
    pub(super) mem: faer::dyn_stack::MemBuffer,
}

/// Relative diagonal shifts tried in turn when the reduced matrix does not factor
/// ([`Reduced::factor`]).
pub(super) const SHIFTS: [f64; 7] = [0.0, 1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2];

/// Accuracy of a Newton step's solve of the reduced system: its residual at most this share
/// of the right-hand side, an inexact Newton step (Dembo, Eisenstat, Steihaug, "Inexact Newton
/// methods", SIAM J. Numer. Anal. 19(2), 1982; as SLIM's, `crate::methods::slim::INEXACT`).
/// A single-precision factor ([`refined_llt`], large charts) reaches it by conjugate gradients
/// it preconditions, in one step as a rule ([`RefinedLlt::solve_inexact`]), where refinement to
/// round-off took three (two triangular solves and a product with the matrix each); a
/// double-precision factor solves directly, as before. On camelhead subdivided twice (one
/// chart of 363,264 triangles, 363,042 rows) each solve took 0.08 s instead of 0.20–0.22 s, the
/// angle solve 3.30 s instead of 4.00 s, with the same 5 iterations and 3 factorizations to the
/// same residual (2.16e-6) and the same map to its conformal distortion (1.0060).
pub(super) const STEP_ACCURACY: f64 = 1e-4;

/// Sequential: faer's supernodal Cholesky is left-looking and parallel only inside its dense
/// blocks, which measured slower than sequential at 22k and 363k triangles.
const PAR: faer::Par = faer::Par::Seq;

impl Reduced {
    pub(super) fn new(p: &Problem<'_>) -> Result<Self, SolveError> {
        use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymmetricOrdering};
        let m = p.m();
        let other = |e: &dyn std::fmt::Debug| SolveError::Other(format!("{e:?}"));
        if m > MAX_ROWS {
            return Err(SolveError::Other(format!("{m} vertex constraint rows exceed the {MAX_ROWS} of the 32-bit reduced system")));
        }
        let a = faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &p.col_ptr, None, &p.row_idx);
        let ordering = vertex_ordering(p).map_err(|e| other(&e))?;
        let params = crate::solvers::ordering::symbolic_params(&ordering);
        let (fwd, inv) = (ordering.fwd, ordering.inv);
        let (fwd, inv): (Vec<u32>, Vec<u32>) = (fwd.iter().map(|&x| x as u32).collect(), inv.iter().map(|&x| x as u32).collect());
        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, m);
        // faer's relaxed supernodes store explicit zeros: 126 factor entries per row on the
        // 1M-triangle disk, 115 with fundamental supernodes only (`relax: None`, 7 % less peak
        // memory, same speed), but the other rounding moves the converged UVs by up to 2e-9,
        // so the default is kept.
        let symbolic = factorize_symbolic_cholesky(a, faer::Side::Upper, SymmetricOrdering::Custom(perm), params)
            .map_err(|e| other(&e))?;
        let mem = faer::dyn_stack::MemBuffer::try_new(RefinedLlt::<f64>::solve_scratch(&symbolic, PAR, 1)).map_err(|e| other(&e))?;
        Ok(Reduced { symbolic, factor: RefinedLlt::new(refined_llt::single_pays(m)), values: Vec::new(), mem })
    }

    /// Numeric factorization for `values` on the pattern of `p` (kept for the solves),
    /// regularised when it is not positive definite: the diagonal is raised by each shift of
    /// [`SHIFTS`] in turn (times the mean absolute diagonal entry) until the factorization
    /// succeeds. Returns the relative shift used (0 when none was needed).
    ///
    /// The reduced matrix `J₂ P J₂ᵀ` is positive semi-definite by construction, and definite
    /// when the vertex rows are independent of the triangle rows; near-degenerate corners
    /// (cotangents of 1e6 and more in the wheel rows) and vertex rows that are nearly
    /// dependent on irregular boundaries (long seams, slits, fins) make it fail Cholesky in
    /// floating point. Shifting the diagonal by δ is the regularised KKT system with `−δ I`
    /// in its multiplier block (as interior-point solvers do for rank-deficient constraint
    /// Jacobians): the step keeps the angle updates' triangle sums and lowers the constraint
    /// residuals a little less than a full Newton step, and the iteration goes on instead of
    /// giving up.
    ///
    /// Failures: still not positive definite with the largest shift, or the factorization's
    /// workspace cannot be allocated.
    pub(super) fn factor(&mut self, p: &Problem<'_>, values: Vec<f64>) -> Result<f64, SolveError> {
        let m = p.m();
        self.values = values;
        let req = RefinedLlt::<f64>::factor_scratch(&self.symbolic, PAR);
        let mut mem = faer::dyn_stack::MemBuffer::try_new(req).map_err(|e| SolveError::Other(format!("{e:?}")))?;
        let mean = (0..m).map(|r| self.values[p.diagonal_slot(r)].abs()).sum::<f64>() / m.max(1) as f64;
        let mean = if mean > 0.0 && mean.is_finite() { mean } else { 1.0 };
        let mut applied = 0.0;
        let mut last = SolveError::NotPositiveDefinite;
        for &shift in &SHIFTS {
            if shift > applied {
                let delta = (shift - applied) * mean;
                for r in 0..m {
                    self.values[p.diagonal_slot(r)] += delta;
                }
                applied = shift;
            }
            let a = faer::sparse::SparseColMatRef::new(faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &p.col_ptr, None, &p.row_idx), &self.values);
            match self.factor.factor(&self.symbolic, a, faer::Side::Upper, PAR, faer::dyn_stack::MemStack::new(&mut mem)) {
                Ok(()) => return Ok(shift),
                Err(SolveError::NotPositiveDefinite) => last = SolveError::NotPositiveDefinite,
                Err(e) => return Err(e),
            }
        }
        Err(last)
    }

    /// Solve with the last factorization, in place.
    pub(super) fn solve(&mut self, p: &Problem<'_>, rhs: &mut [f64]) -> Result<(), SolveError> {
        let m = rhs.len();
        let a = faer::sparse::SparseColMatRef::new(faer::sparse::SymbolicSparseColMatRef::new_checked(m, m, &p.col_ptr, None, &p.row_idx), &self.values);
        // To the step's accuracy first (`STEP_ACCURACY`), from zero; to round-off when that
        // does not converge.
        let b = rhs.to_vec();
        rhs.fill(0.0);
        let stack = faer::dyn_stack::MemStack::new(&mut self.mem);
        let solved = self.factor.solve_inexact(&self.symbolic, a, &b, rhs, STEP_ACCURACY, PAR, stack)?;
        if solved && rhs.iter().all(|x| x.is_finite()) {
            return Ok(());
        }
        rhs.copy_from_slice(&b);
        drop(b);
        let rhs_mat = faer::MatMut::from_column_major_slice_mut(rhs, m, 1);
        let stack = faer::dyn_stack::MemStack::new(&mut self.mem);
        self.factor.solve_in_place(&self.symbolic, a, faer::Side::Upper, rhs_mat, PAR, stack)?;
        if rhs.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(SolveError::NonFinite)
        }
    }
}

/// A fill-reducing ordering of the reduced matrix: approximate minimum degree (nested
/// dissection for large charts) on the graph of the constrained vertices (half the size of
/// the matrix), each vertex's rows kept together. The AMD order is the chart's shared vertex
/// order restricted to these vertices when the problem has one ([`Problem::vertex_order`]).
pub(super) fn vertex_ordering(p: &Problem<'_>) -> Result<crate::solvers::ordering::Permutation, faer::sparse::FaerError> {
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
    // AMD, or nested dissection for large charts (see `solvers::ordering`); AMD taken from the
    // chart's shared vertex order when there is one.
    use crate::solvers::ordering::OrderingKind;
    let shared = p.vertex_order.filter(|_| OrderingKind::Auto.resolve(g) == OrderingKind::Amd).and_then(|order| {
        let mut group_of = vec![u32::MAX; order.len()];
        for gv in 0..g {
            let v = p.rows[start[gv]].vertex as usize;
            *group_of.get_mut(v)? = gv as u32;
        }
        let gfwd: Vec<usize> = order.iter().filter_map(|&v| group_of.get(v as usize).filter(|&&gv| gv != u32::MAX).map(|&gv| gv as usize)).collect();
        (gfwd.len() == g).then_some(gfwd)
    });
    let gfwd = match shared {
        Some(gfwd) => gfwd,
        None => {
            // Group graph, upper triangle by columns.
            let mut col_ptr = vec![0usize; g + 1];
            let mut row_idx = Vec::new();
            let mut mark = vec![usize::MAX; g];
            for gc in 0..g {
                for c in start[gc]..start[gc + 1] {
                    for &r in &p.row_idx[p.col_ptr[c] as usize..p.col_ptr[c + 1] as usize] {
                        let gr = group[r as usize];
                        if mark[gr] != gc {
                            mark[gr] = gc;
                            row_idx.push(gr);
                        }
                    }
                }
                row_idx[col_ptr[gc]..].sort_unstable();
                col_ptr[gc + 1] = row_idx.len();
            }
            crate::solvers::ordering::fill_reducing(OrderingKind::Auto, g, &col_ptr, &row_idx)?.fwd
        }
    };
    let mut fwd = Vec::with_capacity(m);
    for &gv in &gfwd {
        fwd.extend(start[gv]..start[gv + 1]);
    }
    let mut inv = vec![0usize; m];
    for (i, &r) in fwd.iter().enumerate() {
        inv[r] = i;
    }
    // Interior vertices have two rows each (angle sum and wheel): the factor's supernodes are
    // then at least two columns wide, as in the 2×2-block systems.
    Ok(crate::solvers::ordering::Permutation { fwd, inv, blocks: 2 * g >= m })
}
