//! Minimise a quadratic with some unknowns fixed: factor once, solve many.
//!
//! For a sparse matrix `Q` (n × n), a set `C` of fixed unknowns with values `x_C` and a linear
//! term `b`, the minimiser of `½ xᵀ Q x − bᵀ x` (or, for a non-symmetric `Q`, the solution of
//! the rows of `Q x = b` that belong to free unknowns) satisfies
//!
//! ```text
//! Q_FF x_F = b_F − Q_FC x_C
//! ```
//!
//! `Q_FF` is factored once (sparse Cholesky when symmetric positive definite, sparse LU
//! otherwise) with its symbolic analysis kept, so that
//! * new fixed values or a new `b` cost one solve ([`FixedValueSolver::solve`]), and
//! * new matrix values on the same pattern cost one numeric refactorisation
//!   ([`FixedValueSolver::refactor`]) — the pattern of ARAP/SLIM global steps.
//!
//! The scalar is `f64` by default or [`faer::c64`]: a complex Hermitian `Q` (conformal
//! energies are Hermitian forms in `w = u + iv`) halves the dimension of the real system.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{Pair, SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, Side};

use super::ordering::{fill_reducing, symbolic_params, Ordering, OrderingKind};
use super::refined_llt::{self, RefinedLlt};
use super::SolveError;

/// The scalars the solver works in: `f64`, or `c64` for Hermitian problems.
pub trait Scalar:
    faer::traits::ComplexField
    + Copy
    + Send
    + Sync
    + PartialEq
    + std::fmt::Debug
    + std::ops::Mul<Output = Self>
    + std::ops::SubAssign
    + std::ops::AddAssign
    + 'static
{
    /// Additive identity.
    fn zero_value() -> Self;
    /// Complex conjugate (identity for reals).
    fn conjugate(self) -> Self;
    /// Neither NaN nor infinite.
    fn finite(self) -> bool;
    /// Real part.
    fn real(self) -> f64;
    /// The scalar with real part `x` (and no imaginary part).
    fn from_real(x: f64) -> Self;
    /// Product with a real number.
    fn scale(self, s: f64) -> Self;
    /// The single-precision scalar of the same kind (`f32`, `c32`), for mixed-precision
    /// factorizations ([`super::refined_llt`]).
    type Low: faer::traits::ComplexField + Copy + Send + Sync + 'static;
    /// Rounded to single precision; `None` when that is not finite.
    fn to_low(self) -> Option<Self::Low>;
    /// Back to double precision.
    fn from_low(low: Self::Low) -> Self;
    /// Single-precision zero.
    fn low_zero() -> Self::Low;
    /// Absolute value (modulus).
    fn magnitude(self) -> f64;
}

impl Scalar for f64 {
    fn zero_value() -> Self {
        0.0
    }
    fn conjugate(self) -> Self {
        self
    }
    fn finite(self) -> bool {
        self.is_finite()
    }
    fn real(self) -> f64 {
        self
    }
    fn from_real(x: f64) -> Self {
        x
    }
    fn scale(self, s: f64) -> Self {
        self * s
    }
    type Low = f32;
    fn to_low(self) -> Option<f32> {
        let low = self as f32;
        low.is_finite().then_some(low)
    }
    fn from_low(low: f32) -> Self {
        low as f64
    }
    fn low_zero() -> f32 {
        0.0
    }
    fn magnitude(self) -> f64 {
        self.abs()
    }
}

impl Scalar for faer::c64 {
    fn zero_value() -> Self {
        faer::c64::new(0.0, 0.0)
    }
    fn conjugate(self) -> Self {
        self.conj()
    }
    fn finite(self) -> bool {
        self.re.is_finite() && self.im.is_finite()
    }
    fn real(self) -> f64 {
        self.re
    }
    fn from_real(x: f64) -> Self {
        faer::c64::new(x, 0.0)
    }
    fn scale(self, s: f64) -> Self {
        faer::c64::new(self.re * s, self.im * s)
    }
    type Low = faer::c32;
    fn to_low(self) -> Option<faer::c32> {
        let low = faer::c32::new(self.re as f32, self.im as f32);
        (low.re.is_finite() && low.im.is_finite()).then_some(low)
    }
    fn from_low(low: faer::c32) -> Self {
        faer::c64::new(low.re as f64, low.im as f64)
    }
    fn low_zero() -> faer::c32 {
        faer::c32::new(0.0, 0.0)
    }
    fn magnitude(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// Number of `Q_FC` entries among `slots` (the coupling's length after every load).
fn coupling_len(slots: &[Slot]) -> usize {
    slots.iter().filter(|s| matches!(s, Slot::FreeFixed(..) | Slot::FreeFixedConj(..))).count()
}

/// In-place Cholesky `A = L Lᴴ` of the Hermitian positive definite `nf × nf` matrix whose
/// lower triangle is stored column-major in `a` (`a[r + c·nf]`, `r ≥ c`); the strict upper
/// triangle is not read. Column by column (left-looking), no allocation: the factorization
/// of the few-unknown systems of tiny charts. Fails with
/// [`SolveError::NotPositiveDefinite`] when a pivot is not positive (or not finite).
fn dense_cholesky_in_place<T: Scalar>(a: &mut [T], nf: usize) -> Result<(), SolveError> {
    for j in 0..nf {
        let mut d = a[j + j * nf].real();
        for k in 0..j {
            let l = a[j + k * nf];
            d -= (l * l.conjugate()).real();
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err(SolveError::NotPositiveDefinite);
        }
        let d = d.sqrt();
        a[j + j * nf] = T::from_real(d);
        for i in j + 1..nf {
            let mut s = a[i + j * nf];
            for k in 0..j {
                let p = a[i + k * nf] * a[j + k * nf].conjugate();
                s -= p;
            }
            a[i + j * nf] = s.scale(1.0 / d);
        }
    }
    Ok(())
}

/// Solve `L Lᴴ x = b` in place in `x` with the factor of [`dense_cholesky_in_place`].
fn dense_cholesky_solve<T: Scalar>(l: &[T], nf: usize, x: &mut [T]) {
    for j in 0..nf {
        let mut s = x[j];
        for k in 0..j {
            let p = l[j + k * nf] * x[k];
            s -= p;
        }
        x[j] = s.scale(1.0 / l[j + j * nf].real());
    }
    for j in (0..nf).rev() {
        let mut s = x[j];
        for i in j + 1..nf {
            let p = l[i + j * nf].conjugate() * x[i];
            s -= p;
        }
        x[j] = s.scale(1.0 / l[j + j * nf].real());
    }
}

/// Whether `Q` is symmetric (Cholesky) or general (LU).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// `Q` symmetric (Hermitian for complex scalars) positive (semi)definite; `Q_FF` must be
    /// positive definite. Give the lower triangle only (row ≥ column): an entry (r, c) stands
    /// for (c, r) too (conjugated), and entries above the diagonal are ignored.
    Symmetric,
    /// `Q` general; `Q_FF` must be non-singular.
    General,
}

enum Symbolic<T: Scalar> {
    /// Cholesky with our fill-reducing ordering (see [`super::ordering`]); the factor's values
    /// and the factorization/solve scratch are allocated once and reused by every refactor
    /// (the scratch behind a mutex, so that `solve(&self)` can use it and the solver stays
    /// `Sync`). The free unknowns are numbered in elimination order and `Q_FF` is stored in
    /// the triangle `side` that faer's numeric factorization reads (lower for supernodal,
    /// upper for simplicial factors), so a refactorization neither permutes nor transposes
    /// it (on camelhead's SLIM system that permutation was about 6% of each factorization).
    ///
    /// Systems refactored every iteration ([`OrderingKind::Auto`]) of at least
    /// [`refined_llt::MIXED_MIN`] free unknowns are factored in single precision and solved
    /// by iterative refinement to double-precision accuracy ([`refined_llt`]).
    Llt { symbolic: Box<SymbolicCholesky<usize>>, side: Side, state: std::sync::Mutex<LltState<T>> },
    Lu(SymbolicLu<usize>),
    /// At most [`DENSE_MAX`] free unknowns: dense factorizations, no symbolic analysis (the
    /// charts of one or a few faces that Smart UV Project makes by the thousand).
    Dense,
}

/// The numeric factor of a sparse Cholesky solver and its workspace.
struct LltState<T: Scalar> {
    factor: RefinedLlt<T>,
    mem: MemBuffer,
}

enum Factor<T> {
    /// The values of the last successful Cholesky factorization are in `Symbolic::Llt`.
    Llt,
    Lu(Box<Lu<usize, T>>),
    /// Dense Cholesky factor, in place of `Q_FF` in `ff_values` ([`dense_cholesky_in_place`]).
    DenseLlt,
    DenseLu(Box<faer::linalg::solvers::PartialPivLu<T>>),
}

/// Systems with at most this many free unknowns are factored dense: below this size a dense
/// factorization costs less than the sparse ordering and symbolic analysis alone.
pub const DENSE_MAX: usize = 24;

#[cfg(test)]
thread_local! {
    /// Tests only: factor every system of this thread sparse, so that a method's results on
    /// tiny charts can be compared between the dense path and the general one.
    pub(crate) static FORCE_SPARSE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// [`DENSE_MAX`], or 0 while a test forces the sparse path.
fn dense_max() -> usize {
    #[cfg(test)]
    if FORCE_SPARSE.with(|f| f.get()) {
        return 0;
    }
    DENSE_MAX
}

/// Where an input triplet goes.
#[derive(Clone, Copy)]
enum Slot {
    /// Entry of `Q_FF`: its position in the compressed columns (duplicates share one).
    FreeFree(u32),
    /// Entry of `Q_FF` stored as its mirror in the other triangle: add the conjugate.
    FreeFreeConj(u32),
    /// Entry of `Q_FC`: (free row, fixed column position).
    FreeFixed(u32, u32),
    /// Upper-triangle entry of `Q_FC` given by its lower mirror: use the conjugate.
    FreeFixedConj(u32, u32),
    /// Row of a fixed unknown, or upper triangle of a symmetric matrix: unused.
    Unused,
}

/// Where triplet `(r, c)` goes, given each unknown's free position (`u32::MAX` when fixed)
/// and fixed position; `free_free(free row, free column)` numbers a `Q_FF` entry (its
/// compressed position later, or its dense index). Symmetric systems use the lower triangle
/// only; an entry (r, c) also stands for (c, r).
fn slot_of(symmetry: Symmetry, r: u32, c: u32, free_pos: &[u32], fixed_pos: &[u32], mut free_free: impl FnMut(u32, u32) -> u32) -> Slot {
    let (fr, fc) = (free_pos[r as usize], free_pos[c as usize]);
    match symmetry {
        Symmetry::Symmetric if r < c => Slot::Unused,
        Symmetry::Symmetric if fr == u32::MAX && fc != u32::MAX => Slot::FreeFixedConj(fc, fixed_pos[r as usize]),
        _ if fr == u32::MAX => Slot::Unused,
        _ if fc == u32::MAX => Slot::FreeFixed(fr, fixed_pos[c as usize]),
        _ => Slot::FreeFree(free_free(fr, fc)),
    }
}

/// Top bit of a [`compressed_order`] entry: a duplicate of the previous entry.
const DUPLICATE: u32 = 1 << 31;

/// The entries `pairs` (indices below `n`, fewer than 2³¹ of them) in compressed-column order
/// (by column, then row), duplicates flagged with [`DUPLICATE`]: two stable counting sorts,
/// by row and then by column, without comparisons.
fn compressed_order(n: usize, pairs: &[Pair<usize, usize>]) -> Vec<u32> {
    fn by(n: usize, pairs: &[Pair<usize, usize>], key: impl Fn(&Pair<usize, usize>) -> usize, input: impl Iterator<Item = u32>) -> Vec<u32> {
        let mut start = vec![0u32; n + 1];
        for p in pairs {
            start[key(p) + 1] += 1;
        }
        for c in 0..n {
            start[c + 1] += start[c];
        }
        let mut out = vec![0u32; pairs.len()];
        for i in input {
            let k = key(&pairs[i as usize]);
            out[start[k] as usize] = i;
            start[k] += 1;
        }
        out
    }
    let by_row = by(n, pairs, |p| p.row, 0..pairs.len() as u32);
    let mut order = by(n, pairs, |p| p.col, by_row.into_iter());
    let mut prev = (usize::MAX, usize::MAX);
    for e in order.iter_mut() {
        let p = &pairs[*e as usize];
        let key = (p.col, p.row);
        if key == prev {
            *e |= DUPLICATE;
        }
        prev = key;
    }
    order
}

/// Flag of a [`renumbered`] position: the entry is stored as its mirror (conjugated).
const CONJUGATE: u32 = 1 << 31;

/// The Hermitian pattern `a` (one triangle, compressed columns) renumbered by `inv` (new
/// index of every old one) into the triangle `side` of the new numbering, rows sorted, and
/// the new position of every old entry, with [`CONJUGATE`] set where the entry crossed the
/// diagonal (its mirror is stored).
fn renumbered(a: faer::sparse::SymbolicSparseColMatRef<'_, usize>, inv: &[usize], side: Side) -> (SymbolicSparseColMat<usize>, Vec<u32>) {
    let n = a.ncols();
    let mut pairs = Vec::with_capacity(a.row_idx().len());
    let mut crossed = Vec::with_capacity(a.row_idx().len());
    for c in 0..n {
        for &r in a.row_idx_of_col_raw(c) {
            let (i, j) = (inv[r], inv[c]);
            let (row, col) = match side {
                Side::Lower => (i.max(j), i.min(j)),
                Side::Upper => (i.min(j), i.max(j)),
            };
            crossed.push(row != i);
            pairs.push(Pair { row, col });
        }
    }
    // No duplicates: `a` has none and renumbering is one to one.
    let order = compressed_order(n, &pairs);
    let mut col_ptr = vec![0usize; n + 1];
    let mut row_idx = Vec::with_capacity(pairs.len());
    let mut moved = vec![0u32; pairs.len()];
    for (at, &e) in order.iter().enumerate() {
        let k = (e & !DUPLICATE) as usize;
        row_idx.push(pairs[k].row);
        col_ptr[pairs[k].col + 1] += 1;
        moved[k] = at as u32 | if crossed[k] { CONJUGATE } else { 0 };
    }
    for c in 0..n {
        col_ptr[c + 1] += col_ptr[c];
    }
    (SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx), moved)
}

/// The quadratic-with-fixed-values solver (see the module docs).
pub struct FixedValueSolver<T: Scalar = f64> {
    n: usize,
    symmetry: Symmetry,
    free: Vec<u32>,
    fixed: Vec<u32>,
    slots: Vec<Slot>,
    ff_symbolic: SymbolicSparseColMat<usize>,
    /// Values of `Q_FF` in the order of `ff_symbolic`, rewritten in place by every refactor.
    ff_values: Vec<T>,
    coupling: Vec<(u32, u32, T)>,
    symbolic: Symbolic<T>,
    factor: Option<Factor<T>>,
}

impl<T: Scalar> FixedValueSolver<T> {
    /// Analyse and factor `Q_FF` for the matrix given as triplets `(row, col, value)`
    /// (duplicates are summed) with the unknowns `fixed` held at values given later.
    ///
    /// Preconditions: indices `< n`; `fixed` without duplicates. Failures:
    /// [`SolveError::NotPositiveDefinite`] / [`SolveError::Singular`] when `Q_FF` cannot be
    /// factored, [`SolveError::Other`] on allocation failure.
    ///
    /// The fill-reducing ordering is [`OrderingKind::Auto`], chosen for systems that are
    /// refactored many times (nested dissection on large systems); a system factored once
    /// should use [`FixedValueSolver::with_ordering`] with [`OrderingKind::Amd`].
    pub fn new(n: usize, triplets: &[(u32, u32, T)], fixed: &[u32], symmetry: Symmetry) -> Result<Self, SolveError> {
        Self::new_with_dense_max(n, triplets, fixed, symmetry, dense_max(), OrderingKind::Auto.into())
    }

    /// The analysis of [`FixedValueSolver::new`] without a factorization: the triplets give
    /// only the pattern (their values are ignored), and the first [`FixedValueSolver::refactor`]
    /// loads values and factors. Lets a method analyse its system while it computes the
    /// values (e.g. beside a starting map, on another thread). [`FixedValueSolver::solve`]
    /// before a successful refactor fails as after a failed one
    /// ([`SolveError::NotPositiveDefinite`]).
    ///
    /// Preconditions and failures as [`FixedValueSolver::new`], except that no factorization
    /// can fail here. Reads this thread's test switches (dense path, precision) when called.
    pub fn analyse(n: usize, triplets: &[(u32, u32, T)], fixed: &[u32], symmetry: Symmetry) -> Result<Self, SolveError> {
        Self::analysed(n, triplets, fixed, symmetry, dense_max(), OrderingKind::Auto.into())
    }

    /// [`FixedValueSolver::new`] with the given fill-reducing ordering of `Q_FF` (used by its
    /// Cholesky factorization; the LU of [`Symmetry::General`] systems orders itself).
    ///
    /// Nested dissection costs more to compute than AMD and saves numeric work on every
    /// factorization of a large system (see [`crate::solvers::ordering`]): for a system
    /// factored once (LSCM, Tutte, harmonic, mean value) AMD is the faster choice at every
    /// size measured.
    pub fn with_ordering<'a>(n: usize, triplets: &[(u32, u32, T)], fixed: &[u32], symmetry: Symmetry, ordering: impl Into<Ordering<'a>>) -> Result<Self, SolveError> {
        Self::new_with_dense_max(n, triplets, fixed, symmetry, dense_max(), ordering.into())
    }

    /// [`FixedValueSolver::with_ordering`] for a system solved to the accuracy of a starting
    /// map rather than to round-off: factored in single precision when the system is large
    /// enough for it to pay ([`refined_llt::single_pays`]), whatever the ordering, and solved by
    /// [`FixedValueSolver::solve_inexact`] or preconditioned by
    /// [`FixedValueSolver::apply_factor`]. Preconditions and failures as
    /// [`FixedValueSolver::new`].
    pub fn approximate_with<'a>(
        n: usize,
        triplets: &[(u32, u32, T)],
        fixed: &[u32],
        symmetry: Symmetry,
        ordering: impl Into<Ordering<'a>>,
    ) -> Result<Self, SolveError> {
        let mut solver = Self::analysed(n, triplets, fixed, symmetry, dense_max(), ordering.into())?;
        let nf = solver.free.len();
        if let Symbolic::Llt { state, .. } = &mut solver.symbolic {
            let state = state.get_mut().unwrap_or_else(std::sync::PoisonError::into_inner);
            state.factor = RefinedLlt::new(refined_llt::single_pays(nf));
        }
        solver.load_values(triplets.iter().map(|t| t.2));
        solver.factor_loaded()?;
        Ok(solver)
    }

    /// `Q_FF⁻¹ b_F` by one application of the factor in its precision (no refinement), the
    /// fixed unknowns 0: a preconditioner. `b` has length n (its fixed entries are ignored).
    /// Dense and LU factors solve directly. Failures: as [`FixedValueSolver::solve`].
    pub fn apply_factor(&self, b: &[T]) -> Result<Vec<T>, SolveError> {
        if let (Some(Factor::Llt), Symbolic::Llt { symbolic, state, .. }) = (&self.factor, &self.symbolic) {
            let mut state = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let state = &mut *state;
            let rhs: Vec<T> = self.free.iter().map(|&g| b[g as usize]).collect();
            let mut y = vec![T::zero_value(); rhs.len()];
            let par = faer::get_global_parallelism();
            state.factor.precondition(symbolic, &rhs, &mut y, par, MemStack::new(&mut state.mem))?;
            if !y.iter().all(|v| v.finite()) {
                return Err(SolveError::NonFinite);
            }
            return Ok(self.full(&y, &vec![T::zero_value(); self.fixed.len()]));
        }
        let zeros = vec![vec![T::zero_value(); self.fixed.len()]];
        Ok(self.solve(&zeros, &[b.to_vec()])?.pop().unwrap_or_default())
    }

    /// [`FixedValueSolver::analyse`] with the given ordering (see
    /// [`FixedValueSolver::with_ordering`]).
    pub fn analyse_with<'a>(n: usize, triplets: &[(u32, u32, T)], fixed: &[u32], symmetry: Symmetry, ordering: impl Into<Ordering<'a>>) -> Result<Self, SolveError> {
        Self::analysed(n, triplets, fixed, symmetry, dense_max(), ordering.into())
    }

    /// [`FixedValueSolver::with_ordering`], factoring dense up to `dense_max` free unknowns.
    fn new_with_dense_max(
        n: usize,
        triplets: &[(u32, u32, T)],
        fixed: &[u32],
        symmetry: Symmetry,
        dense_max: usize,
        ordering: Ordering<'_>,
    ) -> Result<Self, SolveError> {
        let mut solver = Self::analysed(n, triplets, fixed, symmetry, dense_max, ordering)?;
        solver.load_values(triplets.iter().map(|t| t.2));
        solver.factor_loaded()?;
        Ok(solver)
    }

    /// The analysis of [`FixedValueSolver::new_with_dense_max`]: pattern, ordering and
    /// symbolic factorization, no values loaded and nothing factored.
    fn analysed(
        n: usize,
        triplets: &[(u32, u32, T)],
        fixed: &[u32],
        symmetry: Symmetry,
        dense_max: usize,
        ordering: Ordering<'_>,
    ) -> Result<Self, SolveError> {
        let mut free_pos = vec![0u32; n];
        for &c in fixed {
            free_pos[c as usize] = u32::MAX;
        }
        let mut free = Vec::with_capacity(n - fixed.len().min(n));
        for i in 0..n {
            if free_pos[i] != u32::MAX {
                free_pos[i] = free.len() as u32;
                free.push(i as u32);
            }
        }
        let mut fixed_pos = vec![u32::MAX; n];
        for (k, &c) in fixed.iter().enumerate() {
            fixed_pos[c as usize] = k as u32;
        }
        let nf = free.len();
        if nf <= dense_max {
            return Self::new_dense(n, triplets, fixed, symmetry, free, &free_pos, &fixed_pos);
        }
        let mut pairs = Vec::with_capacity(triplets.len());
        let mut slots = Vec::with_capacity(triplets.len());
        for &(r, c, _) in triplets {
            slots.push(slot_of(symmetry, r, c, &free_pos, &fixed_pos, |fr, fc| {
                pairs.push(Pair { row: fr as usize, col: fc as usize });
                (pairs.len() - 1) as u32
            }));
        }
        if pairs.len() >= DUPLICATE as usize {
            return Err(SolveError::Other(format!("{} matrix entries exceed the solver's 2³¹ limit", pairs.len())));
        }
        // The compressed columns (duplicates summed into one) and the position of every entry
        // in them, so that new values go straight to their place: 12 bytes per input triplet
        // are kept. One counting sort by column, then each column's rows sorted.
        let mut position = vec![0u32; pairs.len()];
        let mut col_ptr = vec![0usize; nf + 1];
        let mut row_idx = Vec::new();
        let mut at = u32::MAX;
        for e in compressed_order(nf, &pairs) {
            let i = (e & !DUPLICATE) as usize;
            if e & DUPLICATE == 0 {
                at = at.wrapping_add(1);
                row_idx.push(pairs[i].row);
                col_ptr[pairs[i].col + 1] += 1;
            }
            position[i] = at;
        }
        drop(pairs);
        for c in 0..nf {
            col_ptr[c + 1] += col_ptr[c];
        }
        row_idx.shrink_to_fit();
        let ff_symbolic = SymbolicSparseColMat::new_checked(nf, nf, col_ptr, None, row_idx);
        for slot in slots.iter_mut() {
            if let Slot::FreeFree(k) = slot {
                *k = position[*k as usize];
            }
        }
        drop(position);
        let (ff_symbolic, symbolic) = match symmetry {
            Symmetry::Symmetric => {
                let other = |e: &dyn std::fmt::Debug| SolveError::Other(format!("{e:?}"));
                let a = ff_symbolic.as_ref();
                let perm = match ordering.of_vertices(n, &free_pos, nf) {
                    Some(perm) => perm,
                    None => fill_reducing(ordering.kind(), nf, a.col_ptr(), a.row_idx()).map_err(|e| other(&e))?,
                };
                // The free unknowns are renumbered in elimination order and `Q_FF` is kept in
                // that order, in the triangle the factorization reads (lower for supernodal,
                // upper for simplicial factors): no refactorization permutes or transposes it.
                // (faer's analysis without an ordering reads the upper triangle.)
                let (upper, moved) = renumbered(a, &perm.inv, Side::Upper);
                let symbolic = factorize_symbolic_cholesky(upper.as_ref(), Side::Upper, SymmetricOrdering::Identity, symbolic_params(&perm))
                    .map_err(|e| other(&e))?;
                let side = match symbolic.raw() {
                    faer::sparse::linalg::cholesky::SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
                    _ => Side::Lower,
                };
                let (stored, moved) = if side == Side::Lower {
                    drop((upper, moved));
                    renumbered(a, &perm.inv, Side::Lower)
                } else {
                    (upper, moved)
                };
                for slot in slots.iter_mut() {
                    *slot = match *slot {
                        Slot::FreeFree(k) if moved[k as usize] & CONJUGATE != 0 => Slot::FreeFreeConj(moved[k as usize] & !CONJUGATE),
                        Slot::FreeFree(k) => Slot::FreeFree(moved[k as usize]),
                        Slot::FreeFixed(r, c) => Slot::FreeFixed(perm.inv[r as usize] as u32, c),
                        Slot::FreeFixedConj(r, c) => Slot::FreeFixedConj(perm.inv[r as usize] as u32, c),
                        other => other,
                    };
                }
                drop(moved);
                free = perm.fwd.iter().map(|&old| free[old]).collect();
                let par = faer::get_global_parallelism();
                let mem = MemBuffer::try_new(RefinedLlt::<T>::scratch(&symbolic, par, 2)).map_err(|e| other(&e))?;
                let factor = RefinedLlt::new(ordering.kind() == OrderingKind::Auto && refined_llt::single_pays(nf));
                (stored, Symbolic::Llt { symbolic: Box::new(symbolic), side, state: std::sync::Mutex::new(LltState { factor, mem }) })
            }
            Symmetry::General => {
                let lu = Symbolic::Lu(SymbolicLu::try_new(ff_symbolic.as_ref()).map_err(|e| SolveError::Other(format!("{e:?}")))?);
                (ff_symbolic, lu)
            }
        };
        let nnz_ff = ff_symbolic.row_idx().len();
        Ok(Self::of_analysis(n, fixed, symmetry, free, slots, ff_symbolic, nnz_ff, symbolic))
    }

    /// The solver of the given analysis, with no values loaded and nothing factored.
    #[allow(clippy::too_many_arguments)]
    fn of_analysis(
        n: usize,
        fixed: &[u32],
        symmetry: Symmetry,
        free: Vec<u32>,
        slots: Vec<Slot>,
        ff_symbolic: SymbolicSparseColMat<usize>,
        n_values: usize,
        symbolic: Symbolic<T>,
    ) -> Self {
        let coupling = Vec::with_capacity(coupling_len(&slots));
        FixedValueSolver {
            n,
            symmetry,
            free,
            fixed: fixed.to_vec(),
            slots,
            ff_symbolic,
            ff_values: vec![T::zero_value(); n_values],
            coupling,
            symbolic,
            factor: None,
        }
    }

    /// The dense path of [`FixedValueSolver::new_with_dense_max`]: no compressed pattern and no
    /// symbolic analysis; every `Q_FF` triplet goes straight to its place `r + c·nf` of the
    /// column-major dense matrix (lower triangle only when symmetric), so a chart of one or a
    /// few faces costs a handful of small allocations.
    fn new_dense(
        n: usize,
        triplets: &[(u32, u32, T)],
        fixed: &[u32],
        symmetry: Symmetry,
        free: Vec<u32>,
        free_pos: &[u32],
        fixed_pos: &[u32],
    ) -> Result<Self, SolveError> {
        let nf = free.len();
        let slots: Vec<Slot> =
            triplets.iter().map(|&(r, c, _)| slot_of(symmetry, r, c, free_pos, fixed_pos, |fr, fc| fr + fc * nf as u32)).collect();
        let ff_symbolic = SymbolicSparseColMat::try_new_from_indices(0, 0, &[]).map_err(|e| SolveError::Other(format!("{e:?}")))?.0;
        Ok(Self::of_analysis(n, fixed, symmetry, free, slots, ff_symbolic, nf * nf, Symbolic::Dense))
    }

    /// Numeric refactorisation for new values on the same triplet pattern (same length and
    /// order as the triplets given to [`FixedValueSolver::new`]); the symbolic analysis is
    /// reused.
    pub fn refactor(&mut self, values: &[T]) -> Result<(), SolveError> {
        assert_eq!(values.len(), self.slots.len(), "refactor needs one value per original triplet");
        self.load_values(values.iter().copied());
        self.factor_loaded()
    }

    /// Write new values (one per original triplet, in their order) into `Q_FF`, duplicates
    /// summed in input order, and into the coupling `Q_FC`.
    fn load_values(&mut self, values: impl Iterator<Item = T>) {
        self.coupling.clear();
        self.ff_values.iter_mut().for_each(|v| *v = T::zero_value());
        for (slot, v) in self.slots.iter().zip(values) {
            match *slot {
                Slot::FreeFree(k) => self.ff_values[k as usize] += v,
                Slot::FreeFreeConj(k) => self.ff_values[k as usize] += v.conjugate(),
                Slot::FreeFixed(r, c) => self.coupling.push((r, c, v)),
                Slot::FreeFixedConj(r, c) => self.coupling.push((r, c, v.conjugate())),
                Slot::Unused => {}
            }
        }
    }

    /// Numeric factorization of the loaded `Q_FF`.
    fn factor_loaded(&mut self) -> Result<(), SolveError> {
        self.factor = None;
        self.factor = Some(match &mut self.symbolic {
            Symbolic::Llt { symbolic, side, state } => {
                let mat = SparseColMatRef::new(self.ff_symbolic.as_ref(), &self.ff_values);
                let par = faer::get_global_parallelism();
                let state = state.get_mut().unwrap_or_else(std::sync::PoisonError::into_inner);
                state.factor.factor(symbolic, mat, *side, par, MemStack::new(&mut state.mem))?;
                Factor::Llt
            }
            Symbolic::Lu(sym) => Factor::Lu(Box::new(Lu::try_new_with_symbolic(sym.clone(), SparseColMatRef::new(self.ff_symbolic.as_ref(), &self.ff_values)).map_err(|e| match e {
                faer::sparse::linalg::LuError::SymbolicSingular { .. } => SolveError::Singular,
                other => SolveError::Other(format!("{other:?}")),
            })?)),
            Symbolic::Dense => {
                let nf = self.free.len();
                // Column-major values (lower triangle when symmetric; see `new_dense`).
                match self.symmetry {
                    Symmetry::Symmetric => {
                        dense_cholesky_in_place(&mut self.ff_values, nf)?;
                        Factor::DenseLlt
                    }
                    Symmetry::General => {
                        let v = &self.ff_values;
                        let dense = Mat::<T>::from_fn(nf, nf, |r, c| v[r + c * nf]);
                        let lu = dense.partial_piv_lu();
                        let u = lu.U();
                        if (0..nf).any(|i| u[(i, i)] == T::zero_value() || !u[(i, i)].finite()) {
                            return Err(SolveError::Singular);
                        }
                        Factor::DenseLu(Box::new(lu))
                    }
                }
            }
        });
        Ok(())
    }

    /// [`FixedValueSolver::solve`] with the dense Cholesky factor: column by column in one
    /// scratch vector, no matrix allocated (the few-unknown systems of tiny charts).
    fn solve_dense_cholesky(&self, fixed_values: &[Vec<T>], b: &[Vec<T>]) -> Result<Vec<Vec<T>>, SolveError> {
        let nf = self.free.len();
        let mut y = vec![T::zero_value(); nf];
        let mut out = Vec::with_capacity(fixed_values.len());
        for (col, xc) in fixed_values.iter().enumerate() {
            match b.get(col).filter(|bc| !bc.is_empty()) {
                Some(bc) => self.free.iter().zip(y.iter_mut()).for_each(|(&g, yi)| *yi = bc[g as usize]),
                None => y.iter_mut().for_each(|yi| *yi = T::zero_value()),
            }
            for &(r, c, v) in &self.coupling {
                let prod = v * xc[c as usize];
                y[r as usize] -= prod;
            }
            dense_cholesky_solve(&self.ff_values, nf, &mut y);
            let mut x = vec![T::zero_value(); self.n];
            for (&v, &g) in y.iter().zip(&self.free) {
                if !v.finite() {
                    return Err(SolveError::NonFinite);
                }
                x[g as usize] = v;
            }
            for (j, &c) in self.fixed.iter().enumerate() {
                x[c as usize] = xc[j];
            }
            out.push(x);
        }
        Ok(out)
    }

    /// Number of unknowns.
    pub fn n(&self) -> usize {
        self.n
    }
    /// The fixed unknowns, in the order their values are expected.
    pub fn fixed(&self) -> &[u32] {
        &self.fixed
    }
    /// Whether the matrix was treated as symmetric.
    pub fn symmetry(&self) -> Symmetry {
        self.symmetry
    }

    /// Solve for one column (`fixed_values`, linear term `b` of length n or empty) to the
    /// accuracy an inexact Newton step needs: the residual `relative` times its value at
    /// `guess` (length n). A single-precision factor ([`refined_llt`]) is used as the
    /// preconditioner of conjugate gradients from the guess
    /// ([`RefinedLlt::solve_inexact`]): one or two triangular solves instead of the several
    /// of a refinement to double-precision accuracy. A double-precision factor solves
    /// directly; dense and LU factors, and a run that does not converge, give the direct
    /// solve of [`FixedValueSolver::solve`]. Failures: as
    /// [`FixedValueSolver::solve`].
    pub fn solve_inexact(&self, fixed_values: &[T], b: &[T], guess: &[T], relative: f64) -> Result<Vec<T>, SolveError> {
        if let (Some(Factor::Llt), Symbolic::Llt { symbolic, state, .. }) = (&self.factor, &self.symbolic) {
            let mut state = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
            let state = &mut *state;
            let rhs = self.free_rhs(fixed_values, b);
            let mut y: Vec<T> = self.free.iter().map(|&g| guess[g as usize]).collect();
            let mat = SparseColMatRef::new(self.ff_symbolic.as_ref(), &self.ff_values);
            let par = faer::get_global_parallelism();
            if state.factor.solve_inexact(symbolic, mat, &rhs, &mut y, relative, par, MemStack::new(&mut state.mem))? {
                return Ok(self.full(&y, fixed_values));
            }
        }
        Ok(self.solve(&[fixed_values.to_vec()], &[b.to_vec()])?.pop().unwrap_or_default())
    }

    /// `b_F − Q_FC x_C` for one column (`b` of length n, or empty for zero).
    fn free_rhs(&self, fixed_values: &[T], b: &[T]) -> Vec<T> {
        let mut rhs: Vec<T> = if b.is_empty() { vec![T::zero_value(); self.free.len()] } else { self.free.iter().map(|&g| b[g as usize]).collect() };
        for &(r, c, v) in &self.coupling {
            rhs[r as usize] -= v * fixed_values[c as usize];
        }
        rhs
    }

    /// The full solution vector of the free values `y` and the fixed `fixed_values`.
    fn full(&self, y: &[T], fixed_values: &[T]) -> Vec<T> {
        let mut x = vec![T::zero_value(); self.n];
        for (&g, &v) in self.free.iter().zip(y) {
            x[g as usize] = v;
        }
        for (&c, &v) in self.fixed.iter().zip(fixed_values) {
            x[c as usize] = v;
        }
        x
    }

    /// Solve for several right-hand sides at once. Column `k` has fixed values
    /// `fixed_values[k]` (one per fixed unknown) and linear term `b[k]` (length n, or empty
    /// for zero). Returns the full solution vectors (fixed unknowns hold their values).
    pub fn solve(&self, fixed_values: &[Vec<T>], b: &[Vec<T>]) -> Result<Vec<Vec<T>>, SolveError> {
        if let Some(Factor::DenseLlt) = self.factor {
            return self.solve_dense_cholesky(fixed_values, b);
        }
        let k = fixed_values.len();
        let nf = self.free.len();
        let mut rhs = Mat::<T>::from_fn(nf, k, |_, _| T::zero_value());
        for col in 0..k {
            let column = self.free_rhs(&fixed_values[col], b.get(col).map_or(&[][..], |v| &v[..]));
            for (i, v) in column.into_iter().enumerate() {
                rhs[(i, col)] = v;
            }
        }
        match (&self.factor, &self.symbolic) {
            (Some(Factor::Llt), Symbolic::Llt { symbolic, side, state }) => {
                let par = faer::get_global_parallelism();
                let mut state = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                let state = &mut *state;
                if k > 2 {
                    // More columns than the scratch was sized for (never in practice).
                    state.mem = MemBuffer::try_new(RefinedLlt::<T>::scratch(symbolic, par, k)).map_err(|e| SolveError::Other(format!("{e:?}")))?;
                }
                let mat = SparseColMatRef::new(self.ff_symbolic.as_ref(), &self.ff_values);
                state.factor.solve_in_place(symbolic, mat, *side, rhs.as_mut(), par, MemStack::new(&mut state.mem))?;
            }
            (Some(Factor::Lu(f)), _) => f.solve_in_place(rhs.as_mut()),
            (Some(Factor::DenseLlt), _) => unreachable!("solved by solve_dense_cholesky"),
            (Some(Factor::DenseLu(f)), _) => f.solve_in_place(rhs.as_mut()),
            _ => return Err(SolveError::NotPositiveDefinite),
        }
        let mut out = Vec::with_capacity(k);
        for col in 0..k {
            let y: Vec<T> = (0..nf).map(|i| rhs[(i, col)]).collect();
            if !y.iter().all(|v| v.finite()) {
                return Err(SolveError::NonFinite);
            }
            out.push(self.full(&y, &fixed_values[col]));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dense path of small systems and the sparse path solve the same systems to
    /// round-off: symmetric, general and complex Hermitian, with fixed unknowns; and both
    /// refuse a singular one.
    #[test]
    fn dense_and_sparse_factorizations_agree() {
        // A 4 × 5 grid graph: Laplacian + small shift, made non-symmetric for `General`.
        let (w, h) = (4u32, 5u32);
        let n = (w * h) as usize;
        let mut edges = Vec::new();
        for j in 0..h {
            for i in 0..w {
                let v = j * w + i;
                if i + 1 < w {
                    edges.push((v, v + 1));
                }
                if j + 1 < h {
                    edges.push((v, v + w));
                }
            }
        }
        let fixed = [0u32, 7, 19];
        let fixed_values = vec![vec![1.0, -2.0, 0.5]];
        let b = vec![(0..n).map(|i| (i as f64 * 0.37).sin()).collect::<Vec<f64>>()];
        for sym in [Symmetry::Symmetric, Symmetry::General] {
            let mut t: Vec<(u32, u32, f64)> = (0..n as u32).map(|v| (v, v, 0.1)).collect();
            for (k, &(a, c)) in edges.iter().enumerate() {
                let skew = if sym == Symmetry::General { 0.3 * ((k % 3) as f64 - 1.0) } else { 0.0 };
                let wgt = 1.0 + 0.1 * k as f64;
                t.extend([(a, a, wgt), (c, c, wgt), (c, a, -wgt + skew), (a, c, -wgt - skew)]);
            }
            let dense = FixedValueSolver::new_with_dense_max(n, &t, &fixed, sym, usize::MAX, OrderingKind::Auto.into()).unwrap();
            let sparse = FixedValueSolver::new_with_dense_max(n, &t, &fixed, sym, 0, OrderingKind::Auto.into()).unwrap();
            assert!(matches!(dense.symbolic, Symbolic::Dense) && !matches!(sparse.symbolic, Symbolic::Dense));
            let (xd, xs) = (dense.solve(&fixed_values, &b).unwrap(), sparse.solve(&fixed_values, &b).unwrap());
            for i in 0..n {
                assert!((xd[0][i] - xs[0][i]).abs() < 1e-12 * (1.0 + xs[0][i].abs()), "{sym:?} {i}: {} vs {}", xd[0][i], xs[0][i]);
            }
        }
        // Complex Hermitian: conformal-like entries with an imaginary part off the diagonal.
        let mut t: Vec<(u32, u32, faer::c64)> = (0..n as u32).map(|v| (v, v, faer::c64::new(0.1, 0.0))).collect();
        for (k, &(a, c)) in edges.iter().enumerate() {
            let wgt = 1.0 + 0.05 * k as f64;
            let (lo, hi) = (a.max(c), a.min(c));
            t.extend([(a, a, faer::c64::new(wgt, 0.0)), (c, c, faer::c64::new(wgt, 0.0)), (lo, hi, faer::c64::new(-0.9 * wgt, 0.2))]);
        }
        let fv = vec![vec![faer::c64::new(1.0, 1.0), faer::c64::new(0.0, -1.0), faer::c64::new(2.0, 0.0)]];
        let dense = FixedValueSolver::new_with_dense_max(n, &t, &fixed, Symmetry::Symmetric, usize::MAX, OrderingKind::Auto.into()).unwrap();
        let sparse = FixedValueSolver::new_with_dense_max(n, &t, &fixed, Symmetry::Symmetric, 0, OrderingKind::Auto.into()).unwrap();
        let (xd, xs) = (dense.solve(&fv, &[]).unwrap(), sparse.solve(&fv, &[]).unwrap());
        for i in 0..n {
            let d = xd[0][i] - xs[0][i];
            assert!(d.re.hypot(d.im) < 1e-12, "c64 {i}");
        }
        // Singular: an unknown that no entry touches (a zero row and column).
        let lap: Vec<(u32, u32, f64)> = edges.iter().flat_map(|&(a, c)| [(a, a, 1.0), (c, c, 1.0), (c, a, -1.0), (a, c, -1.0)]).collect();
        for dense_max in [0, usize::MAX] {
            for sym in [Symmetry::Symmetric, Symmetry::General] {
                assert!(FixedValueSolver::new_with_dense_max(n + 1, &lap, &[0], sym, dense_max, OrderingKind::Auto.into()).is_err(), "{sym:?} {dense_max}");
            }
        }
    }

    /// An analysis without values, then a refactor, solves exactly as the solver built with
    /// the values (dense and sparse paths, symmetric and general); before that refactor, and
    /// after one that failed, a solve is refused.
    #[test]
    fn analyse_then_refactor_solves_like_new() {
        let n = 30usize;
        let mut t: Vec<(u32, u32, f64)> = (0..n as u32).map(|v| (v, v, 0.05 + 0.01 * v as f64)).collect();
        for v in 0..n as u32 - 1 {
            let w = 1.0 + 0.1 * (v % 4) as f64;
            t.extend([(v, v, w), (v + 1, v + 1, w), (v + 1, v, -w), (v, v + 1, -w)]);
        }
        let fixed = [3u32, 17];
        let fv = vec![vec![0.25, -1.5]];
        let b = vec![(0..n).map(|i| (i as f64 * 0.7).cos()).collect::<Vec<f64>>()];
        for sym in [Symmetry::Symmetric, Symmetry::General] {
            for dense_max in [0, usize::MAX] {
                let made = FixedValueSolver::new_with_dense_max(n, &t, &fixed, sym, dense_max, OrderingKind::Auto.into()).unwrap();
                let zeros: Vec<(u32, u32, f64)> = t.iter().map(|&(r, c, _)| (r, c, 0.0)).collect();
                let mut later = FixedValueSolver::analysed(n, &zeros, &fixed, sym, dense_max, OrderingKind::Auto.into()).unwrap();
                assert!(later.solve(&fv, &b).is_err(), "{sym:?} {dense_max}: solved before any factorization");
                let values: Vec<f64> = t.iter().map(|e| e.2).collect();
                later.refactor(&values).unwrap();
                let (x, y) = (made.solve(&fv, &b).unwrap(), later.solve(&fv, &b).unwrap());
                assert_eq!(x, y, "{sym:?} {dense_max}");
                let negated: Vec<f64> = values.iter().map(|v| -v).collect();
                if sym == Symmetry::Symmetric {
                    assert!(later.refactor(&negated).is_err() && later.solve(&fv, &b).is_err(), "{dense_max}: negative definite");
                }
            }
        }
    }

    /// A system solved to a start's accuracy: [`FixedValueSolver::approximate_with`] factors a
    /// large one in single precision whatever its ordering (`with_ordering` with AMD factors in
    /// double), one [`FixedValueSolver::apply_factor`] is the exact solution to a few digits
    /// with the fixed unknowns at 0, and [`FixedValueSolver::solve_inexact`] reaches the
    /// double-precision solution to the asked accuracy.
    #[test]
    fn approximate_systems_factor_in_single_precision_and_apply_their_factor_once() {
        use crate::solvers::refined_llt::{MIXED_MIN, SINGLE_FACTORIZATIONS};
        // A weighted grid Laplacian with a small shift, the border fixed: above `MIXED_MIN`.
        let (w, h) = (160usize, 110usize);
        let n = w * h;
        let mut t: Vec<(u32, u32, f64)> = (0..n as u32).map(|v| (v, v, 1e-3)).collect();
        for j in 0..h {
            for i in 0..w {
                let v = (j * w + i) as u32;
                for u in [(i + 1 < w).then(|| v + 1), (j + 1 < h).then(|| v + w as u32)].into_iter().flatten() {
                    let wgt = 1.0 + ((v as usize * 7919) % 1000) as f64 / 1000.0;
                    t.extend([(v, v, wgt), (u, u, wgt), (u.max(v), u.min(v), -wgt)]);
                }
            }
        }
        let fixed: Vec<u32> = (0..n as u32).filter(|&v| (v as usize) < w || (v as usize) % w == 0).collect();
        assert!(n - fixed.len() >= MIXED_MIN);
        let fv: Vec<f64> = fixed.iter().map(|&v| (v as f64 * 0.01).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).cos()).collect();
        let singles = || SINGLE_FACTORIZATIONS.with(|c| c.get());
        let before = singles();
        let exact = FixedValueSolver::with_ordering(n, &t, &fixed, Symmetry::Symmetric, OrderingKind::Amd).unwrap();
        assert_eq!(singles(), before, "a system factored once with AMD is factored in double precision");
        let approx = FixedValueSolver::approximate_with(n, &t, &fixed, Symmetry::Symmetric, OrderingKind::Amd).unwrap();
        assert_eq!(singles(), before + 1, "not factored in single precision");
        let x = exact.solve(&[fv.clone()], &[b.clone()]).unwrap().pop().unwrap();
        let big = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = |y: &[f64]| x.iter().zip(y).fold(0.0f64, |m, (p, q)| m.max((p - q).abs())) / big;
        let y = approx.solve_inexact(&fv, &b, &vec![0.0; n], 1e-10).unwrap();
        assert!(diff(&y) < 1e-8, "inexact solve {:e} from the exact one", diff(&y));
        // Once, with the fixed unknowns at 0: the exact solution with zero fixed values.
        let x0 = exact.solve(&[vec![0.0; fixed.len()]], &[b.clone()]).unwrap().pop().unwrap();
        let once = approx.apply_factor(&b).unwrap();
        let big0 = x0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d0 = x0.iter().zip(&once).fold(0.0f64, |m, (p, q)| m.max((p - q).abs())) / big0;
        assert!(d0 > 0.0 && d0 < 1e-3, "one application of the single factor: {d0:e} from the exact solution");
        assert!(fixed.iter().all(|&v| once[v as usize] == 0.0), "fixed unknowns not 0");
    }

    /// The dense Cholesky refuses a symmetric indefinite matrix, like the sparse one, and a
    /// positive definite one solves to round-off on random small systems (every size up to
    /// the dense limit, random fixed unknowns).
    #[test]
    fn dense_cholesky_solves_random_small_systems_and_refuses_indefinite_ones() {
        let indefinite = [(0u32, 0u32, 1.0), (1, 1, 1.0), (1, 0, 2.0)];
        for dense_max in [0, usize::MAX] {
            let r = FixedValueSolver::new_with_dense_max(2, &indefinite, &[], Symmetry::Symmetric, dense_max, OrderingKind::Auto.into());
            assert!(matches!(r, Err(SolveError::NotPositiveDefinite)), "{dense_max}");
        }
        let mut seed = 12345u64;
        let mut rand = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for n in 2..=DENSE_MAX + 2 {
            // Q = Mᵀ M + I as lower-triangle triplets, duplicates split in two.
            let m: Vec<f64> = (0..n * n).map(|_| rand() - 0.5).collect();
            let mut t = Vec::new();
            for r in 0..n {
                for c in 0..=r {
                    let v = (0..n).map(|k| m[k * n + r] * m[k * n + c]).sum::<f64>() + if r == c { 1.0 } else { 0.0 };
                    t.push((r as u32, c as u32, 0.25 * v));
                    t.push((r as u32, c as u32, 0.75 * v));
                }
            }
            let fixed: Vec<u32> = (0..n as u32).filter(|_| rand() < 0.2).collect();
            let fv = vec![fixed.iter().map(|_| rand()).collect::<Vec<f64>>()];
            let b = vec![(0..n).map(|_| rand()).collect::<Vec<f64>>()];
            let dense = FixedValueSolver::new_with_dense_max(n, &t, &fixed, Symmetry::Symmetric, usize::MAX, OrderingKind::Auto.into()).unwrap();
            let sparse = FixedValueSolver::new_with_dense_max(n, &t, &fixed, Symmetry::Symmetric, 0, OrderingKind::Auto.into()).unwrap();
            let (xd, xs) = (dense.solve(&fv, &b).unwrap(), sparse.solve(&fv, &b).unwrap());
            for i in 0..n {
                assert!((xd[0][i] - xs[0][i]).abs() < 1e-11 * (1.0 + xs[0][i].abs()), "n {n}, {i}: {} vs {}", xd[0][i], xs[0][i]);
            }
        }
    }

    /// `solve_inexact` on a grid Laplacian with a shift: with a single-precision factor (a
    /// system refactored every iteration, large enough for mixed precision) the residual is
    /// at most the asked fraction of the guess's, and the answer is near the direct solve's
    /// (within what that fraction allows); with a double-precision factor (small system) it
    /// is the direct solve itself.
    #[test]
    fn inexact_solves_reach_the_asked_residual() {
        for (k, single) in [(140usize, true), (40, false)] {
            let n = k * k;
            let id = |i: usize, j: usize| (j * k + i) as u32;
            let mut t: Vec<(u32, u32, f64)> = (0..n as u32).map(|v| (v, v, 1e-3 * (1.0 + (v % 7) as f64))).collect();
            for j in 0..k {
                for i in 0..k {
                    let w = 1.0 + 0.5 * ((i * 3 + j) % 5) as f64;
                    for (a, b) in [(id(i, j), (i + 1 < k).then(|| id(i + 1, j))), (id(i, j), (j + 1 < k).then(|| id(i, j + 1)))] {
                        if let Some(b) = b {
                            t.extend([(a, a, w), (b, b, w), (a.max(b), a.min(b), -w)]);
                        }
                    }
                }
            }
            let fixed = [id(0, 0), id(k - 1, k / 2)];
            let fv = vec![0.5, -2.0];
            let b: Vec<f64> = (0..n).map(|i| ((i as f64) * 0.013).sin()).collect();
            let s = FixedValueSolver::new(n, &t, &fixed, Symmetry::Symmetric).unwrap();
            let precision = match &s.symbolic {
                Symbolic::Llt { state, .. } => state.lock().unwrap().factor.precision(),
                _ => None,
            };
            assert_eq!(precision, Some(if single { refined_llt::Precision::Single } else { refined_llt::Precision::Double }), "k {k}");
            let direct = s.solve(&[fv.clone()], &[b.clone()]).unwrap().pop().unwrap();
            let guess: Vec<f64> = direct.iter().enumerate().map(|(i, v)| v + 0.3 * ((i as f64) * 0.7).cos()).collect();
            // Residual of the free rows at x: b_F − (Q x)_F.
            let residual = |x: &[f64]| -> f64 {
                let mut r = b.clone();
                for &(i, j, v) in &t {
                    r[i as usize] -= v * x[j as usize];
                    if i != j {
                        r[j as usize] -= v * x[i as usize];
                    }
                }
                fixed.iter().for_each(|&c| r[c as usize] = 0.0);
                r.iter().map(|v| v * v).sum::<f64>().sqrt()
            };
            let (r_guess, r_direct) = (residual(&guess), residual(&direct));
            for relative in [1e-2, 1e-4] {
                let x = s.solve_inexact(&fv, &b, &guess, relative).unwrap();
                assert_eq!((x[fixed[0] as usize], x[fixed[1] as usize]), (fv[0], fv[1]));
                let r = residual(&x);
                if single {
                    assert!(r <= relative * r_guess * (1.0 + 1e-9), "k {k}: residual {r} for {relative} of {r_guess}");
                    assert!(r > r_direct, "k {k}: the inexact solve is not the direct one ({r} vs {r_direct})");
                } else {
                    assert_eq!(x, direct, "k {k}: a double-precision factor solves directly");
                }
            }
        }
    }

    /// 1D Dirichlet problem on a path: the solution with both ends fixed is linear.
    #[test]
    fn path_laplacian_gives_linear_interpolation_and_resolves_without_refactor() {
        let n = 11;
        let mut t = Vec::new();
        for i in 0..n - 1 {
            let (a, b) = (i as u32, (i + 1) as u32);
            // Both triangles: the symmetric solver ignores the upper one.
            t.extend([(a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)]);
        }
        for sym in [Symmetry::Symmetric, Symmetry::General] {
            let s = FixedValueSolver::new(n, &t, &[0, 10], sym).unwrap();
            let x = s.solve(&[vec![0.0, 1.0], vec![2.0, -3.0]], &[]).unwrap();
            for i in 0..n {
                let f = i as f64 / 10.0;
                assert!((x[0][i] - f).abs() < 1e-12);
                assert!((x[1][i] - (2.0 - 5.0 * f)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn refactor_reuses_the_pattern_and_singular_systems_are_errors() {
        let t = vec![(0, 0, 2.0), (1, 1, 2.0), (0, 1, -1.0), (1, 0, -1.0)];
        let mut s = FixedValueSolver::new(2, &t, &[], Symmetry::Symmetric).unwrap();
        let x = s.solve(&[vec![]], &[vec![1.0, 1.0]]).unwrap();
        assert!((x[0][0] - 1.0).abs() < 1e-12 && (x[0][1] - 1.0).abs() < 1e-12);
        s.refactor(&[4.0, 4.0, -1.0, -1.0]).unwrap();
        let x = s.solve(&[vec![]], &[vec![3.0, 3.0]]).unwrap();
        assert!((x[0][0] - 1.0).abs() < 1e-12);
        // Singular: the unanchored Laplacian.
        let r = s.refactor(&[1.0, 1.0, -1.0, -1.0]);
        assert!(r.is_err() || s.solve(&[vec![]], &[vec![1.0, -1.0]]).is_err());
    }

    /// A grid large enough for nested dissection (see `ordering::ND_MIN_SIZE`): the 5-point
    /// Laplacian with a linear function on the border reproduces it exactly inside, and AMD's
    /// size class (a small grid) agrees too; refactoring reuses the buffers.
    #[test]
    fn nested_dissection_sized_system_reproduces_linear_functions() {
        for k in [30usize, 215] {
            let id = |i: usize, j: usize| (j * k + i) as u32;
            let mut t = Vec::new();
            let mut fixed = Vec::new();
            for j in 0..k {
                for i in 0..k {
                    if i == 0 || j == 0 || i == k - 1 || j == k - 1 {
                        fixed.push(id(i, j));
                    }
                    if i + 1 < k {
                        let (a, b) = (id(i, j), id(i + 1, j));
                        t.extend([(a, a, 1.0), (b, b, 1.0), (b, a, -1.0)]);
                    }
                    if j + 1 < k {
                        let (a, b) = (id(i, j), id(i, j + 1));
                        t.extend([(a, a, 1.0), (b, b, 1.0), (b, a, -1.0)]);
                    }
                }
            }
            let n = k * k;
            assert_eq!(super::super::ordering::OrderingKind::Auto.resolve(n - fixed.len()) == super::super::ordering::OrderingKind::NestedDissection, k > 200);
            let f = |v: u32| {
                let (i, j) = ((v as usize % k) as f64, (v as usize / k) as f64);
                0.5 + i - 2.0 * j
            };
            let mut s = FixedValueSolver::new(n, &t, &fixed, Symmetry::Symmetric).unwrap();
            for scale in [1.0, 3.0] {
                let values: Vec<f64> = t.iter().map(|e| e.2 * scale).collect();
                s.refactor(&values).unwrap();
                let x = s.solve(&[fixed.iter().map(|&v| f(v)).collect()], &[]).unwrap();
                for v in 0..n as u32 {
                    assert!((x[0][v as usize] - f(v)).abs() < 1e-8 * k as f64, "k {k} vertex {v}");
                }
            }
        }
    }

    #[test]
    fn the_solver_can_be_shared_across_threads() {
        fn assert_send_sync<S: Send + Sync>() {}
        assert_send_sync::<FixedValueSolver<f64>>();
        assert_send_sync::<FixedValueSolver<faer::c64>>();
    }
}
