//! `scaffold`: globally bijective maps — no flipped triangle and no boundary self-overlap —
//! by minimising symmetric Dirichlet on the chart plus a scaffold mesh of the free space.
//!
//! Paper: Z. Jiang, S. Schaefer, D. Panozzo, "Simplicial complex augmentation framework for
//! bijective maps", ACM TOG 36(6) (SIGGRAPH Asia), 2017 (SCAF).
//!
//! Every iteration:
//! 1. *Scaffold.* A box around the chart's current UVs (its bounding box grown by
//!    [`BOX_MARGIN`], with points along its sides) and the chart's boundary vertices (all
//!    loops) are triangulated by a constrained Delaunay triangulation (`spade`) with the
//!    boundary edges as constraints. Triangles inside the chart are dropped; the rest —
//!    between the chart and the box, and inside the holes — is the scaffold. Chart ∪ scaffold
//!    is a triangulated square whose boundary (the box) is fixed.
//! 2. *Energy.* Symmetric Dirichlet D(J) = ‖J‖² + ‖J⁻¹‖² on the chart triangles (3D rest
//!    shapes, weighted by 3D area) plus, on every scaffold triangle, D relative to its shape at
//!    the start of the iteration, all scaffold triangles sharing the total weight
//!    [`SCAFFOLD_WEIGHT`] × chart area. D is a barrier: +∞ as any triangle degenerates.
//! 3. *Step.* One SLIM global step (Rabinovich et al. 2017: reweighted proxy
//!    Σ w ‖W (J − R)‖², W from the singular values, R the closest rotation) on the whole
//!    square with the box fixed, solved through [`FixedValueSolver`], then the flip-free line
//!    search over chart *and* scaffold triangles.
//!
//! Guarantee: all chart and scaffold triangles stay positively oriented and the box boundary is
//! fixed, so chart ∪ scaffold stays an embedded triangulation of the box (a locally injective
//! map of a disk onto a convex polygon's interior with the boundary fixed is injective):
//! no chart triangle flips and the chart boundary cannot cross itself or a hole. The start
//! (mean value weights, boundary on a circle) satisfies it.
//!
//! Monotonicity: the scaffold energy is at its minimum (J = I) at the start of every
//! iteration, and the line search lowers chart + scaffold energy, so the chart's own symmetric
//! Dirichlet energy strictly decreases every iteration ([`solve_with_history`] returns it).
//!
//! Pins: the energy does not see them; the finished map is moved onto the pins by the
//! least-squares similarity (which scales it; exact for one or two pins) and the report says
//! so.
//!
//! Failures: a chart that is not a disk ([`super::require_disk`]); a singular system. When the
//! scaffold cannot be rebuilt (a boundary vertex collinear with a boundary edge to round-off,
//! so the triangulation would split the constraint) the iterations stop and the last map —
//! valid by the guarantee — is returned with a note.

use super::mips::{flip_free_start, honour_pins_by_similarity, RestTriangle};
use super::{ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::solvers::line_search::{flip_free_line_search, LineSearchOptions};
use crate::solvers::{FixedValueSolver, Symmetry};
use rayon::prelude::*;

/// Options of [`solve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaffoldOptions {
    /// Most iterations (one scaffold rebuild and one global step each). Default 100.
    pub max_iterations: usize,
    /// Stop when the chart energy changes by less than this, relative to the energy.
    /// Default 1e-6.
    pub tolerance: f64,
}

impl Default for ScaffoldOptions {
    fn default() -> Self {
        ScaffoldOptions { max_iterations: 100, tolerance: 1e-6 }
    }
}

/// The box around the chart is its UV bounding box grown by this fraction of its larger side
/// on every side.
pub const BOX_MARGIN: f64 = 0.5;
/// Total weight of the scaffold triangles relative to the chart's 3D area.
pub const SCAFFOLD_WEIGHT: f64 = 0.01;
/// Points per side of the box (corners included once).
const BOX_POINTS_PER_SIDE: usize = 8;

/// Symmetric Dirichlet density ‖J‖² (1 + 1/det²) of a row-major Jacobian (+∞ unless
/// det J > 0); 4 for a rotation. The same density as SLIM's ([`super::slim`]).
#[inline]
pub fn symmetric_dirichlet_density(j: [f64; 4]) -> f64 {
    super::slim::density([[j[0], j[1]], [j[2], j[3]]])
}

/// Weighted symmetric Dirichlet Σ w_t D(J_t) of a set of triangles (+∞ on a non-positive one).
fn weighted_energy(rest: &[RestTriangle], weight: &[f64], triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    rest.par_iter()
        .zip(weight.par_iter())
        .zip(triangles.par_iter())
        .with_min_len(2048)
        .map(|((r, &w), t)| {
            if w == 0.0 {
                return 0.0;
            }
            w * symmetric_dirichlet_density(r.jacobian([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]]))
        })
        .sum()
}

/// The SLIM proxy of one triangle (row-major Jacobian): K = W² (symmetric 2×2, as
/// [k00, k01, k11]) and P = K R, exactly SLIM's local step ([`super::slim`]).
fn slim_proxy(j: [f64; 4]) -> ([f64; 3], [f64; 4]) {
    let (k, p) = super::slim::reweight([[j[0], j[1]], [j[2], j[3]]]);
    (k, [p[0][0], p[0][1], p[1][0], p[1][1]])
}

/// The scaffold of one iteration.
struct Scaffold {
    /// Box points (appended after the chart vertices).
    box_points: Vec<[f64; 2]>,
    /// Scaffold triangles over chart vertex ids and box point ids (n + k), counter-clockwise.
    triangles: Vec<[u32; 3]>,
}

/// Triangulate the free space of the box around the chart's boundary loops.
fn build_scaffold(chart: &Chart, uv: &[[f64; 2]]) -> Result<Scaffold, String> {
    use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};
    let n = uv.len();
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in uv {
        if !(p[0].is_finite() && p[1].is_finite()) {
            return Err("non-finite UV".into());
        }
        lo = [lo[0].min(p[0]), lo[1].min(p[1])];
        hi = [hi[0].max(p[0]), hi[1].max(p[1])];
    }
    let side = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if !(side > 0.0) {
        return Err("the chart collapsed to a point".into());
    }
    let grow = BOX_MARGIN * side;
    let (x0, y0, x1, y1) = (lo[0] - grow, lo[1] - grow, hi[0] + grow, hi[1] + grow);
    let k = BOX_POINTS_PER_SIDE;
    let mut box_points = Vec::with_capacity(4 * k);
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x0 + f * (x1 - x0), y0]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x1, y0 + f * (y1 - y0)]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x1 - f * (x1 - x0), y1]);
    }
    for i in 0..k {
        let f = i as f64 / k as f64;
        box_points.push([x0, y1 - f * (y1 - y0)]);
    }
    // CDT vertices: boundary vertices of all loops, then the box points.
    let mut ids: Vec<u32> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    let mut edges: Vec<[usize; 2]> = Vec::new();
    for lp in &chart.boundary_loops {
        for &v in lp {
            if slot[v as usize] == usize::MAX {
                slot[v as usize] = ids.len();
                ids.push(v);
            }
        }
        for i in 0..lp.len() {
            edges.push([slot[lp[i] as usize], slot[lp[(i + 1) % lp.len()] as usize]]);
        }
    }
    let nb = ids.len();
    let mut points: Vec<Point2<f64>> = ids.iter().map(|&v| Point2::new(uv[v as usize][0], uv[v as usize][1])).collect();
    points.extend(box_points.iter().map(|p| Point2::new(p[0], p[1])));
    let total = points.len();
    let built = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut conflicts = 0usize;
        let cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(points, edges.clone(), |_| conflicts += 1);
        (cdt, conflicts)
    }));
    let (cdt, conflicts) = built.map_err(|_| "the constrained triangulation panicked".to_string())?;
    let cdt = cdt.map_err(|e| format!("constrained triangulation failed: {e:?}"))?;
    if conflicts > 0 || cdt.num_vertices() != total {
        return Err("the chart boundary touches itself at round-off level".into());
    }
    // Label faces: left of a loop edge is chart, right is scaffold; flood fill across
    // non-constraint edges.
    let nf = cdt.all_faces().len();
    let mut label = vec![0u8; nf]; // 0 unknown, 1 chart, 2 scaffold
    let mut stack = Vec::new();
    for e in &edges {
        let (a, b) = (spade::handles::FixedVertexHandle::from_index(e[0]), spade::handles::FixedVertexHandle::from_index(e[1]));
        let Some(de) = cdt.get_edge_from_neighbors(a, b) else {
            return Err("a boundary edge is missing from the constrained triangulation".into());
        };
        stack.push((de.face().fix(), 1));
        stack.push((de.rev().face().fix(), 2));
    }
    while let Some((fixed_face, l)) = stack.pop() {
        let f = fixed_face.index();
        if label[f] == l {
            continue;
        }
        if label[f] != 0 {
            return Err("the chart boundary does not separate the chart from the free space".into());
        }
        label[f] = l;
        let fh = cdt.face(fixed_face);
        let Some(inner) = fh.as_inner() else {
            return Err("the chart reaches the outside of the box".into());
        };
        for de in inner.adjacent_edges() {
            let other = de.rev().face();
            if !de.is_constraint_edge() && !other.is_outer() {
                stack.push((other.fix(), l));
            }
        }
    }
    let mut triangles = Vec::new();
    for f in cdt.inner_faces() {
        let i = f.fix().index();
        match label[i] {
            1 => {}
            _ => {
                // Unlabelled faces cannot exist (every region touches a loop); treat as scaffold.
                let vs = f.vertices();
                let map = |k: usize| {
                    if k < nb {
                        ids[k]
                    } else {
                        (n + k - nb) as u32
                    }
                };
                triangles.push([map(vs[0].fix().index()), map(vs[1].fix().index()), map(vs[2].fix().index())]);
            }
        }
    }
    Ok(Scaffold { box_points, triangles })
}

/// Normalised chart energy Σ A D(J) / (4 Σ A): 1 for an isometry (the DESIGN.md symmetric
/// Dirichlet measure).
fn chart_energy(rest: &[RestTriangle], area: &[f64], total: f64, tris: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    weighted_energy(rest, area, tris, uv) / (4.0 * total)
}

/// Map one chart; see the module docs.
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &ScaffoldOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
}

/// [`solve`], also returning the chart's normalised symmetric Dirichlet energy before the first
/// iteration and after each iteration (strictly decreasing, see the module docs).
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ScaffoldOptions,
) -> Result<(ChartSolution, Vec<f64>), ChartFailure> {
    super::require_disk(chart)?;
    let tris = &chart.triangles;
    let n = chart.positions.len();
    let mut uv = flip_free_start(chart)?;
    crate::metrics::area_normalize(&chart.positions, tris, &mut uv, [0.0, 0.0]);
    let rest: Vec<RestTriangle> = tris
        .iter()
        .map(|t| RestTriangle::from_3d([chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]]))
        .collect();
    let area: Vec<f64> = rest.iter().map(|r| r.area).collect();
    let total: f64 = area.iter().sum();
    if !(total > 0.0) {
        return Err(ChartFailure("the chart has zero 3D area".into()));
    }
    let mut energy = chart_energy(&rest, &area, total, tris, &uv);
    let mut history = vec![energy];
    let mut sol = ChartSolution::direct(Vec::new());
    if !energy.is_finite() {
        sol.uv = uv;
        sol.fallback = Some(super::Fallback {
            method: "mean_value",
            reason: "the flip-free start has a degenerate UV triangle, so the symmetric Dirichlet energy is infinite".into(),
        });
        return Ok((sol, history));
    }
    let ls = LineSearchOptions::default();
    let mut change = f64::INFINITY;
    let mut iterations = 0;
    let mut stop_note: Option<String> = None;
    for _ in 0..options.max_iterations {
        let scaffold = match build_scaffold(chart, &uv) {
            Ok(s) => s,
            Err(why) => {
                stop_note = Some(format!("scaffold iterations stopped early: {why}"));
                break;
            }
        };
        let nb = scaffold.box_points.len();
        let big_n = n + nb;
        let mut all: Vec<[f64; 2]> = uv.clone();
        all.extend_from_slice(&scaffold.box_points);
        let s_rest: Vec<RestTriangle> = scaffold
            .triangles
            .iter()
            .map(|t| RestTriangle::from_2d([all[t[0] as usize], all[t[1] as usize], all[t[2] as usize]]))
            .collect();
        let ws = SCAFFOLD_WEIGHT * total / scaffold.triangles.len().max(1) as f64;
        let s_weight: Vec<f64> = s_rest.iter().map(|r| if r.area > 0.0 { ws } else { 0.0 }).collect();
        if s_rest.iter().any(|r| r.area == 0.0) {
            stop_note = Some("scaffold iterations stopped early: a degenerate scaffold triangle".into());
            break;
        }
        // Global step: assemble Q x = b over 2·big_n unknowns (u, v interleaved), box fixed.
        let mut trip: Vec<(u32, u32, f64)> = Vec::with_capacity((tris.len() + scaffold.triangles.len()) * 21);
        let mut b = vec![0.0; 2 * big_n];
        let mut add_triangle = |t: &[u32; 3], r: &RestTriangle, w: f64, k: [f64; 3], p: [f64; 4], trip: &mut Vec<(u32, u32, f64)>| {
            let kk = [[k[0], k[1]], [k[1], k[2]]];
            for a in 0..3 {
                for s in 0..2 {
                    let ia = 2 * t[a] + s as u32;
                    b[ia as usize] += w * (r.g[0][a] * p[2 * s] + r.g[1][a] * p[2 * s + 1]);
                    for c in 0..3 {
                        let lac = r.g[0][a] * r.g[0][c] + r.g[1][a] * r.g[1][c];
                        for s2 in 0..2 {
                            let ic = 2 * t[c] + s2 as u32;
                            if ia >= ic {
                                trip.push((ia, ic, w * kk[s][s2] * lac));
                            }
                        }
                    }
                }
            }
        };
        let proxies: Vec<([f64; 3], [f64; 4])> = rest
            .par_iter()
            .zip(tris.par_iter())
            .with_min_len(2048)
            .map(|(r, t)| slim_proxy(r.jacobian([uv[t[0] as usize], uv[t[1] as usize], uv[t[2] as usize]])))
            .collect();
        for ((t, r), (k, p)) in tris.iter().zip(&rest).zip(&proxies) {
            if r.area > 0.0 {
                add_triangle(t, r, r.area, *k, *p, &mut trip);
            }
        }
        // Scaffold triangles sit at their rest shape: J = I, so K = 4 I and P = 4 I.
        for (t, r) in scaffold.triangles.iter().zip(&s_rest) {
            add_triangle(t, r, ws, [4.0, 0.0, 4.0], [4.0, 0.0, 0.0, 4.0], &mut trip);
        }
        let fixed: Vec<u32> = (n..big_n).flat_map(|i| [2 * i as u32, 2 * i as u32 + 1]).collect();
        let fixed_vals: Vec<f64> = scaffold.box_points.iter().flat_map(|p| [p[0], p[1]]).collect();
        let solver = FixedValueSolver::new(2 * big_n, &trip, &fixed, Symmetry::Symmetric)?;
        let x = solver.solve(&[fixed_vals], &[b])?;
        let dir: Vec<[f64; 2]> = (0..big_n)
            .map(|i| if i < n { [x[0][2 * i] - all[i][0], x[0][2 * i + 1] - all[i][1]] } else { [0.0, 0.0] })
            .collect();
        let mut both: Vec<[u32; 3]> = tris.clone();
        both.extend_from_slice(&scaffold.triangles);
        let s_tris = &scaffold.triangles;
        let total_energy = |q: &[[f64; 2]]| {
            weighted_energy(&rest, &area, tris, q) + weighted_energy(&s_rest, &s_weight, s_tris, q)
        };
        let e0 = total_energy(&all);
        let out = flip_free_line_search(&both, &mut all, &dir, e0, total_energy, &ls);
        iterations += 1;
        if out.step == 0.0 {
            change = 0.0;
            break;
        }
        uv.copy_from_slice(&all[..n]);
        let e = chart_energy(&rest, &area, total, tris, &uv);
        change = (energy - e) / e.abs().max(f64::MIN_POSITIVE);
        energy = e;
        history.push(energy);
        if change < options.tolerance {
            break;
        }
    }
    sol.uv = uv;
    sol.iterations = iterations;
    sol.residual = change;
    let pin_note = honour_pins_by_similarity(&mut sol.uv, pins, "scaffold");
    sol.note = match (stop_note, pin_note) {
        (Some(a), Some(b)) => Some(format!("{a}; {b}")),
        (a, b) => a.or(b),
    };
    Ok((sol, history))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slim_proxy_of_a_rotation_is_four_identity_and_weights_match_singular_values() {
        let (c, s) = (0.6f64, 0.8f64);
        let (k, p) = slim_proxy([c, -s, s, c]);
        assert!((k[0] - 4.0).abs() < 1e-12 && k[1].abs() < 1e-12 && (k[2] - 4.0).abs() < 1e-12);
        assert!((p[0] - 4.0 * c).abs() < 1e-12 && (p[1] + 4.0 * s).abs() < 1e-12);
        // diag(2, 0.5): w² = (σ+1)(σ²+1)/σ³ on each axis, R = I.
        let (k, p) = slim_proxy([2.0, 0.0, 0.0, 0.5]);
        let w = |x: f64| (x + 1.0) * (x * x + 1.0) / (x * x * x);
        assert!((k[0] - w(2.0)).abs() < 1e-9 && k[1].abs() < 1e-12 && (k[2] - w(0.5)).abs() < 1e-9, "{k:?}");
        assert!((p[0] - w(2.0)).abs() < 1e-9 && (p[3] - w(0.5)).abs() < 1e-9);
        assert!((symmetric_dirichlet_density([c, -s, s, c]) - 4.0).abs() < 1e-12);
    }
}
