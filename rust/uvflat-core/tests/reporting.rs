//! What the unwrap reports beside the UVs: non-manifold edges, reason codes, degenerate charts.

mod common;

use common::*;
use uvflat_core::{unwrap, ChartStatus, UnwrapOptions};

fn soup(positions: Vec<[f64; 3]>, corner_verts: Vec<u32>, face_sizes: Vec<u32>) -> Soup {
    Soup { positions, corner_verts, face_sizes }
}

#[test]
fn non_manifold_edges_are_counted_and_cut() {
    // Three triangles on edge 0-1 (a fin).
    let s = soup(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, -1.0, 0.0], [0.5, 0.0, 1.0]],
        vec![0, 1, 2, 1, 0, 3, 0, 1, 4],
        vec![3, 3, 3],
    );
    let r = unwrap(&s.input(), &UnwrapOptions::default()).unwrap();
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.charts.len(), 3, "the non-manifold edge is a cut");
    let disk = planar_disk(3, 8);
    assert_eq!(unwrap(&disk.input(), &UnwrapOptions::default()).unwrap().non_manifold_edges, 0);
}

#[test]
fn reason_codes() {
    let disk = planar_disk(3, 8);
    let r = unwrap(&disk.input(), &UnwrapOptions::default()).unwrap();
    assert_eq!(r.charts[0].reason_code(), "solved");
    // a closed tetrahedron: no boundary
    let tet = soup(
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3],
        vec![3, 3, 3, 3],
    );
    // (automatic seams off: with them the tetrahedron is cut open and solved)
    let no_cuts = UnwrapOptions {
        auto_seams: uvflat_core::AutoSeamOptions { enabled: false, ..Default::default() },
        ..Default::default()
    };
    let r = unwrap(&tet.input(), &no_cuts).unwrap();
    assert_eq!(r.charts[0].status, ChartStatus::Failed);
    assert_eq!(r.charts[0].reason_code(), "failed_closed");
}

#[test]
fn a_chart_without_area_is_all_flips_never_nan() {
    let s = soup(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], vec![0, 1, 2], vec![3]);
    let r = unwrap(&s.input(), &UnwrapOptions::default()).unwrap();
    let c = &r.charts[0];
    if c.status != ChartStatus::Failed {
        assert_eq!(c.flips, 1);
        assert!(!c.distortion.conformal.is_nan() && !c.distortion.area.is_nan());
    }
}
