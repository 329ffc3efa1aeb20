//! Boundary first flattening with the outline's lengths kept: the conformal map of least area
//! distortion.
//!
//! Paper: R. Sawhney, K. Crane, "Boundary First Flattening", ACM Transactions on Graphics
//! 37(1), 2017 (§4–5), on the discrete Yamabe equation of Springborn, Schröder, Pinkall 2008.
//! A conformal map scales lengths by `e^u`; `u = 0` on the boundary is the paper's choice for
//! least area distortion (any other conformal flattening adds a harmonic function to `u`, and
//! this `u` varies least: its Dirichlet energy is the smallest), and its
//! scale factor is exactly the one automatic seams plan their cuts on
//! ([`crate::cuts::cones`]), so a chart cut by that plan comes out with the stretch the plan
//! predicted. Steps, on one sparse Cholesky factorization of the cotangent Laplacian `L`
//! with the boundary held:
//!
//! 1. `u`: `(L u)_i = −K_i` at every inside vertex (`K_i` = 2π − its angle sum), `u = 0` on
//!    the boundary.
//! 2. The flat outline's turning at each boundary vertex: `κ̃_i = κ_i + (L u)_i`, where
//!    `κ_i` = π − its angle sum is the surface's own (the normal derivative of `u` is
//!    `(L u)_i` there); they add up to 2π.
//! 3. The outline: edges keep their 3D lengths and turn by `κ̃`; the lengths are then
//!    changed least in `Σ (ℓ̃ − ℓ)² / ℓ` so that the curve closes (the paper's §5.3).
//! 4. Inside: each coordinate is extended harmonically from the outline (two more solves
//!    with the same factor). Triangles it folds (negative cotangent weights, a sharp corner of
//!    the outline) are unfolded locally without turning any other over
//!    ([`super::quad_repair::unfold`]); if some are left, the inside is extended again with
//!    mean value weights (positive, Floater 2003; one LU factorization) and unfolded, and the
//!    map with fewer folds is kept.
//!
//! Preconditions: a disk chart. Holes (boundary loops but the longest) are filled by a
//! virtual fan for the solve ([`super::fixed_boundary::filled_chart`]) and dropped after it,
//! so the holes come out as the fan's harmonic interior leaves them. Pins: two or more pinned
//! vertices at distinct UVs make the chart an LSCM solve with those pins (the report says
//! so); one pin translates the result onto it.
//!
//! No flip-free promise: onto an outline that is not convex a fold may be left after step 4
//! (the pipeline's check counts it and its repair acts on it). On a flat chart the map is the
//! chart itself (`u = 0`, `κ̃ = κ`, and cotangent weights reproduce linear functions).
//!
//! Failures: none of its own. When the factorization fails, the outline has fewer than three
//! vertices, or closing the outline would shrink an edge to nothing (an outline far from
//! closing: a chart too curved for one conformal map with this outline), the chart is mapped
//! by LSCM instead (its free map), reported as a fallback with the reason; that fails only
//! where LSCM's system is singular (a chart of disconnected pieces).

use std::f64::consts::PI;

use super::fixed_boundary::{cotangent_triplets, filled_chart, laplacian_triplets, Weights};
use super::{chart_angles, lscm, ChartFailure, ChartSolution, Fallback};
use crate::charts::{Chart, ChartKind};
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};

/// The least share of its 3D length an outline edge may keep when the outline is closed
/// (step 3): below it the outline is too far from closing for the map to mean anything.
pub const MIN_CLOSED_LENGTH: f64 = 0.05;

/// Map one chart (see the module docs).
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])]) -> Result<ChartSolution, ChartFailure> {
    if let Some(pinned) = lscm::instead_for_pins(chart, pins, "bff") {
        return pinned;
    }
    let filled;
    let disk = if chart.kind == ChartKind::DiskWithHoles {
        filled = filled_chart(chart);
        &filled
    } else {
        chart
    };
    let mut s = match flatten(disk) {
        Ok(mut uv) => {
            uv.truncate(chart.positions.len());
            ChartSolution::direct(uv)
        }
        Err(ChartFailure(why)) => {
            // Never a chart left without UVs for want of a closed outline: LSCM maps it.
            let mut s = lscm::solve(chart, &[])?;
            s.fallback = Some(Fallback { method: "lscm", reason: format!("bff: {why}") });
            s
        }
    };
    if let Some(note) = super::nonlinear::pins::translate_onto_single_pin(&mut s.uv, pins, "bff") {
        s.note = Some(note);
    }
    Ok(s)
}

/// Steps 1–4 of the module docs on a disk (its first boundary loop is the outline).
fn flatten(disk: &Chart) -> Result<Vec<[f64; 2]>, ChartFailure> {
    let outline = disk.outer_loop().map(|l| &disk.boundary_loops[l][..]).unwrap_or(&[]);
    let m = outline.len();
    if m < 3 {
        return Err(ChartFailure(format!("the chart's outline has {m} vertices; bff needs at least 3")));
    }
    let n = disk.positions.len();
    let angles = chart_angles(&disk.positions, &disk.triangles);
    let mut angle_sum = vec![0.0; n];
    for (t, a) in disk.triangles.iter().zip(&angles) {
        for k in 0..3 {
            angle_sum[t[k] as usize] += a[k];
        }
    }
    let triplets = cotangent_triplets(&disk.triangles, &angles);
    let solver = FixedValueSolver::with_ordering(n, &triplets, outline, Symmetry::Symmetric, OrderingKind::Amd)?;
    // 1. The log scale factor, zero on the outline.
    let minus_k: Vec<f64> = angle_sum.iter().map(|s| s - 2.0 * PI).collect();
    let u = solver.solve(&[vec![0.0; m]], &[minus_k])?.pop().unwrap_or_default();
    if !u.iter().all(|x| x.is_finite()) {
        return Err(ChartFailure("the scale factor of the conformal map is not finite".into()));
    }
    // 2. (L u) on the outline: the normal derivative of u.
    let mut on_outline = vec![false; n];
    for &v in outline {
        on_outline[v as usize] = true;
    }
    let mut lu = vec![0.0; n];
    for &(r, c, w) in &triplets {
        let (r, c) = (r as usize, c as usize);
        if on_outline[r] {
            lu[r] += w * u[c];
        }
        if r != c && on_outline[c] {
            lu[c] += w * u[r];
        }
    }
    let turning: Vec<f64> = outline.iter().map(|&v| PI - angle_sum[v as usize] + lu[v as usize]).collect();
    // 3. The outline with its 3D lengths, turned by κ̃ and closed.
    let corners = outline_curve(disk, outline, &turning)?;
    // 4. The inside, harmonic from the outline.
    let xs: Vec<f64> = corners.iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = corners.iter().map(|p| p[1]).collect();
    let sol = solver.solve(&[xs.clone(), ys.clone()], &[])?;
    let mut uv: Vec<[f64; 2]> = sol[0].iter().zip(&sol[1]).map(|(&x, &y)| [x, y]).collect();
    // The harmonic extension may fold a few triangles (negative cotangent weights, a sharp
    // corner of the outline): they are unfolded locally, without turning anything over; what
    // is left is tried again from the extension with mean value weights, which are positive
    // (Floater 2003) and fold far less.
    let (left, _) = super::quad_repair::unfold(&disk.positions, &disk.triangles, &mut uv, &[]);
    if left > 0 {
        let mv = laplacian_triplets(&disk.positions, &disk.triangles, Weights::MeanValue);
        let general = FixedValueSolver::with_ordering(n, &mv, outline, Symmetry::General, OrderingKind::Amd)?;
        let sol = general.solve(&[xs, ys], &[])?;
        let mut other: Vec<[f64; 2]> = sol[0].iter().zip(&sol[1]).map(|(&x, &y)| [x, y]).collect();
        if other.iter().all(|p| p[0].is_finite() && p[1].is_finite())
            && super::quad_repair::unfold(&disk.positions, &disk.triangles, &mut other, &[]).0 < left
        {
            uv = other;
        }
    }
    if !uv.iter().all(|p| p[0].is_finite() && p[1].is_finite()) {
        return Err(ChartFailure("the harmonic extension of the outline is not finite".into()));
    }
    Ok(uv)
}

/// The closed outline of step 3: the points of `outline` in the plane, edge `k` (from
/// `outline[k]` to `outline[k + 1]`) of 3D length `ℓ_k` and direction `φ_k = Σ_{j ≤ k, j ≥ 1}
/// turning[j]` (edge 0 along +x), its lengths then changed least in `Σ (ℓ̃ − ℓ)² / ℓ` so the
/// edges add up to zero: `ℓ̃_k = ℓ_k (1 − t_k · λ)` with `λ = (Σ ℓ t tᵀ)⁻¹ Σ ℓ t`.
pub fn outline_curve(disk: &Chart, outline: &[u32], turning: &[f64]) -> Result<Vec<[f64; 2]>, ChartFailure> {
    let m = outline.len();
    let mut phi = 0.0;
    let mut tangent = Vec::with_capacity(m);
    let mut length = Vec::with_capacity(m);
    for k in 0..m {
        if k > 0 {
            phi += turning[k];
        }
        tangent.push([phi.cos(), phi.sin()]);
        let (a, b) = (disk.positions[outline[k] as usize], disk.positions[outline[(k + 1) % m] as usize]);
        length.push(crate::geometry::norm(crate::geometry::sub(b, a)));
    }
    let (mut sxx, mut sxy, mut syy, mut rx, mut ry) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (t, &l) in tangent.iter().zip(&length) {
        sxx += l * t[0] * t[0];
        sxy += l * t[0] * t[1];
        syy += l * t[1] * t[1];
        rx += l * t[0];
        ry += l * t[1];
    }
    let det = sxx * syy - sxy * sxy;
    let closable = det > 1e-12 * (sxx + syy) * (sxx + syy);
    if !closable {
        return Err(ChartFailure("the outline's edges all point one way; it cannot be closed".into()));
    }
    let lambda = [(syy * rx - sxy * ry) / det, (sxx * ry - sxy * rx) / det];
    let mut p = [0.0, 0.0];
    let mut points = Vec::with_capacity(m);
    for k in 0..m {
        points.push(p);
        let t = tangent[k];
        let scale = 1.0 - (t[0] * lambda[0] + t[1] * lambda[1]);
        let kept = scale >= MIN_CLOSED_LENGTH;
        if !kept {
            return Err(ChartFailure(format!(
                "closing the flat outline would shrink the edge at mesh vertex {} to {:.0}% of its length: \
                 the chart is too curved for one conformal map with this outline (add seams)",
                disk.mesh_vertex[outline[k] as usize],
                100.0 * scale.max(0.0)
            )));
        }
        p = [p[0] + length[k] * scale * t[0], p[1] + length[k] * scale * t[1]];
    }
    Ok(points)
}
