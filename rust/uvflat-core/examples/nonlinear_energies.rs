//! Energies the nonlinear methods reach on the largest chart of each given mesh:
//!
//! ```text
//! cargo run --release --example nonlinear_energies -- MESH...
//! ```
//!
//! Per method: ARAP (its own energy per unit area), SLIM, MIPS, scaffold (their own energies
//! and the symmetric Dirichlet of [`uvflat_core::metrics`]), ABF++ (constraint residual and
//! conformal distortion); iterations and flips (quads counted on both diagonals). Used to
//! check that a change of the shared nonlinear kernel leaves the results where they were.
#[path = "../tests/common/mod.rs"]
mod common;

use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{abf, arap, mips, scaffold, slim};
use uvflat_core::metrics;

fn main() {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    for path in &paths {
        let soup = common::load(std::path::Path::new(path));
        let mesh = PolyMesh::new(&soup.positions, &soup.corner_verts, &soup.face_sizes).unwrap();
        let charts = build_charts(&mesh, &[], None);
        let chart = charts.iter().max_by_key(|c| c.triangles.len()).unwrap();
        let name = std::path::Path::new(path).file_name().unwrap().to_string_lossy().to_string();
        let report = |method: &str, own: f64, iterations: usize, uv: &[[f64; 2]], extra: String| {
            let m = metrics::chart_metrics(&chart.positions, &chart.triangles, uv, &chart.boundary_loops);
            let flips = metrics::count_flips_with_quads(&chart.triangles, &chart.quads, uv);
            println!(
                "{name:>16} {method:>8} own {own:.12e} sd {:.12e} conformal {:.12e} it {iterations:>4} flips {flips}{extra}",
                m.distortion.symmetric_dirichlet, m.distortion.conformal
            );
        };
        let (s, h) = arap::solve_with_history(chart, &[], &arap::ArapOptions::default()).unwrap();
        report("arap", *h.last().unwrap(), s.iterations, &s.uv, String::new());
        let (s, h) = slim::solve_with_history(chart, &[], &slim::SlimOptions::default()).unwrap();
        report("slim", *h.energy.last().unwrap(), s.iterations, &s.uv, String::new());
        let (s, h) = mips::solve_with_history(chart, &[], &mips::MipsOptions::default()).unwrap();
        report("mips", *h.last().unwrap(), s.iterations, &s.uv, String::new());
        let (s, h) = scaffold::solve_with_history(chart, &[], &scaffold::ScaffoldOptions::default()).unwrap();
        report("scaffold", *h.energy.last().unwrap(), s.iterations, &s.uv, String::new());
        let a = abf::solve_angles(chart, &abf::AbfOptions::default()).unwrap();
        let s = abf::solve(chart, &[], &abf::AbfOptions::default()).unwrap();
        report("abf", a.residual, a.iterations, &s.uv, format!(" stationarity {:.3e} converged {}", a.stationarity, a.converged));
    }
}
