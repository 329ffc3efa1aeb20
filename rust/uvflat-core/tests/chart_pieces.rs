//! What the pipeline knows about a cut chart's pieces without building them: how many there
//! are ([`ChartCutter::pieces_after`], checked against the charts actually built for random
//! cuts of triangle, quad and n-gon meshes), and the vertex order a large piece inherits from
//! its chart ([`Chart::inherit_vertex_order`]).

mod common;

use common::{brick_hexagons, cube, sphere, QuadRng, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{AutoSeamOptions, ChartCuts, ChartCutter};
use uvflat_core::mesh::PolyMesh;

/// Random cuts of the one chart of `s` (each edge cut with probability `p`): the cutter's
/// count equals the number of charts built with those seams.
fn check_counts(s: &Soup, seed: u64) {
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let chart = &charts[0];
    let options = AutoSeamOptions::default();
    let avoid = vec![false; s.positions.len()];
    let cutter = ChartCutter::new(&mesh, chart, &options, &avoid);
    let mut rng = QuadRng(seed);
    for p in [0.0, 0.02, 0.1, 0.3, 0.6] {
        let mut cut = ChartCuts::default();
        for e in &cutter.graph().edges {
            if rng.next() < p {
                cut.edges.push(*e);
                let (a, b) = (chart.mesh_vertex[e[0] as usize], chart.mesh_vertex[e[1] as usize]);
                cut.seams.push([a.min(b), a.max(b)]);
            }
        }
        let built = build_charts(&mesh, &cut.seams, None).len();
        assert_eq!(cutter.pieces_after(&cut), built, "p = {p}, {} cut edges", cut.edges.len());
    }
}

#[test]
fn pieces_after_a_cut_are_the_charts_built_along_it() {
    check_counts(&cube(5), 3);
    check_counts(&brick_hexagons(8, 7), 11);
    check_counts(&sphere(16, 12, |_| true), 5);
    check_counts(&sphere(24, 12, |c| c[2] > -0.5), 9);
}

#[test]
fn a_large_piece_inherits_its_charts_vertex_order() {
    // A closed sphere of 41,282 vertices (over the size where an ordering costs about a second), cut
    // along one meridian from pole to pole: a disk whose meridian vertices are doubled.
    let (nu, nv) = (320, 130);
    let s = sphere(nu, nv, |_| true);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    let ring = |j: usize| (1 + (j - 1) * nu) as u32;
    let mut seams: Vec<[u32; 2]> = vec![[0, ring(1)]];
    for j in 1..nv - 1 {
        seams.push([ring(j), ring(j + 1)]);
    }
    let south = (s.positions.len() - 1) as u32;
    seams.push([ring(nv - 1), south]);
    let pieces = build_charts(&mesh, &seams, None);
    assert_eq!(pieces.len(), 1);
    let piece = &pieces[0];
    let n = piece.positions.len();
    assert_eq!(n, s.positions.len() + nv - 1, "the meridian's vertices between the poles are doubled");

    // Without the chart's order known, nothing is inherited.
    let fresh = build_charts(&mesh, &seams, None).remove(0);
    fresh.inherit_vertex_order(chart);
    let own = fresh.vertex_order().to_vec();

    let parent = chart.vertex_order().to_vec();
    piece.inherit_vertex_order(chart);
    let order = piece.vertex_order();
    assert_ne!(order, own.as_slice(), "the piece took the chart's order, not one of its own");
    // A permutation of the piece's vertices.
    let mut seen = vec![false; n];
    for &v in order {
        assert!(!std::mem::replace(&mut seen[v as usize], true), "vertex {v} twice");
    }
    assert!(seen.iter().all(|&x| x));
    // In the chart's order by mesh vertex, both copies of a doubled vertex side by side.
    let mut rank = vec![0usize; s.positions.len()];
    for (r, &v) in parent.iter().enumerate() {
        rank[chart.mesh_vertex[v as usize] as usize] = r;
    }
    let ranks: Vec<usize> = order.iter().map(|&v| rank[piece.mesh_vertex[v as usize] as usize]).collect();
    assert!(ranks.windows(2).all(|w| w[0] <= w[1]), "the chart's order is kept");
}
