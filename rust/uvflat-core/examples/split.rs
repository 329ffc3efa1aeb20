//! The split candidates of every chart of a mesh (the Fiedler vector, the minimum cuts of its
//! levels and the planar split), timed: the cost of a split in the repair.
//! `cargo run --release -p uvflat-core --example split -- MESH [LEVELS]`
use uvflat_core::charts::build_charts;
use uvflat_core::cuts;

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let s = common::mesh_from_args(&args);
    let mesh = uvflat_core::mesh::PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let avoid = vec![false; s.positions.len()];
    let options = cuts::AutoSeamOptions::default();
    for chart in build_charts(&mesh, &[], None).iter().filter(|c| c.faces.len() >= 2) {
        // As in the repair: the cutter (and with it the chart's vertex order) exists already.
        let t = std::time::Instant::now();
        let cutter = cuts::ChartCutter::new(&mesh, chart, &options, &avoid);
        let _ = chart.vertex_order();
        let setup = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let f = cuts::fiedler::fiedler_vector(chart);
        let fiedler = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let candidates = cuts::split::candidates(cutter.graph(), cutter.costs(), chart, &avoid);
        let edges: Vec<usize> = candidates.iter().map(|c| c.len()).collect();
        println!(
            "{} triangles: cutter {setup:.2} s, Fiedler vector {fiedler:.2} s ({}), candidates {:.2} s with seam edges {edges:?}",
            chart.triangles.len(),
            if f.is_some() { "found" } else { "none" },
            t.elapsed().as_secs_f64()
        );
    }
}
