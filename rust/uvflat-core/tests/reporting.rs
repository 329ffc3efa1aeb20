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

/// A Möbius strip of `n` quads: the closing quad runs its first edge the way the first quad
/// does, so the surface is one-sided.
fn moebius(n: usize) -> Soup {
    let mut positions = Vec::new();
    for i in 0..n {
        let t = std::f64::consts::TAU * i as f64 / n as f64;
        for s in [-0.3, 0.3] {
            let r = 1.0 + s * (t / 2.0).cos();
            positions.push([r * t.cos(), r * t.sin(), s * (t / 2.0).sin()]);
        }
    }
    let n = n as u32;
    let mut corner_verts = Vec::new();
    for i in 0..n - 1 {
        corner_verts.extend([2 * i, 2 * i + 1, 2 * i + 3, 2 * i + 2]);
    }
    corner_verts.extend([2 * (n - 1), 2 * (n - 1) + 1, 0, 1]);
    soup(positions, corner_verts, vec![4; n as usize])
}

#[test]
fn edges_between_opposite_normals_are_counted_and_cut() {
    // A flipped face inside a disk: its three inner edges are cuts, so it is an island of
    // its own, and nothing else is counted.
    let mut disk = planar_disk(3, 8);
    let inner = (0..disk.face_sizes.len())
        .find(|&f| {
            let verts = &disk.corner_verts[3 * f..3 * f + 3];
            let outer_ring = 1 + 8 * 3 * 2 / 2; // the first vertex of the outline's ring
            verts.iter().all(|&v| v < outer_ring)
        })
        .unwrap();
    disk.corner_verts[3 * inner..3 * inner + 3].reverse();
    let r = unwrap(&disk.input(), &UnwrapOptions::default()).unwrap();
    assert_eq!((r.inconsistent_edges, r.non_manifold_edges), (3, 0));
    assert_eq!(r.charts.len(), 2);
    assert!(r.charts.iter().all(|c| c.status == ChartStatus::Solved && c.flips == 0));
    assert_eq!(unwrap(&planar_disk(3, 8).input(), &UnwrapOptions::default()).unwrap().inconsistent_edges, 0);

    // A Möbius strip: the one edge where the orientation cannot agree is cut, which makes the
    // strip a disk; nothing flips.
    let strip = moebius(40);
    let r = unwrap(&strip.input(), &UnwrapOptions::default()).unwrap();
    assert_eq!(r.inconsistent_edges, 1);
    assert_eq!(r.charts.len(), 1);
    assert_eq!(r.charts[0].kind, uvflat_core::ChartKind::Disk);
    assert_eq!(r.charts[0].flips, 0);
    assert!(r.new_seams.is_empty(), "no cut beyond the inconsistent edge: {:?}", r.new_seams);
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
