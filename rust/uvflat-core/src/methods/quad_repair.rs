//! Make the non-convex quads of an otherwise flip-free map strictly convex by moving as few
//! vertices as little as possible, without flipping anything on the way; the same step
//! unfolds the few flipped triangles of an otherwise valid map ([`unfold`]).
//!
//! Used after methods whose flip-free promise covers triangles but not the other diagonal of
//! quads (ABF: its angles are per triangle, so a quad's corner may reach π). A quad is
//! strictly convex exactly when both of its diagonal splits are positive
//! ([`crate::metrics::quad_folds`]); the triangles of the splits that are not positive are the
//! *bad* triangles.
//!
//! Method: Gauss–Newton on the penalty P(x) = Σ_bad (τ_t − 2A_t(x))₊², where 2A_t is a bad
//! triangle's doubled signed area and τ_t = 10⁻³ |e1| |e2| (its edge lengths at the start, so
//! a repaired corner is clearly below π). Each iteration takes the steepest descent direction
//! of P (non-zero only at the bad triangles' vertices), the step minimising the linearised
//! penalty, shortened to stay below the first step at which any triangle of the barrier set
//! (the chart's triangles and every positive triangle of the quads' other splits) would
//! degenerate ([`crate::solvers::line_search::max_flip_free_step`]), then halved until P
//! decreases with every barrier triangle positive. So triangles never flip and repaired quads
//! never fold again.
//!
//! Preconditions: every chart triangle positive under `uv` (the chart's orientation).
//! Failure mode: none; when the barrier blocks the repair (a bad quad whose fix would flip a
//! neighbour), the returned count says how many quads are still not convex.

use crate::charts::Chart;
use crate::solvers::line_search::{all_positive, max_flip_free_step};

/// Most Gauss–Newton iterations of [`repair_quads`].
pub const MAX_ITERATIONS: usize = 300;

#[inline]
fn doubled_area(t: &[u32; 3], uv: &[[f64; 2]]) -> f64 {
    let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
    (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0])
}

/// Gradient of the doubled signed area of `t` with respect to its three corners.
#[inline]
fn area_gradient(t: &[u32; 3], uv: &[[f64; 2]]) -> [[f64; 2]; 3] {
    let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
    [[p1[1] - p2[1], p2[0] - p1[0]], [p2[1] - p0[1], p0[0] - p2[0]], [p0[1] - p1[1], p1[0] - p0[0]]]
}

/// Move `uv` (a map of `chart` with every triangle positive) so that its quads become strictly
/// convex; vertices with `fixed[v]` do not move (`fixed` may be empty: none fixed). Returns
/// the number of quads still not strictly convex and the number of vertices moved.
pub fn repair_quads(chart: &Chart, uv: &mut [[f64; 2]], fixed: &[bool]) -> (usize, usize) {
    if chart.quads.is_empty() || !all_positive(&chart.triangles, uv) {
        return (super::nonconvex_quads(chart, uv), 0);
    }
    // Bad triangles (either split of a non-convex quad, not clearly positive) and the barrier.
    let mut barrier = chart.triangles.clone();
    let mut bad: Vec<([u32; 3], f64)> = Vec::new();
    for q in &chart.quads {
        for t in q.other_split(&chart.triangles) {
            if doubled_area(&t, uv) > 0.0 {
                barrier.push(t);
            }
        }
        if crate::metrics::quad_folds(q, uv, 1.0) == 0 {
            continue;
        }
        for t in q.all_splits() {
            let (p0, p1, p2) = (uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]);
            let l = (p1[0] - p0[0]).hypot(p1[1] - p0[1]) * (p2[0] - p0[0]).hypot(p2[1] - p0[1]);
            bad.push((t, 1e-3 * l));
        }
    }
    if bad.is_empty() {
        return (0, 0);
    }
    let moved = raise_areas(&bad, &barrier, uv, fixed);
    (super::nonconvex_quads(chart, uv), moved)
}

/// Unfold the few flipped triangles of an otherwise valid map: every triangle of `triangles`
/// that is not positive under `uv` is a bad triangle (its target doubled area 10⁻³ × the
/// product of its two longest 3D edges from `positions`, for a map at about the 3D scale; so
/// a triangle whose corner lies on another in 3D gets room too),
/// every positive one the barrier, and the penalty is lowered as in [`repair_quads`].
/// Vertices with `fixed[v]` do not move (`fixed` may be empty). Returns the triangles still
/// flipped ([`crate::metrics::count_flips`]) and the vertices moved.
///
/// Used by maps with no barrier of their own whose folds are few and local (the harmonic
/// extension of `bff`). Failure mode: none; a fold whose fix would flip a neighbour stays.
pub fn unfold(positions: &[[f64; 3]], triangles: &[[u32; 3]], uv: &mut [[f64; 2]], fixed: &[bool]) -> (usize, usize) {
    use crate::geometry::{norm, sub};
    let length = |a: u32, b: u32| norm(sub(positions[b as usize], positions[a as usize]));
    let positive = |t: &[u32; 3]| doubled_area(t, uv) > 0.0;
    let bad: Vec<([u32; 3], f64)> = triangles
        .iter()
        .filter(|t| !positive(t))
        .map(|t| {
            let mut l = [length(t[0], t[1]), length(t[1], t[2]), length(t[2], t[0])];
            l.sort_by(f64::total_cmp);
            (*t, 1e-3 * l[1] * l[2])
        })
        .collect();
    if bad.is_empty() {
        return (crate::metrics::count_flips(triangles, uv), 0);
    }
    // Only the bad triangles' vertices move, so only the positive triangles around them can
    // turn over: they are the barrier.
    let mut moving = vec![false; uv.len()];
    for (t, _) in &bad {
        for &v in t {
            moving[v as usize] = true;
        }
    }
    let barrier: Vec<[u32; 3]> = triangles
        .iter()
        .filter(|t| doubled_area(t, uv) > 0.0 && t.iter().any(|&v| moving[v as usize]))
        .copied()
        .collect();
    let moved = raise_areas(&bad, &barrier, uv, fixed);
    (crate::metrics::count_flips(triangles, uv), moved)
}

/// Gauss–Newton on the penalty of the module docs: the `bad` triangles' doubled areas raised
/// towards their targets, no `barrier` triangle ever turned over, `fixed` vertices kept.
/// Returns the number of vertices moved.
fn raise_areas(bad: &[([u32; 3], f64)], barrier: &[[u32; 3]], uv: &mut [[f64; 2]], fixed: &[bool]) -> usize {
    let is_fixed = |v: u32| fixed.get(v as usize).copied().unwrap_or(false);
    let penalty = |x: &[[f64; 2]]| -> f64 {
        bad.iter().map(|(t, tau)| (tau - doubled_area(t, x)).max(0.0).powi(2)).sum()
    };
    let start = uv.to_vec();
    // Only the bad triangles' vertices have a direction: a step moves those alone.
    let mut moving: Vec<usize> = bad.iter().flat_map(|(t, _)| t.iter().map(|&v| v as usize)).collect();
    moving.sort_unstable();
    moving.dedup();
    let mut p = penalty(uv);
    let mut dir = vec![[0.0f64; 2]; uv.len()];
    let mut trial = uv.to_vec();
    for _ in 0..MAX_ITERATIONS {
        if bad.iter().all(|(t, tau)| doubled_area(t, uv) >= 0.5 * tau) {
            break;
        }
        // Steepest descent of P: Σ r_t ∇(2A_t) over the active bad triangles.
        for &(t, _) in bad {
            for &v in &t {
                dir[v as usize] = [0.0, 0.0];
            }
        }
        for (t, tau) in bad {
            let r = (tau - doubled_area(t, uv)).max(0.0);
            if r == 0.0 {
                continue;
            }
            let g = area_gradient(t, uv);
            for k in 0..3 {
                if !is_fixed(t[k]) {
                    let d = &mut dir[t[k] as usize];
                    d[0] += r * g[k][0];
                    d[1] += r * g[k][1];
                }
            }
        }
        // Step minimising the linearised penalty: Σ r s / Σ s², s = ∇(2A)·d.
        let (mut num, mut den) = (0.0, 0.0);
        for (t, tau) in bad {
            let r = (tau - doubled_area(t, uv)).max(0.0);
            let g = area_gradient(t, uv);
            let s: f64 = (0..3).map(|k| g[k][0] * dir[t[k] as usize][0] + g[k][1] * dir[t[k] as usize][1]).sum();
            if r > 0.0 || s < 0.0 {
                num += r * s;
                den += s * s;
            }
        }
        if !(den > 0.0) || !(num > 0.0) {
            break;
        }
        let mut step = (num / den).min(0.8 * max_flip_free_step(barrier, uv, &dir));
        let mut accepted = false;
        for _ in 0..40 {
            if !(step > 0.0) || !step.is_finite() {
                break;
            }
            for &v in &moving {
                let (x, d) = (uv[v], dir[v]);
                trial[v] = [x[0] + step * d[0], x[1] + step * d[1]];
            }
            let pt = penalty(&trial);
            if pt < p && all_positive(barrier, &trial) {
                for &v in &moving {
                    uv[v] = trial[v];
                }
                p = pt;
                accepted = true;
                break;
            }
            step *= 0.5;
        }
        if !accepted {
            break;
        }
        // The directions of vertices outside the bad triangles stay zero.
        for &(t, _) in bad {
            for &v in &t {
                dir[v as usize] = [0.0, 0.0];
            }
        }
    }
    uv.iter().zip(&start).filter(|(a, b)| a != b).count()
}