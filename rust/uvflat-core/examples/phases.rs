//! Time the phases of one LSCM unwrap: `cargo run --release --example phases -- MESH.off`.
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{chart_angles, lscm};

fn main() {
    let path = std::env::args().nth(1).expect("mesh path");
    let s = common::load(std::path::Path::new(&path));
    // As `unwrap` does: sequential factorization inside a chart.
    faer::set_global_parallelism(faer::Par::Seq);
    for _ in 0..3 {
        let t = Instant::now();
        let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let t_mesh = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let charts = build_charts(&mesh, &[], None);
        let t_charts = t.elapsed().as_secs_f64();
        let c = &charts[0];
        let t = Instant::now();
        let ang = chart_angles(&c.positions, &c.triangles);
        std::hint::black_box(lscm::conformal_hermitian(&c.triangles, &ang));
        let t_asm = t.elapsed().as_secs_f64();
        let pins = lscm::auto_pins(c);
        let t = Instant::now();
        let solver = lscm::LscmSolver::new(c.positions.len(), &c.triangles, &ang, &[pins[0].0, pins[1].0]).unwrap();
        let t_factor = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let uv = solver.solve(&[pins[0].1, pins[1].1]).unwrap();
        let t_solve = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let m = uvflat_core::metrics::chart_metrics(&c.positions, &c.triangles, &uv, &c.boundary_loops);
        let t_metrics = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let r = uvflat_core::unwrap(&s.input(), &Default::default()).unwrap();
        let t_all = t.elapsed().as_secs_f64();
        println!(
            "mesh {t_mesh:.4} charts {t_charts:.4} assemble {t_asm:.4} assemble+analyse+factor (complex) {t_factor:.4} solve {t_solve:.4} metrics {t_metrics:.4} | unwrap {t_all:.4} flips {} {}",
            m.flips, r.charts[0].flips
        );
    }
}

