//! Automatic seams on one mesh: per-chart report.
//! `cargo run --release -p uvflat-core --example autoseams -- MESH [METHOD]`
use uvflat_core::{unwrap, Method, MeshInput, UnwrapOptions};

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let s = common::load(std::path::Path::new(&args[1]));
    let method = Method::parse(args.get(2).map(|s| s.as_str()).unwrap_or("abf"), &[]).unwrap();
    let input: MeshInput = s.input();
    {
        use uvflat_core::charts::build_charts;
        use uvflat_core::cuts;
        let mesh = uvflat_core::mesh::PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
        let avoid = vec![false; s.positions.len()];
        for c in build_charts(&mesh, &[], None).iter().filter(|c| cuts::needs_cut(c)) {
            let t = std::time::Instant::now();
            let cut = cuts::cut_chart(&mesh, c, &cuts::AutoSeamOptions::default(), &avoid, &[], 0);
            println!(
                "cut of a {}-face chart: {} cones, max |u| {:.3} (bound {:.3}), {} edges, {:.3} s",
                c.faces.len(), cut.cones.len(), cut.max_log_scale, 2f64.ln(), cut.edges.len(), t.elapsed().as_secs_f64()
            );
        }
    }
    let t = std::time::Instant::now();
    let r = unwrap(&input, &UnwrapOptions { method, ..Default::default() }).unwrap();
    println!("{} charts, {} new seams, {:.3} s", r.charts.len(), r.new_seams.len(), t.elapsed().as_secs_f64());
    for c in &r.charts {
        println!(
            "chart {:>3} {:>6} faces {:?} {:>8} cones {} cut {:.3} flips {} overlap {} conf {:.3} area {:.3} outside {:.3} {:.2}s {:?}",
            c.id, c.faces, c.kind, c.status.name(), c.cones, c.cut_length, c.flips, c.overlap, c.distortion.conformal, c.distortion.area,
            c.density.outside, c.seconds, c.reason
        );
    }
}
