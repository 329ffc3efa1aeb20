//! Time ABF++ (and optionally plain ABF) per chart and end to end:
//! `cargo run --release --example abf -- MESH.off [abf|abf++] [free|convex]`.
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;
use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::abf::{self, AbfBoundary, AbfOptions, AbfSolver};
use uvflat_core::{unwrap, Method, UnwrapOptions};

fn main() {
    let path = std::env::args().nth(1).expect("mesh path");
    let solver = match std::env::args().nth(2).as_deref() {
        Some("abf") => AbfSolver::Plain,
        _ => AbfSolver::AbfPlusPlus,
    };
    let boundary = match std::env::args().nth(3).as_deref() {
        Some("convex") => AbfBoundary::Convex,
        _ => AbfBoundary::Free,
    };
    let opts = AbfOptions { solver, boundary, ..Default::default() };
    let s = common::load(std::path::Path::new(&path));
    faer::set_global_parallelism(faer::Par::Seq);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    for c in charts.iter().filter(|c| c.defect.is_none() && !c.boundary_loops.is_empty()).take(3) {
        let t = Instant::now();
        let a = abf::solve_angles(c, &opts);
        let dt = t.elapsed().as_secs_f64();
        match a {
            Ok(a) => println!(
                "chart {} tris: {} iters, residual {:.2e}, stationarity {:.2e}, converged {}, active {}, {dt:.4} s",
                c.triangles.len(), a.iterations, a.residual, a.stationarity, a.converged, a.convex_active.len()
            ),
            Err(e) => println!("chart {} tris: error {e:?}", c.triangles.len()),
        }
    }
    for _ in 0..3 {
        let t = Instant::now();
        let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(opts), ..Default::default() }).unwrap();
        let dt = t.elapsed().as_secs_f64();
        let flips: usize = r.charts.iter().map(|c| c.flips).sum();
        let c = &r.charts[0];
        println!(
            "unwrap {:?} {}: {dt:.4} s, {} charts, flips {flips}, chart0 {:?} iters {} residual {:.2e} overlap {} conformal {:.4} reason {:?}",
            opts.solver, opts.boundary.name(), r.charts.len(), c.status, c.iterations, c.residual, c.overlap, c.distortion.conformal, c.reason
        );
    }
}
