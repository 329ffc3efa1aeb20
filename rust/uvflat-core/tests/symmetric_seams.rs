//! Mirror-symmetric seams: on a mesh that is its own mirror image, with
//! `AutoSeamOptions::symmetry`, the set of new seam edges maps onto itself under the mirror.

use std::collections::BTreeSet;

use uvflat_core::charts::build_charts;
use uvflat_core::cuts::{self, symmetry, AutoSeamOptions, ChartGraph, Symmetry};
use uvflat_core::mesh::PolyMesh;
use uvflat_core::{unwrap, ChartKind, ChartStatus, UnwrapOptions};

mod common;

use common::{cube_sphere, Soup as Mesh};

/// A closed blob mirror-symmetric in the plane x = 0 only: a subdivided cube projected on the
/// sphere (n × n quads a side, n a power of two so the grid is exactly symmetric), bent by a
/// map that is odd in x for x and even in x for y and z, with two "ears" at (±0.6, 0.8, 0) and
/// one snout at (0, 0.2, 1) on the plane. `ears` = (left, right) heights.
fn blob(n: usize, ears: (f64, f64)) -> Mesh {
    let Mesh { mut positions, corner_verts, face_sizes } = cube_sphere(n);
    for p in &mut positions {
        let [x, y, z] = *p;
        let bump = |d: [f64; 3]| (-((x - d[0]).powi(2) + (y - d[1]).powi(2) + (z - d[2]).powi(2)) / 0.06).exp();
        let out = 1.0 + ears.0 * bump([-0.6, 0.8, 0.0]) + ears.1 * bump([0.6, 0.8, 0.0]) + 0.3 * bump([0.0, 0.2, 1.0]);
        let (x, y, z) = (x * out, y * out, z * out);
        *p = [x * (1.0 + 0.2 * y), 1.4 * y + 0.3 * x * x - 0.2 * z * z, 0.8 * z + 0.25 * y * y + 0.15 * x * x];
    }
    Mesh { positions, corner_verts, face_sizes }
}

/// Rotate and move every position (a generic rigid motion).
fn moved(mut m: Mesh) -> Mesh {
    let (a, b) = (0.7f64, -0.4f64);
    let rz = |p: [f64; 3]| [a.cos() * p[0] - a.sin() * p[1], a.sin() * p[0] + a.cos() * p[1], p[2]];
    let rx = |p: [f64; 3]| [p[0], b.cos() * p[1] - b.sin() * p[2], b.sin() * p[1] + b.cos() * p[2]];
    for p in &mut m.positions {
        let q = rx(rz(*p));
        *p = [q[0] + 3.0, q[1] - 1.0, q[2] + 0.5];
    }
    m
}

/// The mirror of mesh vertices in the plane through `centre` with unit `normal`, by brute
/// force (nearest reflected vertex, which must be within 1e-9).
fn mirror_of(m: &Mesh, centre: [f64; 3], normal: [f64; 3]) -> Vec<u32> {
    m.positions
        .iter()
        .map(|p| {
            let d = (p[0] - centre[0]) * normal[0] + (p[1] - centre[1]) * normal[1] + (p[2] - centre[2]) * normal[2];
            let r = [p[0] - 2.0 * d * normal[0], p[1] - 2.0 * d * normal[1], p[2] - 2.0 * d * normal[2]];
            let (w, dist) = m
                .positions
                .iter()
                .enumerate()
                .map(|(w, q)| (w, ((q[0] - r[0]).powi(2) + (q[1] - r[1]).powi(2) + (q[2] - r[2]).powi(2)).sqrt()))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            assert!(dist < 1e-9, "the test mesh is not symmetric: {dist}");
            w as u32
        })
        .collect()
}

fn image(seams: &[[u32; 2]], mirror: &[u32]) -> BTreeSet<[u32; 2]> {
    seams
        .iter()
        .map(|s| {
            let (a, b) = (mirror[s[0] as usize], mirror[s[1] as usize]);
            [a.min(b), a.max(b)]
        })
        .collect()
}

fn set(seams: &[[u32; 2]]) -> BTreeSet<[u32; 2]> {
    seams.iter().copied().collect()
}

fn centroid(m: &Mesh) -> [f64; 3] {
    let n = m.positions.len() as f64;
    let mut c = [0.0; 3];
    for p in &m.positions {
        for k in 0..3 {
            c[k] += p[k] / n;
        }
    }
    c
}

/// Cut the blob's single chart with `symmetry`; returns the cut.
fn cut(m: &Mesh, symmetry: Symmetry) -> cuts::ChartCuts {
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let charts = build_charts(&mesh, &[], None);
    assert_eq!(charts.len(), 1);
    let avoid = vec![false; m.positions.len()];
    let o = AutoSeamOptions { symmetry, ..Default::default() };
    let c = cuts::cut_chart(&mesh, &charts[0], &o, &avoid, &[], 0);
    // The cut opens the closed blob into one disk.
    let pieces = build_charts(&mesh, &c.seams, None);
    assert_eq!(pieces.len(), 1, "the cut disconnects the chart");
    assert_eq!(pieces[0].kind, ChartKind::Disk);
    c
}

#[test]
fn without_symmetry_the_seams_are_not_their_own_mirror_image() {
    // The control: the mesh is symmetric, yet an ordinary cut is not.
    let m = blob(16, (0.5, 0.5));
    let mirror = mirror_of(&m, centroid(&m), [1.0, 0.0, 0.0]);
    let c = cut(&m, Symmetry::None);
    assert!(!c.mirrored);
    assert_ne!(image(&c.seams, &mirror), set(&c.seams));
}

#[test]
fn with_symmetry_x_the_seams_map_onto_themselves() {
    let m = blob(16, (0.5, 0.5));
    let mirror = mirror_of(&m, centroid(&m), [1.0, 0.0, 0.0]);
    let c = cut(&m, Symmetry::X);
    assert!(c.mirrored);
    assert!(!c.seams.is_empty());
    assert_eq!(image(&c.seams, &mirror), set(&c.seams));
    // The cones come in mirror pairs (or lie on the plane).
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    let cones: BTreeSet<u32> = c.cones.iter().map(|&v| chart.mesh_vertex[v as usize]).collect();
    let mirrored: BTreeSet<u32> = cones.iter().map(|&v| mirror[v as usize]).collect();
    assert_eq!(cones, mirrored);
}

#[test]
fn without_vertices_on_the_plane_the_cut_crosses_it_by_one_edge() {
    // An odd grid: no vertex lies on x = 0, every edge across the plane joins a mirror pair.
    let m = blob(15, (0.5, 0.5));
    assert!(m.positions.iter().all(|p| p[0].abs() > 1e-6));
    let mirror = mirror_of(&m, centroid(&m), [1.0, 0.0, 0.0]);
    let c = cut(&m, Symmetry::X);
    assert!(c.mirrored);
    assert_eq!(image(&c.seams, &mirror), set(&c.seams));
    let crossing = c.seams.iter().filter(|s| m.positions[s[0] as usize][0] * m.positions[s[1] as usize][0] < 0.0).count();
    assert_eq!(crossing, 1);
}

#[test]
fn auto_finds_the_mirror_plane_of_a_moved_mesh() {
    let m = moved(blob(16, (0.5, 0.5)));
    // The mirror plane moved with the mesh: through the centroid, normal R·x̂.
    let (a, b) = (0.7f64, -0.4f64);
    let nz = [a.cos(), a.sin(), 0.0];
    let normal = [nz[0], b.cos() * nz[1] - b.sin() * nz[2], b.sin() * nz[1] + b.cos() * nz[2]];
    let mirror = mirror_of(&m, centroid(&m), normal);
    let c = cut(&m, Symmetry::Auto);
    assert!(c.mirrored);
    assert_eq!(image(&c.seams, &mirror), set(&c.seams));
    // No world axis is a mirror of the moved mesh: asking for X finds none and plans as usual.
    let x = cut(&m, Symmetry::X);
    assert!(!x.mirrored);
}

#[test]
fn an_asymmetric_mesh_has_no_mirror() {
    let m = blob(16, (0.5, 0.3));
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    let graph = ChartGraph::new(&mesh, chart);
    for s in [Symmetry::None, Symmetry::X, Symmetry::Y, Symmetry::Z, Symmetry::Auto] {
        assert!(symmetry::detect(&graph, &chart.positions, s).is_none(), "{s:?}");
    }
    // The symmetric blob has exactly the x mirror, an involution that keeps edges.
    let m = blob(16, (0.5, 0.5));
    let mesh = PolyMesh::new(&m.positions, &m.corner_verts, &m.face_sizes).unwrap();
    let chart = &build_charts(&mesh, &[], None)[0];
    let graph = ChartGraph::new(&mesh, chart);
    assert!(symmetry::detect(&graph, &chart.positions, Symmetry::Y).is_none());
    assert!(symmetry::detect(&graph, &chart.positions, Symmetry::Z).is_none());
    let mirror = symmetry::detect(&graph, &chart.positions, Symmetry::X).unwrap();
    for v in 0..chart.positions.len() {
        assert_eq!(mirror.vertex[mirror.vertex[v] as usize] as usize, v);
    }
    for e in 0..graph.edges.len() {
        assert_eq!(mirror.edge[mirror.edge[e] as usize] as usize, e);
    }
}

#[test]
fn an_unwrap_with_symmetry_has_mirror_symmetric_new_seams() {
    let m = blob(16, (0.5, 0.5));
    let mirror = mirror_of(&m, centroid(&m), [1.0, 0.0, 0.0]);
    let mut o = UnwrapOptions::default();
    o.auto_seams.symmetry = Symmetry::X;
    let r = unwrap(&m.input(), &o).unwrap();
    assert!(!r.new_seams.is_empty());
    // One island: no split broke the symmetry.
    assert_eq!(r.charts.len(), 1, "{:?}", r.charts);
    assert_eq!(image(&r.new_seams, &mirror), set(&r.new_seams));
    // And the island keeps the atlas rule.
    assert_eq!(r.charts[0].status, ChartStatus::Solved, "{:?}", r.charts[0]);
}
