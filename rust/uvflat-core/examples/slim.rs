//! Per-iteration time split of SLIM (and ARAP totals) on the largest chart of a mesh:
//!
//! ```text
//! cargo run --release --example slim -- MESH [--subdivide K] [--iterations N] [--start auto|mean_value] [--step newton|proxy]
//! ```
//!
//! `--subdivide K` splits every triangle into four by its edge midpoints, K times (camelhead
//! with K = 2 has about 360k triangles). Prints, per SLIM iteration, the energy (symmetric
//! Dirichlet per unit area, 1 is perfect), the accepted step and the seconds spent in assembly
//! (local step + matrix values + right-hand side), numeric factorisation, solve and line search.
//! Factorisations are sequential, as in `unwrap`; with `FAER_PAR=1` in the environment they use
//! faer's parallel (rayon) kernels instead.
#[path = "../tests/common/mod.rs"]
mod common;

use std::collections::HashMap;
use std::time::Instant;

use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::{arap, slim};

/// Split every triangle into four (polygons are fanned first).
fn subdivide(s: &common::Soup) -> common::Soup {
    let mut positions = s.positions.clone();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut corner_verts = Vec::new();
    let mut at = 0usize;
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (positions[a as usize], positions[b as usize]);
            positions.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.5 * (p[2] + q[2])]);
            (positions.len() - 1) as u32
        })
    };
    for &k in &s.face_sizes {
        let f = &s.corner_verts[at..at + k as usize];
        at += k as usize;
        for i in 1..f.len() - 1 {
            let (a, b, c) = (f[0], f[i], f[i + 1]);
            let (ab, bc, ca) = (midpoint(a, b, &mut positions), midpoint(b, c, &mut positions), midpoint(c, a, &mut positions));
            corner_verts.extend([a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
        }
    }
    let face_sizes = vec![3u32; corner_verts.len() / 3];
    common::Soup { positions, corner_verts, face_sizes }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: slim MESH [--subdivide K] [--iterations N] [--start auto|mean_value] [--step newton|proxy]");
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    let mut soup = common::load(std::path::Path::new(path));
    for _ in 0..flag("--subdivide").map(|k| k.parse::<usize>().unwrap()).unwrap_or(0) {
        soup = subdivide(&soup);
    }
    let mut options = slim::SlimOptions::default();
    if let Some(n) = flag("--iterations") {
        options.max_iterations = n.parse().unwrap();
        options.tolerance = 0.0;
    }
    if flag("--step").as_deref() == Some("proxy") {
        options.step = slim::SlimStep::Proxy;
    }
    if flag("--start").as_deref() == Some("mean_value") {
        options.start = slim::SlimStart::MeanValue;
    }
    faer::set_global_parallelism(if std::env::var("FAER_PAR").is_ok() { faer::Par::rayon(0) } else { faer::Par::Seq });
    let mesh = PolyMesh::new(&soup.positions, &soup.corner_verts, &soup.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    let chart = charts.iter().max_by_key(|c| c.triangles.len()).unwrap();
    println!("{path}: largest chart {} triangles, {} vertices", chart.triangles.len(), chart.positions.len());

    let t = Instant::now();
    let (sol, h) = slim::solve_with_history(chart, &[], &options).unwrap();
    let total = t.elapsed().as_secs_f64();
    println!("SLIM start {} energy {:.6} ({:.3} s)", h.start, h.energy[0], h.start_seconds);
    println!("{:>4} {:>12} {:>8} {:>9} {:>9} {:>9} {:>9}", "it", "energy", "step", "assemble", "factor", "solve", "search");
    for (i, s) in h.seconds.iter().enumerate() {
        let e = h.energy.get(i + 1).copied().unwrap_or(f64::NAN);
        let st = h.step.get(i).copied().unwrap_or(0.0);
        println!("{:>4} {:>12.6} {:>8.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}", i + 1, e, st, s[0], s[1], s[2], s[3]);
    }
    let sum: [f64; 4] = h.seconds.iter().fold([0.0; 4], |a, s| [a[0] + s[0], a[1] + s[1], a[2] + s[2], a[3] + s[3]]);
    let m = uvflat_core::metrics::chart_metrics(&chart.positions, &chart.triangles, &sol.uv, &chart.boundary_loops);
    println!(
        "SLIM total {total:.3} s ({} it; assemble {:.3} factor {:.3} solve {:.3} search {:.3}); flips {}, symmetric Dirichlet {:.6}, conformal {:.6}",
        sol.iterations, sum[0], sum[1], sum[2], sum[3], m.flips, m.distortion.symmetric_dirichlet, m.distortion.conformal
    );

    let mut arap_options = arap::ArapOptions::default();
    if let Ok(n) = std::env::var("ARAP_ITERATIONS") {
        arap_options.max_iterations = n.parse().unwrap();
        arap_options.tolerance = 0.0;
    }
    let t = Instant::now();
    let (sol, eh) = arap::solve_with_history(chart, &[], &arap_options).unwrap();
    let total = t.elapsed().as_secs_f64();
    if std::env::var("ARAP_DIAG").is_ok() {
        let bm = chart.boundary_mask();
        for t in &chart.triangles {
            let q = [sol.uv[t[0] as usize], sol.uv[t[1] as usize], sol.uv[t[2] as usize]];
            let a = uvflat_core::geometry::signed_area_2d(q);
            if a <= 0.0 {
                let p = [chart.positions[t[0] as usize], chart.positions[t[1] as usize], chart.positions[t[2] as usize]];
                let ang = uvflat_core::geometry::raw_angles(p);
                println!("flip min angle {:.4} area3 {:.3e} uv area {:.3e} boundary {}", ang.iter().cloned().fold(9.0, f64::min), uvflat_core::geometry::triangle_area(p), a, t.iter().any(|&v| bm[v as usize]));
            }
        }
    }
    if std::env::var("ARAP_HISTORY").is_ok() {
        println!("ARAP energies {eh:?}");
    }
    let m = uvflat_core::metrics::chart_metrics(&chart.positions, &chart.triangles, &sol.uv, &chart.boundary_loops);
    println!(
        "ARAP total {total:.3} s ({} it, energy {:.6} -> {:.6}); flips {}, symmetric Dirichlet {:.6}",
        sol.iterations,
        eh[0],
        eh.last().unwrap(),
        m.flips,
        m.distortion.symmetric_dirichlet
    );
}
