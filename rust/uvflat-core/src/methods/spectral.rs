//! Spectral conformal parameterization.
//!
//! Paper: P. Mullen, Y. Tong, P. Alliez, M. Desbrun, "Spectral Conformal Parameterization",
//! SGP 2008. Minimise the LSCM energy `xᵀ Q x` subject to `xᵀ B x = 1` and `x` B-orthogonal
//! to the constant maps, with `B` the boundary mass (half the incident boundary edge lengths
//! at each boundary vertex): the Fiedler vector of `Q x = λ B x`. No pins are needed, so the
//! boundary is free of the arbitrary choice LSCM makes.
//!
//! Solved by inverse iteration on one sparse Cholesky factorization of `Q + εB` (ε small and
//! relative to Q's diagonal): the shifted pencil has exactly the same eigenvectors, and
//! B-orthogonality to the constants is preserved by the iteration. Converged when two
//! successive B-normalised iterates differ by less than `tolerance` up to a rotation of the
//! plane (the smallest eigenvalue comes as a rotation pair).
//!
//! Preconditions: a disk chart (holes allowed: all loops count as boundary). Pins: two or
//! more pinned vertices at distinct UVs make the chart an LSCM solve with those pins (the
//! report says so); one pin translates the result onto it. Failures: the factorization fails
//! even with a larger shift, or the iteration produces non-finite values.

use super::{chart_angles, lscm, ChartFailure, ChartSolution, SpectralOptions};
use crate::charts::Chart;
use crate::geometry::{norm, sub};
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};

/// Map one chart.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &SpectralOptions) -> Result<ChartSolution, ChartFailure> {
    let angles = chart_angles(&chart.positions, &chart.triangles);
    if lscm::pins_span(pins) {
        let (uv, _) = lscm::solve_with_angles(chart, &angles, pins)?;
        let mut s = ChartSolution::direct(uv);
        s.note = Some("pinned chart: solved as LSCM with the pins (spectral takes no pins)".into());
        return Ok(s);
    }
    let n = chart.positions.len();
    let m = 2 * n;
    let q = lscm::conformal_triplets(&chart.triangles, &angles);
    // Boundary mass.
    let mut b = vec![0.0; m];
    for lp in &chart.boundary_loops {
        for i in 0..lp.len() {
            let (a, c) = (lp[i] as usize, lp[(i + 1) % lp.len()] as usize);
            let l = 0.5 * norm(sub(chart.positions[c], chart.positions[a]));
            for k in [a, c] {
                b[2 * k] += l;
                b[2 * k + 1] += l;
            }
        }
    }
    let bsum: f64 = b.iter().sum();
    if !(bsum > 0.0) {
        return Err(ChartFailure("spectral: the chart's boundary has zero length".into()));
    }
    let mut diag = vec![0.0; m];
    for &(i, j, v) in &q {
        if i == j {
            diag[i as usize] += v;
        }
    }
    let mean_diag = diag.iter().sum::<f64>() / m as f64;
    // Shift by a multiple of B: (Q + εB) x = μ B x has exactly the eigenvectors of Q x = λ B x
    // (μ = λ + ε) and is positive definite, since no conformal map vanishes on the boundary.
    let mean_b = bsum / m as f64;
    let mut factor = None;
    for rel in [1e-8, 1e-6, 1e-4] {
        let eps = rel * mean_diag.max(f64::MIN_POSITIVE) / mean_b;
        let mut k = q.clone();
        k.extend((0..m as u32).filter(|&i| b[i as usize] > 0.0).map(|i| (i, i, eps * b[i as usize])));
        if let Ok(f) = FixedValueSolver::with_ordering(m, &k, &[], Symmetry::Symmetric, OrderingKind::Amd) {
            factor = Some(f);
            break;
        }
    }
    let factor = factor.ok_or_else(|| ChartFailure("spectral: the conformal energy matrix could not be factored".into()))?;

    // B-orthogonal projection away from the constant maps, then B-normalisation.
    let project = |x: &mut [f64]| {
        for c in 0..2 {
            let (mut s, mut w) = (0.0, 0.0);
            for i in 0..n {
                s += b[2 * i + c] * x[2 * i + c];
                w += b[2 * i + c];
            }
            let mean = s / w;
            for i in 0..n {
                x[2 * i + c] -= mean;
            }
        }
        let nb: f64 = x.iter().zip(&b).map(|(a, w)| a * a * w).sum::<f64>().sqrt();
        if nb > 0.0 {
            for a in x.iter_mut() {
                *a /= nb;
            }
        }
        nb
    };
    // Start from the chart's projection onto the plane of its two longest bounding-box axes.
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &chart.positions {
        for d in 0..3 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &c| (hi[c] - lo[c]).total_cmp(&(hi[a] - lo[a])));
    let mut x: Vec<f64> = chart.positions.iter().flat_map(|p| [p[axes[0]], p[axes[1]]]).collect();
    project(&mut x);
    // Converged when the B-normalised iterate stops moving. (The Rayleigh quotient converges
    // quadratically faster than the vector and is pure round-off on developable charts, whose
    // λ is 0, so it is no stopping test.)
    let mut iterations = 0;
    let mut change = f64::INFINITY;
    for it in 0..options.max_iterations {
        if crate::progress::cancelled() {
            break; // the unwrap discards this chart
        }
        iterations = it + 1;
        let rhs: Vec<f64> = x.iter().zip(&b).map(|(a, w)| a * w).collect();
        let y = factor.solve(&[vec![]], &[rhs])?;
        let mut next = y.into_iter().next().unwrap();
        if !(project(&mut next) > 0.0) {
            return Err(ChartFailure("spectral: inverse iteration collapsed".into()));
        }
        // Distance between the two iterates up to a rotation of the plane (the eigenvalue comes
        // in a rotation pair, inside which the iterate may drift): with w = u + iv and both
        // B-normalised, the residual of w_new after its projection c·w_old (c = Σ b w̄_old w_new)
        // vanishes exactly when they differ by a rotation.
        let (mut cr, mut ci) = (0.0, 0.0);
        for i in 0..n {
            let (uo, vo, un, vn) = (x[2 * i], x[2 * i + 1], next[2 * i], next[2 * i + 1]);
            cr += b[2 * i] * (uo * un + vo * vn);
            ci += b[2 * i] * (uo * vn - vo * un);
        }
        let mut d2 = 0.0;
        for i in 0..n {
            let (uo, vo, un, vn) = (x[2 * i], x[2 * i + 1], next[2 * i], next[2 * i + 1]);
            let (ru, rv) = (un - (cr * uo - ci * vo), vn - (cr * vo + ci * uo));
            d2 += b[2 * i] * (ru * ru + rv * rv);
        }
        change = d2.sqrt();
        x = next;
        if change <= options.tolerance {
            break;
        }
    }
    let mut uv: Vec<[f64; 2]> = (0..n).map(|i| [x[2 * i], x[2 * i + 1]]).collect();
    let mut note = None;
    if pins.first().is_some() {
        super::nonlinear::pins::translate_onto_first_pin(&mut uv, pins);
        note = Some("one pinned vertex: the chart was translated onto it".into());
    }
    let mut s = ChartSolution::direct(uv);
    s.iterations = iterations;
    s.residual = change;
    s.note = note;
    if change > options.tolerance {
        s.note = Some(format!(
            "spectral: not converged after {iterations} iterations (last change of the normalised iterate {change:.1e})"
        ));
    }
    Ok(s)
}
