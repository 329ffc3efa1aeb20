//! What the pipeline knows about a cut chart's pieces without building them: how many there
//! are and which triangles each holds ([`ChartCutter::pieces_after`],
//! [`ChartCutter::triangle_pieces`], checked against the charts actually built for random
//! cuts of triangle, quad and n-gon meshes), each piece's predicted flattening read on the
//! chart with the cut held, and the vertex order a large piece inherits from its chart
//! ([`Chart::inherit_vertex_order`]).

mod common;

use common::{brick_hexagons, cube, sphere, QuadRng, Soup};
use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{cones::ScaleSolver, predicted_ratios, AutoSeamOptions, ChartCuts, ChartCutter};
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
        let built = build_charts(&mesh, &cut.seams, None);
        assert_eq!(cutter.pieces_after(&cut), built.len(), "p = {p}, {} cut edges", cut.edges.len());
        // The labels are the built charts: a chart's faces share one label, charts differ.
        let (labels, n) = cutter.triangle_pieces(&cut);
        assert_eq!(n, built.len(), "p = {p}");
        assert_eq!(labels.len(), chart.triangles.len());
        let mut piece_of_face = vec![usize::MAX; s.face_sizes.len()];
        for (k, c) in built.iter().enumerate() {
            for &f in &c.faces {
                piece_of_face[f as usize] = k;
            }
        }
        let mut label_of_piece = vec![u32::MAX; built.len()];
        for (t, &f) in chart.triangle_face.iter().enumerate() {
            let k = piece_of_face[f as usize];
            assert!(labels[t] < n as u32);
            if label_of_piece[k] == u32::MAX {
                label_of_piece[k] = labels[t];
            }
            assert_eq!(label_of_piece[k], labels[t], "p = {p}: face {f} of piece {k} labelled apart from it");
        }
        let mut seen = label_of_piece.clone();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), built.len(), "p = {p}: two pieces share a label");
    }
}

/// A cut into several pieces is predicted on the chart with the cut's vertices held: per
/// piece, relative to the piece's own mean, the density ratios of the piece's own system.
#[test]
fn each_piece_of_a_cut_is_predicted_as_on_its_own() {
    // An open sphere (its south cap off: a disk of quads and triangles), cut along two
    // parallels into a cap, a band and the rest.
    let s = sphere(24, 12, |c| c[2] > -0.8);
    let mesh = PolyMesh::new(&s.positions, &s.corner_verts, &s.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    let chart = &charts[0];
    let options = AutoSeamOptions::default();
    let avoid = vec![false; s.positions.len()];
    let cutter = ChartCutter::new(&mesh, chart, &options, &avoid);
    let on = |v: u32, j: f64| (chart.positions[v as usize][2] - (std::f64::consts::PI * j / 12.0).cos()).abs() < 1e-9;
    let mut cut = ChartCuts::default();
    for e in &cutter.graph().edges {
        if [3.0, 7.0].iter().any(|&j| on(e[0], j) && on(e[1], j)) {
            cut.edges.push(*e);
            let (a, b) = (chart.mesh_vertex[e[0] as usize], chart.mesh_vertex[e[1] as usize]);
            cut.seams.push([a.min(b), a.max(b)]);
        }
    }
    assert_eq!(cut.edges.len(), 48);
    let built = build_charts(&mesh, &cut.seams, None);
    let (labels, n) = cutter.triangle_pieces(&cut);
    assert_eq!((n, built.len()), (3, 3));
    let all = cutter.predicted_ratios_after(&cut).expect("a disk cut into pieces is predicted");
    for piece in &built {
        let own = predicted_ratios(piece, &ScaleSolver::new(piece).unwrap()).unwrap();
        // This piece's triangles of the chart, and their mean ratio.
        let label = labels[chart.triangle_face.iter().position(|&f| f == piece.faces[0]).unwrap()];
        let mine: Vec<usize> = (0..labels.len()).filter(|&t| labels[t] == label).collect();
        assert_eq!(mine.len(), piece.triangles.len());
        let area: f64 = mine.iter().map(|&t| all[t].1).sum();
        let mean = mine.iter().map(|&t| all[t].0 * all[t].1).sum::<f64>() / area;
        // Per face, the area-weighted ratio (a quad's two triangles summed), to the solves' round-off.
        let mut per_face = std::collections::BTreeMap::<u32, [f64; 2]>::new();
        for &t in &mine {
            per_face.entry(chart.triangle_face[t]).or_default()[0] += all[t].0 / mean * all[t].1;
        }
        for (t, &f) in piece.triangle_face.iter().enumerate() {
            per_face.get_mut(&f).expect("the same faces")[1] += own[t].0 * own[t].1;
        }
        let spread = own.iter().map(|x| x.0).fold(0.0f64, f64::max) / own.iter().map(|x| x.0).fold(f64::MAX, f64::min);
        assert!(spread > 1.05, "the pieces' flattening is not trivially flat ({spread})");
        for (f, [a, b]) in per_face {
            assert!((a - b).abs() <= 1e-7 * b.abs(), "face {f}: {a} on the chart, {b} on the piece's own system");
        }
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
