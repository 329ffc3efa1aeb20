//! As-rigid-as-possible parameterization by local/global iterations.
//!
//! Paper: L. Liu, L. Zhang, Y. Xu, C. Gotsman, S. J. Gortler, "A Local/Global Approach to Mesh
//! Parameterization", Computer Graphics Forum 27(5) (SGP), 2008.
//!
//! Energy, over the chart triangles f with 3D area A_f and Jacobian J_f (UV map of the
//! triangle in a local 2D frame of its plane):
//!
//! ```text
//! E(x) = Σ_f A_f · min_{R ∈ SO(2)} ‖J_f − R‖²_F
//! ```
//!
//! * Start: LSCM of the chart ([`super::lscm::solve_with_angles`]), honouring the pins.
//! * Local step: the closest rotation of every J_f (closed form in 2D:
//!   `R = rot(atan2(J₂₁ − J₁₂, J₁₁ + J₂₂))`), in parallel.
//! * Global step: minimise `Σ A_f ‖J_f − R_f‖²` over the UVs: the cotangent-weighted Poisson
//!   system `L u = b_u`, `L v = b_v`. Its matrix does not depend on the rotations, so it is
//!   factored once ([`FixedValueSolver`]) and each iteration is two triangular solves. The
//!   pinned vertices are fixed; without pins one vertex is held at its LSCM position (the
//!   energy is translation invariant, so this loses nothing).
//!
//! Both steps minimise E over one set of variables with the other fixed, so the energy never
//! increases; the history returned by [`solve_with_history`] shows it. The iteration stops
//! after `max_iterations` or when the relative energy change falls below `tolerance`.
//!
//! No injectivity guarantee: ARAP can fold triangles (the report counts flips).
//!
//! Preconditions: a disk chart, possibly with holes. Degenerate 3D triangles get a thin valid
//! reference shape (clamped angles, [`crate::geometry::clamped_angles`]). Failures: a singular
//! system (disconnected chart) becomes a chart failure; a solve that turns non-finite during
//! the iteration ends it with the last map and says so in the note.

use rayon::prelude::*;

use super::{chart_angles, lscm, ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::geometry::{clamped_angles, norm, sub};
use crate::solvers::{FixedValueSolver, Symmetry};

/// Options of the ARAP method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArapOptions {
    /// Most local/global iterations. Default 100.
    pub max_iterations: usize,
    /// Stop when the energy changes by less than this, relative. Default 1e-6.
    pub tolerance: f64,
}

impl Default for ArapOptions {
    fn default() -> Self {
        ArapOptions { max_iterations: 100, tolerance: 1e-6 }
    }
}

/// Per-triangle gradient operators of a chart's reference (3D) triangles, shared by the
/// nonlinear methods (ARAP, SLIM).
///
/// Each triangle is laid out in its own 2D frame from its clamped corner angles
/// ([`clamped_angles`]) and its longest 3D edge (law of sines), so the frame is exact for
/// ordinary triangles and thin but valid for degenerate ones; `area` is the area of that frame
/// triangle. The Jacobian of a UV map on triangle f is `J[k][j] = Σ_i grad[f][j][i] · x_k(t_i)`
/// (row k = u or v, column j = x or y of the frame).
#[derive(Debug, Clone)]
pub struct TriangleOperators {
    /// `grad[f][j][i]`: derivative along frame axis j of the hat function of corner i.
    pub grad: Vec<[[f64; 3]; 2]>,
    /// Area of every reference triangle (> 0).
    pub area: Vec<f64>,
    /// Sum of `area`.
    pub total_area: f64,
}

impl TriangleOperators {
    /// Build the operators of `triangles` over `positions`. Never fails: a triangle whose
    /// corners coincide gets an equilateral shape with the chart's mean edge length.
    pub fn new(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Self {
        let edge = |t: &[u32; 3], k: usize| norm(sub(positions[t[(k + 1) % 3] as usize], positions[t[k] as usize]));
        let (sum, count) = triangles.iter().fold((0.0, 0usize), |(s, c), t| (s + edge(t, 0) + edge(t, 1) + edge(t, 2), c + 3));
        let mean_edge = if count > 0 && sum > 0.0 { sum / count as f64 } else { 1.0 };
        let (grad, area): (Vec<[[f64; 3]; 2]>, Vec<f64>) = triangles
            .par_iter()
            .map(|t| {
                let p = [positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]];
                let a = clamped_angles(p);
                let longest = edge(t, 0).max(edge(t, 1)).max(edge(t, 2));
                let longest = if longest > 0.0 { longest } else { mean_edge };
                // Side opposite corner k is proportional to sin a_k.
                let s = longest / a[0].sin().max(a[1].sin()).max(a[2].sin());
                let (l01, l02) = (s * a[2].sin(), s * a[1].sin());
                let (x1, x2, y2) = (l01, l02 * a[0].cos(), l02 * a[0].sin());
                let det = x1 * y2;
                let g = [[-1.0 / x1, 1.0 / x1, 0.0], [(x2 - x1) / det, -x2 / det, x1 / det]];
                (g, 0.5 * det)
            })
            .unzip();
        let total_area = area.iter().sum();
        TriangleOperators { grad, area, total_area }
    }

    /// Jacobian `[[∂u/∂x, ∂u/∂y], [∂v/∂x, ∂v/∂y]]` of triangle `f` (vertices `t`) under `uv`.
    #[inline]
    pub fn jacobian(&self, f: usize, t: &[u32; 3], uv: &[[f64; 2]]) -> [[f64; 2]; 2] {
        let g = &self.grad[f];
        let mut j = [[0.0; 2]; 2];
        for i in 0..3 {
            let x = uv[t[i] as usize];
            for k in 0..2 {
                j[k][0] += g[0][i] * x[k];
                j[k][1] += g[1][i] * x[k];
            }
        }
        j
    }

    /// Per-triangle stiffness `Σ_j grad[j][a]·grad[j][b]` (the cotangent Laplacian of the
    /// triangle divided by its area), row-major 3 × 3.
    #[inline]
    pub fn stiffness(&self, f: usize) -> [[f64; 3]; 3] {
        let g = &self.grad[f];
        let mut l = [[0.0; 3]; 3];
        for a in 0..3 {
            for b in 0..3 {
                l[a][b] = g[0][a] * g[0][b] + g[1][a] * g[1][b];
            }
        }
        l
    }
}

/// The rotation closest to `j` in the Frobenius norm (det +1), as `(cos θ, sin θ)`.
#[inline]
pub fn closest_rotation(j: [[f64; 2]; 2]) -> (f64, f64) {
    let (c, s) = (j[0][0] + j[1][1], j[1][0] - j[0][1]);
    let r = c.hypot(s);
    if r > 0.0 {
        (c / r, s / r)
    } else {
        (1.0, 0.0)
    }
}

/// ARAP energy `Σ A_f ‖J_f − R_f‖²` (with the closest rotations) divided by the total area.
pub fn arap_energy(ops: &TriangleOperators, triangles: &[[u32; 3]], uv: &[[f64; 2]]) -> f64 {
    let e: f64 = triangles
        .par_iter()
        .enumerate()
        .with_min_len(2048)
        .map(|(f, t)| {
            let j = ops.jacobian(f, t, uv);
            let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
            let trace_rt_j = (j[0][0] + j[1][1]).hypot(j[1][0] - j[0][1]);
            ops.area[f] * (fro - 2.0 * trace_rt_j + 2.0).max(0.0)
        })
        .sum();
    e / ops.total_area
}

/// The vertices held fixed by a global step and their UVs: all pins when they span more than
/// a point, else the first pin (or vertex 0 without pins) at its current UV.
pub(crate) fn anchors(pins: &[(u32, [f64; 2])], uv: &[[f64; 2]]) -> Vec<(u32, [f64; 2])> {
    if lscm::pins_span(pins) {
        pins.to_vec()
    } else if let Some(&(v, _)) = pins.first() {
        vec![(v, uv[v as usize])]
    } else {
        vec![(0, uv[0])]
    }
}

/// ARAP of one chart (see the module docs).
pub fn solve(chart: &Chart, pins: &[(u32, [f64; 2])], options: &ArapOptions) -> Result<ChartSolution, ChartFailure> {
    solve_with_history(chart, pins, options).map(|(s, _)| s)
}

/// ARAP of one chart, with the energy (per unit area, see [`arap_energy`]) of the start and
/// after every iteration. The history never increases (up to round-off).
pub fn solve_with_history(
    chart: &Chart,
    pins: &[(u32, [f64; 2])],
    options: &ArapOptions,
) -> Result<(ChartSolution, Vec<f64>), ChartFailure> {
    let n = chart.positions.len();
    let tris = &chart.triangles;
    let angles = chart_angles(&chart.positions, tris);
    let (mut uv, pin_note) = lscm::solve_with_angles(chart, &angles, pins)?;
    let ops = TriangleOperators::new(&chart.positions, tris);

    // Global matrix Σ A_f L_f over n unknowns (the same for u and v), lower triangle.
    let mut trip = Vec::with_capacity(tris.len() * 6);
    for (f, t) in tris.iter().enumerate() {
        let l = ops.stiffness(f);
        for a in 0..3 {
            for b in 0..=a {
                let (r, c) = (t[a].max(t[b]), t[a].min(t[b]));
                trip.push((r, c, ops.area[f] * l[a][b]));
            }
        }
    }
    let fixed = anchors(pins, &uv);
    let fixed_ids: Vec<u32> = fixed.iter().map(|p| p.0).collect();
    let fixed_vals = [fixed.iter().map(|p| p.1[0]).collect::<Vec<f64>>(), fixed.iter().map(|p| p.1[1]).collect::<Vec<f64>>()];
    let solver = FixedValueSolver::new(n, &trip, &fixed_ids, Symmetry::Symmetric)?;

    let mut energy = arap_energy(&ops, tris, &uv);
    let mut history = vec![energy];
    let mut change = 0.0;
    let mut iterations = 0;
    let mut stopped = None;
    while iterations < options.max_iterations && energy > 1e-15 && !crate::progress::cancelled() {
        // Local step: closest rotations; right-hand side Σ A_f R_f D_f per vertex.
        let contrib: Vec<[[f64; 2]; 3]> = tris
            .par_iter()
            .enumerate()
            .with_min_len(2048)
            .map(|(f, t)| {
                let (c, s) = closest_rotation(ops.jacobian(f, t, &uv));
                let r = [[c, -s], [s, c]];
                let g = &ops.grad[f];
                let a = ops.area[f];
                let mut out = [[0.0; 2]; 3];
                for i in 0..3 {
                    for k in 0..2 {
                        out[i][k] = a * (r[k][0] * g[0][i] + r[k][1] * g[1][i]);
                    }
                }
                out
            })
            .collect();
        let mut b = [vec![0.0; n], vec![0.0; n]];
        for (t, c) in tris.iter().zip(&contrib) {
            for i in 0..3 {
                b[0][t[i] as usize] += c[i][0];
                b[1][t[i] as usize] += c[i][1];
            }
        }
        // Global step.
        // A failed solve (non-finite values) ends the iteration with the last map.
        let x = match solver.solve(&fixed_vals, &b) {
            Ok(x) => x,
            Err(e) => {
                stopped = Some(e.to_string());
                break;
            }
        };
        uv = (0..n).map(|i| [x[0][i], x[1][i]]).collect();
        iterations += 1;
        let e = arap_energy(&ops, tris, &uv);
        history.push(e);
        change = (energy - e).abs() / energy.max(f64::MIN_POSITIVE);
        energy = e;
        if change < options.tolerance {
            break;
        }
    }
    let mut note = format!("ARAP energy {energy:.6e} per unit area after {iterations} iteration(s)");
    if let Some(reason) = stopped {
        note = format!("{note}; stopped early, the global step failed: {reason}");
    }
    if let Some(p) = pin_note {
        note = format!("{note}; {p}");
    }
    let sol = ChartSolution { uv, iterations, residual: change, note: Some(note), fallback: None };
    Ok((sol, history))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operators_give_the_identity_jacobian_for_the_triangle_itself() {
        // A 3D triangle mapped to a congruent copy: J is a rotation (reflection-free).
        let p = [[0.3, -0.2, 0.5], [1.4, 0.1, 0.2], [0.6, 0.9, -0.4]];
        let ops = TriangleOperators::new(&p, &[[0, 1, 2]]);
        let q = crate::geometry::local_frame(p);
        let (c, s) = (0.6f64.cos(), 0.6f64.sin());
        let uv: Vec<[f64; 2]> = q.iter().map(|z| [c * z[0] - s * z[1] + 2.0, s * z[0] + c * z[1] - 1.0]).collect();
        let j = ops.jacobian(0, &[0, 1, 2], &uv);
        assert!((j[0][0] - c).abs() < 1e-12 && (j[0][1] + s).abs() < 1e-12);
        assert!((j[1][0] - s).abs() < 1e-12 && (j[1][1] - c).abs() < 1e-12);
        assert!((ops.area[0] - crate::geometry::triangle_area(p)).abs() < 1e-12);
        assert!(arap_energy(&ops, &[[0, 1, 2]], &uv) < 1e-24);
        let (rc, rs) = closest_rotation(j);
        assert!((rc - c).abs() < 1e-12 && (rs - s).abs() < 1e-12);
        // The stiffness rows sum to zero (constants are in the kernel).
        let l = ops.stiffness(0);
        for row in l {
            assert!(row.iter().sum::<f64>().abs() < 1e-12);
        }
    }
}
