//! Mixed-precision sparse Cholesky: factor in single precision, solve to double-precision
//! accuracy by iterative refinement.
//!
//! Papers: J. H. Wilkinson, "Rounding Errors in Algebraic Processes", 1963 (iterative
//! refinement); C. B. Moler, "Iterative refinement in floating point", JACM 14(2), 1967;
//! A. Buttari, J. Dongarra, J. Kurzak, P. Luszczek, S. Tomov, "Using mixed precision for sparse
//! matrix computations to enhance the performance while achieving 64-bit accuracy", ACM TOMS
//! 34(4), 2008.
//!
//! For a Hermitian positive definite `A` (double precision values, one triangle stored) the
//! factor `L Lᴴ ≈ A` is computed in single precision (`f32`, or `c32` for complex systems):
//! half the memory of the factor, and on large systems about half the time of the numeric
//! factorization, which is memory bound. A solve then iterates
//!
//! ```text
//! x ← x + (L Lᴴ)⁻¹ r,    r = b − A x   (r and x in double precision)
//! ```
//!
//! from `x = 0` until the normwise backward error `‖r‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞)` is below
//! [`BACKWARD_ERROR`]. Each step divides the error by about `1 / (κ(A) ε_single)`, so while
//! the condition number `κ(A)` is well below `1 / ε_single ≈ 10⁷` a few steps give the answer a
//! double-precision factorization would, to round-off.
//!
//! Failures and fallback: a matrix whose values do not fit single precision, a single
//! factorization that meets a non-positive pivot, and a refinement that stops converging
//! (a step that does not halve the residual, or more than [`MAX_STEPS`] steps: `A` too
//! ill-conditioned for single precision) all switch to a double-precision factorization of the
//! same matrix. After a second such fallback the factor stays in double precision for every
//! later factorization (a chart's systems keep their conditioning from one iteration to the
//! next, so trying single precision again would pay both factorizations each time). The first
//! fallback earns one more try ([`RETRIES`]): an iteration's first system is often the only
//! ill-conditioned one, built on a start that squeezes some triangles. On the bunny
//! subdivided twice and cut by automatic seams (one SLIM chart of 111k triangles, 112k
//! unknowns), SLIM's first system did not factor in single precision; its three Newton
//! systems did, in 0.09–0.12 s each against 0.15 s in double (`docs/performance.md`). Only a
//! matrix that double precision cannot factor either fails
//! ([`SolveError::NotPositiveDefinite`]).
//!
//! Used for systems of at least [`MIXED_MIN`] unknowns that are factored again at every
//! iteration (SLIM, MIPS, scaffold, ABF++'s reduced system): below that size the refinement's
//! extra triangular solves cost about what single precision saves. A system factored once
//! (LSCM) stays in double precision: its one factorization saves less than the refinement
//! costs (the 300k-triangle disk's LSCM took 1.3 s mixed against 0.9 s).
//!
//! Preconditions: `A` Hermitian with finite values; the symbolic analysis is of `A`'s pattern.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Index, MatMut, Par, Side};

use super::{Scalar, SolveError};

/// Systems with at least this many unknowns are factored in single precision when they are
/// refactored every iteration (see the module docs and the README's performance section).
pub const MIXED_MIN: usize = 16_000;

/// Whether a system of `n` unknowns refactored every iteration is factored in single
/// precision ([`MIXED_MIN`]).
pub fn single_pays(n: usize) -> bool {
    #[cfg(test)]
    if FORCE_DOUBLE.with(|f| f.get()) {
        return false;
    }
    n >= MIXED_MIN
}

#[cfg(test)]
thread_local! {
    /// Tests only: factor every system of this thread in double precision, so that results
    /// can be compared with the mixed-precision path.
    pub(crate) static FORCE_DOUBLE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// Tests only: single-precision factorizations done on this thread.
    pub(crate) static SINGLE_FACTORIZATIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Fallbacks to double precision after which single precision is tried again on the next
/// factorization (module docs): one.
pub const RETRIES: usize = 1;

/// Refinement stops once the normwise backward error is below this.
pub const BACKWARD_ERROR: f64 = 1e-12;

/// Most refinement steps per solve before falling back to double precision.
pub const MAX_STEPS: usize = 10;

/// Which precision holds the current factor.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// Single precision, refined.
    Single,
    /// Double precision, solved directly.
    Double,
}

/// The numeric factor of a Cholesky solver whose symbolic analysis is kept by the caller (see
/// the module docs). `T` is the double-precision scalar (`f64` or `c64`).
pub struct RefinedLlt<T: Scalar> {
    single: Vec<T::Low>,
    /// The single-precision factor is of `A / scale` (`scale = max |a_ij|`), so that small or
    /// large values neither underflow nor overflow.
    scale: f64,
    double: Vec<T>,
    precision: Option<Precision>,
    allow_single: bool,
    /// Fallbacks to double precision so far ([`RETRIES`]).
    fallbacks: usize,
    /// Refinement steps of the last solve (0 for a double-precision one).
    pub last_steps: usize,
}

impl<T: Scalar> RefinedLlt<T> {
    /// A factor that tries single precision first when `allow_single`.
    pub fn new(allow_single: bool) -> Self {
        let (single, double) = (Vec::new(), Vec::new());
        RefinedLlt { single, scale: 1.0, double, precision: None, allow_single, fallbacks: 0, last_steps: 0 }
    }

    /// The precision of the current factor (`None` before the first factorization).
    pub fn precision(&self) -> Option<Precision> {
        self.precision
    }

    /// Workspace for factorizations in either precision and solves of `cols` right-hand sides.
    pub fn scratch<I: Index>(symbolic: &SymbolicCholesky<I>, par: Par, cols: usize) -> StackReq {
        StackReq::any_of(&[Self::factor_scratch(symbolic, par), Self::solve_scratch(symbolic, par, cols)])
    }

    /// Workspace for factorizations in either precision.
    pub fn factor_scratch<I: Index>(symbolic: &SymbolicCholesky<I>, par: Par) -> StackReq {
        StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default()),
            symbolic.factorize_numeric_llt_scratch::<T::Low>(par, Default::default()),
        ])
    }

    /// Workspace for solves of `cols` right-hand sides in either precision (a fallback to
    /// double precision during a solve allocates its factorization workspace itself).
    pub fn solve_scratch<I: Index>(symbolic: &SymbolicCholesky<I>, par: Par, cols: usize) -> StackReq {
        StackReq::any_of(&[symbolic.solve_in_place_scratch::<T>(cols, par), symbolic.solve_in_place_scratch::<T::Low>(cols, par)])
    }

    /// Numeric factorization of `a` (the triangle `side` of a Hermitian matrix on the
    /// analysed pattern): single precision when allowed and possible, double otherwise.
    ///
    /// Failures: [`SolveError::NotPositiveDefinite`] when double precision meets a
    /// non-positive pivot.
    pub fn factor<I: Index>(&mut self, symbolic: &SymbolicCholesky<I>, a: SparseColMatRef<'_, I, T>, side: Side, par: Par, stack: &mut MemStack) -> Result<(), SolveError> {
        self.precision = None;
        if self.allow_single {
            let scale = a.val().iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
            let low: Option<Vec<T::Low>> = if scale > 0.0 && scale.is_finite() { a.val().iter().map(|&v| v.scale(1.0 / scale).to_low()).collect() } else { None };
            if let Some(low) = low {
                self.scale = scale;
                self.double = Vec::new();
                self.single.resize(symbolic.len_val(), T::low_zero());
                let a_low = SparseColMatRef::new(a.symbolic(), &low);
                if symbolic.factorize_numeric_llt(&mut self.single, a_low, side, Default::default(), par, stack, Default::default()).is_ok() {
                    self.precision = Some(Precision::Single);
                    #[cfg(test)]
                    SINGLE_FACTORIZATIONS.with(|c| c.set(c.get() + 1));
                    return Ok(());
                }
            }
        }
        self.factor_double(symbolic, a, side, par, stack)
    }

    /// Double-precision factorization; after more than [`RETRIES`] of them every later one is
    /// double too (module docs).
    fn factor_double<I: Index>(&mut self, symbolic: &SymbolicCholesky<I>, a: SparseColMatRef<'_, I, T>, side: Side, par: Par, stack: &mut MemStack) -> Result<(), SolveError> {
        if self.allow_single {
            self.fallbacks += 1;
            self.allow_single = self.fallbacks <= RETRIES;
        }
        self.single = Vec::new();
        self.double.resize(symbolic.len_val(), T::zero_value());
        symbolic
            .factorize_numeric_llt(&mut self.double, a, side, Default::default(), par, stack, Default::default())
            .map_err(|_| SolveError::NotPositiveDefinite)?;
        self.precision = Some(Precision::Double);
        Ok(())
    }

    /// Solve `A X = B` in place in `rhs` (one column per right-hand side) with the current
    /// factor of `a` (the same matrix as factored). A refinement that stops converging
    /// refactors `a` in double precision and solves again (see the module docs).
    pub fn solve_in_place<I: Index>(
        &mut self,
        symbolic: &SymbolicCholesky<I>,
        a: SparseColMatRef<'_, I, T>,
        side: Side,
        mut rhs: MatMut<'_, T>,
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), SolveError> {
        self.last_steps = 0;
        match self.precision {
            None => return Err(SolveError::NotPositiveDefinite),
            Some(Precision::Double) => {
                LltRef::new(symbolic, &self.double).solve_in_place_with_conj(faer::Conj::No, rhs.as_mut(), par, stack);
                return Ok(());
            }
            Some(Precision::Single) => {}
        }
        let n = rhs.nrows();
        let a_norm = inf_norm(a);
        let mut solved = Vec::with_capacity(rhs.ncols());
        for col in 0..rhs.ncols() {
            let b: Vec<T> = (0..n).map(|i| rhs[(i, col)]).collect();
            match self.refine(symbolic, a, a_norm, &b, par, stack) {
                Some(x) => solved.push(x),
                None => {
                    // Too ill-conditioned for single precision: double, directly, every column
                    // (in a workspace of its own: `stack` may be sized for solves only).
                    let req = symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default());
                    let mut mem = MemBuffer::try_new(req).map_err(|e| SolveError::Other(format!("{e:?}")))?;
                    self.factor_double(symbolic, a, side, par, MemStack::new(&mut mem))?;
                    LltRef::new(symbolic, &self.double).solve_in_place_with_conj(faer::Conj::No, rhs.as_mut(), par, stack);
                    return Ok(());
                }
            }
        }
        for (col, x) in solved.into_iter().enumerate() {
            for (i, v) in x.into_iter().enumerate() {
                rhs[(i, col)] = v;
            }
        }
        Ok(())
    }

    /// `out = (L Lᴴ)⁻¹ r` with the current factor, in its precision, without refinement: the
    /// preconditioner of [`RefinedLlt::solve_inexact`]. Failures:
    /// [`SolveError::NotPositiveDefinite`] before any successful factorization.
    pub(crate) fn precondition<I: Index>(
        &self,
        symbolic: &SymbolicCholesky<I>,
        r: &[T],
        out: &mut [T],
        par: Par,
        stack: &mut MemStack,
    ) -> Result<(), SolveError> {
        let n = r.len();
        match self.precision {
            None => Err(SolveError::NotPositiveDefinite),
            Some(Precision::Double) => {
                out.copy_from_slice(r);
                LltRef::new(symbolic, &self.double).solve_in_place_with_conj(faer::Conj::No, MatMut::from_column_major_slice_mut(out, n, 1), par, stack);
                Ok(())
            }
            Some(Precision::Single) => {
                let r_norm = r.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
                if r_norm == 0.0 || !r_norm.is_finite() {
                    out.copy_from_slice(r);
                    return Ok(());
                }
                let mut d: Vec<T::Low> = r.iter().map(|v| v.scale(1.0 / r_norm).to_low().unwrap_or(T::low_zero())).collect();
                LltRef::new(symbolic, &self.single).solve_in_place_with_conj(faer::Conj::No, MatMut::from_column_major_slice_mut(&mut d, n, 1), par, stack);
                let back = r_norm / self.scale;
                for (o, di) in out.iter_mut().zip(d) {
                    *o = T::from_low(di).scale(back);
                }
                Ok(())
            }
        }
    }

    /// Solve `A x = b` to the accuracy of an inexact Newton step, from the guess in `x`:
    /// with a single-precision factor, conjugate gradients preconditioned by it
    /// ([`super::conjugate_gradient`]) until the residual is `relative` times its value at
    /// the guess, in at most [`MAX_STEPS`] steps; with a double-precision one, directly.
    /// Returns whether `x` holds such a solution; when not (no convergence, a breakdown, a
    /// non-finite value), [`RefinedLlt::solve_in_place`] is the way to the answer.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_inexact<I: Index>(&self, symbolic: &SymbolicCholesky<I>, a: SparseColMatRef<'_, I, T>, b: &[T], x: &mut [T], relative: f64, par: Par, stack: &mut MemStack) -> Result<bool, SolveError> {
        match self.precision {
            None => Err(SolveError::NotPositiveDefinite),
            Some(Precision::Double) => {
                self.precondition(symbolic, b, x, par, stack)?;
                Ok(x.iter().all(|v| v.finite()))
            }
            Some(Precision::Single) => {
                let mut failed = None;
                let outcome = super::conjugate_gradient::solve(
                    b,
                    x,
                    relative,
                    MAX_STEPS,
                    |v, out| {
                        out.iter_mut().for_each(|o| *o = T::zero_value());
                        sub_hermitian_product(a, v, out);
                        out.iter_mut().for_each(|o| *o = T::zero_value() - *o);
                    },
                    |r, out| {
                        if let Err(e) = self.precondition(symbolic, r, out, par, stack) {
                            failed = Some(e);
                        }
                    },
                );
                if let Some(e) = failed {
                    return Err(e);
                }
                Ok(matches!(outcome, super::conjugate_gradient::Cg::Converged(_)) && x.iter().all(|v| v.finite()))
            }
        }
    }

    /// Iterative refinement of one right-hand side; `None` when it stops converging.
    fn refine<I: Index>(&mut self, symbolic: &SymbolicCholesky<I>, a: SparseColMatRef<'_, I, T>, a_norm: f64, b: &[T], par: Par, stack: &mut MemStack) -> Option<Vec<T>> {
        let n = b.len();
        let b_norm = b.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
        let mut x = vec![T::zero_value(); n];
        let mut r = b.to_vec();
        let mut r_norm = b_norm;
        let mut d = vec![T::low_zero(); n];
        let llt = LltRef::new(symbolic, &self.single);
        for step in 0..=MAX_STEPS {
            if !r_norm.is_finite() {
                return None;
            }
            let x_norm = x.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
            if r_norm <= BACKWARD_ERROR * (a_norm * x_norm + b_norm) {
                self.last_steps += step;
                return Some(x);
            }
            if step == MAX_STEPS {
                return None;
            }
            // (A / scale)⁻¹ (r / ‖r‖) in single precision, both scaled to about 1.
            for (di, ri) in d.iter_mut().zip(&r) {
                *di = ri.scale(1.0 / r_norm).to_low().unwrap_or(T::low_zero());
            }
            llt.solve_in_place_with_conj(faer::Conj::No, MatMut::from_column_major_slice_mut(&mut d, n, 1), par, stack);
            let back = r_norm / self.scale;
            for (xi, di) in x.iter_mut().zip(&d) {
                *xi += T::from_low(*di).scale(back);
            }
            r.copy_from_slice(b);
            sub_hermitian_product(a, &x, &mut r);
            let next = r.iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
            if step > 0 && !(next <= 0.5 * r_norm) {
                return None;
            }
            r_norm = next;
        }
        None
    }
}

/// `r −= A x` for the Hermitian `A` given by one triangle (either) with its diagonal.
fn sub_hermitian_product<I: Index, T: Scalar>(a: SparseColMatRef<'_, I, T>, x: &[T], r: &mut [T]) {
    let s: SymbolicSparseColMatRef<'_, I> = a.symbolic();
    let val = a.val();
    for c in 0..s.ncols() {
        let xc = x[c];
        let mut acc = T::zero_value();
        for k in s.col_range(c) {
            let row = s.row_idx()[k].zx();
            let v = val[k];
            r[row] -= v * xc;
            if row != c {
                acc += v.conjugate() * x[row];
            }
        }
        r[c] -= acc;
    }
}

/// `‖A‖∞` of the Hermitian `A` given by one triangle: the largest absolute row sum.
fn inf_norm<I: Index, T: Scalar>(a: SparseColMatRef<'_, I, T>) -> f64 {
    let s = a.symbolic();
    let mut rows = vec![0.0f64; s.nrows()];
    for c in 0..s.ncols() {
        for k in s.col_range(c) {
            let row = s.row_idx()[k].zx();
            let m = a.val()[k].magnitude();
            rows[row] += m;
            if row != c {
                rows[c] += m;
            }
        }
    }
    rows.into_iter().fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::MemBuffer;
    use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymmetricOrdering};
    use faer::sparse::SymbolicSparseColMat;

    /// Lower triangle of `scale · (L + shift · I)` for the `w × h` grid graph's Laplacian `L`
    /// with edge weights in [1, 2), as compressed columns; `entry(value, edge number)` makes
    /// an off-diagonal entry (with an imaginary part for complex scalars).
    fn grid<T: Scalar>(w: usize, h: usize, shift: f64, scale: f64, entry: impl Fn(f64, usize) -> T) -> (SymbolicSparseColMat<usize>, Vec<T>) {
        let n = w * h;
        let mut cols: Vec<Vec<(usize, T)>> = vec![Vec::new(); n];
        let mut diag = vec![shift; n];
        let mut k = 0;
        for j in 0..h {
            for i in 0..w {
                let v = j * w + i;
                for u in [(i + 1 < w).then(|| v + 1), (j + 1 < h).then(|| v + w)].into_iter().flatten() {
                    let wgt = 1.0 + ((k * 7919) % 1000) as f64 / 1000.0;
                    k += 1;
                    diag[v] += wgt;
                    diag[u] += wgt;
                    cols[v].push((u, entry(-wgt * scale, k)));
                }
            }
        }
        let (mut col_ptr, mut row_idx, mut val) = (vec![0usize], Vec::new(), Vec::new());
        for v in 0..n {
            row_idx.push(v);
            val.push(T::from_real(diag[v] * scale));
            for &(u, x) in &cols[v] {
                row_idx.push(u);
                val.push(x);
            }
            col_ptr.push(row_idx.len());
        }
        (SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx), val)
    }

    /// Solve with single precision allowed and with double only; returns the precision used
    /// and the largest difference relative to the largest entry of the double solution.
    fn compare<T: Scalar>(a: &SymbolicSparseColMat<usize>, val: &[T], b: &[T]) -> (Option<Precision>, f64, usize) {
        let n = a.nrows();
        let sym = factorize_symbolic_cholesky(a.as_ref(), Side::Lower, SymmetricOrdering::Amd, Default::default()).unwrap();
        let mut mem = MemBuffer::new(RefinedLlt::<T>::scratch(&sym, Par::Seq, 1));
        let mat = SparseColMatRef::new(a.as_ref(), val);
        let mut out = Vec::new();
        let mut precision = None;
        let mut steps = 0;
        for allow in [true, false] {
            let mut f = RefinedLlt::<T>::new(allow);
            f.factor(&sym, mat, Side::Lower, Par::Seq, MemStack::new(&mut mem)).unwrap();
            let mut x = b.to_vec();
            f.solve_in_place(&sym, mat, Side::Lower, MatMut::from_column_major_slice_mut(&mut x, n, 1), Par::Seq, MemStack::new(&mut mem)).unwrap();
            if allow {
                precision = f.precision();
                steps = f.last_steps;
            }
            out.push(x);
        }
        let big = out[1].iter().fold(0.0f64, |m, v| m.max(v.magnitude()));
        let diff = out[0].iter().zip(&out[1]).fold(0.0f64, |m, (&p, &q)| {
            let mut d = p;
            d -= q;
            m.max(d.magnitude())
        });
        (precision, diff / big, steps)
    }

    fn rhs<T: Scalar>(n: usize, entry: impl Fn(f64, usize) -> T) -> Vec<T> {
        (0..n).map(|i| entry(((i * 37) % 101) as f64 / 50.0 - 1.0, i)).collect()
    }

    /// A well-conditioned system is factored in single precision and refined to the double
    /// solution; tiny or huge values (outside single precision's range) are scaled, not lost;
    /// complex Hermitian systems too.
    #[test]
    fn single_precision_refines_to_the_double_solution() {
        let real = |x: f64, _k: usize| x;
        for scale in [1.0, 1e-45, 1e45] {
            let (a, val) = grid(40, 30, 1e-3, scale, real);
            let (precision, diff, steps) = compare(&a, &val, &rhs(a.nrows(), real));
            assert_eq!(precision, Some(Precision::Single), "scale {scale}");
            assert!(diff < 1e-9, "scale {scale}: {diff}");
            assert!(steps >= 1, "a refinement step at least");
        }
        let complex = |x: f64, k: usize| faer::c64::new(x, 0.1 * x * ((k % 3) as f64 - 1.0));
        let (a, val) = grid(30, 30, 1e-2, 1.0, complex);
        let (precision, diff, _) = compare(&a, &val, &rhs(a.nrows(), complex));
        assert_eq!(precision, Some(Precision::Single));
        assert!(diff < 1e-9, "complex: {diff}");
    }

    /// Too ill-conditioned for single precision (κ ≈ 10¹², the refinement diverges or the
    /// single factorization fails): double precision takes over and gives the same answer.
    #[test]
    fn ill_conditioned_systems_fall_back_to_double_precision() {
        let real = |x: f64, _k: usize| x;
        let (a, val) = grid(40, 40, 1e-10, 1.0, real);
        let (precision, diff, _) = compare(&a, &val, &rhs(a.nrows(), real));
        assert_eq!(precision, Some(Precision::Double));
        assert!(diff < 1e-12, "{diff}");
        // After one fallback the next factorization tries single precision again (a well
        // conditioned matrix on the same pattern gets it); after a second, never again.
        let (_, good) = grid(40, 40, 1e-3, 1.0, real);
        let sym = factorize_symbolic_cholesky(a.as_ref(), Side::Lower, SymmetricOrdering::Amd, Default::default()).unwrap();
        let mut mem = MemBuffer::new(RefinedLlt::<f64>::scratch(&sym, Par::Seq, 1));
        let (ill, good) = (SparseColMatRef::new(a.as_ref(), &val), SparseColMatRef::new(a.as_ref(), &good));
        let mut f = RefinedLlt::<f64>::new(true);
        let mut factor_and_solve = |f: &mut RefinedLlt<f64>, mat: SparseColMatRef<'_, usize, f64>| {
            f.factor(&sym, mat, Side::Lower, Par::Seq, MemStack::new(&mut mem)).unwrap();
            let mut x = rhs(a.nrows(), real);
            let x = MatMut::from_column_major_slice_mut(&mut x, a.nrows(), 1);
            f.solve_in_place(&sym, mat, Side::Lower, x, Par::Seq, MemStack::new(&mut mem)).unwrap();
            f.precision()
        };
        assert_eq!(factor_and_solve(&mut f, ill), Some(Precision::Double));
        assert_eq!(factor_and_solve(&mut f, good), Some(Precision::Single), "single precision tried again");
        assert_eq!(factor_and_solve(&mut f, ill), Some(Precision::Double));
        let before = SINGLE_FACTORIZATIONS.with(|c| c.get());
        assert_eq!(factor_and_solve(&mut f, good), Some(Precision::Double), "a second fallback is for good");
        assert_eq!(SINGLE_FACTORIZATIONS.with(|c| c.get()), before, "single precision tried a third time");
    }

    /// The iterative methods give the same maps with their large systems factored in single
    /// precision as in double (a bumpy 100 × 100 grid: 20,000 SLIM / MIPS unknowns, 19,208
    /// ABF++ reduced rows, both above [`MIXED_MIN`]); SLIM and MIPS, whose Newton steps are
    /// solved inexactly in single precision, nearly the same maps at no higher energy.
    #[test]
    fn iterative_methods_give_the_same_maps_in_mixed_precision() {
        use crate::methods::{abf, mips, scaffold, slim};
        let chart = crate::charts::bumpy_grid_chart(100);
        assert!(2 * chart.positions.len() >= MIXED_MIN);
        type Run<'a> = Box<dyn Fn() -> Vec<[f64; 2]> + 'a>;
        let runs: Vec<(&str, Run)> = vec![
            ("slim", Box::new(|| slim::solve(&chart, &[], &Default::default()).unwrap().uv)),
            ("mips", Box::new(|| mips::solve(&chart, &[], &Default::default()).unwrap().uv)),
            ("scaffold", Box::new(|| scaffold::solve(&chart, &[], &Default::default()).unwrap().uv)),
            ("abf", Box::new(|| abf::solve(&chart, &[], &Default::default()).unwrap().uv)),
        ];
        for (name, run) in runs {
            SINGLE_FACTORIZATIONS.with(|c| c.set(0));
            let mixed = run();
            let singles = SINGLE_FACTORIZATIONS.with(|c| c.get());
            SINGLE_FACTORIZATIONS.with(|c| c.set(0));
            FORCE_DOUBLE.with(|f| f.set(true));
            let double = run();
            FORCE_DOUBLE.with(|f| f.set(false));
            assert!(singles > 0, "{name}: no single-precision factorization");
            assert_eq!(SINGLE_FACTORIZATIONS.with(|c| c.get()), 0, "{name}: forced double precision");
            let extent = double.iter().fold(0.0f64, |m, p| m.max(p[0].abs()).max(p[1].abs()));
            let diff = mixed.iter().zip(&double).fold(0.0f64, |m, (a, b)| m.max((a[0] - b[0]).abs()).max((a[1] - b[1]).abs()));
            // SLIM and MIPS solve Newton steps inexactly (`slim::INEXACT`): their
            // maps agree less closely, and their energies must not be higher.
            let inexact = matches!(name, "slim" | "mips");
            let bound = if inexact { 1e-4 } else { 1e-7 };
            assert!(diff <= bound * extent, "{name}: maps differ by {diff:.3e} of {extent:.3e}");
            if inexact {
                let ops = crate::methods::nonlinear::TriangleOperators::new(&chart.positions, &chart.triangles);
                let energy = |uv: &[[f64; 2]]| {
                    let e = crate::methods::nonlinear::energy::symmetric_dirichlet;
                    let m = crate::methods::nonlinear::energy::mips_energy;
                    if name == "mips" { m(&ops, &chart.triangles, uv) } else { e(&ops, &chart.triangles, uv) }
                };
                let (em, ed) = (energy(&mixed), energy(&double));
                assert!(em <= ed * (1.0 + 1e-6), "{name}: energy {em} mixed against {ed} double");
            }
        }
    }

    /// Between the two: a system too ill-conditioned for iterative refinement from a
    /// single-precision factor (it stops converging and refactors in double precision) is
    /// still solved to a tight accuracy by conjugate gradients preconditioned by that factor
    /// ([`RefinedLlt::solve_inexact`], SLIM's proxy steps), in single precision and to the
    /// double-precision answer.
    #[test]
    fn conjugate_gradients_reach_what_refinement_gives_up_on() {
        let real = |x: f64, _k: usize| x;
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for shift in [1e-7, 1e-8] {
            let (a, val) = grid(60, 60, shift, 1.0, real);
            let b = rhs(a.nrows(), real);
            let (precision, _, _) = compare(&a, &val, &b);
            assert_eq!(precision, Some(Precision::Double), "shift {shift:e}: refinement kept single precision");
            let sym = factorize_symbolic_cholesky(a.as_ref(), Side::Lower, SymmetricOrdering::Amd, Default::default());
            let sym = sym.unwrap();
            let mut mem = MemBuffer::new(RefinedLlt::<f64>::scratch(&sym, Par::Seq, 1));
            let mat = SparseColMatRef::new(a.as_ref(), &val);
            let mut f = RefinedLlt::<f64>::new(true);
            f.factor(&sym, mat, Side::Lower, Par::Seq, MemStack::new(&mut mem)).unwrap();
            let mut x = vec![0.0; a.nrows()];
            let solved = f.solve_inexact(&sym, mat, &b, &mut x, 1e-10, Par::Seq, MemStack::new(&mut mem)).unwrap();
            assert!(solved, "shift {shift:e}: conjugate gradients did not converge");
            assert_eq!(f.precision(), Some(Precision::Single), "shift {shift:e}");
            let mut r = b.clone();
            sub_hermitian_product(mat, &x, &mut r);
            assert!(norm(&r) <= 1.01e-10 * norm(&b), "shift {shift:e}: residual {:.3e} of {:.3e}", norm(&r), norm(&b));
            // The double-precision answer, by a double factorization.
            let mut d = RefinedLlt::<f64>::new(false);
            d.factor(&sym, mat, Side::Lower, Par::Seq, MemStack::new(&mut mem)).unwrap();
            let mut y = b.clone();
            let y_mat = MatMut::from_column_major_slice_mut(&mut y, a.nrows(), 1);
            d.solve_in_place(&sym, mat, Side::Lower, y_mat, Par::Seq, MemStack::new(&mut mem)).unwrap();
            let diff = x.iter().zip(&y).map(|(p, q)| (p - q) * (p - q)).sum::<f64>().sqrt();
            assert!(diff <= 1e-7 * norm(&y), "shift {shift:e}: {:.3e} from the double solution", diff / norm(&y));
        }
    }

    /// A matrix that is not positive definite fails in both precisions.
    #[test]
    fn indefinite_matrices_are_refused() {
        let (a, mut val) = grid(10, 10, 0.0, 1.0, |x: f64, _k: usize| x);
        val[0] = -1.0;
        let sym = factorize_symbolic_cholesky(a.as_ref(), Side::Lower, SymmetricOrdering::Amd, Default::default()).unwrap();
        let mut mem = MemBuffer::new(RefinedLlt::<f64>::scratch(&sym, Par::Seq, 1));
        let mut f = RefinedLlt::<f64>::new(true);
        let r = f.factor(&sym, SparseColMatRef::new(a.as_ref(), &val), Side::Lower, Par::Seq, MemStack::new(&mut mem));
        assert_eq!(r, Err(SolveError::NotPositiveDefinite));
        assert_eq!(f.precision(), None);
        let mut x = vec![1.0; 100];
        let s = f.solve_in_place(&sym, SparseColMatRef::new(a.as_ref(), &val), Side::Lower, MatMut::from_column_major_slice_mut(&mut x, 100, 1), Par::Seq, MemStack::new(&mut mem));
        assert!(s.is_err());
    }
}
