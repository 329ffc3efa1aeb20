//! Time ABF++ (and optionally plain ABF) per chart and end to end:
//! `cargo run --release --example abf -- MESH.off [abf|abf++] [free|convex] [SUBDIVISIONS] [seq|par]`.
//!
//! SUBDIVISIONS (default 0) splits every triangle into four at its edge midpoints that many
//! times (camelhead: 1 → 90,816, 2 → 363,264, 3 → 1,453,056 triangles); `par` sets faer's
//! global parallelism for the per-chart angle timings (it affects the plain ABF LU solver
//! only: the ABF++ reduced system is factored sequentially, which measured faster).
//! Prints wall and CPU time (all threads) and the peak resident memory (VmHWM) at the end.
//! `ABF_REPS=N` repeats each per-chart angle solve N times and reports the fastest;
//! `ABF_TOL=T` sets the Newton tolerance (default 1e-9) to see what a looser one saves.
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
    let mut opts = AbfOptions { solver, boundary, ..Default::default() };
    if let Some(t) = std::env::var("ABF_TOL").ok().and_then(|x| x.parse().ok()) {
        opts.tolerance = t;
    }
    let levels: usize = std::env::args().nth(4).map(|a| a.parse().expect("subdivisions")).unwrap_or(0);
    let par = std::env::args().nth(5).as_deref() == Some("par");
    let mut s = common::load(std::path::Path::new(&path));
    for _ in 0..levels {
        s = common::subdivide(&s);
    }
    println!("{} faces, {} vertices", s.face_sizes.len(), s.positions.len());
    faer::set_global_parallelism(if par { faer::Par::rayon(0) } else { faer::Par::Seq });
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    let reps: usize = std::env::var("ABF_REPS").ok().and_then(|x| x.parse().ok()).unwrap_or(1);
    for c in charts.iter().filter(|c| c.defect.is_none() && !c.boundary_loops.is_empty()).take(3) {
        let (mut dt, mut dcpu, mut a) = (f64::INFINITY, f64::INFINITY, None);
        for _ in 0..reps {
            let t = Instant::now();
            let cpu0 = common::cpu_seconds();
            a = Some(abf::solve_angles(c, &opts));
            dt = dt.min(t.elapsed().as_secs_f64());
            dcpu = dcpu.min(common::cpu_seconds() - cpu0);
        }
        let a = a.expect("one repetition");
        match a {
            Ok(a) => println!(
                "chart {} tris: {} iters, {} factorizations, residual {:.2e}, stationarity {:.2e}, converged {}, active {}, {dt:.4} s (cpu {dcpu:.4} s)",
                c.triangles.len(), a.iterations, a.factorizations, a.residual, a.stationarity, a.converged, a.convex_active.len()
            ),
            Err(e) => println!("chart {} tris: error {e:?}", c.triangles.len()),
        }
    }
    for _ in 0..if levels > 0 { 1 } else { 3 } {
        let t = Instant::now();
        let cpu0 = common::cpu_seconds();
        let r = unwrap(&s.input(), &UnwrapOptions { method: Method::Abf(opts.clone()), ..Default::default() }).unwrap();
        let dt = t.elapsed().as_secs_f64();
        let dcpu = common::cpu_seconds() - cpu0;
        let flips: usize = r.charts.iter().map(|c| c.flips).sum();
        let c = &r.charts[0];
        println!(
            "unwrap {:?} {}: {dt:.4} s (cpu {dcpu:.4} s), {} charts, flips {flips}, chart0 {:?} iters {} residual {:.2e} overlap {} conformal {:.4} reason {:?}",
            opts.solver, opts.boundary.name(), r.charts.len(), c.status, c.iterations, c.residual, c.overlap, c.distortion.conformal, c.reason
        );
    }
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    if let Some(line) = status.lines().find(|l| l.starts_with("VmHWM")) {
        println!("peak memory {line}");
    }
}


