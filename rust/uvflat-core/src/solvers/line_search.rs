//! Flip-free line search for nonlinear UV energies.
//!
//! Paper: J. Smith, S. Schaefer, "Bijective parameterization with free boundaries", ACM TOG
//! 34(4), 2015, section 4 ("flip-free line search"); used by SLIM (Rabinovich et al. 2017) and
//! by any method whose energy is a barrier against inverted triangles (symmetric Dirichlet,
//! MIPS, scaffold energies).
//!
//! Given UVs `x` with every triangle positively oriented and a per-vertex direction `d`, the
//! signed area of a triangle along `x + t d` is a quadratic in `t`:
//!
//! ```text
//! 2·area(t) = (e1 + t d1) × (e2 + t d2) = c + b t + a t²,
//!   c = e1 × e2 > 0,  b = e1 × d2 + d1 × e2,  a = d1 × d2
//! ```
//!
//! (`e1, e2` the triangle's edge vectors from its first corner, `d1, d2` their directions).
//! Its smallest positive root is the first step at which the triangle degenerates; the minimum
//! over all triangles, [`max_flip_free_step`], bounds the step. The search then starts from
//! `min(1, safety · t_max)` and halves the step until the energy decreases
//! ([`flip_free_line_search`]); a step is accepted only if every triangle is still positively
//! oriented at it and the energy is finite, so round-off in the roots cannot let a flip
//! through.
//!
//! The API is generic: the caller gives the triangles the guarantee covers (chart triangles,
//! plus scaffold triangles for a scaffold method), the current UVs, the direction, and the
//! energy as a closure over UVs that returns `+∞` for an invalid map.

use rayon::prelude::*;

/// Smallest root `t > 0` of `c + b t + a t²` (`+∞` if there is none).
///
/// Robust form: the roots are `q / a` and `c / q` with `q = −(b + sign(b)·√(b² − 4ac)) / 2`,
/// which avoids the cancellation of the textbook formula when `|4ac| ≪ b²`; `a = 0` is the
/// linear case. Preconditions: finite inputs. A negative discriminant (no real root) gives `+∞`.
pub fn first_positive_root(a: f64, b: f64, c: f64) -> f64 {
    let mut best = f64::INFINITY;
    let mut take = |t: f64| {
        if t > 0.0 && t < best {
            best = t;
        }
    };
    if a == 0.0 {
        if b != 0.0 {
            take(-c / b);
        }
        return best;
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return best;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q != 0.0 {
        take(q / a);
        take(c / q);
    } else {
        // b = 0 and disc = 0 imply a·c = 0 with a ≠ 0: the double root t = 0.
        take(0.0);
    }
    best
}

/// Items per rayon task; shorter inputs run sequentially (same results, no task overhead on
/// the tiny charts met by the thousand).
const MIN_LEN: usize = 4096;

/// Twice the signed area of UV triangle `t`.
#[inline]
fn doubled_area(t: &[u32; 3], uv: &[[f64; 2]]) -> f64 {
    let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
    (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])
}

/// The first step `t > 0` at which some triangle of `triangles` degenerates along
/// `uv + t · dir` (`+∞` if none ever does).
///
/// Preconditions: `uv` and `dir` have one entry per vertex referenced by `triangles`, all
/// finite. Triangles that are not positively oriented at `t = 0` are skipped: no step can keep
/// them positive, and the caller's energy (which must be `+∞` on them) decides.
pub fn max_flip_free_step(triangles: &[[u32; 3]], uv: &[[f64; 2]], dir: &[[f64; 2]]) -> f64 {
    let first_flip = |t: &[u32; 3]| {
        let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
        let (d0, d1, d2) = (dir[t[0] as usize], dir[t[1] as usize], dir[t[2] as usize]);
        let e1 = [p1[0] - p0[0], p1[1] - p0[1]];
        let e2 = [p2[0] - p0[0], p2[1] - p0[1]];
        let f1 = [d1[0] - d0[0], d1[1] - d0[1]];
        let f2 = [d2[0] - d0[0], d2[1] - d0[1]];
        let c = e1[0] * e2[1] - e1[1] * e2[0];
        if c <= 0.0 || c.is_nan() {
            return f64::INFINITY;
        }
        let b = e1[0] * f2[1] - e1[1] * f2[0] + f1[0] * e2[1] - f1[1] * e2[0];
        let a = f1[0] * f2[1] - f1[1] * f2[0];
        first_positive_root(a, b, c)
    };
    if triangles.len() < MIN_LEN {
        return triangles.iter().map(first_flip).fold(f64::INFINITY, f64::min);
    }
    triangles.par_iter().with_min_len(MIN_LEN).map(first_flip).reduce(|| f64::INFINITY, f64::min)
}

/// Whether every triangle has strictly positive signed area.
pub fn all_positive(triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> bool {
    if triangles.len() < MIN_LEN {
        return triangles.iter().all(|t| doubled_area(t, uv) > 0.0);
    }
    triangles.par_iter().with_min_len(MIN_LEN).all(|t| doubled_area(t, uv) > 0.0)
}

/// Options of [`flip_free_line_search`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineSearchOptions {
    /// The first trial step is `min(max_step, safety · t_flip)`. Default 0.8 (the search
    /// never starts at a degenerate map).
    pub safety: f64,
    /// Largest step tried (the full step of a Newton-like direction). Default 1.
    pub max_step: f64,
    /// Factor applied to the step after each rejected trial. Default 0.5.
    pub shrink: f64,
    /// Most rejected trials before giving up (step 0). Default 40.
    pub max_backtracks: usize,
}

impl Default for LineSearchOptions {
    fn default() -> Self {
        LineSearchOptions { safety: 0.8, max_step: 1.0, shrink: 0.5, max_backtracks: 40 }
    }
}

/// Result of [`flip_free_line_search`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineSearchOutcome {
    /// Accepted step (0 when no trial decreased the energy; the UVs are then unchanged).
    pub step: f64,
    /// Energy at the accepted point (the initial energy when `step == 0`).
    pub energy: f64,
    /// First step at which a triangle would degenerate ([`max_flip_free_step`]).
    pub flip_step: f64,
    /// Rejected trials.
    pub backtracks: usize,
}

/// Move `uv` along `dir` by the largest trial step that keeps every triangle positively
/// oriented and strictly decreases `energy` (Smith & Schaefer 2015).
///
/// `energy0` is the energy at the current `uv` (the caller usually has it from the previous
/// iteration); `energy` evaluates the energy of any UVs and must return `+∞` (or NaN) for
/// maps it does not accept. Trials: `t = min(max_step, safety · t_flip)`, then `t · shrink`
/// repeatedly; a trial is accepted when all triangles are positive at it and its energy is
/// finite and `< energy0`.
///
/// Preconditions: `uv.len() == dir.len()`; all triangles positively oriented at `uv` (those
/// that are not are skipped by the step bound, see [`max_flip_free_step`]). Never fails: with
/// no acceptable trial (a non-descent direction, or convergence at round-off level) the step
/// is 0 and `uv` is left unchanged.
pub fn flip_free_line_search<E>(
    triangles: &[[u32; 3]],
    uv: &mut [[f64; 2]],
    dir: &[[f64; 2]],
    energy0: f64,
    energy: E,
    options: &LineSearchOptions,
) -> LineSearchOutcome
where
    E: Fn(&[[f64; 2]]) -> f64,
{
    assert_eq!(uv.len(), dir.len(), "one direction per vertex");
    let flip_step = max_flip_free_step(triangles, uv, dir);
    let mut t = options.max_step.min(options.safety * flip_step);
    let mut trial = uv.to_vec();
    let mut backtracks = 0;
    while t > 0.0 && t.is_finite() && backtracks <= options.max_backtracks {
        let step = |((q, p), d): ((&mut [f64; 2], &[f64; 2]), &[f64; 2])| *q = [p[0] + t * d[0], p[1] + t * d[1]];
        if trial.len() < MIN_LEN {
            trial.iter_mut().zip(uv.iter()).zip(dir.iter()).for_each(step);
        } else {
            trial.par_iter_mut().zip(uv.par_iter()).zip(dir.par_iter()).with_min_len(MIN_LEN).for_each(step);
        }
        if all_positive(triangles, &trial) {
            let e = energy(&trial);
            if e.is_finite() && e < energy0 {
                uv.copy_from_slice(&trial);
                return LineSearchOutcome { step: t, energy: e, flip_step, backtracks };
            }
        }
        t *= options.shrink;
        backtracks += 1;
    }
    LineSearchOutcome { step: 0.0, energy: energy0, flip_step, backtracks }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_match_the_quadratic_including_cancellation_and_linear_cases() {
        // (t − 2)(t − 3) = t² − 5t + 6: first positive root 2.
        assert!((first_positive_root(1.0, -5.0, 6.0) - 2.0).abs() < 1e-15);
        // Linear: 1 − 4t → 0.25; increasing: none.
        assert_eq!(first_positive_root(0.0, -4.0, 1.0), 0.25);
        assert_eq!(first_positive_root(0.0, 4.0, 1.0), f64::INFINITY);
        // No real root.
        assert_eq!(first_positive_root(1.0, 0.0, 1.0), f64::INFINITY);
        // Tiny a: the root near −c/b must be accurate (textbook formula loses it).
        let (a, b, c) = (1e-12, -1.0, 1e-3);
        let r = first_positive_root(a, b, c);
        let val = c + b * r + a * r * r;
        assert!(val.abs() < 1e-18, "{r} gives {val}");
        assert!((r - 1e-3).abs() < 1e-12);
        // Both roots negative: none.
        assert_eq!(first_positive_root(1.0, 5.0, 6.0), f64::INFINITY);
    }

    #[test]
    fn step_bound_is_where_the_triangle_collapses_and_search_stops_short_of_it() {
        // Unit right triangle; moving the apex straight down collapses it at t = 1.
        let tris = [[0u32, 1, 2]];
        let mut uv = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let dir = vec![[0.0, 0.0], [0.0, 0.0], [0.0, -1.0]];
        assert!((max_flip_free_step(&tris, &uv, &dir) - 1.0).abs() < 1e-15);
        // An energy favouring a flat triangle (its doubled area), infinite once flipped. The search must stop before t = 1 and keep it positive.
        let energy = |q: &[[f64; 2]]| {
            let a = doubled_area(&[0, 1, 2], q);
            if a > 0.0 {
                a
            } else {
                f64::INFINITY
            }
        };
        let e0 = energy(&uv);
        let out = flip_free_line_search(&tris, &mut uv, &dir, e0, energy, &LineSearchOptions::default());
        assert!(out.step > 0.0 && out.step <= 0.8 + 1e-15, "{out:?}");
        assert!(out.energy < e0);
        assert!(doubled_area(&tris[0], &uv) > 0.0);
        // A direction that only increases the energy gives step 0 and leaves the UVs alone.
        let before = uv.clone();
        let up = vec![[0.0, 0.0], [0.0, 0.0], [0.0, 1.0]];
        let e1 = energy(&uv);
        let out = flip_free_line_search(&tris, &mut uv, &up, e1, energy, &LineSearchOptions::default());
        assert_eq!(out.step, 0.0);
        assert_eq!(uv, before);
    }

    #[test]
    fn rotation_direction_never_degenerates_a_triangle_before_its_quadratic_root() {
        // Random-ish directions on a fan: the bound equals the first zero of the sampled areas.
        let uv = vec![[0.0, 0.0], [1.0, 0.1], [0.2, 1.0], [-0.9, 0.3], [-0.2, -1.0]];
        let tris = [[0u32, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]];
        let dir = vec![[0.3, -0.2], [-1.7, 0.4], [0.5, -2.1], [1.1, 0.9], [-0.4, 1.3]];
        let t = max_flip_free_step(&tris, &uv, &dir);
        assert!(t.is_finite() && t > 0.0);
        let at = |s: f64| -> Vec<[f64; 2]> { uv.iter().zip(&dir).map(|(p, d)| [p[0] + s * d[0], p[1] + s * d[1]]).collect() };
        assert!(all_positive(&tris, &at(t * (1.0 - 1e-9))));
        let min_area = tris.iter().map(|tr| doubled_area(tr, &at(t))).fold(f64::INFINITY, f64::min);
        assert!(min_area.abs() < 1e-12, "{min_area}");
        // A simple root: just past it the triangle is inverted.
        assert!(!all_positive(&tris, &at(t * (1.0 + 1e-6))));
    }
}
