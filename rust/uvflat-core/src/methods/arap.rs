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
//! Pins: with two or more pinned vertices at distinct UVs they are the fixed values of every
//! global step (they hold exactly), and the rest shapes are the 3D triangles scaled by the
//! pins' scale ([`super::nonlinear::pins::pins_scale`]), so the unpinned part lies at the
//! pins' scale rather than at 3D scale around them; with one pin the chart is solved free and
//! held at its LSCM position, which is translated onto the pin.
//!
//! No injectivity guarantee: ARAP can fold triangles (the report counts flips).
//!
//! Preconditions: a disk chart, possibly with holes. Degenerate 3D triangles get a thin valid
//! reference shape (clamped angles, [`crate::geometry::clamped_angles`]). Failures: a singular
//! system (disconnected chart) becomes a chart failure; a solve that turns non-finite during
//! the iteration ends it with the last map and says so in the note.

use rayon::prelude::*;

use super::nonlinear::iterate::{stopped_early_note, Change, Iteration};
use super::{chart_angles, lscm, ChartFailure, ChartSolution};
use crate::charts::Chart;
use crate::solvers::ordering::OrderingKind;
use crate::solvers::{FixedValueSolver, Symmetry};

pub use super::nonlinear::energy::arap_energy;
pub use super::nonlinear::proxy::closest_rotation;
pub use super::nonlinear::TriangleOperators;

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
    // The paper's start: LSCM with its two automatic pins (`lscm::solve_with_angles`). The free
    // map fixed on the boundary (`lscm::solve_free`) crushes less, but from it ARAP stalled
    // on a piece of the camel's head (energy 0.19 per unit area, 25% of the piece outside
    // the density bound) that the repair could no longer split.
    let (mut uv, pin_note) = lscm::solve_with_angles(chart, &angles, pins)?;
    // Pins spanning more than a point fix the map's scale: the rest shapes are the 3D ones at
    // that scale, so the unpinned part is laid out at the pins' scale (module docs).
    let (rest, scale) = super::nonlinear::pins::rest_positions(chart, pins);
    let ops = TriangleOperators::new(&rest, tris);
    drop(rest);

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
    let fixed = super::nonlinear::pins::anchors(pins, &uv);
    let fixed_ids: Vec<u32> = fixed.iter().map(|p| p.0).collect();
    let fixed_vals = [fixed.iter().map(|p| p.1[0]).collect::<Vec<f64>>(), fixed.iter().map(|p| p.1[1]).collect::<Vec<f64>>()];
    let solver = FixedValueSolver::with_ordering(n, &trip, &fixed_ids, Symmetry::Symmetric, OrderingKind::Amd)?;

    let mut it = Iteration::new(arap_energy(&ops, tris, &uv), options.max_iterations, options.tolerance, Change::OfPrevious, 0.0);
    let mut stopped = None;
    while it.go_on() && it.energy() > 1e-15 {
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
        if it.record(arap_energy(&ops, tris, &uv)) {
            break;
        }
    }
    let (energy, iterations, change) = (it.energy(), it.iterations, it.change);
    let history = it.history;
    let mut note = format!("ARAP energy {energy:.6e} per unit area after {iterations} iteration(s)");
    if let Some(reason) = stopped {
        note = format!("{note}; {}", stopped_early_note(&reason));
    }
    if let Some(p) = pin_note.or_else(|| super::nonlinear::pins::pins_scale_note(pins.len(), scale)) {
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
