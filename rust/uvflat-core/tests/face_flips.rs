//! Per-face flips: `Unwrapped::face_flips` and `MeshMetrics::face_flips` hold the flipped
//! triangles of every face as the reports count them, so each chart's `flips` is the sum over
//! its faces (quads on both diagonal splits, n-gons on the render triangles as well as on the
//! core's own split when a render diagonal is already an edge of the chart).

mod common;

use uvflat_core::metrics::{measure, measure_with_triangles};
use uvflat_core::{unwrap, AutoSeamOptions, Method, MeshInput, UnwrapOptions, Unwrapped};

/// Every chart's `flips` is the sum of `face_flips` over its faces; faces without UVs hold 0.
/// Returns the total.
fn assert_sums(name: &str, r: &Unwrapped) -> usize {
    assert_eq!(r.face_flips.len(), r.face_chart.len(), "{name}");
    let mut per_chart = vec![0usize; r.charts.len()];
    for (f, &c) in r.face_chart.iter().enumerate() {
        if c >= 0 && r.face_solved(f) {
            per_chart[c as usize] += r.face_flips[f] as usize;
        } else {
            assert_eq!(r.face_flips[f], 0, "{name}: face {f} has no UVs but holds flips");
        }
    }
    for (report, &sum) in r.charts.iter().zip(&per_chart) {
        assert_eq!(report.flips, sum, "{name}: chart {} reports {} flips, its faces hold {sum}", report.id, report.flips);
    }
    per_chart.iter().sum()
}

fn lscm(auto_seams: bool) -> UnwrapOptions {
    UnwrapOptions {
        method: Method::parse("lscm", &[]).unwrap(),
        auto_seams: AutoSeamOptions { enabled: auto_seams, ..Default::default() },
        ..Default::default()
    }
}

/// A regular pentagon `0..5` and a triangle `[0, 2, 1]` folded over its ear (vertex 1 inside
/// the chart, shared by the two faces only): the edge 0-2 exists, so the pentagon's render fan
/// from corner 0 cannot be the core's split and is measured beside it.
fn pentagon_and_cap() -> (Vec<[f64; 3]>, Vec<u32>, Vec<u32>, Vec<[u32; 3]>, Vec<[f64; 2]>) {
    let ring: Vec<[f64; 2]> = (0..5)
        .map(|k| {
            let a = std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU * k as f64 / 5.0;
            [a.cos(), a.sin()]
        })
        .collect();
    let positions: Vec<[f64; 3]> = ring.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let corner_verts = vec![0, 1, 2, 3, 4, 0, 2, 1];
    let face_sizes = vec![5, 3];
    // Blender's loop triangles: the pentagon as a fan from its first corner, then the triangle.
    let triangles = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [5, 6, 7]];
    let mut uv: Vec<[f64; 2]> = corner_verts.iter().map(|&v| ring[v as usize]).collect();
    uv.truncate(8);
    (positions, corner_verts, face_sizes, triangles, uv)
}

#[test]
fn a_cap_over_an_ear_is_the_flipped_face() {
    let (p, cv, fs, tris, uv) = pentagon_and_cap();
    // The cap runs against the pentagon's three triangles: it is the one flip.
    let m = measure_with_triangles(&p, &cv, &fs, &uv, None, &tris).unwrap();
    assert_eq!(m.charts, 1);
    assert_eq!(m.face_flips, vec![0, 1]);
    assert_eq!(m.flips, 1);
}

#[test]
fn a_fold_only_the_render_triangles_show_is_charged_to_its_ngon() {
    let (p, cv, fs, tris, mut uv) = pentagon_and_cap();
    // Vertex 1 moved to the centre in UV (corners 1 and 7): every split of the pentagon that
    // avoids the edge 0-2 stays positive, and so does the cap, but the render triangle
    // (0, 1, 2) folds. The core counts it on the pentagon.
    uv[1] = [0.0, 0.0];
    uv[7] = [0.0, 0.0];
    let m = measure_with_triangles(&p, &cv, &fs, &uv, None, &tris).unwrap();
    assert_eq!(m.face_flips, vec![1, 0]);
    assert_eq!(m.flips, 1);
    // Without the render triangles the core's own split is all there is: no flip.
    let own = measure(&p, &cv, &fs, &uv, None).unwrap();
    assert_eq!(own.face_flips, vec![0, 0]);
    assert_eq!(own.flips, 0);
}

#[test]
fn a_dart_quad_holds_its_fold() {
    // A square in 3D, a dart in UV: split 0-2 positive, split 1-3 folds once.
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0]];
    let cv = vec![0, 1, 2, 3, 1, 4, 2];
    let fs = vec![4, 3];
    let uv = vec![[0.0, 0.0], [2.0, 0.0], [0.5, 0.5], [0.0, 2.0], [2.0, 0.0], [3.0, 0.0], [0.5, 0.5]];
    let m = measure(&p, &cv, &fs, &uv, None).unwrap();
    assert_eq!(m.face_flips, vec![1, 0]);
    assert_eq!(m.flips, 1);
    // Unselected faces are not measured and hold 0.
    let m = measure(&p, &cv, &fs, &uv, Some(&[false, true])).unwrap();
    assert_eq!(m.face_flips, vec![0, 0]);
}

#[test]
fn reports_are_the_sum_of_their_faces_on_quads_and_ngons() {
    // LSCM folds the darts of the quad grid and the concave hexagons of the brick wall.
    let (grid, seams) = common::curved_quad_grid(24, 0x9e37_79b9_7f4a_7c15);
    let bricks = common::brick_hexagons(16, 0x2545_f491_4f6c_dd1d);
    let mut folded = 0;
    for (name, soup, seams) in [("quad grid", &grid, &seams[..]), ("brick hexagons", &bricks, &[][..])] {
        // A fan from every face's first corner as the render triangulation, and none.
        let mut fan = Vec::new();
        let mut start = 0u32;
        for &s in &soup.face_sizes {
            fan.extend((1..s - 1).map(|k| [start, start + k, start + k + 1]));
            start += s;
        }
        for triangles in [&fan[..], &[][..]] {
            for auto in [false, true] {
                let input = MeshInput { seams, triangles, ..soup.input() };
                let r = unwrap(&input, &lscm(auto)).unwrap();
                let name = format!("{name}, render triangles {}, auto seams {auto}", !triangles.is_empty());
                let total = assert_sums(&name, &r);
                // The same UVs measured from scratch: the same faces.
                let m = measure_with_triangles(&soup.positions, &soup.corner_verts, &soup.face_sizes, &r.uv, None, triangles).unwrap();
                assert_eq!(m.flips, m.face_flips.iter().map(|&n| n as usize).sum::<usize>(), "{name}");
                if !auto {
                    assert_eq!(m.face_flips, r.face_flips, "{name}: measure and the unwrap disagree");
                }
                folded += total;
            }
        }
    }
    assert!(folded > 0, "the test surfaces should make LSCM fold");
}

#[test]
fn shared_meshes_reports_are_the_sum_of_their_faces() {
    let Some(dir) = common::shared_meshes() else { return };
    // (LSCM with automatic seams on the closed quad cube repairs for a minute: abf only.)
    for (file, methods) in [("halftunnel.off", &["lscm", "abf"][..]), ("alligator.obj", &["lscm", "abf"]), ("cube_40k.obj", &["abf"])] {
        let soup = common::load(&dir.join(file));
        for &method in methods {
            let options = UnwrapOptions { method: Method::parse(method, &[]).unwrap(), ..Default::default() };
            let r = unwrap(&soup.input(), &options).unwrap();
            assert_sums(&format!("{file} {method}"), &r);
        }
    }
}
