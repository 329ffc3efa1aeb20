//! Per-iteration time split of the `scaffold` method on the largest chart of a mesh:
//!
//! ```text
//! cargo run --release -p uvflat-core --example scaffold -- MESH [--iterations N] [--repeat R]
//! ```
//!
//! Prints, per iteration, the chart's symmetric Dirichlet energy (per unit area / 4, 1 is
//! perfect), the scaffold size and the seconds spent in the scaffold triangulation, assembly,
//! symbolic analysis, numeric factorisation, solve and line search (`*` after the scaffold
//! size: a fresh re-mesh; without it the previous iteration's scaffold was kept); then the totals, the
//! end-to-end `unwrap` time of the whole mesh with `scaffold` and with `slim`, and the
//! finished map's flips, boundary overlap and symmetric Dirichlet. `--repeat R` runs the chart
//! R times and reports the minimum total.
#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Instant;

use uvflat_core::charts::build_charts;
use uvflat_core::mesh::PolyMesh;
use uvflat_core::methods::scaffold;
use uvflat_core::{unwrap, Method, UnwrapOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("usage: scaffold MESH [--iterations N] [--repeat R]");
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned();
    let soup = common::load(std::path::Path::new(path));
    let mut options = scaffold::ScaffoldOptions::default();
    if let Some(n) = flag("--iterations") {
        options.max_iterations = n.parse().unwrap();
        options.tolerance = 0.0;
    }
    let repeat: usize = flag("--repeat").map(|r| r.parse().unwrap()).unwrap_or(1);
    // As `unwrap` does: sequential factorisation inside a chart.
    faer::set_global_parallelism(faer::Par::Seq);
    let mesh = PolyMesh::new(&soup.positions, &soup.corner_verts, &soup.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    let chart = charts.iter().max_by_key(|c| c.triangles.len()).unwrap();
    println!(
        "{path}: largest chart {} triangles, {} vertices, {} boundary vertices",
        chart.triangles.len(),
        chart.positions.len(),
        chart.boundary_loops.iter().map(|l| l.len()).sum::<usize>()
    );

    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeat {
        let t = Instant::now();
        let r = scaffold::solve_with_history(chart, &[], &options).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    let (sol, h) = last.unwrap();
    println!("start {} energy {:.6} ({:.3} s, {} symbolic analyses)", h.start, h.energy[0], h.start_seconds, h.analyses);
    println!(
        "{:>4} {:>10} {:>7} {:>7} {:>8} {:>8} {:>8} {:>8} {:>8}",
        "it", "energy", "scaf", "cdt", "assemble", "symbolic", "numeric", "solve", "search"
    );
    for (i, s) in h.seconds.iter().enumerate() {
        let e = h.energy.get(i + 1).copied().unwrap_or(f64::NAN);
        println!(
            "{:>4} {:>10.6} {:>6}{} {:>7.4} {:>8.4} {:>8.4} {:>8.4} {:>8.4} {:>8.4}",
            i + 1,
            e,
            h.scaffold_triangles[i],
            if h.remeshed[i] { "*" } else { " " },
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5]
        );
    }
    let sum: [f64; 6] = h.seconds.iter().fold([0.0; 6], |mut a, s| {
        for k in 0..6 {
            a[k] += s[k];
        }
        a
    });
    let m = uvflat_core::metrics::chart_metrics(&chart.positions, &chart.triangles, &sol.uv, &chart.boundary_loops);
    println!(
        "scaffold chart {best:.3} s (min of {repeat}; {} it; cdt {:.3} assemble {:.3} symbolic {:.3} numeric {:.3} solve {:.3} search {:.3}); flips {}, overlap {}, symmetric Dirichlet {:.6}",
        sol.iterations, sum[0], sum[1], sum[2], sum[3], sum[4], sum[5], m.flips, m.overlap, m.distortion.symmetric_dirichlet
    );
    for m in [Method::Scaffold(options), Method::Slim(Default::default())] {
        let t = Instant::now();
        let r = unwrap(&soup.input(), &UnwrapOptions { method: m.clone(), ..Default::default() }).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let flips: usize = r.charts.iter().map(|c| c.flips).sum();
        let overlaps = r.charts.iter().filter(|c| c.overlap).count();
        let w: f64 = r.charts.iter().map(|c| c.faces as f64).sum();
        let sd = r.charts.iter().map(|c| c.faces as f64 * c.distortion.symmetric_dirichlet).sum::<f64>() / w;
        println!(
            "unwrap {:<8} {secs:.3} s, {} chart(s), flips {flips}, overlapping charts {overlaps}, symmetric Dirichlet {sd:.6}",
            m.name(),
            r.charts.len()
        );
    }
}
