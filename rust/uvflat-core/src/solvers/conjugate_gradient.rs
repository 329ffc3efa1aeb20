//! Preconditioned conjugate gradients for Hermitian positive definite systems.
//!
//! Papers: M. R. Hestenes, E. Stiefel, "Methods of conjugate gradients for solving linear
//! systems", J. Res. NBS 49(6), 1952; the preconditioned form as in Y. Saad, "Iterative
//! Methods for Sparse Linear Systems", 2nd ed., SIAM 2003, algorithm 9.1.
//!
//! Used with the Cholesky factor of an earlier matrix of the same pattern as the
//! preconditioner (the iterative methods' global steps, whose matrices change little from one
//! iteration to the next): when the factor is close to the matrix, a few steps reach the
//! accuracy a Newton-type step needs, for the cost of a few triangular solves instead of a
//! numeric factorization.
//!
//! Preconditions: `A` Hermitian positive definite, the preconditioner Hermitian positive
//! definite (up to the rounding of a single-precision factor). Failures: a non-positive or
//! non-finite curvature `pᴴ A p` or preconditioned residual `rᴴ M⁻¹ r` ([`Cg::Breakdown`]:
//! `A` or the preconditioner is not positive definite, or the values overflowed).

use super::Scalar;

/// How a run of [`solve`] ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cg {
    /// The residual norm fell to the asked fraction of its start, in this many steps (0: the
    /// guess solved the system exactly).
    Converged(usize),
    /// The step limit came first; the iterate is the last one (still an improvement, in the
    /// `A`-norm, on the guess).
    StepLimit,
    /// A non-positive or non-finite curvature or residual: the iterate is not usable.
    Breakdown,
}

/// `Σ conj(a_i) b_i`, real part (the inner products of CG are real for Hermitian operators).
fn dot<T: Scalar>(a: &[T], b: &[T]) -> f64 {
    a.iter().zip(b).map(|(&x, &y)| (x.conjugate() * y).real()).sum()
}

/// Solve `A x = b` from the guess in `x` (overwritten by the iterate) until the residual
/// `‖b − A x‖₂` is at most `relative` times its value at the guess, in at most `max_steps`
/// steps. `apply(v, out)` writes `A v` into `out`; `precondition(r, out)` writes `M⁻¹ r` into
/// `out`. The Euclidean residual is tested before each preconditioner application, so a run
/// of k steps applies the preconditioner k times and `A` k + 1 times.
pub fn solve<T: Scalar>(
    b: &[T],
    x: &mut [T],
    relative: f64,
    max_steps: usize,
    mut apply: impl FnMut(&[T], &mut [T]),
    mut precondition: impl FnMut(&[T], &mut [T]),
) -> Cg {
    let n = b.len();
    let mut r = vec![T::zero_value(); n];
    apply(x, &mut r);
    for (ri, &bi) in r.iter_mut().zip(b) {
        *ri = bi - *ri;
    }
    let r0 = dot(&r, &r);
    if !r0.is_finite() {
        return Cg::Breakdown;
    }
    let goal = relative * relative * r0;
    if r0 == 0.0 {
        return Cg::Converged(0);
    }
    let mut z = vec![T::zero_value(); n];
    precondition(&r, &mut z);
    let mut rz = dot(&r, &z);
    let mut p = z.clone();
    let mut q = vec![T::zero_value(); n];
    for step in 1..=max_steps {
        if !(rz > 0.0) || !rz.is_finite() {
            return Cg::Breakdown;
        }
        apply(&p, &mut q);
        let curvature = dot(&p, &q);
        if !(curvature > 0.0) || !curvature.is_finite() {
            return Cg::Breakdown;
        }
        let alpha = rz / curvature;
        for i in 0..n {
            x[i] += p[i].scale(alpha);
            r[i] -= q[i].scale(alpha);
        }
        let rr = dot(&r, &r);
        if !rr.is_finite() {
            return Cg::Breakdown;
        }
        if rr <= goal {
            return Cg::Converged(step);
        }
        if step == max_steps {
            break;
        }
        precondition(&r, &mut z);
        let next = dot(&r, &z);
        let beta = next / rz;
        rz = next;
        for i in 0..n {
            p[i] = z[i] + p[i].scale(beta);
        }
    }
    Cg::StepLimit
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1D Laplacian with a shift, as a matrix-free operator.
    fn apply_path(shift: f64) -> impl Fn(&[f64], &mut [f64]) {
        move |v: &[f64], out: &mut [f64]| {
            let n = v.len();
            for i in 0..n {
                let left = if i > 0 { v[i - 1] } else { 0.0 };
                let right = if i + 1 < n { v[i + 1] } else { 0.0 };
                out[i] = (2.0 + shift) * v[i] - left - right;
            }
        }
    }

    /// Without a preconditioner CG solves an n × n system in at most n steps (exact
    /// arithmetic; here to round-off); with the exact inverse as preconditioner in one step;
    /// a complex Hermitian system converges like its real counterpart.
    #[test]
    fn cg_converges_in_at_most_n_steps_and_in_one_with_the_exact_preconditioner() {
        let n = 40;
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin() + 0.1).collect();
        let a = apply_path(0.01);
        let mut x = vec![0.0; n];
        let out = solve(&b, &mut x, 1e-12, n + 5, &a, |r, z| z.copy_from_slice(r));
        let Cg::Converged(steps) = out else { panic!("{out:?}") };
        assert!(steps <= n, "{steps} steps");
        let mut ax = vec![0.0; n];
        a(&x, &mut ax);
        let err = ax.iter().zip(&b).map(|(p, q)| (p - q).abs()).fold(0.0, f64::max);
        assert!(err < 1e-9, "residual {err}");
        // The exact inverse (the solution just found, as a dense solve by columns is overkill:
        // precondition by solving with CG itself to round-off).
        let exact = |r: &[f64], z: &mut [f64]| {
            z.iter_mut().for_each(|v| *v = 0.0);
            assert!(matches!(solve(r, z, 1e-14, 4 * n, &a, |s, t| t.copy_from_slice(s)), Cg::Converged(_)));
        };
        let mut y = vec![0.0; n];
        assert_eq!(solve(&b, &mut y, 1e-8, 10, &a, exact), Cg::Converged(1));
        // Complex: (1 + 2i) b against the same real operator gives (1 + 2i) x.
        let s = faer::c64::new(1.0, 2.0);
        let bc: Vec<faer::c64> = b.iter().map(|&v| s * faer::c64::new(v, 0.0)).collect();
        let mut xc = vec![faer::c64::new(0.0, 0.0); n];
        let ac = |v: &[faer::c64], out: &mut [faer::c64]| {
            let (re, im): (Vec<f64>, Vec<f64>) = v.iter().map(|z| (z.re, z.im)).unzip();
            let (mut ore, mut oim) = (vec![0.0; n], vec![0.0; n]);
            a(&re, &mut ore);
            a(&im, &mut oim);
            for i in 0..n {
                out[i] = faer::c64::new(ore[i], oim[i]);
            }
        };
        assert!(matches!(solve(&bc, &mut xc, 1e-12, n + 5, ac, |r, z| z.copy_from_slice(r)), Cg::Converged(_)));
        for i in 0..n {
            let d = xc[i] - s * faer::c64::new(x[i], 0.0);
            assert!(d.re.hypot(d.im) < 1e-8, "{i}");
        }
    }

    /// A step limit is reported as such; an indefinite operator breaks down instead of
    /// returning garbage; an exact guess costs no step.
    #[test]
    fn limits_breakdowns_and_exact_guesses_are_reported() {
        let n = 50;
        let b: Vec<f64> = (0..n).map(|i| 1.0 + (i % 3) as f64).collect();
        let mut x = vec![0.0; n];
        assert_eq!(solve(&b, &mut x, 1e-12, 3, apply_path(0.0), |r, z| z.copy_from_slice(r)), Cg::StepLimit);
        let mut y = vec![0.0; n];
        assert_eq!(solve(&b, &mut y, 1e-8, 100, apply_path(-3.0), |r, z| z.copy_from_slice(r)), Cg::Breakdown);
        let zero = vec![0.0; n];
        let mut z = vec![0.0; n];
        assert_eq!(solve(&zero, &mut z, 1e-3, 10, apply_path(0.5), |r, t| t.copy_from_slice(r)), Cg::Converged(0));
        assert_eq!(z, zero);
    }
}
