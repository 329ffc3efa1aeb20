//! Target angles of ABF (the clamped 3D angles, scaled at every interior vertex to 2π, or to
//! a prescribed sum), the caps and bounds of the convex boundary, and vertex angle sums.
//!
//! Preconditions: a chart; prescribed sums at chart vertices. Failures: none.

use super::*;

/// Largest angle sum of an outer-loop vertex under [`AbfBoundary::Convex`] on a loop of
/// `n` vertices: `π − π/n`, so that every outer vertex turns by at least half the mean turning
/// `2π/n` (a strictly convex outline; see the module docs).
pub fn convex_cap(n: usize) -> f64 {
    PI - PI / n.max(1) as f64
}

/// Lower bound of every angle under [`AbfBoundary::Convex`] on an outer loop of `n` vertices:
/// a quarter of the least turning `π/n` (see [`convex_cap`] and the module docs).
pub fn convex_lower_bound(n: usize) -> f64 {
    0.25 * PI / n.max(1) as f64
}

/// Targets β: the clamped 3D angles, scaled at every interior vertex to sum to 2π.
pub fn target_angles(chart: &Chart) -> Vec<[f64; 3]> {
    target_angles_with_sums(chart, &[])
}

/// Targets β scaled at every interior vertex to 2π, and at every vertex of `prescribed`
/// (chart vertex, angle sum) to its prescribed sum.
pub fn target_angles_with_sums(chart: &Chart, prescribed: &[(u32, f64)]) -> Vec<[f64; 3]> {
    let mut beta = chart_angles(&chart.positions, &chart.triangles);
    let mut goal: Vec<Option<f64>> = chart.boundary_mask().iter().map(|&b| if b { None } else { Some(2.0 * PI) }).collect();
    for &(v, t) in prescribed {
        goal[v as usize] = Some(t);
    }
    let mut sum = vec![0.0; chart.positions.len()];
    for (t, a) in chart.triangles.iter().zip(&beta) {
        for k in 0..3 {
            sum[t[k] as usize] += a[k];
        }
    }
    for (t, a) in chart.triangles.iter().zip(beta.iter_mut()) {
        for k in 0..3 {
            let v = t[k] as usize;
            if let (Some(g), true) = (goal[v], sum[v] > 0.0) {
                a[k] *= g / sum[v];
            }
        }
    }
    beta
}

/// Angle sum at every chart vertex.
pub(super) fn vertex_sums(chart: &Chart, alpha: &[f64]) -> Vec<f64> {
    let mut sum = vec![0.0; chart.positions.len()];
    for (f, t) in chart.triangles.iter().enumerate() {
        for k in 0..3 {
            sum[t[k] as usize] += alpha[3 * f + k];
        }
    }
    sum
}
